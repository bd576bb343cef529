// Python bindings of the stitch geometry: StitchParams, KnitSurface (query,
// crossings, capm), frames and explicit_yarns. Inputs are validated here, at
// the boundary; errors are ValueError naming the argument, index and value.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "bindings.h"
#include "knit/surface.h"
#include "knit/yarns.h"

namespace py = pybind11;

namespace knit::py {
namespace {

using Arr = ::py::array_t<double, ::py::array::c_style | ::py::array::forcecast>;

void check_finite(const char* what, const double* p, ssize_t n) {
  for (ssize_t i = 0; i < n; ++i)
    if (!std::isfinite(p[i]))
      throw ::py::value_error(std::string(what) + "[" + std::to_string(i) + "] must be finite, got " +
                              num(p[i]));
}

// Rows of 3 (shape (3,) or (N, 3)), named as the appearance functions name
// them: "wi_local[4] must be finite, got nan in component 2".
void check_finite_rows(const char* what, const Arr& a) {
  for (ssize_t i = 0; i < a.size(); ++i)
    if (!std::isfinite(a.data()[i]))
      throw ::py::value_error(std::string(what) + (a.ndim() == 2 ? "[" + std::to_string(i / 3) + "]" : "") +
                              " must be finite, got " + num(a.data()[i]) + " in component " +
                              std::to_string(i % 3));
}

// CAPM's segment length, as KnitSurface::march bounds it (kMaxCapmSegment).
void check_max_segment(double max_segment) {
  if (!capm_segment_in_range(max_segment))
    throw ::py::value_error("max_segment must be > 0 and at most " + num(kMaxCapmSegment) + ", got " +
                            num(max_segment));
}

// Broadcast u and v (scalars or 1-D arrays of one length) to N points.
struct Points {
  Arr u, v;
  ssize_t n;
  const double* pu;
  const double* pv;
  bool su, sv;
};

// |uv_scale * u| and |uv_scale * v| must stay within kMaxPatternCoord.
void check_pattern_range(const char* what, const double* p, ssize_t n, double uv_scale) {
  for (ssize_t i = 0; i < n; ++i)
    if (!(std::abs(uv_scale * p[i]) <= double(kMaxPatternCoord)))
      throw ::py::value_error(std::string(what) + "[" + std::to_string(i) + "] = " + num(p[i]) +
                              " maps to pattern coordinate " + num(uv_scale * p[i]) + " (uv_scale " +
                              num(uv_scale) + "), beyond the +-" + num(kMaxPatternCoord) +
                              " that single-precision pattern space resolves; wrap it by the pattern "
                              "period first");
}

Points points(const Arr& u, const Arr& v, double uv_scale) {
  if (u.ndim() > 1 || v.ndim() > 1) throw ::py::value_error("u and v must be scalars or 1-D arrays");
  const ssize_t nu = u.size(), nv = v.size();
  if (nu != nv && nu != 1 && nv != 1)
    throw ::py::value_error("u and v must have the same length, got " + std::to_string(nu) + " and " +
                            std::to_string(nv));
  check_finite("u", u.data(), nu);
  check_finite("v", v.data(), nv);
  check_pattern_range("u", u.data(), nu, uv_scale);
  check_pattern_range("v", v.data(), nv, uv_scale);
  return {u, v, std::max(nu, nv), u.data(), v.data(), nu == 1, nv == 1};
}

::py::array_t<double> vec_array(ssize_t n) { return ::py::array_t<double>({n, ssize_t(3)}); }

void put(double* row, const Vec3& a) {
  row[0] = a.x;
  row[1] = a.y;
  row[2] = a.z;
}

// Per-point results of query() and capm() as numpy arrays. A miss has
// position (x, y, nan), stitch and color -1. set() writes through pointers
// taken at construction (with the GIL), so rows can be set from any thread.
struct HitArrays {
  explicit HitArrays(ssize_t n)
      : hit(n), pos(vec_array(n)), nor(vec_array(n)), tan(vec_array(n)), layers(n), stitch(n), color(n),
        row(n), col(n), p_hit(hit.mutable_data()), p_pos(pos.mutable_data()), p_nor(nor.mutable_data()),
        p_tan(tan.mutable_data()), p_layers(layers.mutable_data()), p_stitch(stitch.mutable_data()),
        p_color(color.mutable_data()), p_row(row.mutable_data()), p_col(col.mutable_data()) {}
  void set(ssize_t i, const SurfaceHit& h, float x, float y) const {
    p_hit[i] = h.hit;
    put(p_pos + 3 * i, h.hit ? h.position : Vec3{x, y, std::nanf("")});
    put(p_nor + 3 * i, h.normal);
    put(p_tan + 3 * i, h.tangent);
    p_layers[i] = h.layers;
    p_stitch[i] = h.hit ? h.stitch : -1;
    p_color[i] = h.hit ? h.color : -1;
    p_row[i] = h.row;
    p_col[i] = h.col;
  }
  ::py::dict dict() const {
    ::py::dict d;
    d["hit"] = hit;
    d["position"] = pos;
    d["normal"] = nor;
    d["tangent"] = tan;
    d["layers"] = layers;
    d["stitch"] = stitch;
    d["color"] = color;
    d["row"] = row;
    d["col"] = col;
    return d;
  }
  ::py::array_t<bool> hit;
  ::py::array_t<double> pos, nor, tan;
  ::py::array_t<int> layers, stitch, color, row, col;
  bool* p_hit;
  double *p_pos, *p_nor, *p_tan;
  int *p_layers, *p_stitch, *p_color, *p_row, *p_col;
};

class PyKnitSurface {
 public:
  PyKnitSurface(const Pattern& p, const StitchParams& sp, double uv_scale)
      : surf_(p, sp), uv_scale_(uv_scale) {
    if (!std::isfinite(uv_scale) || uv_scale <= 0)
      throw ::py::value_error("uv_scale must be finite and > 0, got " + num(uv_scale));
  }

  ::py::dict query(const Arr& u, const Arr& v) const {
    Points P = points(u, v, uv_scale_);
    HitArrays out(P.n);
    ::py::array_t<double> z(P.n);
    double* pz = z.mutable_data();
    // Ranges of points through KnitSurface::query_batch (32 or 16 at a time
    // with AVX-512, 16 or 8 with AVX2, where the CPU has it), in pieces of at most kQueryBlock; the
    // ranges on every core from kParallelRows points up.
    constexpr ssize_t kQueryBlock = 1024;
    for_each_range(P.n, kQueryBlock, [&](ssize_t begin, ssize_t end) {
      std::vector<float> xs(static_cast<size_t>(kQueryBlock)), ys(static_cast<size_t>(kQueryBlock));
      std::vector<SurfaceHit> hs(static_cast<size_t>(kQueryBlock));
      for (ssize_t i0 = begin; i0 < end; i0 += kQueryBlock) {
        const ssize_t m = std::min(kQueryBlock, end - i0);
        for (ssize_t j = 0; j < m; ++j) {
          const ssize_t i = i0 + j;
          xs[size_t(j)] = float(uv_scale_ * P.pu[P.su ? 0 : i]);
          ys[size_t(j)] = float(uv_scale_ * P.pv[P.sv ? 0 : i]);
        }
        surf_.query_batch(xs.data(), ys.data(), size_t(m), hs.data());
        for (ssize_t j = 0; j < m; ++j) {
          out.set(i0 + j, hs[size_t(j)], xs[size_t(j)], ys[size_t(j)]);
          pz[i0 + j] = hs[size_t(j)].hit ? hs[size_t(j)].position.z : std::nan("");
        }
      }
    });
    ::py::dict d = out.dict();
    d["z"] = z;
    return d;
  }

  ::py::list crossings(double u, double v) const {
    if (!std::isfinite(u) || !std::isfinite(v))
      throw ::py::value_error("u and v must be finite, got " + num(u) + ", " + num(v));
    check_pattern_range("u", &u, 1, uv_scale_);
    check_pattern_range("v", &v, 1, uv_scale_);
    const float x = float(uv_scale_ * u), y = float(uv_scale_ * v);
    const float top = surf_.shell_top() + 0.01f;
    ::py::list out;
    for (const TubeCrossing& c : surf_.crossings(x, y)) {
      ::py::dict d;
      d["z_top"] = top - c.s_in;
      d["z_bottom"] = top - c.s_out;
      d["normal"] = ::py::make_tuple(c.normal.x, c.normal.y, c.normal.z);
      d["tangent"] = ::py::make_tuple(c.tangent.x, c.tangent.y, c.tangent.z);
      d["row"] = c.row;
      d["col"] = c.col;
      d["layer"] = c.layer;
      d["stitch"] = c.stitch;
      d["color"] = c.color;
      d["t"] = c.t;
      out.append(d);
    }
    return out;
  }

  ::py::dict capm(const Arr& u, const Arr& v, const Arr& wi, const FrameProvider* frame, int max_steps,
                  double max_segment, double max_bend) const {
    Points P = points(u, v, uv_scale_);
    if (!(wi.ndim() == 1 && wi.shape(0) == 3) && !(wi.ndim() == 2 && wi.shape(1) == 3))
      throw ::py::value_error("wi_local must have shape (3,) or (N, 3)");
    const ssize_t nw = wi.ndim() == 1 ? 1 : wi.shape(0);
    if (nw != 1 && P.n != 1 && nw != P.n)
      throw ::py::value_error("wi_local has " + std::to_string(nw) + " rows but u, v have " +
                              std::to_string(P.n) + " points");
    check_finite_rows("wi_local", wi);
    for (ssize_t i = 0; i < nw; ++i) {
      const double* w = wi.data() + 3 * i;
      if (!(w[2] > 0))
        throw ::py::value_error("wi_local[" + std::to_string(i) +
                                "] must point away from the surface (z > 0), got z = " + num(w[2]));
    }
    if (max_steps < 1 || max_steps > 4096)
      throw ::py::value_error("max_steps must be in [1, 4096], got " + std::to_string(max_steps));
    check_max_segment(max_segment);
    if (!(max_bend > 0) || !std::isfinite(max_bend))
      throw ::py::value_error("max_bend must be finite and > 0, got " + num(max_bend));
    CapmOptions opt;
    opt.max_steps = max_steps;
    opt.max_segment = float(max_segment);
    opt.max_bend = float(max_bend);
    const ssize_t n = std::max(P.n, nw);
    HitArrays out(n);
    ::py::array_t<int> steps(n);
    int* ps = steps.mutable_data();
    const double* pw = wi.data();
    for_each_row(n, [&](ssize_t i) {
      const float x = float(uv_scale_ * P.pu[P.su ? 0 : i]), y = float(uv_scale_ * P.pv[P.sv ? 0 : i]);
      const double* w = pw + 3 * (nw == 1 ? 0 : i);
      const SurfaceHit h = surf_.capm(x, y, k::kv3(float(w[0]), float(w[1]), float(w[2])), frame, opt);
      out.set(i, h, std::nanf(""), std::nanf(""));
      ps[i] = h.steps;
    });
    ::py::dict d = out.dict();
    d["steps"] = steps;
    return d;
  }

  ::py::dict aggregate(const Arr& u, const Arr& v, const Arr& fx, const Arr& fy, const Arr& wi, int n_points,
                       double shift_x, double shift_y, double kx, double ky, double max_segment,
                       int max_steps) const {
    Points P = points(u, v, uv_scale_);
    auto vec2 = [](const Arr& a, const char* name) {
      if (a.ndim() != 1 || a.shape(0) != 2) throw ::py::value_error(std::string(name) + " must have shape (2,)");
      check_finite(name, a.data(), 2);
      return k::kv3(float(a.data()[0]), float(a.data()[1]), 0.f);
    };
    const Vec3 ex = vec2(fx, "footprint_x"), ey = vec2(fy, "footprint_y");
    if (wi.ndim() != 1 || wi.shape(0) != 3) throw ::py::value_error("wi_local must have shape (3,)");
    check_finite_rows("wi_local", wi);
    if (wi.data()[2] == 0) throw ::py::value_error("wi_local must not be tangent to the surface (z != 0)");
    if (n_points < 1 || n_points > KNIT_MS_MAX_POINTS)
      throw ::py::value_error("n_points must be in [1, " + std::to_string(KNIT_MS_MAX_POINTS) + "], got " +
                              std::to_string(n_points));
    for (double sh : {shift_x, shift_y})
      if (!(sh >= 0 && sh < 1)) throw ::py::value_error("shift components must be in [0, 1), got " + num(sh));
    for (double kk : {kx, ky})
      if (!std::isfinite(kk)) throw ::py::value_error("curvature must be finite, got " + num(kk));
    check_max_segment(max_segment);
    if (max_steps < 1 || max_steps > 4096)
      throw ::py::value_error("max_steps must be in [1, 4096], got " + std::to_string(max_steps));
    const float sc = float(uv_scale_);
    const Vec3 wl = k::kv3_normalize(k::kv3(float(wi.data()[0]), float(wi.data()[1]), float(wi.data()[2])));
    const ssize_t n = P.n;
    ::py::array_t<double> pd(n), layers(n), steps(n), nor = vec_array(n), tan = vec_array(n), sig = vec_array(n);
    ::py::array_t<int> pts(n), hits(n), pick(n);
    ::py::array_t<double> cw({n, ssize_t(KNIT_MS_COLORS)});
    {
      const KnitSurface& S = surf_;
      double *o_pd = pd.mutable_data(), *o_layers = layers.mutable_data(), *o_steps = steps.mutable_data();
      double *o_nor = nor.mutable_data(), *o_tan = tan.mutable_data(), *o_sig = sig.mutable_data();
      double* o_cw = cw.mutable_data();
      int *o_pts = pts.mutable_data(), *o_hits = hits.mutable_data(), *o_pick = pick.mutable_data();
      for_each_row(n, [&](ssize_t i) {
        const float x = sc * float(P.pu[P.su ? 0 : i]), y = sc * float(P.pv[P.sv ? 0 : i]);
        const k::KnitAggregate a = k::knit_aggregate(
            S.geom(), S.codes(), S.colors(), x, y, k::kv3_scale(ex, sc), k::kv3_scale(ey, sc), wl, n_points,
            float(shift_x), float(shift_y), float(kx), float(ky), float(max_segment), max_steps);
        o_pd[i] = a.p_delta;
        o_layers[i] = a.layers;
        o_steps[i] = a.steps;
        o_pts[i] = a.points;
        o_hits[i] = a.hits;
        o_pick[i] = a.color_pick;
        put(o_nor + 3 * i, a.n);
        put(o_tan + 3 * i, a.tangent);
        put(o_sig + 3 * i, k::kv3(a.sxx, a.sxy, a.syy));
        for (int c = 0; c < KNIT_MS_COLORS; ++c) o_cw[KNIT_MS_COLORS * i + c] = a.color_w[c];
      });
    }
    ::py::dict d;
    d["p_delta"] = pd;
    d["normal"] = nor;
    d["tangent"] = tan;
    d["sigma"] = sig;
    d["layers"] = layers;
    d["steps"] = steps;
    d["points"] = pts;
    d["hits"] = hits;
    d["color_weights"] = cw;
    d["color_pick"] = pick;
    return d;
  }

  const KnitSurface& surface() const { return surf_; }
  double uv_scale() const { return uv_scale_; }

 private:
  KnitSurface surf_;
  double uv_scale_;
};

StitchParams make_params(float a, float h, float d, float r) {
  StitchParams p;
  p.a = a;
  p.h = h;
  p.d = d;
  p.r = r;
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    throw ::py::value_error(e.what());
  }
  return p;
}

}  // namespace

void bind_geometry(::py::module_& m) {
  ::py::class_<StitchParams>(m, "StitchParams", R"doc(
Parameters of Crane's plain-knit stitch curve (paper Eq. 2),
Y(t) = (t + a sin 2t, h cos t, d cos 2t), swept by a tube of radius r.
Validated on construction: finite, a > 0, h > 0, d != 0, r > 0 and r at most
half the yarn clearance (tubes must not pass through each other); a
ValueError names the parameter and value at fault.)doc")
      .def(::py::init(&make_params), ::py::arg("a") = 1.5f, ::py::arg("h") = 4.0f, ::py::arg("d") = 1.0f,
           ::py::arg("r") = 0.65f)
      .def_readonly("a", &StitchParams::a)
      .def_readonly("h", &StitchParams::h)
      .def_readonly("d", &StitchParams::d)
      .def_readonly("r", &StitchParams::r)
      .def_property_readonly("row_spacing", &StitchParams::row_spacing)
      .def("clearance", &StitchParams::clearance,
           "Smallest distance between the centre lines of two different yarn pieces.")
      .def("__repr__", &StitchParams::to_string);

  ::py::class_<FrameProvider>(m, "FrameProvider",
                              "Base-mesh frame field used by CAPM to bend rays (abstract).");
  ::py::class_<FlatFrame, FrameProvider>(m, "FlatFrame", "A flat base: the frame is the same everywhere.")
      .def(::py::init<>());
  ::py::class_<CylinderFrame, FrameProvider>(m, "CylinderFrame", R"doc(
A cylinder of the given radius (pattern units) around the y axis: x is arc
length around it at the yarn centre surface (z = 0), y runs along the axis.)doc")
      .def(::py::init([](float radius) {
             if (!std::isfinite(radius) || radius <= 0)
               throw ::py::value_error("radius must be finite and > 0, got " + num(radius));
             return CylinderFrame(radius);
           }),
           ::py::arg("radius"))
      .def_property_readonly("radius", &CylinderFrame::radius);
  ::py::class_<SphereFrame, FrameProvider>(m, "SphereFrame",
                                           "A sphere: x = R * longitude, y = R * latitude.")
      .def(::py::init([](float radius) {
             if (!std::isfinite(radius) || radius <= 0)
               throw ::py::value_error("radius must be finite and > 0, got " + num(radius));
             return SphereFrame(radius);
           }),
           ::py::arg("radius"))
      .def_property_readonly("radius", &SphereFrame::radius);

  ::py::class_<PyKnitSurface>(m, "KnitSurface", R"doc(
A knit pattern with stitch parameters, queried analytically.

Pattern space: x along the course, y along the wale, z out of the fabric, in
stitch-curve units. A stitch cell is 2*pi wide and `row_spacing` (h + 1/2)
tall; cell (k, c) - row k counted from the BOTTOM of the pattern (pattern
rows are written top first), column c - spans x in [2 pi c, 2 pi (c+1)),
y in [k s, (k+1) s); the pattern repeats in both directions. UV coordinates
map to pattern space by x = uv_scale * u, y = uv_scale * v (default 1: u, v
are pattern-space coordinates). All results are in pattern space, the same
coordinates explicit_yarns() returns.)doc")
      .def(::py::init<const Pattern&, const StitchParams&, double>(), ::py::arg("pattern"),
           ::py::arg("params") = StitchParams{}, ::py::arg("uv_scale") = 1.0)
      .def_property_readonly("shell_top", [](const PyKnitSurface& s) { return s.surface().shell_top(); },
                             "Highest z any yarn tube reaches (|d| + r; more with slip-stitch floats). "
                             "CAPM rays enter at this height.")
      .def_property_readonly("uv_scale", &PyKnitSurface::uv_scale)
      .def_property_readonly("cell_width", [](const PyKnitSurface& s) { return s.surface().cell_width(); })
      .def_property_readonly("cell_height", [](const PyKnitSurface& s) { return s.surface().cell_height(); })
      .def_property_readonly("period", [](const PyKnitSurface& s) {
        return ::py::make_tuple(s.surface().period_x(), s.surface().period_y());
      })
      .def_property_readonly("params", [](const PyKnitSurface& s) { return s.surface().params(); })
      .def("query", &PyKnitSurface::query, ::py::arg("u"), ::py::arg("v"), R"doc(
Vertical (height) query at UV points, vectorised: the first yarn surface seen
from above along the line through (uv_scale*u, uv_scale*v). Returns a dict of
arrays: hit (bool), z (height of that surface, nan on a miss), position (N,3),
normal (N,3, outward tube normal), tangent (N,3, unit yarn direction), layers
(number of tubes the vertical line crosses), stitch (code, -1 on a miss),
color (colour index, -1 on a miss), row, col (cell of the yarn hit).
Runs 32 points at a time with AVX-512, or 16 with AVX2, where the CPU has them
and the pattern has knit and purl stitches only (the same results up to float
rounding; query_path says which), on every core for large arrays.)doc")
      .def_property_readonly(
          "query_path",
          [](const PyKnitSurface& s) {
            return KnitSurface::batch_isa_name(s.surface().batch_isa(KnitSurface::BatchPath::Auto));
          },
          "How query() runs here: 'avx512', 'avx2' or 'scalar' (slip stitches, or a CPU without either).")
      .def("crossings", &PyKnitSurface::crossings, ::py::arg("u"), ::py::arg("v"), R"doc(
Every yarn tube crossed by the vertical line at one UV point, top first: a
list of dicts with z_top and z_bottom (entry and exit heights), normal and
tangent at the top, row, col, layer (row parity), stitch, color and t.)doc")
      .def("capm", &PyKnitSurface::capm, ::py::arg("u"), ::py::arg("v"), ::py::arg("wi_local"),
           ::py::arg("frame") = nullptr, ::py::arg("max_steps") = 32, ::py::arg("max_segment") = 6.2832,
           ::py::arg("max_bend") = 0.05, R"doc(
Curvature-aware parallax march (paper Alg. 1, done with exact segment
queries): the view ray enters the yarn shell at (uv_scale*u, uv_scale*v,
shell_top) travelling along -wi_local; wi_local (shape (3,) or (N,3), z > 0)
points from the surface towards the viewer in the local frame at (u, v).
`frame` (FlatFrame by default, CylinderFrame, SphereFrame) bends the ray with
the base surface. Returns a dict of arrays: hit, position (N,3, pattern
space), normal, tangent, layers (tubes crossed by the vertical line through
the hit), steps (segments marched), stitch, color, row, col.)doc")
      .def("aggregate", &PyKnitSurface::aggregate, ::py::arg("u"), ::py::arg("v"), ::py::arg("footprint_x"),
           ::py::arg("footprint_y"), ::py::arg("wi_local"), ::py::arg("n_points") = 16,
           ::py::arg("shift_x") = 0.5, ::py::arg("shift_y") = 0.5, ::py::arg("kx") = 0.0, ::py::arg("ky") = 0.0,
           ::py::arg("max_segment") = 6.2832, ::py::arg("max_steps") = 32, R"doc(
Multi-scale aggregation over a pixel footprint (paper Sec. 5.1, 6.2) at UV
points: footprint_x = (du/dx, dv/dx) and footprint_y = (du/dy, dv/dy) span the
footprint in UV (scaled by uv_scale to pattern space); n_points Sobol' points
(more for footprints over 16 cells, up to 64), shifted by (shift_x, shift_y),
are marched with CAPM along -wi_local (normalised; z < 0 views the fabric
from behind) on a base of curvature (kx, ky).
Returns a dict of arrays: p_delta (pass-through probability), normal and
tangent (N,3, means), sigma (N,3: LEAN slope covariance xx, xy, yy), layers,
steps (mean CAPM segments), points, hits, color_weights (N,8), color_pick
(the colour index of one hit, picked by the shift as the OSL shader's
ColourIndex output is; -1 when no point hits).)doc");

  m.def(
      "footprint_isotropic",
      [](double len_x, double len_y, const Arr& view, double uv_scale) {
        check_finite("len_x", &len_x, 1);
        check_finite("len_y", &len_y, 1);
        if (view.ndim() != 1 || view.shape(0) != 3) throw ::py::value_error("view_local must have shape (3,)");
        check_finite_rows("view_local", view);
        if (!std::isfinite(uv_scale) || !(uv_scale > 0))
          throw ::py::value_error("uv_scale must be finite and > 0, got " + num(uv_scale));
        const double* w = view.data();
        const k::KFootprintAxes f = k::knit_footprint_isotropic(
            float(len_x), float(len_y), k::kv3(float(w[0]), float(w[1]), float(w[2])), float(uv_scale));
        return ::py::make_tuple(::py::make_tuple(f.fx.x, f.fx.y), ::py::make_tuple(f.fy.x, f.fy.y));
      },
      ::py::arg("len_x"), ::py::arg("len_y"), ::py::arg("view_local"), ::py::arg("uv_scale"), R"doc(
The multi-scale footprint the OSL shader builds from Cycles' UV
differentials (kernel knit_footprint_isotropic, docs/cycles.md): len_x,
len_y the lengths of the two UV differentials, view_local the view
direction in the base frame (x along +u, y along +v, z the normal),
uv_scale pattern units per UV unit. Returns (fx, fy), two (x, y) pairs in
pattern units: a square of side uv_scale (len_x + len_y) / 2 stretched by
1 / max(cos theta, 0.1) along the view's projection. Divided by uv_scale
they are KnitSurface.aggregate's footprint_x, footprint_y.)doc");

  m.def(
      "explicit_yarns",
      [](const Pattern& p, const StitchParams& sp, int tiles_u, int tiles_v, int samples_per_stitch) {
        ExplicitYarns y;
        try {
          y = explicit_yarns(p, sp, tiles_u, tiles_v, samples_per_stitch);
        } catch (const std::invalid_argument& e) {
          throw ::py::value_error(e.what());
        }
        ::py::list curves, colors, rows;
        for (const YarnCurve& c : y.curves) {
          ::py::array_t<double> a({ssize_t(c.points.size()), ssize_t(3)});
          for (size_t i = 0; i < c.points.size(); ++i)
            for (int k = 0; k < 3; ++k) a.mutable_data(ssize_t(i), k)[0] = c.points[i][size_t(k)];
          curves.append(a);
          colors.append(::py::array_t<int>(ssize_t(c.color.size()), c.color.data()));
          rows.append(c.row);
        }
        ::py::dict d;
        d["curves"] = curves;
        d["colors"] = colors;
        d["rows"] = rows;
        d["radius"] = y.radius;
        d["width"] = y.width;
        d["height"] = y.height;
        d["t_step"] = y.t_step;
        return d;
      },
      ::py::arg("pattern"), ::py::arg("params") = StitchParams{}, ::py::arg("tiles_u") = 1,
      ::py::arg("tiles_v") = 1, ::py::arg("samples_per_stitch") = 64, R"doc(
The exact yarn centre curves of tiles_u x tiles_v repeats of the pattern, in
the pattern-space coordinates KnitSurface.query and capm use (one dense
polyline per knitted row, row 0 at the bottom), with the tube radius. Returns
a dict: curves (list of (M,3) arrays), colors (list of per-point colour
index arrays), rows, radius, width, height, t_step (point i of every curve
is at curve parameter i t_step: 2 pi / samples_per_stitch).)doc");
}

}  // namespace knit::py
