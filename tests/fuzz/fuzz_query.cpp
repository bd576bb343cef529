// libFuzzer harness for the geometric queries (docs/geometry.md): a small
// pattern, stitch parameters and a base (flat, cylinder or sphere) from the
// input, then line queries of every mode, vertical queries, the batch and
// CAPM marches at points and directions taken from the input's bytes as raw
// floats (NaN, infinities, denormals and 1e38s included). Parameters the boundary rejects end the
// input (std::invalid_argument); whatever is accepted must give results
// that are finite where they are defined, inside the range asked for, with
// unit normals and valid cells, and must not crash, hang or trip the
// sanitizers. Built as `fuzz_query` (clang, KNIT_FUZZ=ON) and as the
// corpus replay test with any compiler (replay_main.cpp).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "knit/surface.h"

namespace {

[[noreturn]] void fail(const char* what, const std::string& detail) {
  std::fprintf(stderr, "fuzz_query: %s\n%s\n", what, detail.c_str());
  std::abort();
}

// Reads the input front to back; past its end, zeros.
struct Reader {
  const uint8_t* p;
  size_t n;
  uint8_t byte() {
    if (n == 0) return 0;
    --n;
    return *p++;
  }
  float f32() {
    uint8_t b[4] = {byte(), byte(), byte(), byte()};
    float v;
    std::memcpy(&v, b, 4);
    return v;
  }
};

bool finite3(const knit::Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
bool unit3(const knit::Vec3& v) { return finite3(v) && std::fabs(v.x * v.x + v.y * v.y + v.z * v.z - 1.0f) < 1e-3f; }

std::string describe(const char* what, float a, float b, float c, float d, float e, float f) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "%s (%a, %a, %a) (%a, %a, %a)", what, a, b, c, d, e, f);
  return buf;
}

void check_hit(const knit::SurfaceHit& h, const knit::KnitSurface& s, const std::string& where) {
  if (!h.hit) return;
  if (!finite3(h.position) || !unit3(h.normal) || !unit3(h.tangent))
    fail("non-finite or non-unit result of a hit", where);
  if (h.stitch < 0 || h.stitch > 3) fail("stitch code out of range", where);
  if (h.layers < 0) fail("negative layer count", where);
  if (std::fabs(h.position.z) > s.shell_top() * 1.01f + 1e-3f) fail("hit outside the shell", where);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace k = knit::k;
  Reader in{data, size};
  // A pattern of up to 4 x 4 stitches, codes 0-3 (slip stitches included).
  const int rows = 1 + in.byte() % 4, cols = 1 + in.byte() % 4;
  std::vector<std::vector<int>> codes(static_cast<size_t>(rows), std::vector<int>(static_cast<size_t>(cols)));
  for (auto& row : codes)
    for (int& c : row) c = in.byte() % 4;
  knit::StitchParams sp;
  // Either Crane's stitch or raw parameters (most of which the boundary rejects).
  if (in.byte() & 1) {
    sp.a = in.f32();
    sp.h = in.f32();
    sp.d = in.f32();
    sp.r = in.f32();
  }
  knit::Pattern pattern;
  try {
    pattern = knit::Pattern::from_rows(codes);
  } catch (const std::exception& e) {
    fail("a valid pattern was rejected", e.what());
  }
  std::unique_ptr<knit::KnitSurface> surface;
  try {
    surface = std::make_unique<knit::KnitSurface>(pattern, sp);
  } catch (const std::invalid_argument&) {
    return 0;  // rejected at the boundary, as it should be
  }
  const knit::KnitSurface& s = *surface;
  const k::KnitGeom& g = s.geom();
  // The base the CAPM marches bend with: flat, or a cylinder or sphere of any
  // radius Python accepts (finite and > 0, 1e-38 and 3e38 included).
  const int base = in.byte() % 3;
  const float radius = in.f32();
  std::unique_ptr<knit::FrameProvider> frame;
  if (base == 1 && std::isfinite(radius) && radius > 0) frame = std::make_unique<knit::CylinderFrame>(radius);
  if (base == 2 && std::isfinite(radius) && radius > 0) frame = std::make_unique<knit::SphereFrame>(radius);
  std::vector<float> xs, ys;
  // Queries of 7 floats and a mode byte each, at most 16.
  for (int q = 0; q < 16 && in.n >= 29; ++q) {
    const float ox = in.f32(), oy = in.f32(), oz = in.f32();
    const float dx = in.f32(), dy = in.f32(), dz = in.f32();
    const float len = in.f32();
    const int mode = in.byte() % 5;
    const std::string where = describe("query", ox, oy, oz, dx, dy, dz);
    xs.push_back(ox);
    ys.push_back(oy);
    // The vertical query and the layer crossings at (ox, oy).
    check_hit(s.query(ox, oy), s, where);
    for (const knit::TubeCrossing& c : s.crossings(ox, oy))
      if (!std::isfinite(c.s_in) || !std::isfinite(c.s_out) || c.s_out < c.s_in) fail("bad vertical crossing", where);
    // A line query: the kernel takes a unit direction and a finite range, and
    // its hosts' segments are at most a CAPM segment long (kMaxCapmSegment of
    // horizontal travel, through the shell): up to 2,000 units here. (Its
    // work grows with the length: a segment across the whole +-1e7 it
    // accepts takes seconds.)
    const double dn = std::sqrt(double(dx) * dx + double(dy) * dy + double(dz) * dz);
    if (std::isfinite(dn) && dn > 1e-30 && std::isfinite(oz) && std::isfinite(len)) {
      const k::kvec3 D = k::kv3(float(dx / dn), float(dy / dn), float(dz / dn));
      const float s_max = std::fmin(std::fabs(len), 2.0f * knit::kMaxCapmSegment);
      const k::KnitLineHit h = k::knit_line_query(g, s.codes(), s.colors(), k::kv3(ox, oy, oz), D, 0.0f, s_max, mode);
      if (h.hit) {
        if (mode == KNIT_QUERY_COUNT) fail("a counting query reported an entry", where);
        if (!(h.s_in >= 0.0f && h.s_in <= s_max)) fail("entry outside the range asked for", where);
        if (!finite3(h.p) || !unit3(h.n) || !unit3(h.tangent)) fail("non-finite or non-unit line hit", where);
        if (h.code < 0 || h.code > 3) fail("stitch code out of range in a line hit", where);
      }
      if (h.crossings < 0) fail("negative crossing count", where);
      if (mode == KNIT_QUERY_FIRST || mode == KNIT_QUERY_ANY) {
        // FIRST and ANY see the same tubes: ANY finds an entry when FIRST does.
        const k::KnitLineHit other = k::knit_line_query(g, s.codes(), s.colors(), k::kv3(ox, oy, oz), D, 0.0f, s_max,
                                                        mode == KNIT_QUERY_FIRST ? KNIT_QUERY_ANY : KNIT_QUERY_FIRST);
        if (other.hit != h.hit) fail("FIRST and ANY disagree on a hit", where);
      }
      // CAPM from (ox, oy) looking along -D's mirror above the surface.
      const knit::Vec3 wi{D.x, D.y, std::fabs(D.z) + 1e-3f};
      const float wn = std::sqrt(wi.x * wi.x + wi.y * wi.y + wi.z * wi.z);
      const knit::Vec3 wl{wi.x / wn, wi.y / wn, wi.z / wn};
      check_hit(s.capm(ox, oy, wl, frame.get()), s, where + " capm");
      // The same march as a shadow ray asks it (blocked_only: ANY queries,
      // no corrector), from inside the shell at height oz along D.
      if (std::fabs(oz) < s.shell_top() && std::isfinite(ox) && std::isfinite(oy) &&
          std::fabs(ox) < knit::kMaxPatternCoord && std::fabs(oy) < knit::kMaxPatternCoord) {
        const k::KnitCapm st = s.march(k::knit_capm_begin_at(k::kv3(ox, oy, oz), D), D, frame.get(), {}, true);
        if (st.state < KNIT_CAPM_MARCHING || st.state > KNIT_CAPM_LIMIT) fail("march state out of range", where);
        if (st.state == KNIT_CAPM_HIT && (!finite3(st.hit.p) || !(st.hit.s_in >= 0.0f)))
          fail("blocked march: bad hit", where);
        if (!finite3(st.p)) fail("blocked march: non-finite position", where);
      }
    }
  }
  if (!xs.empty()) {
    std::vector<knit::SurfaceHit> out(xs.size());
    s.query_batch(xs.data(), ys.data(), xs.size(), out.data());
    for (size_t i = 0; i < out.size(); ++i)
      check_hit(out[i], s, describe("batch", xs[i], ys[i], 0, 0, 0, 0));
    // The same points again and again, 160 or more in one call: the vector
    // paths run such calls on pairs of registers, the few points above on
    // one, and a point's result must not depend on which (query_batch.cpp).
    std::vector<float> xr, yr;
    while (xr.size() < 160) {
      xr.insert(xr.end(), xs.begin(), xs.end());
      yr.insert(yr.end(), ys.begin(), ys.end());
    }
    std::vector<knit::SurfaceHit> many(xr.size());
    s.query_batch(xr.data(), yr.data(), xr.size(), many.data());
    for (size_t i = 0; i < many.size(); ++i) {
      const knit::SurfaceHit& a = out[i % out.size()];
      const knit::SurfaceHit& b = many[i];
      if (a.hit != b.hit || a.layers != b.layers || a.row != b.row || a.col != b.col || a.stitch != b.stitch ||
          a.color != b.color || std::memcmp(&a.position, &b.position, sizeof a.position) != 0 ||
          std::memcmp(&a.normal, &b.normal, sizeof a.normal) != 0 ||
          std::memcmp(&a.tangent, &b.tangent, sizeof a.tangent) != 0)
        fail("a batch of many points gave another result than a batch of few",
             describe("batch", xr[i], yr[i], 0, 0, 0, 0));
    }
  }
  return 0;
}
