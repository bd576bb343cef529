// query_replay: a fixed, seeded stream of line queries for instruction
// counts and result comparisons between versions of the kernel. Timings on
// a shared machine move by 10-40%; instruction counts do not:
//
//   valgrind --tool=callgrind build/bench/query_replay vertical seed 5000
//   callgrind_annotate --inclusive=yes callgrind.out.* | grep -m1 knit_line_query
//
// (instructions per query = that count / N), and
//
//   build/bench/query_replay capm rib 20000 --dump a.txt   (then diff or cmp)
//
// writes every query's result in hexadecimal floats. Kinds:
//   vertical  knit_vertical_query at random points (ENTRY: entry and layers)
//   capm      FIRST queries along segments from the shell top, as a CAPM
//             march's first step (directions up to 0.95 of grazing)
//   shadow    FIRST queries along segments from inside the shell towards
//             the upper hemisphere
//   blocked   the same segments as ANY queries, as self-shadowing marches
//             make them (hit or miss only)
// Patterns: stockinette, seed (2 x 2 knit/purl: every boundary blended),
// rib (1 x 1). Crane's default stitch parameters.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>

#include "knit/surface.h"

namespace {

knit::Pattern pattern_named(const std::string& name) {
  if (name == "stockinette") return knit::Pattern::from_rows({{0}});
  if (name == "seed") return knit::Pattern::from_rows({{0, 1}, {1, 0}});
  if (name == "rib") return knit::Pattern::from_rows({{0, 1}});
  throw std::invalid_argument("query_replay: unknown pattern '" + name + "' (stockinette, seed, rib)");
}

int usage() {
  std::fprintf(stderr, "usage: query_replay vertical|capm|shadow|blocked stockinette|seed|rib N [--dump FILE]\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  namespace k = knit::k;
  if (argc != 4 && argc != 6) return usage();
  const std::string kind = argv[1];
  const bool inside = kind == "shadow" || kind == "blocked";
  if (kind != "vertical" && kind != "capm" && !inside) return usage();
  const long n = std::strtol(argv[3], nullptr, 10);
  if (n <= 0 || n > 100000000) return usage();
  FILE* dump = nullptr;
  if (argc == 6) {
    if (std::string(argv[4]) != "--dump") return usage();
    dump = std::fopen(argv[5], "w");
    if (!dump) {
      std::fprintf(stderr, "query_replay: cannot write %s\n", argv[5]);
      return 1;
    }
  }
  try {
    const knit::KnitSurface s(pattern_named(argv[2]), knit::StitchParams{});
    const k::KnitGeom& g = s.geom();
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    double checksum = 0;
    for (long i = 0; i < n; ++i) {
      const float x = 20 + 60 * U(rng), y = 20 + 60 * U(rng);
      const float th = std::acos(U(rng)) * (inside ? 1.0f : 0.95f), ph = 6.2831853f * U(rng);
      k::KnitLineHit h;
      if (kind == "vertical") {
        h = k::knit_vertical_query(g, s.codes(), s.colors(), x, y);
      } else {
        const float dz = inside ? std::cos(th) : -std::cos(th);
        const k::kvec3 D = k::kv3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), dz);
        const float z0 = inside ? (2 * U(rng) - 1) * g.shell_top : g.shell_top;
        const float hs = std::sqrt(D.x * D.x + D.y * D.y);
        float len = D.z < 0 ? (z0 + g.shell_top) / -D.z : (g.shell_top - z0) / D.z;
        if (hs > 0) len = std::fmin(len, 6.2831853f / hs);  // CAPM's segment: a stitch across
        h = k::knit_line_query(g, s.codes(), s.colors(), k::kv3(x, y, z0), D, 0.0f, len,
                               kind == "blocked" ? KNIT_QUERY_ANY : KNIT_QUERY_FIRST);
      }
      checksum += h.hit ? h.s_in : 0;
      if (dump)
        std::fprintf(dump, "%d %d %a %a %a %a %d %d\n", h.hit, h.crossings, h.s_in, h.n.x, h.n.y, h.t, h.row,
                     h.col);
    }
    if (dump) std::fclose(dump);
    std::printf("%ld %s queries on %s: checksum %.9g\n", n, kind.c_str(), argv[2], checksum);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  return 0;
}
