// The class-table cache (knit/table_cache.h): a material whose tables come
// from the cache must hold the tables a build gives, bit for bit, and shade
// as a material built without the cache; an entry that is damaged, another
// material's or unwritable must cost a build and a note, never a wrong
// table or a failed load; the folder is trimmed least recently used first.
#include <gtest/gtest.h>

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "../../native/src/table_cache_internal.h"  // decode_class_tables
#include "knit/shading.h"
#include "knit/table_cache.h"
#include "knit/table_progress.h"

namespace {

using namespace knit;
namespace fs = std::filesystem;

// A fresh folder for the running test (under the build's test output).
fs::path test_folder() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path dir = fs::path(KNIT_TEST_OUTPUT_DIR) / "table_cache" / info->name();
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// Sets the process's cache for the scope of a test, then turns it off.
struct CacheScope {
  explicit CacheScope(const fs::path& dir, uint64_t max_bytes = uint64_t(512) << 20) {
    set_table_cache({dir.string(), max_bytes});
  }
  ~CacheScope() { set_table_cache({}); }
};

// Saves the variables the cache folder is picked from, and puts them back
// at the end of the scope.
class EnvScope {
 public:
  EnvScope() {
    for (const char* n : {"KNITSHADE_CACHE_DIR", "XDG_CACHE_HOME", "HOME", "TMPDIR"}) {
      const char* v = std::getenv(n);
      saved_.push_back({n, v ? v : "", v != nullptr});
    }
  }
  ~EnvScope() {
    for (const Saved& e : saved_) {
      if (e.had)
        setenv(e.name, e.old.c_str(), 1);
      else
        unsetenv(e.name);
    }
  }

 private:
  struct Saved {
    const char* name;
    std::string old;
    bool had;
  };
  std::vector<Saved> saved_;
};

// Multi-scale: one class (stockinette, one colour: the quick build) unless
// a pattern and palette are given.
KnitMaterialParams params(std::vector<Rgb> colours = {Rgb{0.7f, 0.2f, 0.1f}}, float r = 0.65f) {
  KnitMaterialParams mp;
  mp.mode = KnitMode::MultiScale;
  mp.stitch.r = r;
  mp.bsdf.reflect_colors = colours;
  mp.bsdf.transmit_colors = colours;
  return mp;
}
KnitMaterial material(const char* pattern = "K\n", std::vector<Rgb> colours = {Rgb{0.7f, 0.2f, 0.1f}},
                      float r = 0.65f) {
  return KnitMaterial(Pattern::parse(pattern), params(colours, r));
}

// The paths of the entries holding `m`'s marches and its shadows (its
// other entries, beside table_cache_file(): table_cache.cpp).
std::string entry_file(const KnitMaterial& m, TableBsdf::Stage stage) {
  ClassTableBuild build;
  build.sub_cells = m.params().table_min_cells < 1;
  build.table_bsdf = m.params().table_bsdf;
  return class_table_entry(m, build, table_cache(), stage).path;
}
std::string marches_file(const KnitMaterial& m) { return entry_file(m, TableBsdf::Stage::Marched); }
std::string shadows_file(const KnitMaterial& m) { return entry_file(m, TableBsdf::Stage::Shadows); }

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

// Everything the tables answer, compared bit for bit: the class table's
// node and sub-cell statistics and its eighths' hit fractions, the tabulated BSDF's every stored value,
// and (unless `shading` is false: materials whose parameters differ where
// the tables do not) the shading of footprints of a cell and more seen from
// a few sides.
void expect_same_tables(const KnitMaterial& a, const KnitMaterial& b, bool shading = true) {
  ASSERT_TRUE(a.footprint_table() && b.footprint_table());
  const FootprintTable& ta = *a.footprint_table();
  const FootprintTable& tb = *b.footprint_table();
  EXPECT_EQ(ta.classes_present(), tb.classes_present());
  EXPECT_TRUE(same_bits(ta.node_moments(), tb.node_moments()));
  EXPECT_TRUE(same_bits(ta.sub_moments(), tb.sub_moments()));
  EXPECT_TRUE(same_bits(ta.eighth_hits(), tb.eighth_hits()));
  EXPECT_EQ(ta.one_colour(), tb.one_colour());
  EXPECT_EQ(ta.period_rows(), tb.period_rows());
  EXPECT_EQ(ta.period_cols(), tb.period_cols());
  ASSERT_TRUE(a.table_bsdf() && b.table_bsdf());
  const TableBsdf& ba = *a.table_bsdf();
  const TableBsdf& bb = *b.table_bsdf();
  ASSERT_EQ(ba.folded(), bb.folded());
  ASSERT_EQ(ba.colours(), bb.colours());
  const int entries = ta.classes_present() * (ba.folded() ? ba.colours() : 1);
  int differ = 0;
  for (int s = 0; s < entries; ++s)
    for (int v = 0; v < TableBsdf::kNodes; ++v)
      for (int l = 0; l < TableBsdf::kNodes; ++l) {
        const auto x = ba.value(s, v, l), y = bb.value(s, v, l);
        differ += std::memcmp(x.data(), y.data(), sizeof x) != 0;
      }
  EXPECT_EQ(differ, 0);
  if (!shading) return;
  // Shading through the tables: base hits whose footprints span 1.5 and 4
  // cells, from the front and at a slant.
  int shaded = 0;
  for (float span : {1.5f, 4.0f})
    for (float slant : {0.0f, 0.6f, 1.2f}) {
      BaseHit hit;
      hit.u = 0.37f;
      hit.v = 0.61f;
      const float du = span * a.surface().cell_width() / a.params().uv_scale;
      const float dv = span * a.surface().cell_height() / a.params().uv_scale;
      hit.dudx = du;
      hit.dvdy = dv;
      const Vec3 dir = k::kv3_normalize(k::kv3(std::sin(slant), 0.3f * slant, -std::cos(slant)));
      const KnitShade sa = a.shade(hit, dir, nullptr, {0.25f, 0.75f}, 0.5f);
      const KnitShade sb = b.shade(hit, dir, nullptr, {0.25f, 0.75f}, 0.5f);
      EXPECT_EQ(sa.from_table, sb.from_table);
      shaded += sa.from_table;
      EXPECT_EQ(std::memcmp(&sa.point, &sb.point, sizeof sa.point), 0) << span << " " << slant;
      EXPECT_EQ(std::memcmp(&sa.kd_r, &sb.kd_r, sizeof sa.kd_r), 0);
      EXPECT_EQ(sa.mix.n, sb.mix.n);
      EXPECT_EQ(std::memcmp(sa.mix.share.data(), sb.mix.share.data(), sizeof sa.mix.share), 0);
      if (sa.table_bsdf && sb.table_bsdf) {
        const Vec3 wi = k::kv3_normalize(k::kv3(0.3f, -0.4f, 0.8f));
        const Vec3 ea = sa.table_bsdf->eval(sa.mix, wi, Vec3{0.5f, 0.4f, 0.3f}, Vec3{0.5f, 0.4f, 0.3f});
        const Vec3 eb = sb.table_bsdf->eval(sb.mix, wi, Vec3{0.5f, 0.4f, 0.3f}, Vec3{0.5f, 0.4f, 0.3f});
        EXPECT_EQ(std::memcmp(&ea, &eb, sizeof ea), 0);
      }
    }
  EXPECT_GT(shaded, 0);  // (the footprints did go through the tables)
}

std::vector<char> read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::vector<char>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}
void write_bytes(const fs::path& p, const std::vector<char>& b) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(b.data(), std::streamsize(b.size()));
}

TEST(TableCache, TheBinaryHasABuildId) {
  // Without one nothing is cached; CMake asks the linker for one.
  const std::string& id = library_build_id();
  EXPECT_GE(id.size(), 16u) << id;
  EXPECT_EQ(id.find_first_not_of("0123456789abcdef"), std::string::npos) << id;
}

TEST(TableCache, OffByDefaultAndItsDefaultFolder) {
  EXPECT_TRUE(table_cache().dir.empty());
  const KnitMaterial m = material();
  EXPECT_FALSE(m.table_from_cache());
  EXPECT_TRUE(m.table_cache_file().empty());
  EXPECT_TRUE(m.table_cache_note().empty());

  // default_table_cache_dir: $KNITSHADE_CACHE_DIR ("off": none), then
  // $XDG_CACHE_HOME (absolute only), then $HOME.
  const EnvScope env;
  setenv("HOME", "/home/knitter", 1);
  setenv("XDG_CACHE_HOME", "/var/cache/me", 1);
  setenv("KNITSHADE_CACHE_DIR", "/tmp/tables", 1);
  EXPECT_EQ(default_table_cache_dir(), "/tmp/tables");
  setenv("KNITSHADE_CACHE_DIR", "off", 1);
  EXPECT_EQ(default_table_cache_dir(), "");
  unsetenv("KNITSHADE_CACHE_DIR");
  EXPECT_EQ(default_table_cache_dir(), "/var/cache/me/knitshade");
  setenv("XDG_CACHE_HOME", "relative/cache", 1);
  EXPECT_EQ(default_table_cache_dir(), "/home/knitter/.cache/knitshade");
  unsetenv("XDG_CACHE_HOME");
  EXPECT_EQ(default_table_cache_dir(), "/home/knitter/.cache/knitshade");
  unsetenv("HOME");
  EXPECT_EQ(default_table_cache_dir(), "");
}

TEST(TableCache, AHomeThatCannotBeWrittenFallsBackToAFolderOfTheUsersOwn) {
  // writable_table_cache_dir: the default folder, else (a read-only home)
  // $TMPDIR/knitshade-cache-<uid>, made 0700; never a fallback that is not
  // the user's own. (These tests run as root, for whom permission bits do
  // not stop a write: a home under a file is one that cannot be made.)
  const fs::path dir = test_folder();
  const EnvScope env;
  write_bytes(dir / "a_file", {'x'});
  fs::create_directories(dir / "tmp");
  unsetenv("KNITSHADE_CACHE_DIR");
  unsetenv("XDG_CACHE_HOME");
  setenv("TMPDIR", (dir / "tmp").c_str(), 1);
  const fs::path fallback = dir / "tmp" / ("knitshade-cache-" + std::to_string(long(getuid())));
  // A home that can be written: its own cache folder, made.
  setenv("HOME", (dir / "home").c_str(), 1);
  EXPECT_EQ(writable_table_cache_dir(), (dir / "home" / ".cache" / "knitshade").string());
  EXPECT_TRUE(fs::is_directory(dir / "home" / ".cache" / "knitshade"));
  // One that cannot: the fallback, the user's own and closed to others.
  setenv("HOME", (dir / "a_file" / "home").c_str(), 1);
  EXPECT_EQ(default_table_cache_dir(), (dir / "a_file" / "home" / ".cache" / "knitshade").string());
  EXPECT_EQ(writable_table_cache_dir(), fallback.string());
  ASSERT_TRUE(fs::is_directory(fallback));
  EXPECT_EQ(fs::status(fallback).permissions() & fs::perms::all, fs::perms::owner_all);
  // ... and a cache there works.
  {
    CacheScope scope(writable_table_cache_dir());
    const KnitMaterial first = material();
    EXPECT_TRUE(first.table_cache_note().empty()) << first.table_cache_note();
    EXPECT_TRUE(material().table_from_cache());
  }
  // A fallback others can write to, or a file in its place: not used.
  fs::permissions(fallback, fs::perms::others_write, fs::perm_options::add);
  EXPECT_EQ(writable_table_cache_dir(), "");
  fs::remove_all(fallback);
  write_bytes(fallback, {'x'});
  EXPECT_EQ(writable_table_cache_dir(), "");
  // $KNITSHADE_CACHE_DIR as it is set, writable or not (its note says so).
  setenv("KNITSHADE_CACHE_DIR", (dir / "a_file" / "mine").c_str(), 1);
  EXPECT_EQ(writable_table_cache_dir(), (dir / "a_file" / "mine").string());
  setenv("KNITSHADE_CACHE_DIR", "off", 1);
  EXPECT_EQ(writable_table_cache_dir(), "");
}

TEST(TableCache, ABuildReportsItsProgressAndAReadDoesNot) {
  // The observer of knit/table_progress.h: begin once with the build's
  // units, every unit added before end, from any thread; nothing at all
  // when the tables come from the cache or are finished from its marches,
  // the BSDF's jobs alone when they are marched from its shadows.
  struct Counter : TableBuildProgress {
    std::atomic<uint64_t> added{0};
    uint64_t total = 0, at_end = 0;
    int begins = 0, ends = 0;
    bool added_outside = false;
    void begin(uint64_t t) override {
      ++begins;
      total = t;
      added = 0;
    }
    void add(uint64_t u) override {
      if (begins == ends) added_outside = true;
      added += u;
    }
    void end() override {
      ++ends;
      at_end = added;
    }
  } counter;
  set_table_build_progress(&counter);
  const fs::path dir = test_folder();
  CacheScope scope(dir);
  const KnitMaterial built = material("K P\nP K\n");
  EXPECT_EQ(counter.begins, 1);
  EXPECT_EQ(counter.ends, 1);
  // two classes: per class 24 class-table jobs of 1 unit, 144 BSDF jobs of 2
  EXPECT_EQ(counter.total, uint64_t(2 * (24 + 2 * 144)));
  EXPECT_EQ(counter.at_end, counter.total);
  EXPECT_FALSE(counter.added_outside);
  const KnitMaterial read = material("K P\nP K\n");
  const KnitMaterial recoloured = material("K P\nP K\n", {Rgb{0.2f, 0.6f, 0.2f}});
  ASSERT_TRUE(read.table_from_cache());
  ASSERT_TRUE(recoloured.table_marches_from_cache());
  EXPECT_EQ(counter.begins, 1);
  EXPECT_EQ(counter.ends, 1);
  // Marched from the cached shadows: a bar of the BSDF's jobs alone.
  KnitMaterialParams rough = params();
  rough.bsdf.roughness_y = 0.5f;
  const KnitMaterial remarched(Pattern::parse("K P\nP K\n"), rough);
  ASSERT_TRUE(remarched.table_shadows_from_cache());
  EXPECT_EQ(counter.begins, 2);
  EXPECT_EQ(counter.ends, 2);
  EXPECT_EQ(counter.total, uint64_t(2 * 2 * 144));
  EXPECT_EQ(counter.at_end, counter.total);
  EXPECT_FALSE(counter.added_outside);
  set_table_build_progress(nullptr);
  EXPECT_EQ(table_build_progress(), nullptr);
}

TEST(TableCache, ACachedMaterialHoldsTheBuiltTablesBitForBit) {
  const fs::path dir = test_folder();
  const KnitMaterial plain = material("KP\nPK\n", {Rgb{0.7f, 0.2f, 0.1f}});  // cache off: built
  CacheScope scope(dir);
  const KnitMaterial first = material("KP\nPK\n", {Rgb{0.7f, 0.2f, 0.1f}});
  EXPECT_FALSE(first.table_from_cache());
  EXPECT_TRUE(first.table_cache_note().empty()) << first.table_cache_note();
  ASSERT_FALSE(first.table_cache_file().empty());
  EXPECT_TRUE(fs::is_regular_file(first.table_cache_file()));
  EXPECT_EQ(fs::path(first.table_cache_file()).parent_path(), dir);
  const KnitMaterial second = material("KP\nPK\n", {Rgb{0.7f, 0.2f, 0.1f}});
  EXPECT_TRUE(second.table_from_cache());
  EXPECT_TRUE(second.table_cache_note().empty()) << second.table_cache_note();
  EXPECT_EQ(second.table_cache_file(), first.table_cache_file());
  EXPECT_FALSE(first.table_marches_from_cache());
  EXPECT_FALSE(second.table_marches_from_cache());
  expect_same_tables(plain, second);
  expect_same_tables(first, second);
  // Only its own files in the folder: the three entries (the finished
  // tables, their marches and their shadows), no temporary left over.
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    files.push_back(e.path());
    EXPECT_EQ(e.path().extension(), kTableCacheExtension) << e.path();
  }
  ASSERT_EQ(files.size(), 3u);
  const std::string marches = marches_file(first), shadows = shadows_file(first);
  EXPECT_NE(marches, first.table_cache_file());
  EXPECT_NE(shadows, first.table_cache_file());
  EXPECT_NE(shadows, marches);
  EXPECT_TRUE(fs::is_regular_file(marches));
  EXPECT_TRUE(fs::is_regular_file(shadows));
}

TEST(TableCache, OtherYarnParametersAreMarchedFromTheCachedShadows) {
  // A material that differs from a cached one in its yarn BSDF's or ply's
  // parameters has the same geometry: its tables are marched with the
  // cached shadows (not their marches again) and are a fresh build's to the
  // bit.
  const fs::path dir = test_folder();
  const char* pattern = "K P\nP K\n";
  KnitMaterialParams rough = params();
  rough.bsdf.roughness_x = 0.45f;
  rough.bsdf.eta = 1.4f;
  rough.ply.ply_twist = 0.7f * rough.ply.ply_twist + 0.1f;
  const KnitMaterial plain(Pattern::parse(pattern), rough);  // cache off: built
  CacheScope scope(dir);
  const KnitMaterial first = material(pattern);
  const KnitMaterial other(Pattern::parse(pattern), rough);
  EXPECT_FALSE(other.table_from_cache());
  EXPECT_FALSE(other.table_marches_from_cache());
  EXPECT_TRUE(other.table_shadows_from_cache());
  EXPECT_TRUE(other.table_cache_note().empty()) << other.table_cache_note();
  EXPECT_EQ(shadows_file(other), shadows_file(first));
  EXPECT_NE(marches_file(other), marches_file(first));
  expect_same_tables(plain, other);
  // The shadows' marches are most of a build.
  EXPECT_LT(other.table_seconds(), 0.7 * first.table_seconds())
      << other.table_seconds() << " s against " << first.table_seconds() << " s";
  const KnitMaterial again(Pattern::parse(pattern), rough);
  EXPECT_TRUE(again.table_from_cache());
  // Another yarn radius is another geometry: built.
  const KnitMaterial thin = material(pattern, {Rgb{0.7f, 0.2f, 0.1f}}, 0.55f);
  EXPECT_FALSE(thin.table_shadows_from_cache());
  EXPECT_NE(shadows_file(thin), shadows_file(first));
}

TEST(TableCache, OtherColoursAreFinishedFromTheCachedMarches) {
  // A material that differs from a cached one in its colours (or in
  // table_fold) reads the marches and finishes them: the tables a build
  // with those colours gives, bit for bit, without marching. Two colour
  // indices, so that the fold has a palette to fold.
  const fs::path dir = test_folder();
  const char* pattern = "K P\nP K\ncolors:\n0 1\n1 0\n";
  const std::vector<Rgb> warm{Rgb{0.7f, 0.2f, 0.1f}, Rgb{0.8f, 0.7f, 0.2f}};
  const std::vector<Rgb> cold{Rgb{0.1f, 0.3f, 0.7f}, Rgb{0.2f, 0.6f, 0.5f}};
  const KnitMaterial plain = material(pattern, cold);  // cache off: built with the cold colours
  ASSERT_TRUE(plain.table_bsdf()->folded());
  KnitMaterialParams unfolded_params = params(cold);
  unfolded_params.table_fold = false;
  const KnitMaterial plain_unfolded(Pattern::parse(pattern), unfolded_params);
  ASSERT_FALSE(plain_unfolded.table_bsdf()->folded());
  CacheScope scope(dir);
  const KnitMaterial first = material(pattern, warm);
  EXPECT_FALSE(first.table_from_cache());
  EXPECT_FALSE(first.table_marches_from_cache());
  const KnitMaterial recoloured = material(pattern, cold);
  EXPECT_FALSE(recoloured.table_from_cache());
  EXPECT_TRUE(recoloured.table_marches_from_cache());
  EXPECT_TRUE(recoloured.table_cache_note().empty()) << recoloured.table_cache_note();
  EXPECT_NE(recoloured.table_cache_file(), first.table_cache_file());
  EXPECT_EQ(marches_file(recoloured), marches_file(first));
  expect_same_tables(plain, recoloured);
  // Finishing took a small part of what marching took.
  EXPECT_LT(recoloured.table_seconds(), 0.5 * first.table_seconds())
      << recoloured.table_seconds() << " s against " << first.table_seconds() << " s";
  // Its finished tables are now an entry of their own.
  const KnitMaterial again = material(pattern, cold);
  EXPECT_TRUE(again.table_from_cache());
  expect_same_tables(plain, again);
  // table_fold off: finished from the same marches, unfolded.
  const KnitMaterial unfolded(Pattern::parse(pattern), unfolded_params);
  EXPECT_TRUE(unfolded.table_marches_from_cache());
  expect_same_tables(plain_unfolded, unfolded);
  // A finished table cannot be finished twice.
  EXPECT_THROW(plain.table_bsdf()->finished(plain, *plain.footprint_table()), std::logic_error);
}

TEST(TableCache, TheTablesDoNotDependOnWhatTheKeyLeavesOut) {
  // The key leaves out the parameters the build does not read (table_cache.cpp,
  // put_key): materials that differ in each of them share their entries and
  // must have the same tables, bit for bit, when each is built.
  const fs::path dir = test_folder();
  const char* pattern = "K\n";
  const KnitMaterial base = material(pattern);
  std::vector<std::pair<const char*, KnitMaterialParams>> others;
  KnitMaterialParams p = params();
  p.uv_scale = 17.5f;
  others.push_back({"uv_scale", p});
  p = params();
  p.footprint_points = 4;
  others.push_back({"footprint_points", p});
  p = params();
  p.table_min_cells = 0.75f;  // (still below one: sub-cells)
  others.push_back({"table_min_cells", p});
  p = params();
  p.near_field_below_cell = !p.near_field_below_cell;
  others.push_back({"near_field_below_cell", p});
  for (const auto& [name, mp] : others) {
    SCOPED_TRACE(name);
    const KnitMaterial other(Pattern::parse(pattern), mp);
    expect_same_tables(base, other, false);
    CacheScope scope(dir);
    EXPECT_EQ(material(pattern).table_cache_file(), KnitMaterial(Pattern::parse(pattern), mp).table_cache_file());
  }
}

TEST(TableCache, TwoColoursAndTheWalkFoldedForEachColour) {
  // A pattern of two colour indices: the class table keeps its neighbour
  // shares, and the folded BSDF one entry per class and colour.
  const fs::path dir = test_folder();
  const std::vector<Rgb> palette{Rgb{0.7f, 0.2f, 0.1f}, Rgb{0.1f, 0.3f, 0.7f}};
  const char* pattern = "K K\nK K\ncolors:\n0 1\n1 0\n";
  const KnitMaterial plain = material(pattern, palette);
  ASSERT_FALSE(plain.footprint_table()->one_colour());
  ASSERT_EQ(plain.table_bsdf()->colours(), 2);
  CacheScope scope(dir);
  const KnitMaterial first = material(pattern, palette);
  const KnitMaterial second = material(pattern, palette);
  EXPECT_FALSE(first.table_from_cache());
  EXPECT_TRUE(second.table_from_cache());
  expect_same_tables(plain, second);
}

TEST(TableCache, DamagedEntriesAreMadeAgainWithANote) {
  const fs::path dir = test_folder();
  CacheScope scope(dir);
  const KnitMaterial built = material();
  const fs::path entry = built.table_cache_file(), marches = marches_file(built), shadows = shadows_file(built);
  const std::vector<char> good = read_bytes(entry), good_marches = read_bytes(marches),
                          good_shadows = read_bytes(shadows);
  ASSERT_GT(good.size(), 1000u);
  ASSERT_GT(good_marches.size(), 1000u);

  struct Damage {
    const char* what;
    std::vector<char> bytes;
    const char* note;
  };
  std::vector<Damage> cases;
  std::vector<char> flipped = good;
  flipped[flipped.size() / 2] ^= 0x10;  // one bit in the tables
  cases.push_back({"a flipped bit", flipped, "is damaged (checksum)"});
  cases.push_back({"cut in half", std::vector<char>(good.begin(), good.begin() + ptrdiff_t(good.size() / 2)),
                   "is damaged (checksum)"});
  cases.push_back({"empty", {}, "is not a class-table cache entry"});
  cases.push_back({"another file", std::vector<char>(4096, 'x'), "is not a class-table cache entry"});
  for (const Damage& d : cases) {
    // The finished entry damaged: finished again from the marches.
    write_bytes(entry, d.bytes);
    const KnitMaterial m = material();
    EXPECT_FALSE(m.table_from_cache()) << d.what;
    EXPECT_TRUE(m.table_marches_from_cache()) << d.what;
    EXPECT_NE(m.table_cache_note().find(entry.string()), std::string::npos) << d.what << ": " << m.table_cache_note();
    EXPECT_NE(m.table_cache_note().find(d.note), std::string::npos) << d.what << ": " << m.table_cache_note();
    EXPECT_NE(m.table_cache_note().find("finished the tables from the cached marches"), std::string::npos)
        << m.table_cache_note();
    expect_same_tables(built, m);
    // ... and wrote a good entry in its place.
    EXPECT_EQ(read_bytes(entry), good) << d.what;
    const KnitMaterial again = material();
    EXPECT_TRUE(again.table_from_cache()) << d.what;
    EXPECT_TRUE(again.table_cache_note().empty()) << again.table_cache_note();
    // The finished tables and the marches damaged: marched again from the
    // shadows, both named.
    write_bytes(entry, d.bytes);
    write_bytes(marches, d.bytes);
    const KnitMaterial remarched = material();
    EXPECT_TRUE(remarched.table_shadows_from_cache()) << d.what;
    EXPECT_NE(remarched.table_cache_note().find(entry.string()), std::string::npos) << remarched.table_cache_note();
    EXPECT_NE(remarched.table_cache_note().find(marches.string()), std::string::npos) << remarched.table_cache_note();
    EXPECT_NE(remarched.table_cache_note().find("marched the tables again from the cached shadows"),
              std::string::npos)
        << remarched.table_cache_note();
    expect_same_tables(built, remarched);
    EXPECT_EQ(read_bytes(entry), good) << d.what;
    EXPECT_EQ(read_bytes(marches), good_marches) << d.what;
    // All three damaged: built again, all named.
    write_bytes(entry, d.bytes);
    write_bytes(marches, d.bytes);
    write_bytes(shadows, d.bytes);
    const KnitMaterial rebuilt = material();
    EXPECT_FALSE(rebuilt.table_from_cache()) << d.what;
    EXPECT_FALSE(rebuilt.table_marches_from_cache()) << d.what;
    EXPECT_FALSE(rebuilt.table_shadows_from_cache()) << d.what;
    for (const fs::path& p : {entry, marches, shadows})
      EXPECT_NE(rebuilt.table_cache_note().find(p.string()), std::string::npos) << rebuilt.table_cache_note();
    EXPECT_NE(rebuilt.table_cache_note().find("built the tables again"), std::string::npos)
        << rebuilt.table_cache_note();
    expect_same_tables(built, rebuilt);
    EXPECT_EQ(read_bytes(entry), good) << d.what;
    EXPECT_EQ(read_bytes(marches), good_marches) << d.what;
    EXPECT_EQ(read_bytes(shadows), good_shadows) << d.what;
  }
}

TEST(TableCache, AnotherMaterialsEntryIsNeverUsed) {
  const fs::path dir = test_folder();
  CacheScope scope(dir);
  const KnitMaterial thick = material("K\n", {Rgb{0.7f, 0.2f, 0.1f}}, 0.65f);
  const KnitMaterial thin = material("K\n", {Rgb{0.7f, 0.2f, 0.1f}}, 0.5f);
  const KnitMaterial blue = material("K\n", {Rgb{0.1f, 0.2f, 0.7f}}, 0.65f);
  // Every parameter is in the key: other radius, other colour, other file.
  EXPECT_NE(thick.table_cache_file(), thin.table_cache_file());
  EXPECT_NE(thick.table_cache_file(), blue.table_cache_file());
  EXPECT_FALSE(thin.table_from_cache());
  EXPECT_FALSE(blue.table_from_cache());
  // The thin yarn's entry put where the thick one's belongs (as a collision
  // of their hashes would): the key, stored whole, tells them apart.
  fs::copy_file(thin.table_cache_file(), thick.table_cache_file(), fs::copy_options::overwrite_existing);
  const KnitMaterial again = material("K\n", {Rgb{0.7f, 0.2f, 0.1f}}, 0.65f);
  EXPECT_FALSE(again.table_from_cache());
  EXPECT_TRUE(again.table_cache_note().empty()) << again.table_cache_note();
  expect_same_tables(thick, again);
  EXPECT_FALSE(same_bits(thin.footprint_table()->node_moments(), again.footprint_table()->node_moments()));
}

TEST(TableCache, AFolderThatCannotBeMadeIsANoteNotAFailure) {
  const fs::path dir = test_folder();
  write_bytes(dir / "a_file", {'x'});
  CacheScope scope(dir / "a_file" / "cache");  // (a folder under a file: not even root can make it)
  const KnitMaterial m = material();
  EXPECT_FALSE(m.table_from_cache());
  EXPECT_NE(m.table_cache_note().find("cannot be made"), std::string::npos) << m.table_cache_note();
  EXPECT_NE(m.table_cache_note().find("nothing cached"), std::string::npos) << m.table_cache_note();
  const KnitMaterial plain = [] {
    set_table_cache({});
    return material();
  }();
  expect_same_tables(plain, m);
}

TEST(TableCache, TheFolderIsTrimmedLeastRecentlyUsedFirst) {
  // Materials without a tabulated BSDF, whose class table is their one
  // entry, of other yarn radii: entries of one size, one per material.
  const auto one_entry = [](float r) {
    KnitMaterialParams mp = params({Rgb{0.5f, 0.5f, 0.5f}}, r);
    mp.table_bsdf = false;
    return KnitMaterial(Pattern::parse("K\n"), mp);
  };
  const fs::path dir = test_folder();
  uint64_t one = 0;
  {
    CacheScope scope(dir);
    const KnitMaterial m = one_entry(0.5f);
    one = fs::file_size(m.table_cache_file());
    EXPECT_EQ(marches_file(m), m.table_cache_file());
    EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
  }
  fs::remove_all(dir);
  // Room for two entries (they are all the same size here).
  CacheScope scope(dir, 2 * one + one / 2);
  const std::string a = one_entry(0.6f).table_cache_file();
  const std::string b = one_entry(0.55f).table_cache_file();
  // Age them, b the younger; then use a, which makes it the youngest.
  const auto now = fs::file_time_type::clock::now();
  fs::last_write_time(a, now - std::chrono::hours(2));
  fs::last_write_time(b, now - std::chrono::hours(1));
  EXPECT_TRUE(one_entry(0.6f).table_from_cache());
  EXPECT_GT(fs::last_write_time(a), fs::last_write_time(b));
  // A third entry: b, the least recently used, makes room for it.
  const std::string c = one_entry(0.45f).table_cache_file();
  EXPECT_TRUE(fs::exists(a));
  EXPECT_FALSE(fs::exists(b));
  EXPECT_TRUE(fs::exists(c));
  // Files that are not entries are not the cache's to remove, but for the
  // temporaries of writes stopped before their rename once they are an
  // hour old (a running write's is younger).
  write_bytes(dir / "notes.txt", std::vector<char>(size_t(3 * one), 'n'));
  const fs::path stale = dir / "0123456789abcdef.knittable.tmp.123.0";
  const fs::path young = dir / "0123456789abcdef.knittable.tmp.124.0";
  write_bytes(stale, {'x'});
  write_bytes(young, {'y'});
  fs::last_write_time(stale, now - std::chrono::hours(2));
  const std::string d = one_entry(0.4f).table_cache_file();
  EXPECT_TRUE(fs::exists(dir / "notes.txt"));
  EXPECT_FALSE(fs::exists(stale));
  EXPECT_TRUE(fs::exists(young));
  EXPECT_TRUE(fs::exists(d));
  EXPECT_FALSE(fs::exists(a));  // now the oldest
  EXPECT_TRUE(fs::exists(c));
}

// FNV-1a 64, the entries' checksum (native/src/table_cache.cpp's format).
uint64_t fnv1a(const unsigned char* p, size_t n) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 0x100000001b3ull;
  }
  return h;
}

TEST(TableCache, MutatedEntriesAreRejectedOrReadInBounds) {
  // Entries whose checksum was made to fit their damage (what no accident
  // gives, but a writer's bug could): the decoder checks every size before
  // it reads and the tables' shapes after, so each either is refused with a
  // reason or gives tables that can be used. The seed stitch of two colours:
  // several classes (prefix counts), sub-cells, neighbour shares, the fold.
  const fs::path dir = test_folder();
  CacheScope scope(dir);
  const KnitMaterial m = material("K P\nP K\ncolors:\n0 1\n1 0\n", {Rgb{0.7f, 0.2f, 0.1f}, Rgb{0.1f, 0.3f, 0.7f}});
  ClassTableBuild build;
  build.sub_cells = true;
  build.table_bsdf = true;
  // Both entries of the material: its finished tables and its marches
  // (which are finished before use, as the material does).
  for (const TableBsdf::Stage stage :
       {TableBsdf::Stage::Finished, TableBsdf::Stage::Marched, TableBsdf::Stage::Shadows}) {
    const bool marched = stage == TableBsdf::Stage::Marched, shadows = stage == TableBsdf::Stage::Shadows;
    SCOPED_TRACE(marched ? "the marches' entry" : shadows ? "the shadows' entry" : "the finished entry");
    const ClassTableEntry entry = class_table_entry(m, build, table_cache(), stage);
    if (stage == TableBsdf::Stage::Finished) ASSERT_EQ(entry.path, m.table_cache_file());
    ASSERT_TRUE(fs::is_regular_file(entry.path));
    const std::vector<char> file = read_bytes(entry.path);
    const std::vector<unsigned char> good(file.begin(), file.end());
    const int rows = m.surface().pattern().rows(), cols = m.surface().pattern().cols();
    std::shared_ptr<const TableBsdf> good_tb;
    {
      std::shared_ptr<const FootprintTable> t;
      std::shared_ptr<const TableBsdf> b;
      ASSERT_TRUE(decode_class_tables(good, entry.key, build, stage, rows, cols, t, b).ok);
      good_tb = b;
      EXPECT_TRUE(same_bits(t->node_moments(), m.footprint_table()->node_moments()));
      EXPECT_EQ(b->stage(), stage);
      // The other stages' decoding refuses it.
      for (const TableBsdf::Stage other :
           {TableBsdf::Stage::Finished, TableBsdf::Stage::Marched, TableBsdf::Stage::Shadows})
        if (other != stage) EXPECT_FALSE(decode_class_tables(good, entry.key, build, other, rows, cols, t, b).ok);
    }
    // The layout: magic, key size and key, payload size and payload, checksum.
    const size_t payload_size_at = 8 + 8 + entry.key.size(), payload_at = payload_size_at + 8;
    const size_t payload_end = good.size() - 8;
    ASSERT_GT(payload_end, payload_at + 1000);
    std::mt19937 rng(3);
    int refused = 0, read = 0;
    const k::KnitGeom& g = m.surface().geom();
    for (int trial = 0; trial < 1200; ++trial) {
      std::vector<unsigned char> b = good;
      const int kind = trial % 3;
      const size_t at = payload_at + rng() % (payload_end - payload_at);
      if (kind == 0) {
        b[at] ^= static_cast<unsigned char>(1u << (rng() % 8));  // a bit anywhere in the tables
      } else if (kind == 1) {
        // a size or count in the first 200 bytes (the class table's header
        // and its vectors' lengths), made large, negative or small
        const size_t head = payload_at + rng() % 200;
        const uint64_t v = rng() % 2 ? uint64_t(rng()) << (rng() % 40) : uint64_t(rng() % 64);
        std::memcpy(&b[std::min(head, payload_end - 8)], &v, 8);
      } else {
        // the payload cut short, its size made to fit
        const uint64_t cut = uint64_t(at - payload_at);
        b.erase(b.begin() + ptrdiff_t(at), b.begin() + ptrdiff_t(payload_end));
        std::memcpy(&b[payload_size_at], &cut, 8);
      }
      const uint64_t sum = fnv1a(b.data(), b.size() - 8);
      std::memcpy(&b[b.size() - 8], &sum, 8);
      std::shared_ptr<const FootprintTable> t;
      std::shared_ptr<const TableBsdf> tb;
      const DecodeResult d = decode_class_tables(b, entry.key, build, stage, rows, cols, t, tb);
      if (!d.ok) {
        ++refused;
        EXPECT_FALSE(d.other_key);
        EXPECT_GT(std::strlen(d.why), 5u);
        continue;
      }
      ++read;
      if (shadows) {
        // Every bit read (marching with them is a third of a build: too
        // slow here): a flipped bit or 8 overwritten bytes change at most
        // 64 of them.
        int differ = 0;
        ASSERT_EQ(tb->classes(), good_tb->classes());
        ASSERT_EQ(tb->marches(), good_tb->marches());
        for (int s = 0; s < tb->classes(); ++s)
          for (int v = 0; v < TableBsdf::kNodes; ++v)
            for (int k = 0; k < tb->marches(); ++k)
              for (int l = 0; l < TableBsdf::kNodes; ++l) differ += tb->shadowed(s, v, k, l) != good_tb->shadowed(s, v, k, l);
        EXPECT_LE(differ, 64) << "trial " << trial;
        continue;
      }
      // (the fold of a damaged value, on 30-odd trials: the solve of a whole
      // table is the slow part of this test)
      if (marched && read % 20 != 1) continue;
      if (marched) tb = std::make_shared<const TableBsdf>(tb->finished(m, *t));
      // Read back: use them, as a render would (footprints of 1.5 and 3 cells,
      // from above and at a slant).
      for (float size : {1.5f, 3.0f}) {
        const k::KFootprint f = k::knit_footprint(g, 10.0f, 20.0f, k::kv3(size * K_2PI, 0, 0),
                                                  k::kv3(0, size * g.row_spacing, 0), 4, 0.3f, 0.6f);
        for (Vec3 wi : {k::kv3(0, 0, 1), k::kv3_normalize(k::kv3(0.6f, 0.2f, 0.5f))}) {
          float slot_hits[FootprintTable::kClasses] = {};
          const k::KnitAggregate a = t->aggregate(m.surface(), f, wi, slot_hits);
          (void)a;
          const TableBsdf::Mix mix = tb->mix(slot_hits, wi, 0.4f, 0.4f);
          const Vec3 e = tb->eval(mix, k::kv3_normalize(k::kv3(-0.3f, 0.1f, 0.9f)), Vec3{0.5f, 0.5f, 0.5f},
                                  Vec3{0.5f, 0.5f, 0.5f});
          EXPECT_TRUE(std::isfinite(e.x) && std::isfinite(e.y) && std::isfinite(e.z));
        }
      }
    }
    // Most damage to sizes and every cut is refused; a flipped bit in the
    // statistics is read (it changes a number, not a shape).
    EXPECT_GT(refused, 400);
    EXPECT_GT(read, 200);
    std::printf("mutated %s: %d refused, %d read and used\n",
                marched ? "marches" : shadows ? "shadows" : "finished tables", refused, read);
  }
}

}  // namespace
