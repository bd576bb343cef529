// The exact yarn centre curve in double precision: the reference definition
// the kernel's float evaluation (native/kernel/stitch.h) is tested against.
// Same formulas, written independently for the ground truth.
#include <algorithm>
#include <cmath>

#include "knit/yarns.h"

namespace knit {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kBlend = kPi / 4;  // half width of the knit/purl/float blend

using V3 = std::array<double, 3>;

struct Profile {
  V3 p, dp, ddp;
};

int cell_code(const Pattern& pat, int row_from_bottom, int col) {
  auto mod = [](int a, int n) { return ((a % n) + n) % n; };
  int r = pat.rows() - 1 - mod(row_from_bottom, pat.rows());
  return pat.codes()[size_t(r) * pat.cols() + mod(col, pat.cols())];
}

// Depth signs of cell (row, col): head from the stitch above, legs its own,
// sinker from the stitch below; slip stitches do not take part.
std::array<double, 3> cell_signs(const Pattern& pat, int row, int col) {
  auto sign = [](int code) { return code == 1 ? -1.0 : 1.0; };
  auto loop = [](int code) { return code == 0 || code == 1; };
  const double own = sign(cell_code(pat, row, col));
  const int above = cell_code(pat, row + 1, col), below = cell_code(pat, row - 1, col);
  return {loop(above) ? sign(above) : own, own, loop(below) ? sign(below) : own};
}

Profile profile(const StitchParams& sp, int code, const std::array<double, 3>& sg, double tau,
                double tc, double yk) {
  Profile o{};
  if (code == 0 || code == 1) {
    const double s1 = std::sin(tau), c1 = std::cos(tau), s2 = std::sin(2 * tau), c2 = std::cos(2 * tau);
    // Signed split of cos 2tau into head c^2(1+c)/2, legs -(1-c^2), sinker c^2(1-c)/2.
    const double head = c1 * c1 * (1 + c1) / 2, legs = -(1 - c1 * c1), sink = c1 * c1 * (1 - c1) / 2;
    const double dhead = (2 * c1 + 3 * c1 * c1) / 2, dlegs = 2 * c1, dsink = (2 * c1 - 3 * c1 * c1) / 2;
    const double ddhead = (2 + 6 * c1) / 2, ddlegs = 2, ddsink = (2 - 6 * c1) / 2;
    const double P = sg[0] * head + sg[1] * legs + sg[2] * sink;     // P(c)
    const double dP = sg[0] * dhead + sg[1] * dlegs + sg[2] * dsink;  // dP/dc
    const double ddP = sg[0] * ddhead + sg[1] * ddlegs + sg[2] * ddsink;
    const double d = sp.d;
    o.p = {tc + tau + sp.a * s2, yk + sp.h * c1, d * P};
    o.dp = {1 + 2 * sp.a * c2, -sp.h * s1, -d * dP * s1};             // dc/dtau = -s
    o.ddp = {-4 * sp.a * s2, -sp.h * c1, d * (ddP * s1 * s1 - dP * c1)};
  } else {
    double depth = std::abs(double(sp.d)) + 2.0 * sp.r;
    o.p = {tc + tau, yk - sp.h, code == 2 ? depth : -depth};
    o.dp = {1, 0, 0};
    o.ddp = {0, 0, 0};
  }
  return o;
}

}  // namespace

CurvePoint yarn_curve_exact(const Pattern& pat, const StitchParams& sp, int row, double t) {
  const double s = double(sp.h) + 0.5;
  const double yk = (row + 0.5) * s;
  const int c = int(std::floor(t / (2 * kPi)));
  const double tc = 2 * kPi * c + kPi;
  const int code = cell_code(pat, row, c);
  const auto sg = cell_signs(pat, row, c);
  Profile self = profile(sp, code, sg, t - tc, tc, yk);
  int nc = c;
  double tb = 0;
  if (t - tc > kPi - kBlend) {
    nc = c + 1;
    tb = tc + kPi;
  } else if (t - tc < kBlend - kPi) {
    nc = c - 1;
    tb = tc - kPi;
  }
  if (nc == c) return {self.p, self.dp, self.ddp};
  const int ncode = cell_code(pat, row, nc);
  const auto nsg = cell_signs(pat, row, nc);
  const bool loops = (code == 0 || code == 1) && (ncode == 0 || ncode == 1);
  if (loops ? sg == nsg : ncode == code) return {self.p, self.dp, self.ddp};
  const double ntc = 2 * kPi * nc + kPi;
  Profile other = profile(sp, ncode, nsg, t - ntc, ntc, yk);
  const Profile& lo = nc > c ? self : other;
  const Profile& hi = nc > c ? other : self;
  // Quintic smoothstep over [tb - kBlend, tb + kBlend].
  const double W = 2 * kBlend;
  const double u = std::clamp((t - (tb - kBlend)) / W, 0.0, 1.0);
  const double w = u * u * u * (10 + u * (-15 + 6 * u));
  const double dw = 30 * u * u * (u - 1) * (u - 1) / W;
  const double ddw = 60 * u * (u - 1) * (2 * u - 1) / (W * W);
  CurvePoint out{};
  for (int i = 0; i < 3; ++i) {
    const double dp = hi.p[i] - lo.p[i], d1 = hi.dp[i] - lo.dp[i], d2 = hi.ddp[i] - lo.ddp[i];
    out.p[i] = lo.p[i] + w * dp;
    out.dp[i] = lo.dp[i] + w * d1 + dw * dp;
    out.ddp[i] = lo.ddp[i] + w * d2 + 2 * dw * d1 + ddw * dp;
  }
  return out;
}

}  // namespace knit
