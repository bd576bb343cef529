// Errors of the renderer's input boundary. Every message names the file and,
// for scene fields, the JSON path: "scene.json: materials.wool.a: must be > 0, got -1".
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace knit::render {

class SceneError : public std::runtime_error {
 public:
  // `file`: the scene (or asset) file as the user named it; `path`: JSON path
  // of the field ("" when the error is about the whole file).
  SceneError(const std::string& file, const std::string& path, const std::string& message);
  // A position in the file (syntax errors), 1-based.
  SceneError(const std::string& file, int line, int column, const std::string& message);
  // Both: "scene.json:12:7: materials.wool.a: must be > 0, got -1".
  SceneError(const std::string& file, int line, int column, const std::string& path, const std::string& message);

  const std::string& file() const { return file_; }
  const std::string& path() const { return path_; }
  const std::string& message() const { return message_; }  // without the location
  int line() const { return line_; }                        // 0: not known
  int column() const { return column_; }

 private:
  std::string file_, path_, message_;
  int line_ = 0, column_ = 0;
};

// Non-fatal findings at load time (skipped degenerate triangles, ignored
// parameters); the CLI prints them, tests inspect them.
struct Warnings {
  std::vector<std::string> messages;
  void add(std::string m) { messages.push_back(std::move(m)); }
};

// "%g"-style formatting of a number for messages.
std::string fmt_num(double v);

}  // namespace knit::render
