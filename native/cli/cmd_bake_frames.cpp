// `knitshade bake-frames MESH -o FILE.exr`: bakes the mesh's normal and
// tangent over its UV space (docs/renderer.md#baked-frames).
#ifdef KNIT_HAVE_RENDER

#include <cstdio>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include "cli.h"
#include "cli_args.h"
#include "render/frame_bake.h"
#include "render/mesh.h"

namespace knit::cli {
namespace {

const char* kUsage =
    "usage: knitshade bake-frames MESH -o FRAMES.exr [options]\n"
    "\n"
    "Bakes the base mesh's shading normal and tangent (dP/du) over its UV\n"
    "rectangle into a float EXR with channels N.X N.Y N.Z T.X T.Y T.Z B.sign A.\n"
    "\n"
    "options:\n"
    "  -o, --output FILE   output EXR (required)\n"
    "  --resolution N      N x N texels (default 1024)\n"
    "  --size WxH          W x H texels\n"
    "  --dilate N          texel rings filled beyond chart borders (default 2)\n";

int run(const std::vector<std::string>& args) {
  using namespace knit::render;
  std::string mesh_file, out_file;
  BakeSettings s;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "-h" || a == "--help") {
      std::printf("%s", kUsage);
      return 0;
    } else if (a == "-o" || a == "--output") {
      out_file = option_value(args, i);
    } else if (a == "--resolution") {
      s.width = s.height = static_cast<int>(parse_int_option(a, option_value(args, i), 1, 16384));
    } else if (a == "--size") {
      const SizeOption size = parse_size_option(a, option_value(args, i), 1, 16384);
      s.width = size.width;
      s.height = size.height;
    } else if (a == "--dilate") {
      s.dilate = static_cast<int>(parse_int_option(a, option_value(args, i), 0, 64));
    } else if (!a.empty() && a[0] == '-') {
      throw UsageError{"unknown option " + a};
    } else if (mesh_file.empty()) {
      mesh_file = a;
    } else {
      throw UsageError{"more than one mesh given"};
    }
  }
  if (mesh_file.empty()) throw UsageError{"no mesh given"};
  if (out_file.empty()) throw UsageError{"no output given (-o FRAMES.exr)"};
  Warnings warnings;
  const TriangleMesh mesh = load_mesh(mesh_file, &warnings);
  for (const std::string& w : warnings.messages) std::fprintf(stderr, "knitshade bake-frames: warning: %s\n", w.c_str());
  const BakeResult r = bake_frames(mesh, out_file, s);
  std::printf("baked %dx%d frames of %s over UV [%g, %g] x [%g, %g] (%.1f%% of texels inside the mesh) to %s\n",
              r.width, r.height, mesh_file.c_str(), r.uv_min.x, r.uv_max.x, r.uv_min.y, r.uv_max.y,
              100.0 * static_cast<double>(r.covered) / (static_cast<double>(r.width) * r.height), out_file.c_str());
  return 0;
}

const bool registered = register_command({"bake-frames", "bake a mesh's normal and tangent over UV space to EXR", &run});

}  // namespace
}  // namespace knit::cli

#endif  // KNIT_HAVE_RENDER
