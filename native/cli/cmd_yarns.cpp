// `knitshade yarns PATTERN -o FILE`: the explicit yarn centre curves of a
// pattern (the ground truth geometry), as OBJ polylines or plain text.
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "cli.h"
#include "knit/yarns.h"

namespace knit::cli {
namespace {

const char* kHelp = R"(usage: knitshade yarns PATTERN -o FILE [options]

Writes the exact yarn centre curves of PATTERN (a .knit file) tiled
tiles_u x tiles_v times, in pattern space (docs/geometry.md): one dense
polyline per knitted row, row 0 at the bottom, with the tube radius.

options:
  -o, --output FILE       output file (.obj or .txt; required)
  --format obj|txt        default: from the extension (.txt -> txt, else obj)
  --tiles U V             pattern repeats across and up (default 1 1)
  --samples N             curve points per stitch (default 64)
  --a A --h H --d D --r R stitch parameters (default 1.5 4 1 0.65)
  --scale S               multiply coordinates by S (default 1)

OBJ: `v x y z` vertices and one `l` polyline per row; a header comment gives
the radius. TXT: a header `# knitshade yarns v1`, then `radius R`, `curves N`,
and per curve `curve ROW COUNT` followed by COUNT lines `x y z color`.
)";

double parse_number(const std::string& opt, const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end == nullptr || *end != '\0' || !std::isfinite(v))
    throw UsageError{opt + " needs a finite number, got '" + text + "'"};
  return v;
}

int parse_int(const std::string& opt, const std::string& text, int lo, int hi) {
  const double v = parse_number(opt, text);
  if (v != std::floor(v) || v < lo || v > hi)
    throw UsageError{opt + " needs an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                     "], got '" + text + "'"};
  return int(v);
}

int run(const std::vector<std::string>& argv) {
  std::string out, format;
  int tu = 1, tv = 1, samples = 64;
  double scale = 1;
  StitchParams sp;
  std::vector<std::string> pos;
  for (size_t i = 0; i < argv.size(); ++i) {
    const std::string& a = argv[i];
    auto next = [&]() -> const std::string& {
      if (i + 1 >= argv.size()) throw UsageError{"option " + a + " needs a value"};
      return argv[++i];
    };
    if (a == "-h" || a == "--help") {
      std::fputs(kHelp, stdout);
      return 0;
    } else if (a == "-o" || a == "--output") {
      out = next();
    } else if (a == "--format") {
      format = next();
    } else if (a == "--tiles") {
      tu = parse_int(a, next(), 1, 4096);
      tv = parse_int(a, next(), 1, 4096);
    } else if (a == "--samples") {
      samples = parse_int(a, next(), 4, 4096);
    } else if (a == "--a") {
      sp.a = float(parse_number(a, next()));
    } else if (a == "--h") {
      sp.h = float(parse_number(a, next()));
    } else if (a == "--d") {
      sp.d = float(parse_number(a, next()));
    } else if (a == "--r") {
      sp.r = float(parse_number(a, next()));
    } else if (a == "--scale") {
      scale = parse_number(a, next());
    } else if (!a.empty() && a[0] == '-') {
      throw UsageError{"unknown option " + a};
    } else {
      pos.push_back(a);
    }
  }
  if (pos.size() != 1) throw UsageError{"expected one PATTERN file, got " + std::to_string(pos.size())};
  if (out.empty()) throw UsageError{"missing -o FILE"};
  if (!(scale > 0)) throw UsageError{"--scale must be > 0"};
  if (format.empty()) format = out.size() >= 4 && out.substr(out.size() - 4) == ".txt" ? "txt" : "obj";
  if (format != "obj" && format != "txt") throw UsageError{"--format must be obj or txt, got " + format};
  try {
    sp.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError{e.what()};
  }

  const Pattern pattern = Pattern::from_file(pos[0]);
  const ExplicitYarns y = explicit_yarns(pattern, sp, tu, tv, samples);

  std::ofstream f(out);
  if (!f) throw std::runtime_error("cannot write " + out);
  char buf[128];
  size_t total = 0;
  if (format == "obj") {
    f << "# knitshade yarns: " << pos[0] << ", " << tu << "x" << tv << " tiles, " << sp.to_string()
      << "\n# radius " << y.radius * scale << "\n";
    for (const YarnCurve& c : y.curves)
      for (const auto& p : c.points) {
        std::snprintf(buf, sizeof buf, "v %.7g %.7g %.7g\n", p[0] * scale, p[1] * scale, p[2] * scale);
        f << buf;
      }
    size_t base = 1;
    for (const YarnCurve& c : y.curves) {
      f << "l";
      for (size_t i = 0; i < c.points.size(); ++i) f << ' ' << base + i;
      f << "\n";
      base += c.points.size();
      total += c.points.size();
    }
  } else {
    f << "# knitshade yarns v1\nradius " << y.radius * scale << "\ncurves " << y.curves.size() << "\n";
    for (const YarnCurve& c : y.curves) {
      f << "curve " << c.row << " " << c.points.size() << "\n";
      for (size_t i = 0; i < c.points.size(); ++i) {
        const auto& p = c.points[i];
        std::snprintf(buf, sizeof buf, "%.7g %.7g %.7g %d\n", p[0] * scale, p[1] * scale, p[2] * scale,
                      c.color[i]);
        f << buf;
      }
      total += c.points.size();
    }
  }
  f.close();
  if (!f) throw std::runtime_error("error writing " + out);
  std::printf("wrote %s: %zu curves, %zu points, radius %g\n", out.c_str(), y.curves.size(), total,
              y.radius * scale);
  return 0;
}

const bool registered = register_command({"yarns", "write explicit yarn centre curves (OBJ or text)", run});

}  // namespace
}  // namespace knit::cli
