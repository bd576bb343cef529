#include "render/errors.h"

#include <cmath>
#include <cstdio>

namespace knit::render {

static std::string join_location(const std::string& file, const std::string& path) {
  return path.empty() ? file : file + ": " + path;
}

static std::string join_position(const std::string& file, int line, int column) {
  return file + ":" + std::to_string(line) + ":" + std::to_string(column);
}

SceneError::SceneError(const std::string& file, const std::string& path, const std::string& message)
    : std::runtime_error(join_location(file, path) + ": " + message), file_(file), path_(path), message_(message) {}

SceneError::SceneError(const std::string& file, int line, int column, const std::string& message)
    : std::runtime_error(join_position(file, line, column) + ": " + message),
      file_(file),
      message_(message),
      line_(line),
      column_(column) {}

SceneError::SceneError(const std::string& file, int line, int column, const std::string& path,
                       const std::string& message)
    : std::runtime_error(join_location(join_position(file, line, column), path) + ": " + message),
      file_(file),
      path_(path),
      message_(message),
      line_(line),
      column_(column) {}

std::string fmt_num(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

}  // namespace knit::render
