#include "render/json_strict.h"

#include <cmath>
#include <sstream>
#include <string_view>

#include "render/errors.h"

namespace knit::render {

using nlohmann::json;

std::string json_child_path(const std::string& parent, const std::string& key) {
  return parent.empty() ? key : parent + "." + key;
}

std::string json_index_path(const std::string& parent, size_t index) {
  return parent + "[" + std::to_string(index) + "]";
}

// 1-based line and column of byte offset `byte` (0-based) in `text`.
static void line_col(const std::string& text, size_t byte, int& line, int& col) {
  line = 1;
  col = 1;
  for (size_t i = 0; i < byte && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      col = 1;
    } else {
      ++col;
    }
  }
}

namespace {
struct ParseFrame {
  bool is_object = false;
  std::set<std::string> keys;
  std::string key;
  size_t index = 0;
};

std::string frames_path(const std::vector<ParseFrame>& stack, size_t depth) {
  std::string p;
  for (size_t i = 0; i + 1 < depth && i < stack.size(); ++i) {
    const ParseFrame& f = stack[i];
    p = f.is_object ? json_child_path(p, f.key) : json_index_path(p, f.index);
  }
  return p;
}
}  // namespace

JsonPositions::JsonPositions(const std::string& text) : text_(text) {
  const size_t n = text.size();

  struct Open {
    bool object;
    std::string path;
    size_t index;
  };
  std::vector<Open> open;  // the containers around the position, innermost last
  size_t i = text.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0;  // (a byte-order mark, which the parser skips)
  const auto skip_space = [&] {
    while (i < n && (text[i] == ' ' || text[i] == '\t' || text[i] == '\n' || text[i] == '\r')) ++i;
  };
  // The end (one past the closing quote) of the string starting at s, or
  // npos when it has none.
  const auto string_end = [&](size_t s) {
    for (size_t k = s + 1; k < n; ++k) {
      if (text[k] == '\\') {
        ++k;
      } else if (text[k] == '"') {
        return k + 1;
      }
    }
    return std::string::npos;
  };
  std::string next;        // the path of the value expected at i
  bool want_value = true;  // a value comes next (else ',' or a closing bracket)
  // A member's key at i: records it, makes it `next`; false on bad text.
  const auto read_key = [&] {
    skip_space();
    if (i >= n || text[i] != '"') return false;
    const size_t s = i, e = string_end(i);
    if (e == std::string::npos) return false;
    std::string key = text.substr(s + 1, e - s - 2);
    if (key.find('\\') != std::string::npos) {
      // (escapes: the parser's own decoding, so the path is the one the
      // scene reader builds)
      const json k = json::parse(text.begin() + std::ptrdiff_t(s), text.begin() + std::ptrdiff_t(e), nullptr, false);
      if (k.is_string()) key = k.get<std::string>();
    }
    std::string member = json_child_path(open.back().path, key);
    if (!at_.emplace(member, s).second) duplicate_.emplace(member, s);
    i = e;
    skip_space();
    if (i >= n || text[i] != ':') return false;
    ++i;
    next = std::move(member);
    want_value = true;
    return true;
  };
  for (;;) {
    skip_space();
    if (i >= n) break;
    const char c = text[i];
    if (want_value) {
      at_.emplace(next, i);  // (a member is at its key, recorded already)
      if (c == '{' || c == '[') {
        open.push_back({c == '{', next, 0});
        ++i;
        skip_space();
        if (i < n && text[i] == (c == '{' ? '}' : ']')) {
          ++i;
          open.pop_back();
          want_value = false;
        } else if (c == '{') {
          if (!read_key()) break;
        } else {
          next = json_index_path(open.back().path, 0);
        }
        continue;
      }
      if (c == '"') {
        i = string_end(i);
        if (i == std::string::npos) break;
      } else {
        const size_t s = i;
        while (i < n && std::string_view(",]} \t\r\n").find(text[i]) == std::string_view::npos) ++i;
        if (i == s) break;
      }
      want_value = false;
      continue;
    }
    if (open.empty()) break;
    Open& o = open.back();
    if (c == ',') {
      ++i;
      if (o.object) {
        if (!read_key()) break;
      } else {
        next = json_index_path(o.path, ++o.index);
        want_value = true;
      }
    } else if (c == (o.object ? '}' : ']')) {
      ++i;
      open.pop_back();
    } else {
      break;
    }
  }
}

bool JsonPositions::locate(const std::string& path, int& line, int& column) const {
  std::string p = path == "(top level)" ? std::string() : path;
  for (;;) {
    const auto it = at_.find(p);
    if (it != at_.end()) {
      line_col(text_, it->second, line, column);
      return true;
    }
    if (p.empty()) return false;
    // the enclosing value: "a.b[2]" -> "a.b" -> "a" -> ""
    const size_t cut = p.back() == ']' ? p.rfind('[') : p.rfind('.');
    p.resize(cut == std::string::npos ? 0 : cut);
  }
}

bool JsonPositions::locate_duplicate(const std::string& path, int& line, int& column) const {
  const auto it = duplicate_.find(path);
  if (it == duplicate_.end()) return false;
  line_col(text_, it->second, line, column);
  return true;
}

SceneError JsonPositions::locate(const SceneError& e, const std::string& file) const {
  int line = 0, column = 0;
  if (e.line() > 0 || e.file() != file || e.path().empty() || !locate(e.path(), line, column)) return e;
  return SceneError(e.file(), line, column, e.path(), e.message());
}

json parse_json_strict(const std::string& text, const std::string& file) {
  std::vector<ParseFrame> stack;
  auto callback = [&](int, json::parse_event_t ev, json& parsed) -> bool {
    switch (ev) {
      case json::parse_event_t::object_start:
        stack.emplace_back();
        stack.back().is_object = true;
        break;
      case json::parse_event_t::array_start:
        stack.emplace_back();
        break;
      case json::parse_event_t::key: {
        ParseFrame& f = stack.back();
        std::string k = parsed.get<std::string>();
        if (!f.keys.insert(k).second) {
          const std::string object = frames_path(stack, stack.size());
          const std::string where = object.empty() ? std::string("(top level)") : object;
          int line = 0, col = 0;
          if (JsonPositions(text).locate_duplicate(json_child_path(object, k), line, col))
            throw SceneError(file, line, col, where, "duplicate key '" + k + "'");
          throw SceneError(file, where, "duplicate key '" + k + "'");
        }
        f.key = k;
        break;
      }
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        stack.pop_back();
        if (!stack.empty() && !stack.back().is_object) ++stack.back().index;
        break;
      case json::parse_event_t::value:
        if (!stack.empty() && !stack.back().is_object) ++stack.back().index;
        break;
    }
    return true;
  };
  try {
    return json::parse(text, callback, /*allow_exceptions=*/true, /*ignore_comments=*/false);
  } catch (const json::parse_error& e) {
    int line = 1, col = 1;
    line_col(text, e.byte > 0 ? e.byte - 1 : 0, line, col);
    std::string w = e.what();
    size_t p = w.find("column");
    if (p != std::string::npos) p = w.find(": ", p);
    std::string detail = p != std::string::npos ? w.substr(p + 2) : w;
    throw SceneError(file, line, col, "JSON syntax error: " + detail);
  } catch (const json::out_of_range& e) {
    // e.g. "number overflow parsing '1e999'": find the literal for a position.
    std::string w = e.what();
    int line = 0, col = 0;
    size_t q = w.find("parsing '");
    if (q != std::string::npos) {
      size_t end = w.find('\'', q + 9);
      std::string lit = w.substr(q + 9, end == std::string::npos ? std::string::npos : end - q - 9);
      size_t at = lit.empty() ? std::string::npos : text.find(lit);
      if (at != std::string::npos) line_col(text, at, line, col);
    }
    size_t b = w.find("] ");
    std::string detail = b != std::string::npos ? w.substr(b + 2) : w;
    if (line > 0) throw SceneError(file, line, col, "JSON error: " + detail);
    throw SceneError(file, "", "JSON error: " + detail);
  } catch (const json::exception& e) {
    throw SceneError(file, "", std::string("JSON error: ") + e.what());
  }
}

bool Range::contains(double v) const {
  if (nonzero && v == 0) return false;
  if (lo_open ? !(v > lo) : !(v >= lo)) return false;
  if (hi_open ? !(v < hi) : !(v <= hi)) return false;
  return true;
}

std::string Range::describe() const {
  const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
  std::string s;
  if (has_lo && has_hi) {
    s = std::string("in ") + (lo_open ? "(" : "[") + fmt_num(lo) + ", " + fmt_num(hi) +
        (hi_open ? ")" : "]");
  } else if (has_lo) {
    s = std::string(lo_open ? "> " : ">= ") + fmt_num(lo);
  } else if (has_hi) {
    s = std::string(hi_open ? "< " : "<= ") + fmt_num(hi);
  }
  if (nonzero) s = s.empty() ? "!= 0" : s + " and != 0";
  return s.empty() ? "finite" : s;
}

void JsonNode::fail(const std::string& message) const {
  throw SceneError(*file_, path_.empty() ? std::string("(top level)") : path_, message);
}

std::string JsonNode::type_name() const {
  switch (j_->type()) {
    case json::value_t::object: return "object";
    case json::value_t::array: return "array";
    case json::value_t::string: return "string";
    case json::value_t::boolean: return "boolean";
    case json::value_t::null: return "null";
    case json::value_t::number_integer:
    case json::value_t::number_unsigned:
    case json::value_t::number_float: return "number";
    default: return "value";
  }
}

double JsonNode::number(const Range& r) const {
  if (!j_->is_number()) fail("must be a number, got " + type_name());
  const double v = j_->get<double>();
  if (!std::isfinite(v)) fail("must be finite, got " + fmt_num(v));
  if (!r.contains(v)) fail("must be " + r.describe() + ", got " + fmt_num(v));
  return v;
}

float JsonNode::number_f(const Range& r) const {
  const double v = number(r);
  const float f = static_cast<float>(v);
  if (!std::isfinite(f)) fail("is out of range for a 32-bit float, got " + fmt_num(v));
  return f;
}

int64_t JsonNode::integer(int64_t lo, int64_t hi) const {
  if (!j_->is_number()) fail("must be an integer, got " + type_name());
  if (j_->is_number_float()) {
    const double d = j_->get<double>();
    if (!std::isfinite(d) || std::floor(d) != d)
      fail("must be an integer, got " + fmt_num(d));
    if (d < static_cast<double>(lo) || d > static_cast<double>(hi))
      fail("must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " + fmt_num(d));
    return static_cast<int64_t>(d);
  }
  if (j_->is_number_unsigned()) {
    const uint64_t u = j_->get<uint64_t>();
    if (u > static_cast<uint64_t>(hi) || (lo > 0 && u < static_cast<uint64_t>(lo)))
      fail("must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
           std::to_string(u));
    return static_cast<int64_t>(u);
  }
  const int64_t v = j_->get<int64_t>();
  if (v < lo || v > hi)
    fail("must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
         std::to_string(v));
  return v;
}

bool JsonNode::boolean() const {
  if (!j_->is_boolean()) fail("must be true or false, got " + type_name());
  return j_->get<bool>();
}

std::string JsonNode::string() const {
  if (!j_->is_string()) fail("must be a string, got " + type_name());
  return j_->get<std::string>();
}

std::string JsonNode::choice(const std::vector<std::string>& choices) const {
  const std::string s = string();
  for (const std::string& c : choices)
    if (s == c) return s;
  std::string list;
  for (const std::string& c : choices) list += (list.empty() ? "\"" : ", \"") + c + "\"";
  fail("must be one of " + list + ", got \"" + s + "\"");
}

std::vector<JsonNode> JsonNode::elements(size_t min_len, size_t max_len) const {
  if (!j_->is_array()) fail("must be an array, got " + type_name());
  const size_t n = j_->size();
  if (n < min_len || n > max_len) {
    if (min_len == max_len)
      fail("must have " + std::to_string(min_len) + " elements, got " + std::to_string(n));
    if (max_len == SIZE_MAX)
      fail("must have at least " + std::to_string(min_len) + " elements, got " + std::to_string(n));
    fail("must have " + std::to_string(min_len) + " to " + std::to_string(max_len) +
         " elements, got " + std::to_string(n));
  }
  std::vector<JsonNode> out;
  out.reserve(n);
  for (size_t i = 0; i < n; ++i) out.emplace_back((*j_)[i], json_index_path(path_, i), *file_);
  return out;
}

Vec3 JsonNode::vec3(const Range& component) const {
  auto e = elements(3, 3);
  return {e[0].number_f(component), e[1].number_f(component), e[2].number_f(component)};
}

Vec3 JsonNode::direction() const {
  Vec3 v = vec3(Range::magnitude(1e6));
  const float l = length(v);
  if (!(l > 1e-12f)) fail("must be a non-zero direction, got [0, 0, 0]");
  return v / l;
}

Rgb JsonNode::rgb(const Range& component) const {
  auto e = elements(3, 3);
  return {e[0].number_f(component), e[1].number_f(component), e[2].number_f(component)};
}

JsonObject::JsonObject(const JsonNode& node) : node_(node) {
  if (!node.is_object()) node.fail("must be an object, got " + node.type_name());
}

bool JsonObject::has(const std::string& key) {
  known_.insert(key);
  return node_.json().contains(key);
}

JsonNode JsonObject::at(const std::string& key) {
  if (!has(key)) fail("missing required key '" + key + "'");
  return JsonNode(node_.json().at(key), json_child_path(node_.path(), key), node_.file());
}

std::optional<JsonNode> JsonObject::get(const std::string& key) {
  if (!has(key)) return std::nullopt;
  return JsonNode(node_.json().at(key), json_child_path(node_.path(), key), node_.file());
}

float JsonObject::number(const std::string& key, const Range& r) { return at(key).number_f(r); }
float JsonObject::number(const std::string& key, const Range& r, float def) {
  auto n = get(key);
  return n ? n->number_f(r) : def;
}
int64_t JsonObject::integer(const std::string& key, int64_t lo, int64_t hi) {
  return at(key).integer(lo, hi);
}
int64_t JsonObject::integer(const std::string& key, int64_t lo, int64_t hi, int64_t def) {
  auto n = get(key);
  return n ? n->integer(lo, hi) : def;
}
bool JsonObject::boolean(const std::string& key, bool def) {
  auto n = get(key);
  return n ? n->boolean() : def;
}
std::string JsonObject::string(const std::string& key) { return at(key).string(); }
std::string JsonObject::choice(const std::string& key, const std::vector<std::string>& choices,
                               const std::string& def) {
  auto n = get(key);
  return n ? n->choice(choices) : def;
}
Vec3 JsonObject::vec3(const std::string& key, const Range& component) { return at(key).vec3(component); }
Vec3 JsonObject::vec3(const std::string& key, const Range& component, Vec3 def) {
  auto n = get(key);
  return n ? n->vec3(component) : def;
}
Rgb JsonObject::rgb(const std::string& key, const Range& component) { return at(key).rgb(component); }
Rgb JsonObject::rgb(const std::string& key, const Range& component, Rgb def) {
  auto n = get(key);
  return n ? n->rgb(component) : def;
}

std::vector<std::string> JsonObject::keys() const {
  std::vector<std::string> out;
  for (auto it = node_.json().begin(); it != node_.json().end(); ++it) out.push_back(it.key());
  return out;
}

void JsonObject::finish() const {
  for (auto it = node_.json().begin(); it != node_.json().end(); ++it) {
    if (known_.count(it.key())) continue;
    std::string list;
    for (const std::string& k : known_) list += (list.empty() ? "" : ", ") + k;
    throw SceneError(node_.file(), json_child_path(node_.path(), it.key()),
                     "unknown key '" + it.key() + "'" +
                         (list.empty() ? std::string() : " (expected one of: " + list + ")"));
  }
}

}  // namespace knit::render
