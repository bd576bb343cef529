// `knitshade export-cycles SCENE.json -o SCENE.xml`: the scene in the XML of
// the standalone Cycles app, each knit material's shader beside it
// (render/cycles_export.h; docs/renderer.md, "Export to Cycles").
#ifdef KNIT_HAVE_RENDER

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli.h"
#include "cli_args.h"
#include "render/cycles_export.h"
#include "render/scene_desc.h"

namespace knit::cli {
namespace {

const char* kHelp = R"(usage: knitshade export-cycles SCENE.json -o SCENE.xml [--no-curvature]

Writes the scene (docs/scene-format.md) in the XML of the standalone Cycles
app (Cycles 4.2 built with OSL), and for each knit material its shader
(knitshade osl) next to it as SCENE_MATERIAL.osl. Render with

  cycles --shadingsys osl --samples SPP --width W --height H --output OUT.exr SCENE.xml

(the app takes the size and samples from its options, not from the file;
this command prints the line with the scene's values). Cycles compiles each
.osl to an .oso beside it.

What is written: the pinhole camera (its vertical field of view, as Cycles'
field of view over the image's shorter side), the path depth, exposure; every
object's mesh in world space with smooth normals and per-corner UVs; quad
lights as emissive meshes of the same radiance (one-sided ones black from
behind); point lights (strength 4 pi x intensity) and directional lights
(suns of angle 0, strength = irradiance); the environment as the
background (a colour, or the lat-long image through an environment texture
turned to the scene's orientation), with a background light for importance
sampling; diffuse -> Diffuse BSDF; dielectric -> Principled BSDF, all
transmission, GGX (eta 1: Transparent BSDF); thin -> Transparent + Diffuse;
knit -> a script node of the material's shader with the mesh UV linked into
UV, every parameter set from the material, and on curved meshes their
curvature, carried in the mesh's per-corner `tangent` attribute, linked into
Curvature. The Cycles render is what `bsdf_model: "cycles"` renders natively.

Refused (exit 1, one line naming the file, the field and the value): more
than 8 yarn colours, a pattern over 256 x 256 stitches, transmission colours
that are not the yarn colours times one tint, a ply radius other than the
packed one; and every error the renderer reports for the scene.

options:
  -o, --output FILE   the XML file to write (required); the shaders go beside it
  --no-curvature      leave the knit shaders' Curvature input unlinked (a
                      warning for each curved knit mesh: the march is flat there)
)";

void write_file(const std::filesystem::path& path, const std::string& text, const char* what) {
  std::ofstream f(path, std::ios::binary);
  if (f) f.write(text.data(), std::streamsize(text.size()));
  f.close();
  if (!f) throw std::runtime_error(path.string() + ": cannot write the " + what);
}

int run(const std::vector<std::string>& args) {
  using namespace knit::render;
  std::string scene_file, out;
  CyclesExportOptions options;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "-h" || a == "--help") {
      std::printf("%s", kHelp);
      return 0;
    } else if (a == "-o" || a == "--output") {
      out = option_value(args, i);
      if (out.empty()) throw UsageError{a + ": empty file name"};
    } else if (a == "--no-curvature") {
      options.curvature = false;
    } else if (!a.empty() && a[0] == '-') {
      throw UsageError{"unknown option " + a};
    } else if (scene_file.empty()) {
      scene_file = a;
    } else {
      throw UsageError{"more than one scene file given ('" + scene_file + "' and '" + a + "')"};
    }
  }
  if (scene_file.empty()) throw UsageError{"no scene file given"};
  if (out.empty()) throw UsageError{"no output file given (-o SCENE.xml)"};
  options.xml_file = out;

  // Explicit yarns: the parser builds no multi-scale class table, which the
  // export does not need.
  const SceneDesc desc = load_scene_file(scene_file, /*explicit_yarns=*/true);
  Warnings warnings = desc.warnings;
  const CyclesExport ex = export_cycles(desc, options, warnings);
  for (const std::string& w : warnings.messages)
    std::fprintf(stderr, "knitshade export-cycles: warning: %s\n", w.c_str());

  const std::filesystem::path xml_path(out);
  const std::filesystem::path dir = xml_path.parent_path();
  for (const CyclesShaderFile& s : ex.shaders) write_file(dir / s.file_name, s.text, "shader");
  write_file(xml_path, ex.xml, "scene");

  std::fprintf(stderr, "knitshade export-cycles: wrote %s (%zu mesh%s, %zu knit shader%s)\n", out.c_str(), ex.meshes,
               ex.meshes == 1 ? "" : "es", ex.shaders.size(), ex.shaders.size() == 1 ? "" : "s");
  const std::string image = (dir / (xml_path.stem().string() + ".exr")).string();
  std::fprintf(stderr,
               "knitshade export-cycles: render with: cycles --shadingsys osl --samples %d --width %d --height %d "
               "--output %s %s\n",
               ex.samples, ex.width, ex.height, image.c_str(), out.c_str());
  return 0;
}

const bool registered =
    register_command({"export-cycles", "write a scene as XML for the standalone Cycles app (OSL)", &run});

}  // namespace
}  // namespace knit::cli

#endif  // KNIT_HAVE_RENDER
