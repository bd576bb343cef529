// Python bindings of the appearance model: YarnBSDF (the near-field yarn BSDF
// and its lobes, knit/bsdf.h), PlyProfile (ply/fibre shadowing and frame,
// knit/ply_profile.h) and KnitMaterial (geometry + shading point at a base
// hit, knit/shading.h). docs/python.md documents the API.
//
// Every method is vectorised over N rows: inputs are validated here, at the
// boundary (ValueError naming the argument, the row and the value), then the
// C++ host classes run row by row with the GIL released. Directions of the
// BSDF are in the local shading frame (z = yarn surface normal, x = yarn
// tangent); eval includes the cosine |wi.z|.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "bindings.h"
#include "knit/bsdf.h"
#include "knit/ply_profile.h"
#include "knit/shading.h"
#include "knit/table_progress.h"

namespace py = pybind11;

namespace knit::py {
namespace {

using Arr = ::py::array_t<double, ::py::array::c_style | ::py::array::forcecast>;

// Largest float below 1: a uniform number in [0, 1) given as a double can
// round up to 1.0f, which the kernel's samplers must never see.
constexpr float kBelowOne = 0.99999994f;
// Tolerance on unit length and orthogonality (as knit::check_direction).
constexpr double kUnitTol = 1e-3;

std::string idx(const char* name, ssize_t i, bool single) {
  return single ? std::string(name) : std::string(name) + "[" + std::to_string(i) + "]";
}

// Any array-like as a C-contiguous float64 array; TypeError naming the
// argument when numpy cannot convert it.
Arr as_array(::py::handle h, const char* name) {
  Arr a = Arr::ensure(h);
  if (!a) {
    PyErr_Clear();
    throw ::py::type_error(std::string(name) + " must be a number or an array of numbers, got " +
                           std::string(::py::str(::py::type::handle_of(h).attr("__name__"))));
  }
  return a;
}

// A per-row scalar: a number (one value for every row) or a 1-D array of N values.
struct Column {
  Arr a;
  const char* name = "";
  ssize_t n = 1;
  bool single = true;
  double at(ssize_t i) const { return a.data()[single ? 0 : i]; }
};

Column column(::py::handle h, const char* name) {
  Column c;
  c.a = as_array(h, name);
  c.name = name;
  if (c.a.ndim() > 1)
    throw ::py::value_error(std::string(name) +
                            " must be a number or a 1-D array, got an array of " +
                            std::to_string(c.a.ndim()) + " dimensions");
  c.single = c.a.ndim() == 0;
  c.n = c.single ? 1 : c.a.shape(0);
  if (c.n == 0) throw ::py::value_error(std::string(name) + " must not be empty");
  return c;
}

// Per-row vectors of K components: shape (K,) (one for every row) or (N, K).
struct Rows {
  Arr a;
  const char* name = "";
  ssize_t n = 1;
  ssize_t k = 3;
  bool single = true;
  const double* row(ssize_t i) const { return a.data() + k * (single ? 0 : i); }
  Vec3 vec(ssize_t i) const {
    const double* p = row(i);
    return Vec3{float(p[0]), float(p[1]), float(p[2])};
  }
};

Rows rows(::py::handle h, const char* name, ssize_t k) {
  Rows r;
  r.a = as_array(h, name);
  r.name = name;
  r.k = k;
  const bool ok = (r.a.ndim() == 1 && r.a.shape(0) == k) || (r.a.ndim() == 2 && r.a.shape(1) == k);
  if (!ok) {
    std::string shape = "(";
    for (ssize_t d = 0; d < r.a.ndim(); ++d)
      shape += (d ? ", " : "") + std::to_string(r.a.shape(d));
    shape += r.a.ndim() == 1 ? ",)" : ")";
    throw ::py::value_error(std::string(name) + " must have shape (" + std::to_string(k) +
                            ",) or (N, " + std::to_string(k) + "), got " + shape);
  }
  r.single = r.a.ndim() == 1;
  r.n = r.single ? 1 : r.a.shape(0);
  if (r.n == 0) throw ::py::value_error(std::string(name) + " must not be empty");
  return r;
}

// The common row count of several inputs: each has N rows or is a single value.
class Broadcast {
 public:
  void add(const char* name, ssize_t n, bool single) {
    if (single) return;
    if (n_ < 0) {
      n_ = n;
      first_ = name;
    } else if (n != n_) {
      throw ::py::value_error(std::string(name) + " has " + std::to_string(n) + " rows but " +
                              first_ + " has " + std::to_string(n_) +
                              "; give N rows or a single value");
    }
  }
  void add(const Rows& r) { add(r.name, r.n, r.single); }
  void add(const Column& c) { add(c.name, c.n, c.single); }
  ssize_t n() const { return n_ < 0 ? 1 : n_; }

 private:
  ssize_t n_ = -1;
  std::string first_;
};

void check_finite_rows(const Rows& r) {
  const ssize_t m = r.single ? 1 : r.n;
  for (ssize_t i = 0; i < m; ++i)
    for (ssize_t j = 0; j < r.k; ++j)
      if (!std::isfinite(r.row(i)[j]))
        throw ::py::value_error(idx(r.name, i, r.single) + " must be finite, got " +
                                num(r.row(i)[j]) + " in component " + std::to_string(j));
}

std::string vec_str(const double* p) {
  return "(" + num(p[0]) + ", " + num(p[1]) + ", " + num(p[2]) + ")";
}

// Every row a finite unit vector (length within kUnitTol of 1).
void check_unit_rows(const Rows& r) {
  check_finite_rows(r);
  const ssize_t m = r.single ? 1 : r.n;
  for (ssize_t i = 0; i < m; ++i) {
    const double* p = r.row(i);
    const double len = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    if (!(std::abs(len - 1.0) <= kUnitTol))
      throw ::py::value_error(idx(r.name, i, r.single) +
                              " must be a unit vector (length within 1e-3 of 1), got " +
                              vec_str(p) + " of length " + num(len));
  }
}

void check_finite_column(const Column& c) {
  const ssize_t m = c.single ? 1 : c.n;
  for (ssize_t i = 0; i < m; ++i)
    if (!std::isfinite(c.at(i)))
      throw ::py::value_error(idx(c.name, i, c.single) + " must be finite, got " + num(c.at(i)));
}

void check_range_column(const Column& c, double lo, double hi, bool open_hi) {
  const ssize_t m = c.single ? 1 : c.n;
  for (ssize_t i = 0; i < m; ++i) {
    const double v = c.at(i);
    if (!(v >= lo && (open_hi ? v < hi : v <= hi)))
      throw ::py::value_error(idx(c.name, i, c.single) + " = " + num(v) +
                              ": must be finite and in [" + num(lo) + ", " + num(hi) +
                              (open_hi ? ")" : "]"));
  }
}

void check_int_column(const Column& c, double lo, double hi, const std::string& rule) {
  const ssize_t m = c.single ? 1 : c.n;
  for (ssize_t i = 0; i < m; ++i) {
    const double v = c.at(i);
    if (!std::isfinite(v) || v != std::floor(v))
      throw ::py::value_error(idx(c.name, i, c.single) + " = " + num(v) + ": must be an integer");
    if (v < lo || v > hi)
      throw ::py::value_error(idx(c.name, i, c.single) + " = " + num(v) + ": " + rule);
  }
}

::py::array_t<double> out_rows(ssize_t n, ssize_t k) { return ::py::array_t<double>({n, k}); }

// ---------------------------------------------------------------------------
// YarnBSDF

// The per-hit inputs of the BSDF (knit::BsdfPoint) as columns.
struct PointArgs {
  Column color, layers, shadow, p_delta;
  BsdfPoint at(ssize_t i) const {
    BsdfPoint p;
    p.color = int(color.at(i));
    p.layers = int(std::min(layers.at(i), 1e6));
    p.shadow = float(shadow.at(i));
    p.p_delta = float(p_delta.at(i));
    return p;
  }
};

PointArgs point_args(const YarnBsdf& bsdf, ::py::handle color, ::py::handle layers,
                     ::py::handle shadow, ::py::handle p_delta, Broadcast& bc) {
  PointArgs a{column(color, "color"), column(layers, "layers"), column(shadow, "shadow"),
              column(p_delta, "p_delta")};
  const int nc = bsdf.params().num_colors();
  check_int_column(a.color, 0, nc - 1,
                   "must be a colour index in [0, " + std::to_string(nc) + ") (the YarnBSDF has " +
                       std::to_string(nc) + (nc == 1 ? " colour)" : " colours)"));
  check_int_column(a.layers, 1, 1e300, "must be >= 1");
  check_range_column(a.shadow, 0, 1, false);
  check_range_column(a.p_delta, 0, 1, false);
  bc.add(a.color);
  bc.add(a.layers);
  bc.add(a.shadow);
  bc.add(a.p_delta);
  return a;
}

std::vector<Rgb> colors_arg(::py::handle h, const char* name) {
  Arr a = as_array(h, name);
  std::vector<Rgb> out;
  if (a.ndim() == 1 && a.shape(0) == 3) {
    out.push_back(Rgb{float(a.data()[0]), float(a.data()[1]), float(a.data()[2])});
    return out;
  }
  if (a.ndim() != 2 || a.shape(1) != 3)
    throw ::py::value_error(
        std::string(name) +
        " must be a list of RGB triples (shape (K, 3)) or one RGB triple (shape (3,))");
  for (ssize_t i = 0; i < a.shape(0); ++i) {
    const double* p = a.data() + 3 * i;
    out.push_back(Rgb{float(p[0]), float(p[1]), float(p[2])});
  }
  return out;  // an empty list is left to YarnBsdfParams::validate, which names the field
}

YarnBsdf make_bsdf(double rx, double ry, double tx, double ty, double eta, double body_energy,
                   double body_reflect, double optical_depth, ::py::handle reflect,
                   ::py::handle transmit) {
  YarnBsdfParams p;
  p.roughness_x = float(rx);
  p.roughness_y = float(ry);
  p.trans_roughness_x = float(tx);
  p.trans_roughness_y = float(ty);
  p.eta = float(eta);
  p.body_energy = float(body_energy);
  p.body_reflect = float(body_reflect);
  p.optical_depth = float(optical_depth);
  if (!reflect.is_none()) p.reflect_colors = colors_arg(reflect, "reflect_colors");
  if (!transmit.is_none())
    p.transmit_colors = colors_arg(transmit, "transmit_colors");
  else if (!reflect.is_none())
    p.transmit_colors = p.reflect_colors;  // k_y^B defaults to k_x^B
  try {
    return YarnBsdf(std::move(p));
  } catch (const std::invalid_argument& e) {
    throw ::py::value_error(e.what());
  }
}

::py::array_t<double> colors_array(const std::vector<Rgb>& c) {
  ::py::array_t<double> a = out_rows(ssize_t(c.size()), 3);
  for (size_t i = 0; i < c.size(); ++i) {
    double* p = a.mutable_data(ssize_t(i), 0);
    p[0] = c[i].r;
    p[1] = c[i].g;
    p[2] = c[i].b;
  }
  return a;
}

::py::dict bsdf_kwargs(const YarnBsdf& b) {
  const YarnBsdfParams& p = b.params();
  ::py::dict d;
  d["roughness_x"] = p.roughness_x;
  d["roughness_y"] = p.roughness_y;
  d["trans_roughness_x"] = p.trans_roughness_x;
  d["trans_roughness_y"] = p.trans_roughness_y;
  d["eta"] = p.eta;
  d["body_energy"] = p.body_energy;
  d["body_reflect"] = p.body_reflect;
  d["optical_depth"] = p.optical_depth;
  d["reflect_colors"] = colors_array(p.reflect_colors);
  d["transmit_colors"] = colors_array(p.transmit_colors);
  return d;
}

std::string bsdf_repr(const YarnBsdf& b) {
  const YarnBsdfParams& p = b.params();
  return "knitshade.YarnBSDF(roughness_x=" + num(p.roughness_x) +
         ", roughness_y=" + num(p.roughness_y) + ", trans_roughness_x=" + num(p.trans_roughness_x) +
         ", trans_roughness_y=" + num(p.trans_roughness_y) + ", eta=" + num(p.eta) +
         ", body_energy=" + num(p.body_energy) + ", body_reflect=" + num(p.body_reflect) +
         ", optical_depth=" + num(p.optical_depth) + ", <" + std::to_string(p.num_colors()) +
         (p.num_colors() == 1 ? " colour>)" : " colours>)");
}

Lobe lobe_arg(::py::handle h) {
  if (::py::isinstance<::py::str>(h)) {
    const std::string s = h.cast<std::string>();
    if (s == "specular_reflection") return Lobe::SpecularReflection;
    if (s == "specular_transmission") return Lobe::SpecularTransmission;
    if (s == "body_reflection") return Lobe::BodyReflection;
    if (s == "body_transmission") return Lobe::BodyTransmission;
    throw ::py::value_error("lobe = '" + s +
                            "': must be 'specular_reflection', 'specular_transmission', "
                            "'body_reflection' or 'body_transmission' (or a knitshade.Lobe)");
  }
  if (::py::isinstance<Lobe>(h)) return h.cast<Lobe>();
  throw ::py::type_error("lobe must be a str or a knitshade.Lobe, got " +
                         std::string(::py::str(::py::type::handle_of(h).attr("__name__"))));
}

void put3(::py::array_t<double>& a, ssize_t i, double x, double y, double z) {
  double* p = a.mutable_data(i, 0);
  p[0] = x;
  p[1] = y;
  p[2] = z;
}
void put3(::py::array_t<double>& a, ssize_t i, const Vec3& v) { put3(a, i, v.x, v.y, v.z); }
void put3(::py::array_t<double>& a, ssize_t i, const Rgb& c) { put3(a, i, c.r, c.g, c.b); }

::py::array_t<double> bsdf_eval(const YarnBsdf& b, ::py::handle wo_h, ::py::handle wi_h,
                                ::py::handle color, ::py::handle layers, ::py::handle shadow,
                                ::py::handle p_delta) {
  Rows wo = rows(wo_h, "wo", 3), wi = rows(wi_h, "wi", 3);
  check_unit_rows(wo);
  check_unit_rows(wi);
  Broadcast bc;
  bc.add(wo);
  bc.add(wi);
  PointArgs pt = point_args(b, color, layers, shadow, p_delta, bc);
  const ssize_t n = bc.n();
  ::py::array_t<double> out = out_rows(n, 3);
  double* o = out.mutable_data();
  for_each_row(n, [&](ssize_t i) {
    const Rgb c = b.eval(wo.vec(i), wi.vec(i), pt.at(i));
    o[3 * i] = c.r;
    o[3 * i + 1] = c.g;
    o[3 * i + 2] = c.b;
  });
  return out;
}

::py::array_t<double> bsdf_pdf(const YarnBsdf& b, ::py::handle wo_h, ::py::handle wi_h,
                               ::py::handle color, ::py::handle layers, ::py::handle shadow,
                               ::py::handle p_delta) {
  Rows wo = rows(wo_h, "wo", 3), wi = rows(wi_h, "wi", 3);
  check_unit_rows(wo);
  check_unit_rows(wi);
  Broadcast bc;
  bc.add(wo);
  bc.add(wi);
  PointArgs pt = point_args(b, color, layers, shadow, p_delta, bc);
  const ssize_t n = bc.n();
  ::py::array_t<double> out(n);
  double* o = out.mutable_data();
  for_each_row(n, [&](ssize_t i) { o[i] = b.pdf(wo.vec(i), wi.vec(i), pt.at(i)); });
  return out;
}

::py::dict bsdf_sample(const YarnBsdf& b, ::py::handle wo_h, ::py::handle u_h, ::py::handle color,
                       ::py::handle layers, ::py::handle shadow, ::py::handle p_delta) {
  Rows wo = rows(wo_h, "wo", 3), u = rows(u_h, "u", 3);
  check_unit_rows(wo);
  {
    const ssize_t m = u.single ? 1 : u.n;
    for (ssize_t i = 0; i < m; ++i)
      for (int j = 0; j < 3; ++j) {
        const double v = u.row(i)[j];
        if (!(v >= 0 && v < 1))
          throw ::py::value_error((u.single ? "u[" : "u[" + std::to_string(i) + ", ") +
                                  std::to_string(j) + "] = " + num(v) + ": must be in [0, 1)");
      }
  }
  Broadcast bc;
  bc.add(wo);
  bc.add(u);
  PointArgs pt = point_args(b, color, layers, shadow, p_delta, bc);
  const ssize_t n = bc.n();
  ::py::array_t<double> wi = out_rows(n, 3), weight = out_rows(n, 3), pdf(n);
  ::py::array_t<int32_t> flags(n);
  ::py::array_t<bool> valid(n);
  double* pw = wi.mutable_data();
  double* pwt = weight.mutable_data();
  double* pp = pdf.mutable_data();
  int32_t* pf = flags.mutable_data();
  bool* pv = valid.mutable_data();
  for_each_row(n, [&](ssize_t i) {
    const double* ur = u.row(i);
    const std::array<float, 3> uf = {std::min(float(ur[0]), kBelowOne),
                                     std::min(float(ur[1]), kBelowOne),
                                     std::min(float(ur[2]), kBelowOne)};
    const BsdfSample s = b.sample(wo.vec(i), uf, pt.at(i));
    pw[3 * i] = s.wi.x;
    pw[3 * i + 1] = s.wi.y;
    pw[3 * i + 2] = s.wi.z;
    pwt[3 * i] = s.weight.r;
    pwt[3 * i + 1] = s.weight.g;
    pwt[3 * i + 2] = s.weight.b;
    pp[i] = s.pdf;
    pf[i] = s.flags;
    pv[i] = s.valid();
  });
  ::py::dict d;
  d["wi"] = wi;
  d["weight"] = weight;
  d["pdf"] = pdf;
  d["flags"] = flags;
  d["valid"] = valid;
  return d;
}

::py::array_t<double> bsdf_eval_lobe(const YarnBsdf& b, ::py::handle lobe_h, ::py::handle wo_h,
                                     ::py::handle wi_h, ::py::handle color, ::py::handle layers,
                                     ::py::handle shadow, ::py::handle p_delta) {
  const Lobe lobe = lobe_arg(lobe_h);
  Rows wo = rows(wo_h, "wo", 3), wi = rows(wi_h, "wi", 3);
  check_unit_rows(wo);
  check_unit_rows(wi);
  Broadcast bc;
  bc.add(wo);
  bc.add(wi);
  PointArgs pt = point_args(b, color, layers, shadow, p_delta, bc);
  const ssize_t n = bc.n();
  ::py::array_t<double> out = out_rows(n, 3);
  double* o = out.mutable_data();
  for_each_row(n, [&](ssize_t i) {
    const Rgb c = b.eval_lobe(lobe, wo.vec(i), wi.vec(i), pt.at(i));
    o[3 * i] = c.r;
    o[3 * i + 1] = c.g;
    o[3 * i + 2] = c.b;
  });
  return out;
}

::py::array_t<double> bsdf_lobe_probs(const YarnBsdf& b, ::py::handle wo_h, ::py::handle color,
                                      ::py::handle layers, ::py::handle shadow,
                                      ::py::handle p_delta) {
  Rows wo = rows(wo_h, "wo", 3);
  check_unit_rows(wo);
  Broadcast bc;
  bc.add(wo);
  PointArgs pt = point_args(b, color, layers, shadow, p_delta, bc);
  const ssize_t n = bc.n();
  ::py::array_t<double> out = out_rows(n, 4);
  double* o = out.mutable_data();
  for_each_row(n, [&](ssize_t i) {
    const std::array<float, 4> q = b.lobe_probabilities(wo.vec(i), pt.at(i));
    for (int k = 0; k < 4; ++k) o[4 * i + k] = q[size_t(k)];
  });
  return out;
}

// ---------------------------------------------------------------------------
// PlyProfile

PlyProfile make_ply(int ply_count, ::py::object ply_radius, double ply_twist, int fiber_count,
                    double fiber_twist, double yarn_radius) {
  PlyParams p;
  p.ply_count = ply_count;
  if (ply_radius.is_none()) {
    // Packed plies for the count asked for (an invalid count is reported below).
    p.ply_radius = PlyParams::packed_radius(std::clamp(ply_count, 1, 16));
    if (p.ply_radius >= 1.f) p.ply_radius = 0.5f;  // one ply: the radius is not used
  } else {
    p.ply_radius = float(ply_radius.cast<double>());
  }
  p.ply_twist = float(ply_twist);
  p.fiber_count = fiber_count;
  p.fiber_twist = float(fiber_twist);
  p.yarn_radius = float(yarn_radius);
  try {
    return PlyProfile(p);
  } catch (const std::invalid_argument& e) {
    throw ::py::value_error(e.what());
  }
}

::py::dict ply_eval(const PlyProfile& ply, ::py::handle phi_h, ::py::handle s_h, bool table) {
  Column phi = column(phi_h, "phi"), s = column(s_h, "s");
  check_finite_column(phi);
  check_finite_column(s);
  Broadcast bc;
  bc.add(phi);
  bc.add(s);
  const ssize_t n = bc.n();
  ::py::array_t<double> shadow(n), ply_shadow(n), fiber_shadow(n);
  ::py::array_t<double> normal = out_rows(n, 3), tangent = out_rows(n, 3),
                        bitangent = out_rows(n, 3);
  double* g = shadow.mutable_data();
  double* gp = ply_shadow.mutable_data();
  double* gf = fiber_shadow.mutable_data();
  for_each_row(n, [&](ssize_t i) {
    const float ph = float(phi.at(i)), ss = float(s.at(i));
    const k::KPlyShade r = table ? ply.lookup(ph, ss) : ply.procedural(ph, ss);
    g[i] = r.shadow;
    gp[i] = r.ply_shadow;
    gf[i] = r.fiber_shadow;
    put3(normal, i, r.n);
    put3(tangent, i, r.t);
    put3(bitangent, i, r.b);
  });
  ::py::dict d;
  d["shadow"] = shadow;
  d["ply_shadow"] = ply_shadow;
  d["fiber_shadow"] = fiber_shadow;
  d["normal"] = normal;
  d["tangent"] = tangent;
  d["bitangent"] = bitangent;
  return d;
}

::py::dict ply_kwargs(const PlyProfile& ply) {
  const PlyParams& p = ply.params();
  ::py::dict d;
  d["ply_count"] = p.ply_count;
  d["ply_radius"] = p.ply_radius;
  d["ply_twist"] = p.ply_twist;
  d["fiber_count"] = p.fiber_count;
  d["fiber_twist"] = p.fiber_twist;
  d["yarn_radius"] = p.yarn_radius;
  return d;
}

// ---------------------------------------------------------------------------
// KnitMaterial

const char* mode_name(KnitMode m) {
  return m == KnitMode::MultiScale ? "multi_scale" : "near_field";
}

// knitshade.set_table_build_progress's callback (None: none), and the
// observer that calls it: callback(done, total) in work units, at the
// build's start and end and whenever a job ends on the thread that builds
// (the one holding the GIL; knit/table_progress.h).
::py::object& python_progress_callback() {
  static ::py::object* callback = new ::py::object(::py::none());  // (never destroyed: outlives the interpreter's teardown order)
  return *callback;
}

class PythonTableProgress : public TableBuildProgress {
 public:
  void begin(uint64_t total) override {
    total_ = total;
    done_ = 0;
    call();
  }
  void add(uint64_t units) override {
    done_ += units;
    if (std::this_thread::get_id() == owner_) call();
  }
  void end() override {
    done_ = total_;
    call();
  }
  void rethrow() {
    if (error_) {
      std::exception_ptr e = error_;
      error_ = nullptr;
      std::rethrow_exception(e);
    }
  }

 private:
  void call() {
    if (error_ || std::this_thread::get_id() != owner_) return;
    try {
      python_progress_callback()(uint64_t(done_), total_);
    } catch (...) {  // (never through the build's jobs: kept for rethrow)
      error_ = std::current_exception();
    }
  }
  const std::thread::id owner_ = std::this_thread::get_id();
  std::atomic<uint64_t> done_{0};
  uint64_t total_ = 0;
  std::exception_ptr error_;
};

KnitMaterial make_material(const Pattern& pattern, const StitchParams& stitch, ::py::object bsdf,
                           ::py::object ply, const std::string& mode, bool capm, bool ply_detail,
                           int footprint_points, bool footprint_table, double table_min_cells,
                           bool table_bsdf, bool table_fold, bool self_shadowing, bool near_field_below_cell, double uv_scale,
                           int max_steps, double max_segment, double max_bend, const std::string& bsdf_model) {
  KnitMaterialParams mp;
  mp.stitch = stitch;
  if (bsdf.is_none()) {
    mp.bsdf = YarnBsdfParams{};
  } else if (::py::isinstance<YarnBsdf>(bsdf)) {
    mp.bsdf = bsdf.cast<const YarnBsdf&>().params();
  } else if (::py::isinstance<::py::dict>(bsdf)) {
    ::py::object cls = ::py::module_::import("knitshade").attr("YarnBSDF");
    mp.bsdf = cls(**bsdf.cast<::py::dict>()).cast<const YarnBsdf&>().params();
  } else {
    throw ::py::type_error(
        "bsdf must be a knitshade.YarnBSDF, a dict of its keyword arguments or None, got " +
        std::string(::py::str(::py::type::handle_of(bsdf).attr("__name__"))));
  }
  if (ply.is_none()) {
    mp.ply = PlyParams{};
  } else if (::py::isinstance<PlyProfile>(ply)) {
    mp.ply = ply.cast<const PlyProfile&>().params();
  } else if (::py::isinstance<::py::dict>(ply)) {
    ::py::object cls = ::py::module_::import("knitshade").attr("PlyProfile");
    mp.ply = cls(**ply.cast<::py::dict>()).cast<const PlyProfile&>().params();
  } else {
    throw ::py::type_error(
        "ply must be a knitshade.PlyProfile, a dict of its keyword arguments or None, got " +
        std::string(::py::str(::py::type::handle_of(ply).attr("__name__"))));
  }
  if (mode == "near_field") {
    mp.mode = KnitMode::NearField;
  } else if (mode == "multi_scale") {
    mp.mode = KnitMode::MultiScale;
  } else {
    throw ::py::value_error("mode = '" + mode + "': must be 'near_field' or 'multi_scale'");
  }
  if (bsdf_model == "exact") {
    mp.bsdf_model = KnitBsdfModel::Exact;
  } else if (bsdf_model == "cycles") {
    mp.bsdf_model = KnitBsdfModel::Cycles;
  } else {
    throw ::py::value_error("bsdf_model = '" + bsdf_model + "': must be 'exact' or 'cycles'");
  }
  mp.capm = capm;
  mp.ply_detail = ply_detail;
  mp.footprint_points = footprint_points;
  mp.footprint_table = footprint_table;
  mp.table_min_cells = float(table_min_cells);
  mp.table_bsdf = table_bsdf;
  mp.table_fold = table_fold;
  mp.self_shadowing = self_shadowing;
  mp.near_field_below_cell = near_field_below_cell;
  mp.uv_scale = float(uv_scale);
  mp.capm_options.max_steps = max_steps;
  mp.capm_options.max_segment = float(max_segment);
  mp.capm_options.max_bend = float(max_bend);
  // A progress callback (knitshade.set_table_build_progress) is called
  // from this thread only, which holds the GIL; the build's other threads
  // only count. An exception it raises is kept, the build finished, and
  // raised here.
  PythonTableProgress progress;
  TableBuildProgress* const before = table_build_progress();
  if (!python_progress_callback().is_none()) set_table_build_progress(&progress);
  struct Restore {
    TableBuildProgress* p;
    ~Restore() { set_table_build_progress(p); }
  } restore{before};
  try {
    KnitMaterial m(pattern, std::move(mp));
    progress.rethrow();
    return m;
  } catch (const std::invalid_argument& e) {
    throw ::py::value_error(e.what());
  }
}

// The base hits of a shade()/transmittance() call, validated.
struct HitArgs {
  Column u, v, ppw, kx, ky;
  Rows ray, t, b, n, footprint, shift, offset;
  bool has_t = false, has_b = false, has_n = false, has_footprint = false, has_offset = false;
  const FrameProvider* frame = nullptr;
  float uv_scale = 1;
  ssize_t count = 1;

  BaseHit hit(ssize_t i) const {
    BaseHit h;
    h.u = float(u.at(i));
    h.v = float(v.at(i));
    if (frame) frame->frame(uv_scale * h.u, uv_scale * h.v, h.t, h.b, h.n);
    if (has_t) h.t = t.vec(i);
    if (has_b) h.b = b.vec(i);
    if (has_n) h.n = n.vec(i);
    h.pattern_per_world = float(ppw.at(i));
    h.kx = float(kx.at(i));
    h.ky = float(ky.at(i));
    if (has_footprint) {
      const double* f = footprint.row(i);
      h.dudx = float(f[0]);
      h.dvdx = float(f[1]);
      h.dudy = float(f[2]);
      h.dvdy = float(f[3]);
      if (has_offset) {
        const double* o = offset.row(i);
        h.box_du = float(o[0]);
        h.box_dv = float(o[1]);
      }
    }
    return h;
  }
  std::array<float, 2> shift_at(ssize_t i) const {
    const double* s = shift.row(i);
    return {std::min(float(s[0]), kBelowOne), std::min(float(s[1]), kBelowOne)};
  }
};

HitArgs hit_args(const KnitMaterial& m, ::py::handle u, ::py::handle v, ::py::handle ray_dir,
                 ::py::handle t, ::py::handle b, ::py::handle n, ::py::handle ppw, ::py::handle kx,
                 ::py::handle ky, ::py::handle footprint, ::py::handle shift, ::py::handle offset,
                 const FrameProvider* frame) {
  HitArgs a;
  a.frame = frame;
  a.uv_scale = m.params().uv_scale;
  a.u = column(u, "u");
  a.v = column(v, "v");
  check_finite_column(a.u);
  check_finite_column(a.v);
  // Pattern space is single precision: |uv_scale * u| <= kMaxPatternCoord.
  const double uv_lim = double(kMaxPatternCoord) / double(a.uv_scale);
  check_range_column(a.u, -uv_lim, uv_lim, false);
  check_range_column(a.v, -uv_lim, uv_lim, false);
  a.ray = rows(ray_dir, "ray_dir", 3);
  check_unit_rows(a.ray);
  Broadcast bc;
  bc.add(a.u);
  bc.add(a.v);
  bc.add(a.ray);
  struct Axis {
    ::py::handle h;
    const char* name;
    Rows* r;
    bool* has;
  } axes[3] = {{t, "t", &a.t, &a.has_t}, {b, "b", &a.b, &a.has_b}, {n, "n", &a.n, &a.has_n}};
  int given = 0;
  for (Axis& ax : axes) {
    if (ax.h.is_none()) continue;
    *ax.r = rows(ax.h, ax.name, 3);
    check_unit_rows(*ax.r);
    bc.add(*ax.r);
    *ax.has = true;
    ++given;
  }
  if (given != 0 && given != 3)
    throw ::py::value_error(
        "t, b and n must be given together (an orthonormal frame) or not at all");
  if (given == 3) {
    const Rows* R[3] = {&a.t, &a.b, &a.n};
    const char* names[3][2] = {{"t", "b"}, {"t", "n"}, {"b", "n"}};
    const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
    const ssize_t rows_n =
        std::max({a.t.single ? 1 : a.t.n, a.b.single ? 1 : a.b.n, a.n.single ? 1 : a.n.n});
    for (ssize_t i = 0; i < rows_n; ++i)
      for (int p = 0; p < 3; ++p) {
        const double* x = R[pairs[p][0]]->row(i);
        const double* y = R[pairs[p][1]]->row(i);
        const double d = x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
        if (!(std::abs(d) <= kUnitTol))
          throw ::py::value_error(std::string("the frame (t, b, n) must be orthonormal: ") +
                                  names[p][0] + " . " + names[p][1] + " = " + num(d) +
                                  (rows_n > 1 ? " in row " + std::to_string(i) : ""));
      }
  }
  a.ppw = column(ppw, "pattern_per_world");
  check_finite_column(a.ppw);
  {
    const ssize_t m2 = a.ppw.single ? 1 : a.ppw.n;
    for (ssize_t i = 0; i < m2; ++i)
      if (!(a.ppw.at(i) > 0))
        throw ::py::value_error(idx("pattern_per_world", i, a.ppw.single) + " = " +
                                num(a.ppw.at(i)) + ": must be > 0");
  }
  bc.add(a.ppw);
  a.kx = column(kx, "kx");
  a.ky = column(ky, "ky");
  check_finite_column(a.kx);
  check_finite_column(a.ky);
  bc.add(a.kx);
  bc.add(a.ky);
  if (!footprint.is_none()) {
    a.footprint = rows(footprint, "footprint", 4);
    check_finite_rows(a.footprint);
    bc.add(a.footprint);
    a.has_footprint = true;
  }
  if (!offset.is_none()) {
    // The footprint's centre minus (u, v): (u, v) must lie in the footprint,
    // offset = -(jx (du/dx, dv/dx) + jy (du/dy, dv/dy)) with |jx|, |jy| <= 1/2.
    if (!a.has_footprint) throw ::py::value_error("footprint_offset needs footprint");
    a.offset = rows(offset, "footprint_offset", 2);
    check_finite_rows(a.offset);
    bc.add(a.offset);  // (first: the rows below pair up only when the counts agree)
    const bool single = a.offset.single && a.footprint.single;
    const ssize_t m2 = single ? 1 : std::max(a.offset.single ? 1 : a.offset.n, a.footprint.single ? 1 : a.footprint.n);
    for (ssize_t i = 0; i < m2; ++i) {
      const double *f = a.footprint.row(i), *o = a.offset.row(i);
      const double det = f[0] * f[3] - f[2] * f[1];
      const std::string at = single ? "" : " in row " + std::to_string(i);
      if (!(std::abs(det) > 0)) {
        if (o[0] != 0 || o[1] != 0)
          throw ::py::value_error("footprint_offset" + at + " = (" + num(o[0]) + ", " + num(o[1]) +
                                  "): the footprint has no area, so the offset must be 0");
        continue;
      }
      // -offset = jx (f0, f1) + jy (f2, f3)
      const double jx = (-o[0] * f[3] + o[1] * f[2]) / det, jy = (-o[1] * f[0] + o[0] * f[1]) / det;
      if (!(std::abs(jx) <= 0.5 + 1e-6 && std::abs(jy) <= 0.5 + 1e-6))
        throw ::py::value_error("footprint_offset" + at + " = (" + num(o[0]) + ", " + num(o[1]) +
                                "): puts (u, v) outside its footprint (" + num(jx) + ", " + num(jy) +
                                " footprints from the centre; at most 0.5 each way)");
    }
    a.has_offset = true;
  }
  a.shift = rows(shift, "shift", 2);
  {
    const ssize_t m2 = a.shift.single ? 1 : a.shift.n;
    for (ssize_t i = 0; i < m2; ++i)
      for (int j = 0; j < 2; ++j) {
        const double s = a.shift.row(i)[j];
        if (!(s >= 0 && s < 1))
          throw ::py::value_error(
              (a.shift.single ? "shift[" : "shift[" + std::to_string(i) + ", ") +
              std::to_string(j) + "] = " + num(s) + ": must be in [0, 1)");
      }
  }
  bc.add(a.shift);
  a.count = bc.n();
  return a;
}

::py::dict material_shade(const KnitMaterial& m, const HitArgs& a) {
  const ssize_t n = a.count;
  const double nan = std::nan("");
  ::py::array_t<bool> pass(n), back(n);
  ::py::array_t<double> st = out_rows(n, 3), sb = out_rows(n, 3), sn = out_rows(n, 3),
                        off = out_rows(n, 3);
  ::py::array_t<double> kd_r = out_rows(n, 3), kd_t = out_rows(n, 3), alpha = out_rows(n, 4);
  ::py::array_t<int32_t> color(n), layers(n), steps(n);
  ::py::array_t<double> shadow(n), p_delta(n);
  bool* ppass = pass.mutable_data();
  bool* pback = back.mutable_data();
  int32_t* pc = color.mutable_data();
  int32_t* pl = layers.mutable_data();
  int32_t* ps = steps.mutable_data();
  double* pg = shadow.mutable_data();
  double* pd = p_delta.mutable_data();
  double* pa = alpha.mutable_data();
  for_each_row(n, [&](ssize_t i) {
    const KnitShade sh = m.shade(a.hit(i), a.ray.vec(i), a.frame, a.shift_at(i));
    ppass[i] = sh.pass_through;
    pback[i] = sh.from_back;
    ps[i] = sh.steps;
    if (sh.pass_through) {
      // Nothing was hit: no shading point. The whole footprint passes (p_delta 1).
      for (auto* arr : {&st, &sb, &sn, &off, &kd_r, &kd_t}) put3(*arr, i, nan, nan, nan);
      for (int k = 0; k < 4; ++k) pa[4 * i + k] = nan;
      pc[i] = -1;
      pl[i] = 0;
      pg[i] = nan;
      pd[i] = 1.0;
      return;
    }
    put3(st, i, sh.st);
    put3(sb, i, sh.sb);
    put3(sn, i, sh.sn);
    put3(off, i, sh.offset);
    put3(kd_r, i, sh.kd_r);
    put3(kd_t, i, sh.kd_t);
    pa[4 * i] = sh.spec_r.alpha_x;
    pa[4 * i + 1] = sh.spec_r.alpha_y;
    pa[4 * i + 2] = sh.spec_t.alpha_x;
    pa[4 * i + 3] = sh.spec_t.alpha_y;
    pc[i] = sh.point.color;
    pl[i] = sh.point.layers;
    pg[i] = sh.point.shadow;
    pd[i] = sh.point.p_delta;
  });
  ::py::dict d;
  d["pass_through"] = pass;
  d["from_back"] = back;
  d["st"] = st;
  d["sb"] = sb;
  d["sn"] = sn;
  d["offset"] = off;
  d["color"] = color;
  d["layers"] = layers;
  d["shadow"] = shadow;
  d["p_delta"] = p_delta;
  d["kd_r"] = kd_r;
  d["kd_t"] = kd_t;
  d["alpha"] = alpha;
  d["steps"] = steps;
  return d;
}

::py::array_t<double> material_transmittance(const KnitMaterial& m, const HitArgs& a) {
  ::py::array_t<double> out(a.count);
  double* o = out.mutable_data();
  for_each_row(a.count, [&](ssize_t i) {
    o[i] = m.transmittance(a.hit(i), a.ray.vec(i), a.frame, a.shift_at(i));
  });
  return out;
}

const char* kPointDoc = R"doc(
Per-hit arguments (each a number for every row, or a 1-D array of N values):
color (colour index into the palette, default 0), layers (yarns crossed by
the transmitted path, >= 1, default 1), shadow (ply/fibre shadowing G_{p,f}
in [0, 1], default 1) and p_delta (probability of passing straight through a
gap, in [0, 1], default 0).)doc";

const char* kHitDoc = R"doc(
Arguments, vectorised over N base hits (a number / single vector is used for
every row): u, v (texture coordinates of the base hit; pattern space is
x = uv_scale u, y = uv_scale v); ray_dir ((3,) or (N, 3) world direction the
ray travels, unit); t, b, n (the base mesh's orthonormal world frame at the
hit: t along dP/du, b along dP/dv, n the front side; all three or none;
default the frame of `frame` at the hit, else x, y, z); pattern_per_world
(pattern units per world unit, > 0, default 1); kx, ky (normal curvature of
the base along t and b, 1/world units, > 0 convex, default 0; used when
`frame` is None); footprint ((4,) or (N, 4): du/dx, dv/dx, du/dy, dv/dy of
the pixel, multi-scale only; default 0); shift ((2,) or (N, 2) in [0, 1):
Cranley-Patterson shift of the footprint's Sobol' points, default 0.5, 0.5);
footprint_offset ((2,) or (N, 2), with footprint: the footprint's centre
minus (u, v) in UV, multi-scale only; (u, v) must lie in the footprint. A
renderer that knows where its sample lies in the pixel passes
-(jx (du/dx, dv/dx) + jy (du/dy, dv/dy)), (jx, jy) the sample's offset from
the pixel's centre in pixels, so that all of a pixel's samples aggregate
the same footprint; default 0: the footprint is centred at (u, v));
frame (a FlatFrame, CylinderFrame or SphereFrame in pattern units: bends the
CAPM ray with the base surface; near field only).)doc";

// KnitMaterial.shade and .transmittance take the same per-hit arguments
// (hit_args): one signature, one argument list, for both.
template <class Fn>
void def_hit_method(::py::class_<KnitMaterial>& cls, const char* name, Fn fn, const char* doc) {
  cls.def(
      name,
      [fn](const KnitMaterial& km, ::py::handle u, ::py::handle v, ::py::handle ray_dir, ::py::handle t,
           ::py::handle b, ::py::handle n, ::py::handle ppw, ::py::handle kx, ::py::handle ky,
           ::py::handle footprint, ::py::handle shift, ::py::handle offset, const FrameProvider* frame) {
        return fn(km, hit_args(km, u, v, ray_dir, t, b, n, ppw, kx, ky, footprint, shift, offset, frame));
      },
      ::py::arg("u"), ::py::arg("v"), ::py::arg("ray_dir"), ::py::kw_only(), ::py::arg("t") = ::py::none(),
      ::py::arg("b") = ::py::none(), ::py::arg("n") = ::py::none(), ::py::arg("pattern_per_world") = 1.0,
      ::py::arg("kx") = 0.0, ::py::arg("ky") = 0.0, ::py::arg("footprint") = ::py::none(),
      ::py::arg("shift") = std::vector<double>{0.5, 0.5}, ::py::arg("footprint_offset") = ::py::none(),
      ::py::arg("frame") = nullptr,
      (std::string(doc) + kHitDoc).c_str());
}

}  // namespace

void bind_appearance(::py::module_& m) {
  m.def(
      "set_table_build_progress",
      [](::py::object callback) {
        if (!callback.is_none() && !PyCallable_Check(callback.ptr()))
          throw ::py::type_error("set_table_build_progress: the callback must be callable or None");
        python_progress_callback() = std::move(callback);
      },
      ::py::arg("callback"), R"doc(
Call callback(done, total) while a multi-scale KnitMaterial builds its class
tables (seconds, the first time a material is made; not when they come from
the class-table cache): at the start (done 0), as the build's jobs end, and
at the end (done == total). The units are the build's jobs, weighted as they
cost. It is called on the thread that makes the material, with the GIL held;
an exception it raises is raised by the constructor once the build is over.
None (the default) turns it off.)doc");
  m.attr("BSDF_REFLECT") = int(kBsdfReflect);
  m.attr("BSDF_TRANSMIT") = int(kBsdfTransmit);
  m.attr("BSDF_DELTA") = int(kBsdfDelta);

  ::py::enum_<Lobe>(m, "Lobe",
                    "The four lobes of the yarn BSDF (paper Eq. 1), for YarnBSDF.eval_lobe.")
      .value("SPECULAR_REFLECTION", Lobe::SpecularReflection, "f_R: rough dielectric reflection")
      .value("SPECULAR_TRANSMISSION", Lobe::SpecularTransmission,
             "tau (1 - B) f_T: thin-slab rough dielectric transmission")
      .value("BODY_REFLECTION", Lobe::BodyReflection, "r B G (1 - F_o)(1 - F_i) LS k_R")
      .value("BODY_TRANSMISSION", Lobe::BodyTransmission,
             "tau (1 - r) B G (1 - F_o)(1 - F_i) k_T / pi");

  const std::string point_doc = kPointDoc;

  ::py::class_<YarnBsdf>(m, "YarnBSDF", R"doc(
The near-field yarn BSDF (paper Eq. 1 with the changes of docs/bsdf.md):
specular reflection, specular transmission, body reflection and body
transmission, with double-layer attenuation and delta transmission through
gaps.

Frame: the local shading frame of the yarn surface, z = surface normal,
x = yarn tangent, y = z cross x. wo points to the viewer, wi to the light,
both unit and pointing away from the surface; wo.z * wi.z > 0 is reflection,
< 0 transmission.

eval INCLUDES the cosine: eval(wo, wi) = f(wo, wi) |wi.z| (times
1 - p_delta); pdf is the solid-angle density of sample(); a sample's
weight = eval / pdf (1 for a pass-through event).

Keyword arguments (all optional; defaults of knit::YarnBsdfParams):
roughness_x=0.15, roughness_y=0.45 (GGX alpha of f_R along / across the yarn,
(0, 1]), trans_roughness_x=0.3, trans_roughness_y=0.6 (f_T, (0, 1]),
eta=1.55 ([1, 3]), body_energy=0.7 (B, [0, 1]), body_reflect=0.6 (r, [0, 1]),
optical_depth=1.0 (D, [0, 50]), reflect_colors (k_x^B per colour index: a
list of RGB triples or a (K, 3) array, channels in [0, 1], 1-256 colours;
default [(0.8, 0.8, 0.8)]), transmit_colors (k_y^B, same count; default: the
reflect colours). Values are stored as float32. Invalid values raise
ValueError with the C++ message naming the field and value.)doc")
      .def(::py::init(&make_bsdf), ::py::kw_only(), ::py::arg("roughness_x") = 0.15,
           ::py::arg("roughness_y") = 0.45, ::py::arg("trans_roughness_x") = 0.30,
           ::py::arg("trans_roughness_y") = 0.60, ::py::arg("eta") = 1.55,
           ::py::arg("body_energy") = 0.7, ::py::arg("body_reflect") = 0.6,
           ::py::arg("optical_depth") = 1.0, ::py::arg("reflect_colors") = ::py::none(),
           ::py::arg("transmit_colors") = ::py::none())
      .def_property_readonly("roughness_x",
                             [](const YarnBsdf& b) { return b.params().roughness_x; })
      .def_property_readonly("roughness_y",
                             [](const YarnBsdf& b) { return b.params().roughness_y; })
      .def_property_readonly("trans_roughness_x",
                             [](const YarnBsdf& b) { return b.params().trans_roughness_x; })
      .def_property_readonly("trans_roughness_y",
                             [](const YarnBsdf& b) { return b.params().trans_roughness_y; })
      .def_property_readonly("eta", [](const YarnBsdf& b) { return b.params().eta; })
      .def_property_readonly("body_energy",
                             [](const YarnBsdf& b) { return b.params().body_energy; })
      .def_property_readonly("body_reflect",
                             [](const YarnBsdf& b) { return b.params().body_reflect; })
      .def_property_readonly("optical_depth",
                             [](const YarnBsdf& b) { return b.params().optical_depth; })
      .def_property_readonly(
          "reflect_colors",
          [](const YarnBsdf& b) { return colors_array(b.params().reflect_colors); },
          "k_x^B per colour index, a (K, 3) array (a copy).")
      .def_property_readonly(
          "transmit_colors",
          [](const YarnBsdf& b) { return colors_array(b.params().transmit_colors); },
          "k_y^B per colour index, a (K, 3) array (a copy).")
      .def_property_readonly("num_colors",
                             [](const YarnBsdf& b) { return b.params().num_colors(); })
      .def("params", &bsdf_kwargs, "The keyword arguments that rebuild this BSDF, as a dict.")
      .def("eval", &bsdf_eval, ::py::arg("wo"), ::py::arg("wi"), ::py::kw_only(),
           ::py::arg("color") = 0, ::py::arg("layers") = 1, ::py::arg("shadow") = 1.0,
           ::py::arg("p_delta") = 0.0,
           (R"doc(
eval(wo, wi) -> (N, 3) RGB array: (1 - p_delta) f(wo, wi) |wi.z|, the cosine
included (what light sampling multiplies incoming radiance by). wo and wi
have shape (3,) or (N, 3) and are broadcast; each row must be a finite unit
vector in the local frame (ValueError naming the argument and row). N = 1
when every input is a single value.)doc" +
            point_doc)
               .c_str())
      .def("pdf", &bsdf_pdf, ::py::arg("wo"), ::py::arg("wi"), ::py::kw_only(),
           ::py::arg("color") = 0, ::py::arg("layers") = 1, ::py::arg("shadow") = 1.0,
           ::py::arg("p_delta") = 0.0,
           (R"doc(
pdf(wo, wi) -> (N,) array: the solid-angle density with which sample()
returns wi, times (1 - p_delta) (the pass-through event is discrete and not
part of it).)doc" +
            point_doc)
               .c_str())
      .def("sample", &bsdf_sample, ::py::arg("wo"), ::py::arg("u"), ::py::kw_only(),
           ::py::arg("color") = 0, ::py::arg("layers") = 1, ::py::arg("shadow") = 1.0,
           ::py::arg("p_delta") = 0.0,
           (R"doc(
sample(wo, u) -> dict of arrays: wi (N, 3), weight (N, 3) = eval / pdf, pdf
(N,), flags (N,) int32 (BSDF_REFLECT, BSDF_TRANSMIT, plus BSDF_DELTA for a
pass-through event, whose wi = -wo, weight 1 and pdf = p_delta, a discrete
probability), valid (N,) bool (flags != 0 and pdf > 0; a failed sample has
weight 0, pdf 0, flags 0). u has shape (3,) or (N, 3) with values in [0, 1):
u[:, 0] chooses pass-through, u[:, 1] the lobe (then reused), u[:, 2] the
direction.)doc" +
            point_doc)
               .c_str())
      .def("eval_lobe", &bsdf_eval_lobe, ::py::arg("lobe"), ::py::arg("wo"), ::py::arg("wi"),
           ::py::kw_only(), ::py::arg("color") = 0, ::py::arg("layers") = 1,
           ::py::arg("shadow") = 1.0, ::py::arg("p_delta") = 0.0,
           (R"doc(
eval_lobe(lobe, wo, wi) -> (N, 3): one lobe's weighted contribution to eval,
cosine included, p_delta NOT applied (so for p_delta = 0 the four lobes sum to
eval). lobe: 'specular_reflection', 'specular_transmission',
'body_reflection', 'body_transmission' or a knitshade.Lobe.)doc" +
            point_doc)
               .c_str())
      .def("lobe_probabilities", &bsdf_lobe_probs, ::py::arg("wo"), ::py::kw_only(),
           ::py::arg("color") = 0, ::py::arg("layers") = 1, ::py::arg("shadow") = 1.0,
           ::py::arg("p_delta") = 0.0,
           (R"doc(
lobe_probabilities(wo) -> (N, 4): the probabilities with which sample()
picks each lobe at wo (columns in knitshade.Lobe order), given that it does
not pass through; each row sums to 1, or is all zero when the BSDF is.)doc" +
            point_doc)
               .c_str())
      .def("__repr__", &bsdf_repr)
      .def(::py::pickle([](const YarnBsdf& b) { return bsdf_kwargs(b); },
                        [](const ::py::dict& d) {
                          return make_bsdf(
                              d["roughness_x"].cast<double>(), d["roughness_y"].cast<double>(),
                              d["trans_roughness_x"].cast<double>(),
                              d["trans_roughness_y"].cast<double>(), d["eta"].cast<double>(),
                              d["body_energy"].cast<double>(), d["body_reflect"].cast<double>(),
                              d["optical_depth"].cast<double>(), d["reflect_colors"],
                              d["transmit_colors"]);
                        }));

  ::py::class_<PlyProfile>(m, "PlyProfile", R"doc(
Ply and fibre detail of the yarn (paper Sec. 3.2, 5): the shadowing G_{p,f}
and the perturbed shading frame, from 1D profiles wrapped around the yarn.

Keyword arguments: ply_count=3 (plies per yarn, [1, 16]), ply_radius (ply
radius / yarn radius, (0, 1); default: touching plies,
PlyProfile.packed_radius(ply_count)), ply_twist=0.5 (ply helix angle at the
yarn surface, radians, |.| <= 1.4), fiber_count=40 (fibres per ply,
[0, 10000]; < 4: no fibre profile), fiber_twist=-0.35 (fibre helix angle on
the ply, radians, |.| <= 1.4), yarn_radius=0.75 (pattern units, (0, 1000]).
Invalid values raise ValueError with the C++ message naming the field.)doc")
      .def(::py::init(&make_ply), ::py::kw_only(), ::py::arg("ply_count") = 3,
           ::py::arg("ply_radius") = ::py::none(), ::py::arg("ply_twist") = 0.5,
           ::py::arg("fiber_count") = 40, ::py::arg("fiber_twist") = -0.35,
           ::py::arg("yarn_radius") = 0.75)
      .def_static("packed_radius", &PlyParams::packed_radius, ::py::arg("ply_count"),
                  "Radius (in yarn radii) of ply_count equal touching plies: sin(pi/n) / (1 + "
                  "sin(pi/n)); 1 for "
                  "n = 1.")
      .def_property_readonly("ply_count", [](const PlyProfile& p) { return p.params().ply_count; })
      .def_property_readonly("ply_radius",
                             [](const PlyProfile& p) { return p.params().ply_radius; })
      .def_property_readonly("ply_twist", [](const PlyProfile& p) { return p.params().ply_twist; })
      .def_property_readonly("fiber_count",
                             [](const PlyProfile& p) { return p.params().fiber_count; })
      .def_property_readonly("fiber_twist",
                             [](const PlyProfile& p) { return p.params().fiber_twist; })
      .def_property_readonly("yarn_radius",
                             [](const PlyProfile& p) { return p.params().yarn_radius; })
      .def("params", &ply_kwargs, "The keyword arguments that rebuild this profile, as a dict.")
      .def_property_readonly(
          "kernel_params",
          [](const PlyProfile& p) {
            const k::KPlyParams& q = p.kernel_params();
            ::py::dict d;
            d["ply_count"] = q.ply_count;
            d["ply_radius"] = q.ply_radius;
            d["ply_center"] = q.ply_center;
            d["ply_rate"] = q.ply_rate;
            d["fiber_ring"] = q.fiber_ring;
            d["fiber_radius"] = q.fiber_radius;
            d["fiber_center"] = q.fiber_center;
            d["fiber_rate"] = q.fiber_rate;
            d["yarn_radius"] = q.yarn_radius;
            return d;
          },
          "Derived kernel parameters: ply_center, ply_rate (radians of ply phase per unit of s), "
          "fiber_ring "
          "(fibres on a ply's outer ring; 0: no fibre profile), fiber_radius, fiber_center (ply "
          "radii), "
          "fiber_rate, ...")
      .def_property_readonly_static(
          "table_bytes", [](::py::object) { return PlyProfile::table_bytes(); },
          "Bytes of the 1D profile table a material keeps (3 channels x 256 float32 = 3072).")
      .def_property_readonly(
          "table",
          [](const PlyProfile& p) {
            ::py::array_t<float> a({ssize_t(3), ssize_t(KPLY_TABLE_N)});
            std::copy(p.table().begin(), p.table().end(), a.mutable_data());
            return a;
          },
          "The profile table as a float32 array of shape (3, 256) (a copy): channel 0 ply shadow, "
          "1 ply normal "
          "tilt (radians), 2 fibre shadow, each over one period at warped abscissae "
          "(docs/bsdf.md).")
      .def(
          "lookup",
          [](const PlyProfile& p, ::py::handle phi, ::py::handle s) {
            return ply_eval(p, phi, s, true);
          },
          ::py::arg("phi"), ::py::arg("s"), R"doc(
Table lookup at azimuth phi (radians around the yarn, increasing towards +y
of the local frame) and arc length s (pattern units), each a number or a 1-D
array, broadcast. Returns a dict: shadow (G_{p,f} = ply_shadow *
fiber_shadow), ply_shadow, fiber_shadow (N,), and the perturbed frame in the
yarn's local frame (x tangent, z normal): normal, tangent, bitangent (N, 3).)doc")
      .def(
          "procedural",
          [](const PlyProfile& p, ::py::handle phi, ::py::handle s) {
            return ply_eval(p, phi, s, false);
          },
          ::py::arg("phi"), ::py::arg("s"),
          "As lookup(), computed in closed form (what the OSL shader runs).")
      .def("__repr__",
           [](const PlyProfile& p) {
             const PlyParams& q = p.params();
             return "knitshade.PlyProfile(ply_count=" + std::to_string(q.ply_count) +
                    ", ply_radius=" + num(q.ply_radius) + ", ply_twist=" + num(q.ply_twist) +
                    ", fiber_count=" + std::to_string(q.fiber_count) +
                    ", fiber_twist=" + num(q.fiber_twist) + ", yarn_radius=" + num(q.yarn_radius) +
                    ")";
           })
      .def(::py::pickle([](const PlyProfile& p) { return ply_kwargs(p); },
                        [](const ::py::dict& d) {
                          return make_ply(
                              d["ply_count"].cast<int>(), d["ply_radius"],
                              d["ply_twist"].cast<double>(), d["fiber_count"].cast<int>(),
                              d["fiber_twist"].cast<double>(), d["yarn_radius"].cast<double>());
                        }));

  ::py::class_<KnitMaterial> knit_material(m, "KnitMaterial", R"doc(
The knit model as a renderer sees it: at a hit of the base mesh, run the
geometry (CAPM or the flat height query, near field or multi-scale) and
return the shading point (knit/shading.h).

KnitMaterial(pattern, stitch=StitchParams(), bsdf=None, ply=None,
mode='near_field', capm=True, ply_detail=True, footprint_points=4,
footprint_table=True, table_min_cells=0.25, table_bsdf=True, table_fold=True, self_shadowing=True,
near_field_below_cell=True, uv_scale=40.0, max_steps=32, max_segment=6.2832,
max_bend=0.05, bsdf_model='exact')

bsdf: a YarnBSDF or a dict of its keyword arguments (None: defaults); it
needs a colour for every colour index the pattern uses. ply: a PlyProfile or
a dict of its keyword arguments (None: defaults). mode: 'near_field' (one
CAPM ray) or 'multi_scale' (footprint aggregation, p_delta, LEAN-widened
roughness, mixed colours). footprint_table: multi-scale footprints of a
stitch cell or more are aggregated from a per-class table built here
(docs/multiscale.md) instead of CAPM marches (not for patterns with slip
stitches). table_min_cells, in [0.25, 1]: the smallest footprint, in
stitch cells in both directions, the table serves; below a cell it reads
the table's sub-cell statistics. table_bsdf: the table's footprints are
shaded with a tabulated BSDF built with it (the near field's shading and
self-shadowing averaged per class and pair of directions); False: the yarn
BSDF at the footprint's mean normal with LEAN-widened lobes and no
self-shadowing. table_fold: with table_bsdf, the light that meets other
yarn of the footprint and scatters there is summed into the table as it is
built, per class and colour of the palette when there are at most 16 of
them (a renderer's path then never walks inside the footprint); False:
renderers follow it by a random walk.
self_shadowing: near field, light and bounced rays from a yarn
hit cross the rest of the yarn shell (KnitMaterial.occluded_from,
shade_from) before they leave it. near_field_below_cell: a multi-scale
footprint below a stitch cell in either direction is shaded as the near
field at the hit (C++: KnitMaterial::near_field_at); False: the marched
aggregate of its points. capm=False: no parallax, the
height query at the hit's (u, v). uv_scale: pattern units per UV unit. max_steps, max_segment,
max_bend: CAPM options. bsdf_model: 'exact', or 'cycles' as the OSL shader renders
it in Cycles (docs/cycles.md), which takes footprint_table, table_bsdf,
near_field_below_cell and self_shadowing as False. Invalid values raise
ValueError naming the field.)doc");
  knit_material
      .def(::py::init(&make_material), ::py::arg("pattern"), ::py::arg("stitch") = StitchParams{},
           ::py::kw_only(), ::py::arg("bsdf") = ::py::none(), ::py::arg("ply") = ::py::none(),
           ::py::arg("mode") = "near_field", ::py::arg("capm") = true,
           ::py::arg("ply_detail") = true, ::py::arg("footprint_points") = 4,
           ::py::arg("footprint_table") = true, ::py::arg("table_min_cells") = double(KnitMaterialParams{}.table_min_cells),
           ::py::arg("table_bsdf") = true, ::py::arg("table_fold") = true,
           ::py::arg("self_shadowing") = true,
           ::py::arg("near_field_below_cell") = true, ::py::arg("uv_scale") = 40.0, ::py::arg("max_steps") = 32,
           ::py::arg("max_segment") = 6.2832, ::py::arg("max_bend") = 0.05, ::py::arg("bsdf_model") = "exact")
      .def_property_readonly("pattern",
                             [](const KnitMaterial& km) { return km.surface().pattern(); })
      .def_property_readonly("stitch", [](const KnitMaterial& km) { return km.params().stitch; })
      .def_property_readonly(
          "bsdf", [](const KnitMaterial& km) { return km.bsdf(); },
          "The material's YarnBSDF (a copy).")
      .def_property_readonly(
          "ply", [](const KnitMaterial& km) { return km.ply(); },
          "The material's PlyProfile (a copy).")
      .def_property_readonly("mode",
                             [](const KnitMaterial& km) { return mode_name(km.params().mode); })
      .def_property_readonly("capm", [](const KnitMaterial& km) { return km.params().capm; })
      .def_property_readonly("ply_detail",
                             [](const KnitMaterial& km) { return km.params().ply_detail; })
      .def_property_readonly("footprint_points",
                             [](const KnitMaterial& km) { return km.params().footprint_points; })
      .def_property_readonly("footprint_table",
                             [](const KnitMaterial& km) { return km.params().footprint_table; })
      .def_property_readonly("table_min_cells",
                             [](const KnitMaterial& km) { return km.params().table_min_cells; })
      .def_property_readonly("table_bsdf", [](const KnitMaterial& km) { return km.params().table_bsdf; })
      .def_property_readonly("table_fold", [](const KnitMaterial& km) { return km.params().table_fold; })
      .def_property_readonly("self_shadowing",
                             [](const KnitMaterial& km) { return km.params().self_shadowing; })
      .def_property_readonly("near_field_below_cell",
                             [](const KnitMaterial& km) { return km.params().near_field_below_cell; })
      .def_property_readonly("uv_scale",
                             [](const KnitMaterial& km) { return km.params().uv_scale; })
      .def_property_readonly(
          "bsdf_model",
          [](const KnitMaterial& km) {
            return std::string(km.params().bsdf_model == KnitBsdfModel::Cycles ? "cycles" : "exact");
          },
          "'exact', or 'cycles': as the OSL shader renders it in Cycles (docs/cycles.md).")
      .def_property_readonly(
          "shell_top", [](const KnitMaterial& km) { return km.surface().shell_top(); },
          "Height of the shell top (the base mesh) above the yarn centre plane, pattern "
          "units.")
      .def_property_readonly(
          "table_seconds", &KnitMaterial::table_seconds,
          "Seconds the constructor spent on the multi-scale class table (building it, or "
          "reading it from the class-table cache); 0 without one.")
      .def_property_readonly(
          "table_from_cache", &KnitMaterial::table_from_cache,
          "Whether the class table came from the class-table cache (knitshade.set_table_cache).")
      .def_property_readonly(
          "table_marches_from_cache", &KnitMaterial::table_marches_from_cache,
          "Whether the class table was finished from marches found in the class-table cache: "
          "the cache held this material with other colours (or table_fold), and only the "
          "colours were applied, not the marches run again.")
      .def_property_readonly(
          "table_shadows_from_cache", &KnitMaterial::table_shadows_from_cache,
          "Whether the class table was marched from shadows found in the class-table cache: "
          "the cache held this geometry with other yarn BSDF or ply parameters, and the "
          "self-shadowing marches (most of a build) were not run again.")
      .def_property_readonly(
          "table_cache_note", &KnitMaterial::table_cache_note,
          "What went wrong with the class-table cache, if anything (a damaged entry, a "
          "folder that cannot be written); the table was then built as without it.")
      .def_property_readonly(
          "state_bytes", &KnitMaterial::state_bytes,
          "Memory the model keeps: pattern arrays, ply table, parameters (bytes).")
      .def("__repr__", [](const KnitMaterial& km) {
        const Pattern& p = km.surface().pattern();
        return "<knitshade.KnitMaterial " + std::to_string(p.rows()) + "x" +
               std::to_string(p.cols()) + " " + mode_name(km.params().mode) +
               (km.params().capm ? "" : " no-capm") + " uv_scale=" + num(km.params().uv_scale) +
               ">";
      });
  def_hit_method(knit_material, "shade", material_shade, R"doc(
The shading point of the knit model at N base hits. Returns a dict of arrays:
pass_through (bool: no yarn on this ray, continue straight on), from_back
(bool: the ray reached the fabric from behind the mesh), st, sb, sn ((N, 3)
world shading frame: yarn tangent, bitangent, surface normal; express wo, wi
in it for YarnBSDF), offset ((N, 3) world offset from the base hit to the
yarn hit), color (palette index; multi-scale: the most frequent one), layers
(tubes under the hit, for the double-layer attenuation; 1 in the near field
with self_shadowing, where the renderer traces those tubes), shadow (G_{p,f}), p_delta (multi-scale: fraction of the footprint passing
through; near field 0), kd_r, kd_t ((N, 3) body colours; multi-scale: mixed
over the footprint), alpha ((N, 4): specular reflection alpha_x, alpha_y,
specular transmission alpha_x, alpha_y; multi-scale: LEAN-widened), steps
(CAPM segments marched, summed over footprint points). A footprint read
from the class table with table_bsdf (the default) is shaded by its
tabulated BSDF in the base's frame: st, sb, sn are the base frame, offset
is 0 (shaded at the base hit), layers 1 and alpha the yarn's own
roughness (the renderer does not use them there). Rows with
pass_through have no shading point: st, sb, sn, offset, shadow, kd_r, kd_t,
alpha are nan, color -1, layers 0, and p_delta 1 (so p_delta equals
transmittance() in every row). In multi-scale mode, a footprint below a
stitch cell in either direction is shaded as the near field
(near_field_below_cell).)doc");
  def_hit_method(knit_material, "transmittance", material_transmittance, R"doc(
Fraction of light a shadow ray along ray_dir passes through the fabric at N
base hits, (N,) array: near field 0 or 1 (a yarn or a gap), multi-scale
p_delta (0 or 1 too for footprints below a stitch cell, with near_field_below_cell).)doc");
}

}  // namespace knit::py
