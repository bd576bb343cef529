// A scene (docs/scene-format.md) in the XML of the standalone Cycles app
// (Cycles 4.2, `cycles --shadingsys osl SCENE.xml`): camera, integrator,
// film, meshes with per-corner UVs and smooth normals, lights, and the
// materials as Cycles shader graphs, each knit material as its generated
// OSL shader (knit::osl_source) in a script node with the mesh UV linked.
// docs/renderer.md, "Export to Cycles", describes the mapping and what
// cannot be carried over.
#pragma once

#include <string>
#include <vector>

#include "render/errors.h"
#include "render/scene_desc.h"

namespace knit::render {

struct CyclesExportOptions {
  // Where the XML will be written: the shader files are named after its
  // stem, and every file it refers to is written relative to its folder.
  std::string xml_file;
  // Carry curved knit meshes' curvature to the shader's Curvature input
  // through the per-corner attribute the XML reader takes ("tangent"); false:
  // leave Curvature unlinked (a warning per curved knit mesh).
  bool curvature = true;
};

// One knit material's shader, to be written next to the XML.
struct CyclesShaderFile {
  std::string file_name;  // "<xml stem>_<material>.osl", no folder
  std::string material;   // the scene's material name
  std::string text;       // knit::osl_source of its pattern
};

struct CyclesExport {
  std::string xml;
  std::vector<CyclesShaderFile> shaders;
  // What the app needs on its command line (it takes the image size and the
  // sample count from there, not from the XML).
  int width = 0, height = 0, samples = 0;
  size_t meshes = 0;  // mesh elements written: objects, then quad lights
};

// The Cycles XML of `desc`. Throws SceneError naming the scene file, the
// field and its value for what Cycles cannot be given (more than eight yarn
// colours, a pattern over the shader's 256 x 256, a transmission colour that
// is not one tint of the yarn colours, a ply radius other than the packed
// one), and the loaders' errors (meshes) as the renderer reports them.
// Findings that do not stop the export (parameters the shader has no input
// for) go to `warnings`.
CyclesExport export_cycles(const SceneDesc& desc, const CyclesExportOptions& options, Warnings& warnings);

// The shader file's name for `material` next to `xml_file`: the XML's stem,
// "_", the material name with every character but [A-Za-z0-9_.-] made "_".
std::string cycles_shader_file_name(const std::string& xml_file, const std::string& material);

}  // namespace knit::render
