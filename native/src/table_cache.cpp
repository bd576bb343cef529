// The class-table cache (knit/table_cache.h).
//
// An entry is one file, <hash of the key>.knittable, in the cache folder:
//
//   "KNITTBL1"                      8 bytes
//   key size (u64), key             everything the stage's build reads (class_table_entry)
//   payload size (u64), payload     the FootprintTable, then a flag and the TableBsdf
//   FNV-1a 64 of all bytes before   (u64)
//
// A material with a tabulated BSDF has three entries, one per stage of the
// build (TableBsdf::Stage), each with the class table: its shadows (the
// geometry's key), its marches (the yarn BSDF's and ply's parameters too)
// and its finished tables (the colours and table_fold too); put_key says
// what each holds. Without a tabulated BSDF the class table, which is
// geometry alone, is the one entry, under the shadows' key.
//
// in the machine's own byte order (the build id in the key pins the
// machine's kind). Every size is checked against what is left of the file
// before it is read, and the tables' shapes against each other after.
#include "knit/table_cache.h"

#include <link.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <stdexcept>
#include <system_error>
#include <type_traits>
#include <vector>

#include "knit/shading.h"
#include "knit/table_progress.h"
#include "table_cache_internal.h"

namespace knit {

namespace fs = std::filesystem;

namespace {

std::mutex g_mutex;
TableCacheSettings g_settings;  // dir empty: off

constexpr char kMagic[8] = {'K', 'N', 'I', 'T', 'T', 'B', 'L', '1'};
// A key's first string. Format 3 (2026-12-02): a finished table weighs its
// classes by their cells counted over the whole pattern (format 2 counted a
// sample of at most 1024 per class). Format 4 (2026-12-05): the class
// table keeps hit fractions per eighth of a cell.
constexpr const char* kKeyFormat = "knitshade class table, format 4";
// A key's second string: its stage's name.
const char* stage_name(TableBsdf::Stage stage) {
  return stage == TableBsdf::Stage::Shadows ? "shadows" : stage == TableBsdf::Stage::Marched ? "marches" : "finished";
}
constexpr uint64_t kMaxEntryBytes = uint64_t(1) << 30;  // (a table is a few MiB at most)

uint64_t fnv1a(const unsigned char* p, size_t n, uint64_t h = 0xcbf29ce484222325ull) {
  for (size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 0x100000001b3ull;
  }
  return h;
}

// Bytes appended field by field.
class Writer {
 public:
  template <class T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const unsigned char*>(&v);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
  }
  template <class T>
  void put_vector(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    put(uint64_t(v.size()));
    const auto* p = reinterpret_cast<const unsigned char*>(v.data());
    bytes_.insert(bytes_.end(), p, p + v.size() * sizeof(T));
  }
  void put_string(const std::string& s) {
    put(uint64_t(s.size()));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
  }
  std::vector<unsigned char>& bytes() { return bytes_; }

 private:
  std::vector<unsigned char> bytes_;
};

// Reads what a Writer wrote; every read fails (and stays failed) rather
// than run past the end.
class Reader {
 public:
  Reader(const unsigned char* p, size_t n) : p_(p), left_(n) {}
  template <class T>
  bool get(T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    if (!ok_ || left_ < sizeof(T)) return ok_ = false;
    std::memcpy(&v, p_, sizeof(T));
    p_ += sizeof(T);
    left_ -= sizeof(T);
    return true;
  }
  template <class T>
  bool get_vector(std::vector<T>& v) {
    uint64_t n = 0;
    if (!get(n) || n > left_ / sizeof(T)) return ok_ = false;
    v.resize(size_t(n));
    if (n > 0) std::memcpy(v.data(), p_, size_t(n) * sizeof(T));  // (an empty vector's data() may be null)
    p_ += size_t(n) * sizeof(T);
    left_ -= size_t(n) * sizeof(T);
    return true;
  }
  bool ok() const { return ok_; }
  size_t left() const { return left_; }

 private:
  const unsigned char* p_;
  size_t left_;
  bool ok_ = true;
};

struct BuildIdSearch {
  uintptr_t addr = 0;
  std::string id;
};

int find_build_id(struct dl_phdr_info* info, size_t, void* data) {
  auto* s = static_cast<BuildIdSearch*>(data);
  bool holds = false;
  for (int i = 0; i < info->dlpi_phnum && !holds; ++i) {
    const ElfW(Phdr)& ph = info->dlpi_phdr[i];
    const uintptr_t lo = uintptr_t(info->dlpi_addr + ph.p_vaddr);
    holds = ph.p_type == PT_LOAD && s->addr >= lo && s->addr < lo + ph.p_memsz;
  }
  if (!holds) return 0;
  for (int i = 0; i < info->dlpi_phnum; ++i) {
    const ElfW(Phdr)& ph = info->dlpi_phdr[i];
    if (ph.p_type != PT_NOTE) continue;
    const auto* p = reinterpret_cast<const unsigned char*>(info->dlpi_addr + ph.p_vaddr);
    size_t left = ph.p_memsz;
    while (left >= sizeof(ElfW(Nhdr))) {
      ElfW(Nhdr) nh;
      std::memcpy(&nh, p, sizeof nh);
      const size_t name_at = sizeof nh, desc_at = name_at + ((nh.n_namesz + 3u) & ~size_t(3));
      const size_t next = desc_at + ((nh.n_descsz + 3u) & ~size_t(3));
      if (next > left) break;
      if (nh.n_type == NT_GNU_BUILD_ID && nh.n_namesz == 4 && std::memcmp(p + name_at, "GNU", 4) == 0) {
        static const char* hex = "0123456789abcdef";
        for (size_t k = 0; k < nh.n_descsz; ++k) {
          s->id += hex[p[desc_at + k] >> 4];
          s->id += hex[p[desc_at + k] & 15];
        }
        return 1;
      }
      p += next;
      left -= next;
    }
  }
  return 1;  // the object holding the code, without a build id
}

// The key's fields. A field added to one of these structs must be added
// here too (the static_asserts below catch most additions).
static_assert(sizeof(StitchParams) == 4 * sizeof(float), "StitchParams changed: update the class-table key");
static_assert(sizeof(CapmOptions) == sizeof(int) + 2 * sizeof(float), "CapmOptions changed: update the key");
static_assert(sizeof(PlyParams) == 2 * sizeof(int) + 4 * sizeof(float), "PlyParams changed: update the key");
static_assert(sizeof(YarnBsdfParams) == 8 * sizeof(float) + 2 * sizeof(std::vector<Rgb>),
              "YarnBsdfParams changed: update the key");
static_assert(sizeof(Rgb) == 3 * sizeof(float), "Rgb changed: update the key");

// The key of a stage holds what that stage and the ones before it read
// (TableBsdf::Stage): the shadows the geometry (the pattern, the stitch,
// the CAPM and self-shadowing switches and options) and the build's
// settings; the marches also the yarn BSDF's and the ply's parameters; the
// finished tables also the colours and table_fold. No key holds what no
// stage reads: uv_scale (the tables are in pattern space), footprint_points,
// table_min_cells but for whether it asks for sub-cells (ClassTableBuild::
// sub_cells), near_field_below_cell (how a render picks its route) and the
// mode (the tables are built for multi-scale materials only).
// TableCache.TheTablesDoNotDependOnWhatTheKeyLeavesOut builds tables that
// differ in each of those.
void put_key(Writer& w, const KnitMaterial& m, const ClassTableBuild& b, TableBsdf::Stage stage) {
  w.put_string(kKeyFormat);
  w.put_string(stage_name(stage));
  w.put_string(library_build_id());
  const KnitSurface& s = m.surface();
  w.put_string(KnitSurface::batch_isa_name(s.batch_isa(KnitSurface::BatchPath::Auto)));
  const Pattern& pat = s.pattern();
  w.put(int32_t(pat.rows()));
  w.put(int32_t(pat.cols()));
  // (a byte per cell for each: codes are 0..3 and colour indices below
  // Pattern::kMaxColors = 256, both checked when the pattern is made)
  static_assert(Pattern::kMaxColors <= 256, "colour indices no longer fit a byte: update the key");
  w.put_vector(std::vector<uint8_t>(pat.codes().begin(), pat.codes().end()));
  w.put_vector(std::vector<uint8_t>(pat.colors_or_zero().begin(), pat.colors_or_zero().end()));
  const KnitMaterialParams& p = m.params();
  w.put(p.stitch.a);
  w.put(p.stitch.h);
  w.put(p.stitch.d);
  w.put(p.stitch.r);
  for (bool v : {p.capm, p.footprint_table, p.table_bsdf, p.self_shadowing}) w.put(uint8_t(v));
  w.put(int32_t(p.capm_options.max_steps));
  w.put(p.capm_options.max_segment);
  w.put(p.capm_options.max_bend);
  w.put(int32_t(b.rays_per_direction));
  w.put(uint8_t(b.sub_cells));
  w.put(uint8_t(b.table_bsdf));
  w.put(int32_t(b.hits_per_view));
  w.put(int32_t(b.march_stride));
  if (stage == TableBsdf::Stage::Shadows) return;
  const YarnBsdfParams& y = p.bsdf;
  for (float v : {y.roughness_x, y.roughness_y, y.trans_roughness_x, y.trans_roughness_y, y.eta, y.body_energy,
                  y.body_reflect, y.optical_depth})
    w.put(v);
  w.put(int32_t(p.ply.ply_count));
  w.put(p.ply.ply_radius);
  w.put(p.ply.ply_twist);
  w.put(int32_t(p.ply.fiber_count));
  w.put(p.ply.fiber_twist);
  w.put(p.ply.yarn_radius);
  w.put(uint8_t(p.ply_detail));
  if (stage == TableBsdf::Stage::Marched) return;
  w.put(uint8_t(p.table_fold));
  w.put_vector(y.reflect_colors);
  w.put_vector(y.transmit_colors);
}

std::string hex64(uint64_t v) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

std::string errno_text() { return std::strerror(errno); }

}  // namespace

// Reads and writes the tables' private state.
struct TableCacheCodec {
  // Each table's state, field by field, in one order for writing and for
  // reading (io: Put or Get below).
  template <class IO, class Table>
  static void footprint_fields(IO& io, Table& t) {
    io(t.slot_);
    io(t.slots_);
    io.vec(t.moments_);
    io.vec(t.sub_moments_);
    io.vec(t.eighth_hits_);
    io.vec(t.class_of_);
    io(t.one_colour_);
    io(t.single_class_);
    io(t.period_rows_);
    io(t.period_cols_);
    io.vec(t.prefix_);
    io(t.class_of_slot_);
  }
  // (not its build time: an entry is the same bytes whenever it is built)
  template <class IO, class Table>
  static void bsdf_fields(IO& io, Table& t) {
    io(t.slots_);
    io(t.classes_);
    io(t.colours_);
    io(t.folded_);
    io.vec(t.values_);
    io.vec(t.rows_);
    io.vec(t.hit_frac_);
    io(t.marches_);
    io.vec(t.shadow_bits_);
  }
  struct Put {
    Writer& w;
    template <class T>
    void operator()(const T& v) { w.put(v); }
    void operator()(bool v) { w.put(uint8_t(v)); }
    template <class T>
    void vec(const std::vector<T>& v) { w.put_vector(v); }
  };
  struct Get {
    Reader& r;
    template <class T>
    void operator()(T& v) { r.get(v); }
    void operator()(bool& v) {  // (a byte read as a bool must be 0 or 1)
      uint8_t b = 0;
      r.get(b);
      v = b != 0;
    }
    template <class T>
    void vec(std::vector<T>& v) { r.get_vector(v); }
  };
  static void put(Writer& w, const FootprintTable& t) {
    Put io{w};
    footprint_fields(io, t);
  }
  static void put(Writer& w, const TableBsdf& t) {
    Put io{w};
    bsdf_fields(io, t);
  }
  // False when the bytes do not make a table of a pattern of rows x cols cells.
  static bool get(Reader& r, FootprintTable& t, int rows, int cols) {
    Get io{r};
    footprint_fields(io, t);
    const int slots = t.slots_, prow = t.period_rows_, pcol = t.period_cols_, single = t.single_class_;
    // (the periods divide the pattern's rows and columns)
    if (!r.ok() || slots < 1 || slots > FootprintTable::kClasses || prow < 1 || pcol < 1 || rows % prow != 0 ||
        cols % pcol != 0)
      return false;
    const size_t nodes = size_t(FootprintTable::kThetaBins) * FootprintTable::kPhiBins;
    const size_t sub_stride = t.one_colour_ ? size_t(FootprintTable::kSubStride1) : size_t(FootprintTable::kMoments);
    if (t.moments_.size() != size_t(slots) * nodes * FootprintTable::kMoments) return false;
    if (!t.sub_moments_.empty() &&
        t.sub_moments_.size() != size_t(slots) * FootprintTable::kSub * FootprintTable::kSub * nodes * sub_stride)
      return false;
    // (eighths only beside sub-cells)
    if (!t.eighth_hits_.empty() &&
        (t.sub_moments_.empty() ||
         t.eighth_hits_.size() != size_t(slots) * FootprintTable::kEighth * FootprintTable::kEighth * nodes))
      return false;
    if (t.class_of_.size() != size_t(rows) * size_t(cols)) return false;
    if (!t.prefix_.empty() && t.prefix_.size() != size_t(prow) * size_t(slots) * (size_t(pcol) + 1)) return false;
    int present = 0;
    for (int c = 0; c < FootprintTable::kClasses; ++c) {
      const int s = t.slot_[size_t(c)];
      if (s < -1 || s >= slots) return false;
      if (s >= 0 && t.class_of_slot_[size_t(s)] != c) return false;
      present += s >= 0;
    }
    if (present != slots) return false;
    if (single != -1 && (slots != 1 || single < 0 || single >= FootprintTable::kClasses || t.slot_[size_t(single)] != 0))
      return false;
    for (unsigned char c : t.class_of_)
      if (c >= FootprintTable::kClasses || t.slot_[c] < 0) return false;
    // (no number that would reach an image as NaN or Inf; a bfloat16's
    // exponent all ones is either)
    return std::all_of(t.moments_.begin(), t.moments_.end(), [](float x) { return std::isfinite(x); }) &&
           std::all_of(t.sub_moments_.begin(), t.sub_moments_.end(),
                       [](uint16_t v) { return (v & 0x7f80u) != 0x7f80u; }) &&
           std::all_of(t.eighth_hits_.begin(), t.eighth_hits_.end(), [](uint16_t v) {
             const float h = FootprintTable::from_bf16(v);  // a fraction (NaN fails)
             return h >= 0 && h <= 1;
           });
  }
  // (and of the stage asked for: a marched table is neither folded nor has
  // rows; shadows are bits of `marches` rays per view node, and no values)
  static bool get(Reader& r, TableBsdf& t, int classes, TableBsdf::Stage stage, int marches) {
    Get io{r};
    bsdf_fields(io, t);
    t.seconds_ = 0;  // (built elsewhere)
    const int slots = t.slots_, cls = t.classes_, colours = t.colours_;
    if (!r.ok() || cls != classes || slots < 1 || slots > TableBsdf::kMaxEntries || colours < 1) return false;
    if (t.folded_ ? slots != cls * colours : (slots != cls || colours != 1)) return false;
    const size_t n = size_t(TableBsdf::kNodes);
    // (the fold reads the hit fractions as weights: in [0, 1]; only a
    // marched table keeps them)
    if (t.hit_frac_.size() != (stage == TableBsdf::Stage::Marched ? n * size_t(cls) : 0) ||
        !std::all_of(t.hit_frac_.begin(), t.hit_frac_.end(), [](double v) { return v >= 0 && v <= 1; }))
      return false;
    if (stage == TableBsdf::Stage::Shadows)
      return !t.folded_ && t.values_.empty() && t.rows_.empty() && t.marches_ == marches &&
             t.shadow_bits_.size() == size_t(cls) * n * size_t(marches) * TableBsdf::kShadowWords;
    const bool marched = stage == TableBsdf::Stage::Marched;
    if ((marched && t.folded_) || !t.shadow_bits_.empty() || t.marches_ != 0) return false;
    if (t.values_.size() != n * n * size_t(slots) * TableBsdf::kValues ||
        t.rows_.size() != (marched ? 0 : n * (TableBsdf::kTheta + 1) * size_t(slots) * 4))
      return false;
    // Values finite and >= 0, as the build stores them: a bfloat16's sign
    // bit clear and its exponent not all ones.
    if (!std::all_of(t.values_.begin(), t.values_.end(), [](uint16_t v) { return (v & 0xff80u) < 0x7f80u; }) ||
        !std::all_of(t.rows_.begin(), t.rows_.end(), [](float v) { return std::isfinite(v) && v >= 0; }))
      return false;
    t.derive_sampling();  // (what finish derives, not stored)
    return true;
  }
  static FootprintTable* new_table() { return new FootprintTable(); }
  static TableBsdf* new_bsdf() { return new TableBsdf(); }
};

namespace {
std::atomic<TableBuildProgress*> g_progress{nullptr};
}  // namespace

void set_table_build_progress(TableBuildProgress* progress) { g_progress.store(progress); }
TableBuildProgress* table_build_progress() { return g_progress.load(); }

void set_table_cache(const TableCacheSettings& settings) {
  std::lock_guard<std::mutex> lock(g_mutex);
  g_settings = settings;
}

TableCacheSettings table_cache() {
  std::lock_guard<std::mutex> lock(g_mutex);
  return g_settings;
}

std::string default_table_cache_dir() {
  const char* env = std::getenv("KNITSHADE_CACHE_DIR");
  if (env && *env) return std::string(env) == "off" ? std::string() : std::string(env);
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  if (xdg && *xdg == '/') return (fs::path(xdg) / "knitshade").string();  // (the spec: a relative one is ignored)
  const char* home = std::getenv("HOME");
  if (home && *home) return (fs::path(home) / ".cache" / "knitshade").string();
  return {};
}

namespace {
// Whether `dir` exists as a folder (or can be made) and can be written to.
bool writable_folder(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  return fs::is_directory(dir, ec) && ::access(dir.c_str(), W_OK | X_OK) == 0;
}
}  // namespace

std::string writable_table_cache_dir() {
  const std::string preferred = default_table_cache_dir();
  const char* env = std::getenv("KNITSHADE_CACHE_DIR");
  if ((env && *env) || preferred.empty() || writable_folder(preferred)) return preferred;
  const char* tmp = std::getenv("TMPDIR");
  const fs::path base = tmp && *tmp == '/' ? fs::path(tmp) : fs::path("/tmp");
  const fs::path dir = base / ("knitshade-cache-" + std::to_string(long(::getuid())));
  std::error_code ec;
  if (fs::create_directory(dir, ec)) fs::permissions(dir, fs::perms::owner_all, fs::perm_options::replace, ec);
  // (a folder someone else made there first is not used: it could hold
  // entries of theirs, or be swapped for others)
  struct stat st {};
  if (::lstat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode) || st.st_uid != ::getuid() ||
      (st.st_mode & (S_IWGRP | S_IWOTH)) != 0 || ::access(dir.c_str(), W_OK | X_OK) != 0)
    return {};
  return dir.string();
}

const std::string& library_build_id() {
  static const std::string id = [] {
    BuildIdSearch s;
    s.addr = reinterpret_cast<uintptr_t>(&find_build_id);
    dl_iterate_phdr(&find_build_id, &s);
    return s.id;
  }();
  return id;
}

namespace {
// A temporary file of an entry being written (store_class_tables), left
// behind when its process was stopped before renaming it.
bool is_temporary(const fs::path& p) {
  return p.filename().string().find(std::string(kTableCacheExtension) + ".tmp.") != std::string::npos;
}

// Visits the entries of dir (path, size, time of last use), and removes
// temporaries more than an hour old; throws naming dir when it cannot be
// read.
template <class Visit>
void for_each_entry(const std::string& dir, Visit&& visit) {
  std::error_code ec;
  if (!fs::exists(dir, ec)) return;
  if (!fs::is_directory(dir, ec)) throw std::runtime_error(dir + ": not a folder");
  const auto stale = fs::file_time_type::clock::now() - std::chrono::hours(1);
  fs::directory_iterator it(dir, ec), end;
  for (; !ec && it != end; it.increment(ec)) {
    std::error_code e2;
    const fs::file_time_type time = it->last_write_time(e2);
    if (!e2 && is_temporary(it->path()) && time < stale) fs::remove(it->path(), e2);
    if (it->path().extension() != kTableCacheExtension) continue;
    const uintmax_t size = it->file_size(e2);
    if (!e2) visit(it->path(), uint64_t(size), time);
  }
  if (ec) throw std::runtime_error(dir + ": cannot be read (" + ec.message() + ")");
}
}  // namespace

namespace {
// The stage named by an entry's key (put_key: the format's name, then the
// stage's), from the file's first bytes; "" when they are not of this format.
std::string entry_stage(const fs::path& path) {
  unsigned char head[256] = {};
  std::ifstream in(path, std::ios::binary);
  in.read(reinterpret_cast<char*>(head), sizeof head);
  Reader r(head, size_t(in.gcount()));
  char magic[sizeof kMagic] = {};
  for (char& c : magic) r.get(c);
  uint64_t key_size = 0, len = 0;
  r.get(key_size);
  std::string strings[2];
  for (std::string& s : strings) {
    if (!r.get(len) || len > r.left()) return {};
    s.resize(size_t(len));
    for (char& c : s) r.get(c);
  }
  if (!r.ok() || std::memcmp(magic, kMagic, sizeof kMagic) != 0 || strings[0] != kKeyFormat) return {};
  return strings[1];
}
}  // namespace

TableCacheUsage table_cache_usage(const std::string& dir) {
  TableCacheUsage u;
  for_each_entry(dir, [&](const fs::path& path, uint64_t size, fs::file_time_type) {
    ++u.entries;
    u.bytes += size;
    const std::string stage = entry_stage(path);
    u.finished += stage == stage_name(TableBsdf::Stage::Finished);
    u.marches += stage == stage_name(TableBsdf::Stage::Marched);
    u.shadows += stage == stage_name(TableBsdf::Stage::Shadows);
  });
  return u;
}

TableCacheUsage clear_table_cache(const std::string& dir) {
  std::vector<std::pair<fs::path, uint64_t>> found;
  for_each_entry(dir, [&](const fs::path& p, uint64_t size, fs::file_time_type) { found.emplace_back(p, size); });
  TableCacheUsage removed;
  for (const auto& [path, size] : found) {
    std::error_code ec;
    if (!fs::remove(path, ec) && ec) throw std::runtime_error(path.string() + ": cannot be removed (" + ec.message() + ")");
    ++removed.entries;
    removed.bytes += size;
  }
  return removed;
}

ClassTableEntry class_table_entry(const KnitMaterial& material, const ClassTableBuild& build,
                                  const TableCacheSettings& settings, TableBsdf::Stage stage) {
  ClassTableEntry e;
  e.stage = build.table_bsdf ? stage : TableBsdf::Stage::Shadows;
  if (settings.dir.empty() || library_build_id().empty()) return e;
  Writer w;
  put_key(w, material, build, e.stage);
  e.key.assign(w.bytes().begin(), w.bytes().end());
  const auto* k = reinterpret_cast<const unsigned char*>(e.key.data());
  e.path = (fs::path(settings.dir) / (hex64(fnv1a(k, e.key.size())) + kTableCacheExtension)).string();
  return e;
}

DecodeResult decode_class_tables(const std::vector<unsigned char>& bytes, const std::string& key,
                                 const ClassTableBuild& build, TableBsdf::Stage stage, int rows, int cols,
                                 std::shared_ptr<const FootprintTable>& table,
                                 std::shared_ptr<const TableBsdf>& bsdf) {
  DecodeResult res;
  const auto bad = [&](const char* why) {
    res.why = why;
    return res;
  };
  if (bytes.size() < sizeof kMagic + 3 * sizeof(uint64_t) || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    return bad("is not a class-table cache entry (no KNITTBL1 header)");
  uint64_t stored = 0;
  std::memcpy(&stored, bytes.data() + bytes.size() - sizeof stored, sizeof stored);
  if (fnv1a(bytes.data(), bytes.size() - sizeof stored) != stored) return bad("is damaged (checksum)");
  Reader r(bytes.data() + sizeof kMagic, bytes.size() - sizeof kMagic - sizeof stored);
  std::vector<char> k;
  r.get_vector(k);
  if (!r.ok()) return bad("has a malformed key");
  if (k.size() != key.size() || std::memcmp(k.data(), key.data(), k.size()) != 0) {
    res.other_key = true;  // another material's entry under the same hash: not a fault
    return res;
  }
  std::vector<unsigned char> payload;
  r.get_vector(payload);
  if (!r.ok() || r.left() != 0) return bad("has a malformed payload");
  Reader p(payload.data(), payload.size());
  std::unique_ptr<FootprintTable> t(TableCacheCodec::new_table());
  if (!TableCacheCodec::get(p, *t, rows, cols)) return bad("does not hold a class table of this pattern");
  uint8_t has_bsdf = 0;
  p.get(has_bsdf);
  if (!p.ok() || (has_bsdf != 0) != build.table_bsdf) return bad("has a malformed payload");
  std::unique_ptr<TableBsdf> b;
  if (has_bsdf) {
    b.reset(TableCacheCodec::new_bsdf());
    const int marches = std::max(1, std::max(1, build.hits_per_view) / std::max(1, build.march_stride));
    if (!TableCacheCodec::get(p, *b, t->classes_present(), stage, marches))
      return bad("does not hold its tabulated BSDF");
  }
  if (p.left() != 0) return bad("has bytes after its tables");
  table.reset(t.release());
  bsdf.reset(b.release());
  res.ok = true;
  return res;
}

bool load_class_tables(const ClassTableEntry& entry, const ClassTableBuild& build, int rows, int cols,
                       std::shared_ptr<const FootprintTable>& table, std::shared_ptr<const TableBsdf>& bsdf,
                       std::string& note) {
  if (entry.key.empty()) return false;
  std::error_code ec;
  if (!fs::exists(entry.path, ec)) return false;
  const auto damaged = [&](const std::string& why) {
    note = "class-table cache entry " + entry.path + " " + why;
    return false;
  };
  const uintmax_t size = fs::file_size(entry.path, ec);
  if (ec) return damaged("cannot be read (" + ec.message() + ")");
  if (size > kMaxEntryBytes) return damaged("is " + std::to_string(size) + " bytes, more than any entry");
  std::vector<unsigned char> bytes(static_cast<size_t>(size));
  {
    std::ifstream in(entry.path, std::ios::binary);
    if (!in || !in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(bytes.size())))
      return damaged("cannot be read");
  }
  const DecodeResult d = decode_class_tables(bytes, entry.key, build, entry.stage, rows, cols, table, bsdf);
  if (d.other_key) return false;  // (the build overwrites it)
  if (!d.ok) return damaged(d.why);
  // Used: its time is the folder's order for trimming (least recently used first).
  fs::last_write_time(entry.path, fs::file_time_type::clock::now(), ec);
  return true;
}

void store_class_tables(const ClassTableEntry& entry, const TableCacheSettings& settings,
                        const FootprintTable& table, const TableBsdf* bsdf, std::string& note) {
  if (entry.key.empty()) return;
  Writer payload;
  TableCacheCodec::put(payload, table);
  payload.put(uint8_t(bsdf != nullptr));
  if (bsdf) TableCacheCodec::put(payload, *bsdf);
  Writer w;
  for (char c : kMagic) w.put(c);
  w.put_string(entry.key);
  w.put_vector(payload.bytes());
  w.put(fnv1a(w.bytes().data(), w.bytes().size()));
  const std::vector<unsigned char>& bytes = w.bytes();

  std::error_code ec;
  const fs::path dir = fs::path(entry.path).parent_path();
  fs::create_directories(dir, ec);
  if (ec) {
    note = "class-table cache folder " + dir.string() + " cannot be made (" + ec.message() + "); nothing cached";
    return;
  }
  // A temporary name of this process and call, renamed over the entry:
  // readers see the old entry or the whole new one, never a part.
  static std::atomic<unsigned> counter{0};
  const fs::path tmp = fs::path(entry.path).concat(".tmp." + std::to_string(long(getpid())) + "." +
                                                   std::to_string(counter.fetch_add(1)));
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out || !out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size())) ||
        !out.flush()) {
      note = "class-table cache entry " + tmp.string() + " cannot be written (" + errno_text() + "); nothing cached";
      out.close();
      fs::remove(tmp, ec);
      return;
    }
  }
  fs::rename(tmp, entry.path, ec);
  if (ec) {
    note = "class-table cache entry " + entry.path + " cannot be written (" + ec.message() + "); nothing cached";
    fs::remove(tmp, ec);
    return;
  }
  // Trim the folder's entries to max_bytes, least recently used first (the
  // one just written last of all).
  struct Item {
    fs::path path;
    fs::file_time_type time;
    uintmax_t size;
  };
  std::vector<Item> items;
  uintmax_t total = 0;
  try {
    for_each_entry(dir.string(), [&](const fs::path& p, uint64_t size, fs::file_time_type time) {
      items.push_back({p, time, size});
      total += size;
    });
  } catch (const std::runtime_error& e) {
    note = std::string("class-table cache folder ") + e.what() + "; not trimmed";
    return;
  }
  if (total <= settings.max_bytes) return;
  std::sort(items.begin(), items.end(), [&](const Item& a, const Item& b) {
    const bool an = a.path == fs::path(entry.path), bn = b.path == fs::path(entry.path);
    if (an != bn) return bn;  // the new entry goes last
    return a.time < b.time;
  });
  for (const Item& it : items) {
    if (total <= settings.max_bytes || it.path == fs::path(entry.path)) break;
    if (fs::remove(it.path, ec)) total -= it.size;
  }
}

}  // namespace knit
