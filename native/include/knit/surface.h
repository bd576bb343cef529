// KnitSurface: a pattern plus stitch parameters, queried analytically.
//
// Pattern space (docs/geometry.md): x along the course, y along the wale, z out
// of the fabric, in stitch-curve units. UV maps to pattern space by
// x = uv_scale * u, y = uv_scale * v (isotropic, so loops stay round). The
// fabric's base surface is z = 0; yarn tubes live in |z| <= shell_top().
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "knit/frame.h"
#include "knit/kernel.h"
#include "knit/params.h"
#include "knit/pattern.h"

namespace knit {

// One crossing of a line with one yarn tube.
struct TubeCrossing {
  float s_in = 0, s_out = 0;  // distances along the line (entry, exit)
  Vec3 p_in{}, normal{}, tangent{};  // entry point, outward normal, unit yarn tangent
  int row = 0, col = 0;       // cell of the yarn piece (row from the bottom, unwrapped)
  int stitch = 0, color = 0;  // code and colour index of that cell
  int layer = 0;              // row parity: 0 or 1
  float t = 0;                // curve parameter of the entry point
};

// Result of a vertical query or a CAPM march.
struct SurfaceHit {
  bool hit = false;
  Vec3 position{};   // pattern space
  Vec3 normal{};     // outward tube normal (pattern space, unit)
  Vec3 tangent{};    // yarn tangent (unit)
  int layers = 0;    // tubes crossed by the vertical line through the hit point
  int row = 0, col = 0, stitch = 0, color = 0;
  int steps = 0;     // CAPM segments marched
};

// FrameProvider (base-mesh frame at a pattern-space point) is in knit/frame.h.

class FlatFrame final : public FrameProvider {
 public:
  void frame(float, float, Vec3& t, Vec3& b, Vec3& n) const override;
  bool is_flat() const override { return true; }
};

// A cylinder of radius R (pattern units) around the y axis: x is arc length
// around it, y runs along the axis. The CAPM test case of the paper's Fig. 6/7.
class CylinderFrame final : public FrameProvider {
 public:
  explicit CylinderFrame(float radius) : radius_(radius) {}
  void frame(float x, float y, Vec3& t, Vec3& b, Vec3& n) const override;
  Vec3 curvature(float, float) const override { return {1.0f / radius_, 0, 0}; }
  float radius() const { return radius_; }

 private:
  float radius_;
};

// A sphere of radius R (pattern units): x = R * longitude, y = R * latitude.
class SphereFrame final : public FrameProvider {
 public:
  explicit SphereFrame(float radius) : radius_(radius) {}
  void frame(float x, float y, Vec3& t, Vec3& b, Vec3& n) const override;
  Vec3 curvature(float, float) const override { return {1.0f / radius_, 1.0f / radius_, 0}; }
  float radius() const { return radius_; }

 private:
  float radius_;
};

// Largest |x| or |y| of a pattern-space point the hosts accept (Python,
// renderer): pattern space is single-precision, and at 2^15 = 32768 units
// (about 5,200 stitches from the origin) a float is 0.004 apart, 0.6% of the
// default tube radius. Beyond it positions and normals degrade; the hosts
// reject such inputs rather than return them quietly wrong. The kernel's own
// line query returns a miss beyond KNIT_MAX_COORD (1e7), where its row and
// piece indices would no longer fit an int.
inline constexpr float kMaxPatternCoord = 32768.0f;

// Longest CAPM segment the hosts accept (CapmOptions::max_segment, pattern
// units; the scene format's bound too). A line query's work grows with its
// segment's length (rows plus pieces along it), so a segment of a million
// units would take a third of a second per query.
inline constexpr float kMaxCapmSegment = 1000.0f;
// Whether a CAPM segment length is in (0, kMaxCapmSegment] (NaN is not).
inline bool capm_segment_in_range(double max_segment) { return max_segment > 0 && max_segment <= kMaxCapmSegment; }

struct CapmOptions {
  int max_steps = 32;           // hard cap on marched segments
  float max_segment = 6.2832f;  // longest segment, pattern units of horizontal travel
  float max_bend = 0.05f;       // and at most this many radians of base curvature
};

class KnitSurface {
 public:
  KnitSurface(Pattern pattern, StitchParams params);  // validates params

  const Pattern& pattern() const { return pattern_; }
  const StitchParams& params() const { return params_; }
  float shell_top() const;  // highest z any tube reaches (|d| + r; more with floats)
  float cell_width() const;   // 2 pi
  float cell_height() const;  // row spacing
  float period_x() const;     // cell_width * cols
  float period_y() const;     // cell_height * rows

  // Every tube crossed by the vertical line through (x, y), from the top down.
  std::vector<TubeCrossing> crossings(float x, float y) const;
  // The first tube surface seen from above at (x, y) (paper's height query).
  SurfaceHit query(float x, float y) const;
  // query() at n points (x[i], y[i]) into out[i]. Auto: 16 points at a time
  // with AVX-512, or 8 with AVX2 and FMA, where the CPU has them and the
  // pattern has knit and purl stitches only; the scalar kernel otherwise
  // (src/query_batch.cpp). The paths agree up to float rounding. Simd: the
  // widest SIMD path, Avx2: the 8-lane one (for comparisons on a CPU with
  // AVX-512); either throws std::invalid_argument when it cannot run.
  enum class BatchPath { Auto, Scalar, Simd, Avx2 };
  enum class BatchIsa { Scalar, Avx2, Avx512 };
  void query_batch(const float* x, const float* y, size_t n, SurfaceHit* out,
                   BatchPath path = BatchPath::Auto) const;
  static BatchIsa batch_best_isa();            // the widest SIMD path this CPU and build have
  static bool batch_simd_available();          // batch_best_isa() != Scalar
  static const char* batch_isa_name(BatchIsa isa);  // "avx512", "avx2", "scalar"
  BatchIsa batch_isa(BatchPath path) const;    // which path query_batch takes (throws as it would)
  // CAPM (paper Alg. 1, Sec. 4.2/6.1): the ray enters the shell at
  // (x, y, shell_top()) travelling along -wi_local (wi_local.z > 0, pointing
  // to the viewer, in the frame at (x, y)); `frame` bends it (flat if null).
  SurfaceHit capm(float x, float y, Vec3 wi_local, const FrameProvider* frame = nullptr,
                  const CapmOptions& opt = {}) const;

  // The CAPM march from any start (k::knit_capm_start / begin_at), bending
  // the world-space ray `ray_world` (the direction it travels) with the
  // frames of `frame` (flat if null; its curvature() sets the metric and the
  // segment length). start.D, the ray in the frame at or near start.p,
  // only places the first segment's midpoint (where the frame is fetched
  // and the segment aimed). Returns the final kernel state. blocked_only: the
  // caller only asks whether the ray is blocked (a shadow ray), so each
  // segment's line query stops at the first entry it finds, not the nearest
  // (KNIT_QUERY_ANY), and a hit ends the march as found, without the
  // midpoint corrector that places it (knit_capm_correct: one more line
  // query per hit on a curved base). The state's hit is then only a hit.
  // frame_hint: where the frame lookups may start (FrameProvider::frame_near;
  // BaseHit::frame_hint), -1 when unknown. Throws std::invalid_argument for
  // options out of range (max_steps < 1, max_segment outside
  // (0, kMaxCapmSegment], max_bend <= 0).
  k::KnitCapm march(k::KnitCapm start, Vec3 ray_world, const FrameProvider* frame,
                    const CapmOptions& opt = {}, bool blocked_only = false, int64_t frame_hint = -1) const;
  SurfaceHit to_hit(const k::KnitCapm& st) const;

  // The kernel's view of this surface (for hosts that call the kernel directly).
  const k::KnitGeom& geom() const { return geom_; }
  const int32_t* codes() const { return pattern_.codes().data(); }
  const int32_t* colors() const { return pattern_.colors_or_zero().data(); }
  // query_batch's view of a knit-and-purl pattern, one entry per cell (in
  // codes() order): the depth-sign bits (head, legs, sinker; set for purl)
  // of the cells left of, at and right of it, 3 bits each, plus one entry
  // of padding. Empty for patterns with slip stitches.
  const std::vector<uint16_t>& span_bits() const { return span_bits_; }

 private:
  Pattern pattern_;
  StitchParams params_;
  k::KnitGeom geom_;
  std::vector<uint16_t> span_bits_;
};

}  // namespace knit
