// Strict reading of JSON input files: syntax errors with line/column,
// duplicate keys rejected, unknown keys rejected, every value type- and
// range-checked, and every error naming the file and the field's JSON path
// (and, through JsonPositions, its line and column).
//
//   JsonObject film(root.at("film"));            // must be an object
//   int w = film.integer("width", 1, 16384);     // required
//   float e = film.number("exposure", Range::any(), 0.0f);  // optional, default 0
//   film.finish();                               // any other key is an error
#pragma once

#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "render/errors.h"
#include "render/vec.h"

namespace knit::render {

// Parses `text` (the contents of `file`). Throws SceneError: "file:line:col: ..."
// for syntax errors, "file:line:col: path: duplicate key 'k'" for repeated
// keys (the position of the second one).
nlohmann::json parse_json_strict(const std::string& text, const std::string& file);

// Where each value of a JSON text is, by JSON path (json_child_path,
// json_index_path): an object member at its key, an array element at its
// value, the whole text ("") at its first value. Reads any text without
// throwing, crashing or recursing (bad text: what it could read), so that
// an error found after parsing can name the line and column of its field.
class JsonPositions {
 public:
  explicit JsonPositions(const std::string& text);

  // The 1-based line and column of `path` or, when the text does not hold it
  // (a missing key: "film.width"), of its nearest enclosing value; "(top
  // level)" is the whole text. False when not even that is known.
  bool locate(const std::string& path, int& line, int& column) const;
  // The second occurrence of the member at `path` ("film.width" of a film
  // with two widths).
  bool locate_duplicate(const std::string& path, int& line, int& column) const;

  // `e` with the position of its path added ("scene.json:12:7: path:
  // message"), or `e` itself when it has a position already, names another
  // file or no path, or its path is not found.
  SceneError locate(const SceneError& e, const std::string& file) const;

 private:
  std::string text_;
  std::map<std::string, size_t> at_, duplicate_;  // byte offsets
};

// An allowed interval for a number, with a printable description.
struct Range {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false, hi_open = false;
  bool nonzero = false;

  static Range any() { return {}; }
  static Range positive() { return {0, std::numeric_limits<double>::infinity(), true, false}; }
  static Range non_negative() { return {0, std::numeric_limits<double>::infinity(), false, false}; }
  static Range closed(double a, double b) { return {a, b, false, false}; }
  static Range open(double a, double b) { return {a, b, true, true}; }
  static Range left_open(double a, double b) { return {a, b, true, false}; }
  static Range right_open(double a, double b) { return {a, b, false, true}; }
  static Range not_zero() {
    Range r;
    r.nonzero = true;
    return r;
  }
  static Range magnitude(double m) { return closed(-m, m); }

  bool contains(double v) const;
  std::string describe() const;  // "> 0", "in [0, 1]", "!= 0"
};

// A JSON value with its location, for error messages.
class JsonNode {
 public:
  JsonNode(const nlohmann::json& j, std::string path, const std::string& file)
      : j_(&j), path_(std::move(path)), file_(&file) {}

  const nlohmann::json& json() const { return *j_; }
  const std::string& path() const { return path_; }
  const std::string& file() const { return *file_; }
  [[noreturn]] void fail(const std::string& message) const;

  // Type name for messages: "object", "array", "string", "number", "boolean", "null".
  std::string type_name() const;
  bool is_object() const { return j_->is_object(); }
  bool is_array() const { return j_->is_array(); }
  bool is_string() const { return j_->is_string(); }
  bool is_number() const { return j_->is_number(); }

  double number(const Range& r = Range::any()) const;  // finite, in range
  float number_f(const Range& r = Range::any()) const;  // also finite as a float
  int64_t integer(int64_t lo, int64_t hi) const;        // an integral number in [lo, hi]
  bool boolean() const;
  std::string string() const;
  // One of `choices`; the message lists them.
  std::string choice(const std::vector<std::string>& choices) const;

  // Arrays. `elements` checks the length is in [min_len, max_len].
  std::vector<JsonNode> elements(size_t min_len = 0, size_t max_len = SIZE_MAX) const;
  Vec3 vec3(const Range& component = Range::any()) const;
  // A direction: three numbers, not all zero; returned normalised.
  Vec3 direction() const;
  Rgb rgb(const Range& component) const;

 private:
  const nlohmann::json* j_;
  std::string path_;
  const std::string* file_;
};

// A JSON object whose keys are all accounted for: every key asked about (even
// when absent) is "known"; finish() rejects the rest.
class JsonObject {
 public:
  explicit JsonObject(const JsonNode& node);  // fails unless the node is an object

  const JsonNode& node() const { return node_; }
  const std::string& path() const { return node_.path(); }
  [[noreturn]] void fail(const std::string& message) const { node_.fail(message); }

  bool has(const std::string& key);
  JsonNode at(const std::string& key);                 // required
  std::optional<JsonNode> get(const std::string& key);  // optional

  // Shorthands: required when no default is given.
  float number(const std::string& key, const Range& r);
  float number(const std::string& key, const Range& r, float def);
  int64_t integer(const std::string& key, int64_t lo, int64_t hi);
  int64_t integer(const std::string& key, int64_t lo, int64_t hi, int64_t def);
  bool boolean(const std::string& key, bool def);
  std::string string(const std::string& key);
  std::string choice(const std::string& key, const std::vector<std::string>& choices,
                     const std::string& def);
  Vec3 vec3(const std::string& key, const Range& component = Range::any());
  Vec3 vec3(const std::string& key, const Range& component, Vec3 def);
  Rgb rgb(const std::string& key, const Range& component);
  Rgb rgb(const std::string& key, const Range& component, Rgb def);

  // All keys, sorted (for maps such as "materials").
  std::vector<std::string> keys() const;
  // Rejects unknown keys: "path: unknown key 'colour' (expected one of: ...)".
  void finish() const;

 private:
  JsonNode node_;
  std::set<std::string> known_;
};

// "materials.wool" + "a" -> "materials.wool.a"; "" + "film" -> "film".
std::string json_child_path(const std::string& parent, const std::string& key);
std::string json_index_path(const std::string& parent, size_t index);

}  // namespace knit::render
