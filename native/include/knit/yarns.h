// Explicit yarns: the exact yarn centre curves of a pattern, the ground truth
// for every analytic shortcut. Coordinates are pattern space (docs/geometry.md):
// x along the course (u), y along the wale (v), z out of the fabric; a stitch
// cell is 2*pi wide and row_spacing() tall; cell (row k from the bottom,
// column c) spans x in [2 pi c, 2 pi (c+1)), y in [k s, (k+1) s).
#pragma once

#include <array>
#include <vector>

#include "knit/params.h"
#include "knit/pattern.h"

namespace knit {

struct YarnCurve {
  std::vector<std::array<double, 3>> points;  // dense polyline, pattern space
  std::vector<int> color;                     // colour index per point
  int row = 0;                                // row from the bottom of the tiled area
};

struct ExplicitYarns {
  std::vector<YarnCurve> curves;  // one per knitted row
  double radius = 0;              // tube radius (= params.r)
  double width = 0;               // x extent of the tiled area: 2 pi cols tiles_u
  double height = 0;              // y extent: row_spacing rows tiles_v
  double t_step = 0;              // point i of every curve is at curve parameter i t_step (2 pi / samples_per_stitch)
};

// The yarn centre curve of every row of `tiles_u` x `tiles_v` repeats of the
// pattern, sampled with `samples_per_stitch` points per stitch (double
// precision, exact curve including the knit/purl/float blends).
ExplicitYarns explicit_yarns(const Pattern& pattern, const StitchParams& params, int tiles_u,
                             int tiles_v, int samples_per_stitch = 64);

// The exact centre curve of row `row` (counted from the bottom, any integer,
// the pattern repeats) at curve parameter t (any real; column c covers
// t in [2 pi c, 2 pi (c+1))): position, first and second derivative.
struct CurvePoint {
  std::array<double, 3> p, dp, ddp;
};
CurvePoint yarn_curve_exact(const Pattern& pattern, const StitchParams& params, int row, double t);

}  // namespace knit
