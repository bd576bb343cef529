// Test helpers for the BSDF lobes: random numbers, spherical integration, and
// a chi-square goodness-of-fit test of a sampling routine against its pdf
// (after the method of Mitsuba 3's chi2 test and pbrt-v4's bsdfs_test; code
// written for Knitshade).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "knit/bsdf.h"

namespace knit::test {

constexpr double kPi = 3.14159265358979323846;

// splitmix64: small, fast, good enough for Monte Carlo tests.
class Rng {
 public:
  explicit Rng(uint64_t seed) : s_(seed * 0x9E3779B97F4A7C15ull + 0x632BE59BD9B4E019ull) {}
  uint64_t next() {
    uint64_t z = (s_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1), 24 random bits (exactly representable floats).
  float uniform() { return float(next() >> 40) * (1.0f / 16777216.0f); }
  double uniform_d() { return double(next() >> 11) * (1.0 / 9007199254740992.0); }

 private:
  uint64_t s_;
};

inline Vec3 v3(double x, double y, double z) { return Vec3{float(x), float(y), float(z)}; }

inline Vec3 normalized(Vec3 v) {
  double l = std::sqrt(double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z);
  return v3(v.x / l, v.y / l, v.z / l);
}

// Direction with polar cosine z and azimuth phi (radians).
inline Vec3 dir_zphi(double z, double phi) {
  double s = std::sqrt(std::max(0.0, 1.0 - z * z));
  return v3(s * std::cos(phi), s * std::sin(phi), z);
}

// Direction at polar angle theta (degrees from +z) and azimuth phi (degrees).
inline Vec3 dir_deg(double theta_deg, double phi_deg) {
  double t = theta_deg * kPi / 180.0, p = phi_deg * kPi / 180.0;
  return v3(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
}

inline Vec3 uniform_sphere(Rng& rng) {
  return dir_zphi(1.0 - 2.0 * rng.uniform_d(), 2.0 * kPi * rng.uniform_d());
}

inline double luminance(const Rgb& c) { return (double(c.r) + c.g + c.b) / 3.0; }
inline double maxc(Vec3 c) { return std::max({double(c.x), double(c.y), double(c.z)}); }

// ---- Integration over a (z, phi) rectangle of the sphere (dw = dz dphi) ----

// Gauss-Legendre rule of order 3 or 5 on [-1, 1].
struct GaussRule {
  int n;
  double x[5], w[5];
};
inline const GaussRule& gauss_rule(int order) {
  static const GaussRule g3{3, {-0.7745966692414834, 0.0, 0.7745966692414834, 0, 0},
                            {0.5555555555555556, 0.8888888888888888, 0.5555555555555556, 0, 0}};
  static const GaussRule g5{5,
                            {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831,
                             0.9061798459386640},
                            {0.2369268850561891, 0.4786286704993665, 0.5688888888888889,
                             0.4786286704993665, 0.2369268850561891}};
  return order == 3 ? g3 : g5;
}

using DirFn = std::function<double(Vec3)>;

inline double gl_rect(const DirFn& f, double z0, double z1, double p0, double p1, int order = 5) {
  const GaussRule& g = gauss_rule(order);
  double hz = 0.5 * (z1 - z0), cz = 0.5 * (z1 + z0), hp = 0.5 * (p1 - p0), cp = 0.5 * (p1 + p0);
  double sum = 0;
  for (int i = 0; i < g.n; ++i)
    for (int j = 0; j < g.n; ++j)
      sum += g.w[i] * g.w[j] * f(dir_zphi(cz + hz * g.x[i], cp + hp * g.x[j]));
  return sum * hz * hp;
}

// Adaptive: compares the rule on the cell with the rule on its 4 quarters and
// recurses (to depth 6) where they disagree by more than abs_tol (or 1e-4
// relative).
inline double integrate_rect(const DirFn& f, double z0, double z1, double p0, double p1,
                             double abs_tol, int order = 5, int depth = 0, double whole = -1.0) {
  if (whole < 0) whole = gl_rect(f, z0, z1, p0, p1, order);
  double zm = 0.5 * (z0 + z1), pm = 0.5 * (p0 + p1);
  double q[4] = {gl_rect(f, z0, zm, p0, pm, order), gl_rect(f, zm, z1, p0, pm, order),
                 gl_rect(f, z0, zm, pm, p1, order), gl_rect(f, zm, z1, pm, p1, order)};
  double parts = q[0] + q[1] + q[2] + q[3];
  if (depth >= 6 || std::abs(parts - whole) <= std::max(abs_tol, 1e-4 * std::abs(parts)))
    return parts;
  double t = 0.25 * abs_tol;
  return integrate_rect(f, z0, zm, p0, pm, t, order, depth + 1, q[0]) +
         integrate_rect(f, zm, z1, p0, pm, t, order, depth + 1, q[1]) +
         integrate_rect(f, z0, zm, pm, p1, t, order, depth + 1, q[2]) +
         integrate_rect(f, zm, z1, pm, p1, t, order, depth + 1, q[3]);
}

// Integral of f over the whole sphere (nz x np cells, each adaptive).
inline double integrate_sphere(const DirFn& f, int nz = 32, int np = 32, double abs_tol = 1e-7) {
  double sum = 0;
  for (int i = 0; i < nz; ++i)
    for (int j = 0; j < np; ++j)
      sum += integrate_rect(f, -1.0 + 2.0 * i / nz, -1.0 + 2.0 * (i + 1) / nz, 2 * kPi * j / np,
                            2 * kPi * (j + 1) / np, abs_tol / (nz * np));
  return sum;
}

// ---- Chi-square distribution -----------------------------------------------

// Regularised upper incomplete gamma function Q(a, x) = Gamma(a, x) / Gamma(a):
// power series of P for x < a + 1, Legendre's continued fraction (modified
// Lentz evaluation) of Q otherwise.
inline double gamma_q(double a, double x) {
  if (x <= 0) return 1.0;
  double log_pref = -x + a * std::log(x) - std::lgamma(a);
  if (x < a + 1.0) {
    double term = 1.0 / a, sum = term;
    for (int n = 1; n < 1000000; ++n) {
      term *= x / (a + n);
      sum += term;
      if (std::abs(term) < std::abs(sum) * 1e-16) break;
    }
    return std::max(0.0, 1.0 - sum * std::exp(log_pref));
  }
  const double tiny = 1e-300;
  double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
  for (int i = 1; i < 1000000; ++i) {
    double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1.0 / d;
    double del = d * c;
    h *= del;
    if (std::abs(del - 1.0) < 1e-16) break;
  }
  return std::exp(log_pref) * h;
}

// P(X >= stat) for X ~ chi2(dof).
inline double chi2_pvalue(double stat, int dof) { return gamma_q(0.5 * dof, 0.5 * stat); }

// Per-test significance for an overall level alpha over n tests (Sidak).
inline double sidak(double alpha, int n) { return 1.0 - std::pow(1.0 - alpha, 1.0 / n); }

// ---- Chi-square test of sample() against pdf() -------------------------------

struct Chi2Options {
  int n_z = 32;          // bins in cos(theta) over [-1, 1] (even: z = 0 is a bin edge)
  int n_phi = 64;        // bins in phi over [-pi, pi)
  long samples = 600000;
  double min_expected = 5.0;
  double significance = 0.01;  // per test (already Sidak-corrected by the caller)
  uint64_t seed = 1;
};

struct Chi2Outcome {
  bool pass = false;
  double stat = 0, p_value = 0;
  int dof = 0;
  double pdf_integral = 0;  // integral of pdf over the sphere
  double fail_fraction = 0; // observed fraction of failed samples
  std::string message;
};

// sample(u1, u2, &wi) returns false for a failed sample; pdf(wi) >= 0.
using SampleFn = std::function<bool(float, float, Vec3*)>;

inline std::string chi2_dump(const std::string& name, const Chi2Options& o,
                             const std::vector<double>& obs, const std::vector<double>& expct) {
  namespace fs = std::filesystem;
  fs::path dir = fs::path(KNIT_TEST_OUTPUT_DIR) / "bsdf_chi2";
  std::error_code ec;
  fs::create_directories(dir, ec);
  auto csv = [&](const std::string& suffix, const std::vector<double>& v) {
    std::ofstream f(dir / (name + suffix));
    f << "# rows: cos(theta) bins from -1 to 1; columns: phi bins from -pi to pi\n";
    for (int i = 0; i < o.n_z; ++i) {
      for (int j = 0; j < o.n_phi; ++j) f << (j ? "," : "") << v[size_t(i) * o.n_phi + j];
      f << "\n";
    }
  };
  csv("_observed.csv", obs);
  csv("_expected.csv", expct);
  // Side-by-side greyscale image: observed | expected (scaled to the common maximum).
  double mx = 1e-30;
  for (size_t i = 0; i < obs.size(); ++i) mx = std::max({mx, obs[i], expct[i]});
  std::ofstream img(dir / (name + "_obs_exp.pgm"), std::ios::binary);
  int w = 2 * o.n_phi + 2, h = o.n_z;
  img << "P5\n" << w << " " << h << "\n255\n";
  for (int i = o.n_z - 1; i >= 0; --i) {
    for (int side = 0; side < 2; ++side) {
      const std::vector<double>& v = side ? expct : obs;
      for (int j = 0; j < o.n_phi; ++j)
        img.put(char(std::lround(255.0 * v[size_t(i) * o.n_phi + j] / mx)));
      if (side == 0) img.put(char(128)).put(char(128));  // separator
    }
  }
  return (dir / name).string() + "_{observed,expected}.csv, _obs_exp.pgm";
}

inline Chi2Outcome chi2_test(const std::string& name, const SampleFn& sample, const DirFn& pdf,
                             const Chi2Options& o) {
  Chi2Outcome out;
  const int ncell = o.n_z * o.n_phi;
  std::vector<double> obs(ncell, 0.0), expct(ncell, 0.0);
  double failed = 0;
  Rng rng(o.seed);
  for (long s = 0; s < o.samples; ++s) {
    Vec3 wi{};
    float u1 = rng.uniform(), u2 = rng.uniform();
    if (!sample(u1, u2, &wi)) {
      failed += 1;
      continue;
    }
    double z = std::clamp(double(wi.z), -1.0, 1.0);
    double phi = std::atan2(double(wi.y), double(wi.x));
    int iz = std::clamp(int((z + 1.0) * 0.5 * o.n_z), 0, o.n_z - 1);
    int ip = std::clamp(int((phi + kPi) / (2 * kPi) * o.n_phi), 0, o.n_phi - 1);
    obs[size_t(iz) * o.n_phi + ip] += 1;
  }
  const double n = double(o.samples);
  double total = 0;
  for (int i = 0; i < o.n_z; ++i) {
    for (int j = 0; j < o.n_phi; ++j) {
      double z0 = -1.0 + 2.0 * i / o.n_z, z1 = -1.0 + 2.0 * (i + 1) / o.n_z;
      double p0 = -kPi + 2 * kPi * j / o.n_phi, p1 = -kPi + 2 * kPi * (j + 1) / o.n_phi;
      // Absolute error per cell of 0.02 expected counts: far below the
      // Poisson noise (sqrt(E) >= 2.2 for the cells kept).
      double integral = integrate_rect(pdf, z0, z1, p0, p1, 0.02 / n, 3);
      expct[size_t(i) * o.n_phi + j] = n * integral;
      total += integral;
    }
  }
  out.pdf_integral = total;
  out.fail_fraction = failed / n;
  std::ostringstream msg;
  if (total > 1.0 + 1e-3) {
    msg << name << ": pdf integrates to " << total << " > 1. ";
  }
  // Cells and the failure bin; pool those with small expectation.
  std::vector<std::pair<double, double>> bins;  // (observed, expected)
  double pool_o = 0, pool_e = 0;
  int zero_support = 0;
  auto add = [&](double ob, double ex) {
    if (ex <= 0.0 && ob > 0) ++zero_support;
    if (ex < o.min_expected) {
      pool_o += ob;
      pool_e += ex;
    } else {
      bins.emplace_back(ob, ex);
    }
  };
  for (int c = 0; c < ncell; ++c) add(obs[c], expct[c]);
  add(failed, std::max(0.0, n * (1.0 - total)));
  if (pool_e >= o.min_expected) {
    bins.emplace_back(pool_o, pool_e);
  } else if (pool_e > 0 && !bins.empty()) {
    auto it = std::min_element(bins.begin(), bins.end(),
                               [](auto& a, auto& b) { return a.second < b.second; });
    it->first += pool_o;
    it->second += pool_e;
  } else if (pool_o > 0 && !bins.empty()) {
    ++zero_support;
  }
  double stat = 0;
  for (auto& b : bins) stat += (b.first - b.second) * (b.first - b.second) / b.second;
  out.stat = stat;
  out.dof = int(bins.size()) - 1;
  out.p_value = out.dof > 0 ? chi2_pvalue(stat, out.dof) : 0.0;
  if (zero_support > 0) msg << name << ": " << zero_support << " bins got samples where pdf is 0. ";
  if (out.dof < 1) msg << name << ": too few bins with expectation >= " << o.min_expected << ". ";
  if (out.p_value < o.significance)
    msg << name << ": chi2 = " << stat << " with " << out.dof << " dof, p = " << out.p_value
        << " < " << o.significance << ". ";
  out.pass = msg.str().empty();
  if (!out.pass) msg << "Histograms: " << chi2_dump(name, o, obs, expct);
  out.message = msg.str();
  return out;
}

}  // namespace knit::test
