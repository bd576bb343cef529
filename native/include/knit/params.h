// Stitch parameters of Crane's plain-knit curve (paper Eq. 2):
//   Y(t) = (t + a sin 2t, h cos t, d cos 2t),  t in [-pi, pi] per stitch,
// swept by a round tube of radius r. Rows are `row_spacing()` = h + 1/2 apart
// (Crane's C code: a = 3/2, h = 4, d = 1, row spacing h + 1/2; its r = 1/2 is
// the fibre offset, not a tube radius). Default r = 0.65: with Crane's a, h, d
// the yarn centre lines of a 1x1 rib come within 1.385 of each other (1.536
// in stockinette), so tubes thicker than 0.69 would pass through each other.
#pragma once

#include <string>

namespace knit {

struct StitchParams {
  float a = 1.5f;   // loop roundness, > 0
  float h = 4.0f;   // loop height, > 0
  float d = 1.0f;   // loop depth (bend in and out of the fabric), != 0
  float r = 0.65f;  // yarn (tube) radius, > 0 and at most clearance()/2

  float row_spacing() const { return h + 0.5f; }

  // Smallest distance between centre lines of two different yarn pieces
  // (the two legs of one loop, or loops of neighbouring rows) over the
  // knit/purl neighbourhoods of stockinette, garter, 1x1 rib and seed, and
  // twice the smallest radius of curvature; tubes of radius r pass through
  // each other when 2r exceeds it. Dense search in double precision, cached
  // per (a, h, |d|).
  double clearance() const;

  // Throws std::invalid_argument naming the parameter and value at fault:
  // non-finite values, a <= 0, h <= 0, d == 0, r <= 0, r > clearance()/2,
  // and magnitudes above 1e3.
  void validate() const;

  std::string to_string() const;
};

}  // namespace knit
