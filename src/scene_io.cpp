// Scene files (docs/scenes.md): strict JSON -> Scene.
//
// Every problem a user can put in a file is an InputError of one line,
//   "FILE: KEY.PATH: what is wrong (expected ...)",
// so a typo never silently falls back to a default. All checks go through one reader class,
// `Fields`, so that every key is validated the same way and unknown keys are always caught.
#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "gradel/io/volume_file.h"
#include "gradel/scene.h"
#include "gradel/settings_check.h"

namespace gradel {
namespace {

using nlohmann::json;

// A scene is a few kilobytes; this cap only stops `gradel run /dev/zero` from eating memory.
constexpr size_t kMaxSceneBytes = 16u << 20;

// ---- messages ---------------------------------------------------------------

// Longest piece of user text (a key, a string value) echoed in a message [bytes].
constexpr size_t kShownChars = 60;

// User text as it appears in a message: control characters (a NUL would end the message
// early) written as \u00XX, cut to kShownChars bytes (never inside a UTF-8 sequence) with "...".
std::string shown(std::string_view text, size_t maxBytes = kShownChars) {
  size_t cut = text.size();
  if (cut > maxBytes) {
    cut = maxBytes;
    while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;
  }
  std::string out;
  for (size_t i = 0; i < cut; ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c < 0x20 || c == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += char(c);
    }
  }
  if (cut < text.size()) out += "...";
  return out;
}

// One-line description of a JSON value for "got ..." messages; long values are cut.
std::string describeValue(const json& v) {
  std::string kind;
  switch (v.type()) {
    case json::value_t::null: return "null";
    case json::value_t::boolean: kind = "boolean"; break;
    case json::value_t::string: kind = "string"; break;
    case json::value_t::number_integer:
    case json::value_t::number_unsigned:
    case json::value_t::number_float: kind = "number"; break;
    case json::value_t::array: return "an array of " + std::to_string(v.size());
    case json::value_t::object: return "an object";
    default: return "an unsupported value";
  }
  // dump() escapes control characters; shown() cuts long values.
  return kind + " " + shown(v.dump(-1, ' ', false, json::error_handler_t::replace));
}

// Edit distance counting a swap of neighbours as one edit (optimal string alignment), for
// "did you mean" on mistyped keys.
size_t editDistance(std::string_view a, std::string_view b) {
  std::vector<std::vector<size_t>> d(a.size() + 1, std::vector<size_t>(b.size() + 1));
  for (size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (size_t i = 1; i <= a.size(); ++i)
    for (size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

// Is `typed` a plausible typo of `key`? One edit for short keys, two for longer ones, so that
// two real keys of one object (min / max) are never mistaken for each other.
bool isNearMiss(std::string_view typed, std::string_view key) {
  const size_t d = editDistance(typed, key);
  return d > 0 && d <= (key.size() <= 4 ? 1u : 2u);
}

// Shortest text that reads back to x: "0", "0.01", "1e+05".
std::string numberText(Real x) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, r.ptr);
}

// A closed/open numeric interval with its wording for messages.
struct Bound {
  Real lo = -std::numeric_limits<Real>::infinity();
  Real hi = std::numeric_limits<Real>::infinity();
  bool loOpen = false;
  bool hiOpen = false;

  bool contains(Real x) const { return std::isfinite(x) && (loOpen ? x > lo : x >= lo) && (hiOpen ? x < hi : x <= hi); }
  std::string text() const {
    const bool hasLo = std::isfinite(lo), hasHi = std::isfinite(hi);
    const auto num = numberText;
    if (hasLo && hasHi)
      return std::string("in ") + (loOpen ? "(" : "[") + num(lo) + ", " + num(hi) + (hiOpen ? ")" : "]");
    if (hasLo) return std::string(loOpen ? "> " : ">= ") + num(lo);
    if (hasHi) return std::string(hiOpen ? "< " : "<= ") + num(hi);
    return "";
  }
};

const Bound kAny{};
const Bound kPositive{0, std::numeric_limits<Real>::infinity(), true, false};
// A voxel edge from a nanometre to a kilometre: outside it the rest lattice (positions = origin +
// lattice x voxel_size) and the masses (density x voxel_size^3) lose their precision or underflow.
const Bound kVoxelSize{1e-9, 1e3, false, false};
// A body's position within 1e9 voxels of the origin: beyond it a voxel is below the rounding of
// the coordinates (the rest positions would leave the voxel lattice).
constexpr Real kMaxPositionVoxels = 1e9;
const Bound kNonNegative{0, std::numeric_limits<Real>::infinity(), false, false};
const Bound kUnit{0, 1, false, false};  // [0, 1]

std::string expectNumber(const Bound& b, const char* unit) {
  std::string s = "a number";
  const std::string range = b.text();
  if (!range.empty()) s += " " + range;
  if (unit && *unit) s += std::string(" [") + unit + "]";
  return s;
}

std::string quoteList(const std::vector<std::string>& names) {
  std::string s;
  for (size_t i = 0; i < names.size(); ++i) {
    if (i > 0) s += i + 1 == names.size() ? " or " : ", ";
    s += "\"" + names[i] + "\"";
  }
  return s;
}

// What every reader shares: the file name for messages and the scene's dimension (vectors
// have `dim` components).
struct Context {
  std::string file;
  int dim = 3;
};

[[noreturn]] void failAt(const Context& ctx, const std::string& path, const std::string& what) {
  throw InputError(ctx.file + ": " + (path.empty() ? std::string() : path + ": ") + what);
}

// ---- the strict reader ------------------------------------------------------

// Wraps one JSON object at `path`. Every accessor marks its key as known; finish() then
// reports the first key nobody asked for. Accessors throw InputError naming FILE and PATH.key.
class Fields {
 public:
  Fields(const json& object, std::string path, const Context& ctx)
      : obj_(&object), path_(std::move(path)), ctx_(&ctx) {}

  const std::string& path() const { return path_; }
  std::string keyPath(std::string_view key) const { return path_.empty() ? shown(key) : path_ + "." + shown(key); }
  [[noreturn]] void fail(std::string_view key, const std::string& what) const { failAt(*ctx_, keyPath(key), what); }
  [[noreturn]] void failWrongType(std::string_view key, const json& v, const std::string& expected) const {
    fail(key, "got " + describeValue(v) + " (expected " + expected + ")");
  }
  const Context& context() const { return *ctx_; }

  /// The value, or nullptr when absent.
  const json* take(const char* key) {
    known_.insert(key);
    auto it = obj_->find(key);
    return it == obj_->end() ? nullptr : &*it;
  }
  /// The value; when absent, a mistyped near-miss key is reported first (it is the likelier
  /// mistake), else "missing".
  const json& require(const char* key, const std::string& expected) {
    if (const json* v = take(key)) return *v;
    for (auto it = obj_->begin(); it != obj_->end(); ++it)
      if (!known_.count(it.key()) && isNearMiss(it.key(), key))
        fail(it.key(), "unknown key (did you mean \"" + std::string(key) + "\"?)");
    fail(key, "missing (expected " + expected + ")");
  }
  /// A key that must not be present in this context (and is not listed as expected).
  void forbid(const char* key, const std::string& why) {
    if (obj_->contains(key)) fail(key, "not allowed here: " + why);
  }

  std::optional<Real> optNumber(const char* key, const Bound& b, const char* unit) {
    const json* v = take(key);
    if (!v) return std::nullopt;
    return checkNumber(*v, keyPath(key), b, unit);
  }
  Real number(const char* key, Real def, const Bound& b, const char* unit) {
    return optNumber(key, b, unit).value_or(def);
  }
  Real requireNumber(const char* key, const Bound& b, const char* unit) {
    return checkNumber(require(key, expectNumber(b, unit)), keyPath(key), b, unit);
  }

  std::optional<int> optInteger(const char* key, int lo, int hi) {
    const json* v = take(key);
    if (!v) return std::nullopt;
    return checkInteger(*v, keyPath(key), lo, hi);
  }
  int requireInteger(const char* key, int lo, int hi) {
    return checkInteger(require(key, integerText(lo, hi)), keyPath(key), lo, hi);
  }

  bool optBool(const char* key, bool def) {
    const json* v = take(key);
    if (!v) return def;
    if (!v->is_boolean()) failWrongType(key, *v, "true or false");
    return v->get<bool>();
  }

  std::optional<std::string> optString(const char* key) {
    const json* v = take(key);
    if (!v) return std::nullopt;
    if (!v->is_string()) failWrongType(key, *v, "a string");
    return v->get<std::string>();
  }

  /// One of `choices`; returns its index. Required when `def` < 0.
  int choice(const char* key, const std::vector<std::string>& choices, int def = -1) {
    const json* v = def < 0 ? &require(key, "one of " + quoteList(choices)) : take(key);
    if (!v) return def;
    if (!v->is_string()) failWrongType(key, *v, "one of " + quoteList(choices));
    const std::string s = v->get<std::string>();
    for (size_t i = 0; i < choices.size(); ++i)
      if (s == choices[i]) return int(i);
    fail(key, "unknown value \"" + shown(s) + "\" (expected " + quoteList(choices) + ")");
  }

  /// A string handed to one of the library's parse functions (parseLayoutKind, ...), whose
  /// InputError message is re-thrown with the file and key path in front.
  template <class E>
  E enumeration(const char* key, E def, E (*parse)(const std::string&)) {
    const json* v = take(key);
    if (!v) return def;
    if (!v->is_string()) failWrongType(key, *v, "a string");
    try {
      const std::string text = v->get<std::string>();
      // A value with a NUL or of 100 kB is no valid name either: parse its shown() form, so
      // that the parser's message quotes it safely.
      return parse(shown(text) == text ? text : shown(text));
    } catch (const InputError& e) {
      // The parsers may already start their message with the key's name; don't repeat it.
      std::string msg = e.what();
      const std::string own = std::string(key) + ": ";
      if (msg.rfind(own, 0) == 0) msg.erase(0, own.size());
      fail(key, msg);
    }
  }

  /// A vector of exactly `dim` numbers; z = 0 in 2D.
  std::optional<Vec3> optVec(const char* key, const Bound& b, const char* unit) {
    const json* v = take(key);
    if (!v) return std::nullopt;
    return checkVec(*v, keyPath(key), b, unit);
  }
  Vec3 vec(const char* key, const Vec3& def, const char* unit) { return optVec(key, kAny, unit).value_or(def); }
  Vec3 requireVec(const char* key, const Bound& b, const char* unit) {
    return checkVec(require(key, vecText(b, unit)), keyPath(key), b, unit);
  }

  /// Required array of exactly `dim` integers in [lo, hi].
  std::array<int, 3> requireIntVec(const char* key, int lo, int hi) {
    const int dim = ctx_->dim;
    const std::string expected = std::to_string(dim) + " integers " + rangeText(lo, hi);
    const json& v = require(key, expected);
    if (!v.is_array()) failWrongType(key, v, expected);
    if (int(v.size()) != dim) fail(key, "got " + std::to_string(v.size()) + " values (expected " + expected + ")");
    std::array<int, 3> out{1, 1, 1};
    for (int i = 0; i < dim; ++i) out[i] = checkInteger(v[i], keyPath(key) + "[" + std::to_string(i) + "]", lo, hi);
    return out;
  }

  std::optional<Fields> optObject(const char* key) {
    const json* v = take(key);
    if (!v) return std::nullopt;
    if (!v->is_object()) failWrongType(key, *v, "an object");
    return Fields(*v, keyPath(key), *ctx_);
  }
  Fields requireObject(const char* key) {
    const json& v = require(key, "an object");
    if (!v.is_object()) failWrongType(key, v, "an object");
    return Fields(v, keyPath(key), *ctx_);
  }
  /// An array whose every entry is an object; absent = empty.
  std::vector<Fields> objectArray(const char* key, bool required) {
    const json* v = required ? &require(key, "an array of objects") : take(key);
    std::vector<Fields> out;
    if (!v) return out;
    if (!v->is_array()) failWrongType(key, *v, "an array of objects");
    for (size_t i = 0; i < v->size(); ++i) {
      const std::string p = keyPath(key) + "[" + std::to_string(i) + "]";
      if (!(*v)[i].is_object()) failAt(*ctx_, p, "got " + describeValue((*v)[i]) + " (expected an object)");
      out.emplace_back((*v)[i], p, *ctx_);
    }
    return out;
  }

  /// Reports the first key no accessor asked for.
  void finish() const {
    for (auto it = obj_->begin(); it != obj_->end(); ++it) {
      if (known_.count(it.key())) continue;
      std::string best;
      for (const std::string& k : known_)
        if (isNearMiss(it.key(), k) && (best.empty() || editDistance(it.key(), k) < editDistance(it.key(), best)))
          best = k;
      std::string what = "unknown key";
      if (!best.empty()) {
        what += " (did you mean \"" + best + "\"?)";
      } else {
        what += " (expected one of: ";
        bool first = true;
        for (const std::string& k : known_) what += (first ? "" : ", ") + k, first = false;
        what += ")";
      }
      fail(it.key(), what);
    }
  }

 private:
  Real checkNumber(const json& v, const std::string& path, const Bound& b, const char* unit) const {
    if (!v.is_number()) failAt(*ctx_, path, "got " + describeValue(v) + " (expected " + expectNumber(b, unit) + ")");
    const Real x = v.get<Real>();
    // JSON has no NaN; an overflowing literal such as 1e999 parses as infinity.
    if (!std::isfinite(x)) failAt(*ctx_, path, "not a finite number (expected " + expectNumber(b, unit) + ")");
    if (!b.contains(x))
      failAt(*ctx_, path, shown(v.dump()) + " is out of range (expected " + expectNumber(b, unit) + ")");
    return x;
  }
  static std::string rangeText(int lo, int hi) {
    if (hi == std::numeric_limits<int>::max()) return ">= " + std::to_string(lo);
    return "in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  }
  static std::string integerText(int lo, int hi) { return "an integer " + rangeText(lo, hi); }
  int checkInteger(const json& v, const std::string& path, int lo, int hi) const {
    const std::string expected = integerText(lo, hi);
    if (v.is_number_unsigned()) {
      const uint64_t x = v.get<uint64_t>();
      if (x > uint64_t(hi) || int64_t(x) < lo)
        failAt(*ctx_, path, v.dump() + " is out of range (expected " + expected + ")");
      return int(x);
    }
    if (!v.is_number_integer()) failAt(*ctx_, path, "got " + describeValue(v) + " (expected " + expected + ")");
    const int64_t x = v.get<int64_t>();
    if (x < lo || x > hi) failAt(*ctx_, path, v.dump() + " is out of range (expected " + expected + ")");
    return int(x);
  }
  std::string vecText(const Bound& b, const char* unit) const {
    std::string s = std::to_string(ctx_->dim) + " numbers";
    const std::string range = b.text();
    if (!range.empty()) s += " " + range;
    if (unit && *unit) s += std::string(" [") + unit + "]";
    return s;
  }
  Vec3 checkVec(const json& v, const std::string& path, const Bound& b, const char* unit) const {
    const int dim = ctx_->dim;
    if (!v.is_array()) failAt(*ctx_, path, "got " + describeValue(v) + " (expected " + vecText(b, unit) + ")");
    if (int(v.size()) != dim)
      failAt(*ctx_, path,
             "got " + std::to_string(v.size()) + " numbers (expected " + vecText(b, unit) +
                 (dim == 2 ? ": x, y in a 2D scene)" : ": x, y, z)"));
    Vec3 out(0, 0, 0);
    for (int i = 0; i < dim; ++i) out[i] = checkNumber(v[i], path + "[" + std::to_string(i) + "]", b, unit);
    return out;
  }

  const json* obj_;
  std::string path_;
  const Context* ctx_;
  std::set<std::string> known_;
};

// ---- parsing with duplicate-key detection -----------------------------------

// A SAX handler that accepts everything and records where parsing failed: the offset just past
// the offending token and the token.
struct ErrorPosition : nlohmann::json_sax<json> {
  bool found = false;
  size_t end = 0;
  std::string token;
  bool null() override { return true; }
  bool boolean(bool) override { return true; }
  bool number_integer(number_integer_t) override { return true; }
  bool number_unsigned(number_unsigned_t) override { return true; }
  bool number_float(number_float_t, const string_t&) override { return true; }
  bool string(string_t&) override { return true; }
  bool binary(binary_t&) override { return true; }
  bool start_object(std::size_t) override { return true; }
  bool key(string_t&) override { return true; }
  bool end_object() override { return true; }
  bool start_array(std::size_t) override { return true; }
  bool end_array() override { return true; }
  bool parse_error(std::size_t position, const std::string& lastToken, const nlohmann::detail::exception&) override {
    found = true;
    end = position;
    token = lastToken;
    return false;
  }
};

// nlohmann keeps the last of two equal keys silently; a strict scene file must not, so the
// parser callback tracks the key path and rejects a key seen twice in one object.
json parseStrict(const std::string& text, const Context& ctx) {
  struct Frame {
    bool object = true;
    std::set<std::string> keys;
    std::string key;   // current key (object)
    size_t index = 0;  // current element (array)
  };
  std::vector<Frame> stack;
  auto pathOf = [&stack]() {
    std::string p;
    for (const Frame& f : stack) {
      if (f.object)
        p += (p.empty() ? "" : ".") + shown(f.key);
      else
        p += "[" + std::to_string(f.index) + "]";
    }
    return p;
  };
  auto elementDone = [&stack]() {
    if (!stack.empty() && !stack.back().object) ++stack.back().index;
  };
  json::parser_callback_t cb = [&](int, json::parse_event_t event, json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start: stack.push_back(Frame{true, {}, {}, 0}); break;
      case json::parse_event_t::array_start: stack.push_back(Frame{false, {}, {}, 0}); break;
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        stack.pop_back();
        elementDone();
        break;
      case json::parse_event_t::key: {
        const std::string k = parsed.get<std::string>();
        stack.back().key = k;
        if (!stack.back().keys.insert(k).second) failAt(ctx, pathOf(), "duplicate key");
        break;
      }
      case json::parse_event_t::value: elementDone(); break;
    }
    return true;
  };
  try {
    return json::parse(text, cb, /*allow_exceptions=*/true, /*ignore_comments=*/false);
  } catch (const json::exception& e) {
    // e.what() is "[json.exception.parse_error.101] parse error at line L, column C: ..."; an
    // overflowing number such as 1e999 is "[json.exception.out_of_range.406] number overflow ...".
    std::string msg = e.what();
    if (const size_t p = msg.find("] "); msg.rfind("[json.exception", 0) == 0 && p != std::string::npos)
      msg.erase(0, p + 2);
    std::replace(msg.begin(), msg.end(), '\n', ' ');
    // The DOM parser drops the position of a number overflow; a SAX pass over the same text
    // stops at the same token and knows it.
    if (msg.find(" at line ") == std::string::npos) {
      ErrorPosition where;
      json::sax_parse(text, &where, json::input_format_t::json, /*strict=*/true, /*ignore_comments=*/false);
      if (where.found) {
        // 1-based line and column of the token's first character.
        const size_t start = std::min(text.size(), where.end - std::min(where.end, where.token.size()));
        size_t line = 1, column = 1;
        for (size_t i = 0; i < start; ++i) text[i] == '\n' ? (++line, column = 1) : ++column;
        msg = "at line " + std::to_string(line) + ", column " + std::to_string(column) + ": " + msg;
      }
    }
    throw InputError(ctx.file + ": invalid JSON: " + shown(msg, 200));
  }
}

// ---- sections -----------------------------------------------------------------

// A scene name becomes a directory name (out/<name>), so it is kept to safe characters.
bool isNameChar(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' || c == '.';
}
bool isSafeName(const std::string& s) {
  return !s.empty() && s.size() <= 100 && s[0] != '.' && std::all_of(s.begin(), s.end(), isNameChar);
}

std::string defaultName(const std::string& sourceName) {
  std::string stem = std::filesystem::path(sourceName).stem().string();
  for (char& c : stem)
    if (!isNameChar(c)) c = '_';
  while (!stem.empty() && stem[0] == '.') stem.erase(0, 1);
  if (stem.size() > 100) stem.resize(100);
  return stem.empty() ? "scene" : stem;
}

// Boxes (primitives, the domain) must have a positive extent on every axis of the scene.
void checkMaxAboveMin(const Fields& f, const Vec3& min, const Vec3& max) {
  for (int i = 0; i < f.context().dim; ++i)
    if (!(max[i] > min[i]))
      f.fail("max", "max[" + std::to_string(i) + "] = " + numberText(max[i]) + " is not above min[" +
                        std::to_string(i) + "] = " + numberText(min[i]) + " (expected max > min on every axis)");
}

Primitive readPrimitive(Fields& f) {
  const int dim = f.context().dim;
  Primitive p;
  const int type = f.choice("type", {"box", "sphere", "cylinder"});
  if (type == 0) {
    p.kind = PrimitiveKind::Box;
    f.forbid("center", "a box takes \"min\" and \"max\"");
    f.forbid("radius", "a box takes \"min\" and \"max\"");
    p.min = f.requireVec("min", kAny, "voxels");
    p.max = f.requireVec("max", kAny, "voxels");
    checkMaxAboveMin(f, p.min, p.max);
    // The 2D rasteriser ignores z; keep the box's z extent non-empty all the same.
    if (dim == 2) p.min.z() = -1, p.max.z() = 1;
  } else {
    f.forbid("min", "only a box takes \"min\"");
    f.forbid("max", "only a box takes \"max\"");
    p.center = f.requireVec("center", kAny, "voxels");
    p.radius = f.requireNumber("radius", kPositive, "voxels");
    if (type == 1) {
      p.kind = PrimitiveKind::Sphere;
      f.forbid("half_length", "only a cylinder takes \"half_length\"");
      f.forbid("axis", "only a cylinder takes \"axis\"");
    } else {
      if (dim == 2) f.fail("type", "\"cylinder\" is 3D only (expected \"box\" or \"sphere\" in a 2D scene)");
      p.kind = PrimitiveKind::Cylinder;
      p.halfLength = f.requireNumber("half_length", kPositive, "voxels");
      p.axis = f.choice("axis", {"x", "y", "z"}, 2);
    }
  }
  p.label = uint16_t(f.optInteger("label", 1, 65535).value_or(p.label));
  f.finish();
  return p;
}

// "body.source": a volume or mesh file (io/volume_file.h). Relative paths are relative to the
// scene file's folder; the file must exist when the scene is read, and is read by buildScene.
std::shared_ptr<const VolumeSource> readSource(Fields f, int dim, Real voxelSize) {
  io::VolumeFileSpec spec;
  spec.dim = dim;
  spec.voxelSize = voxelSize;
  const json& file = f.require("file", "a file path");
  if (!file.is_string() || file.get<std::string>().empty()) f.failWrongType("file", file, "a file path");
  std::filesystem::path path = file.get<std::string>();
  if (path.is_relative()) path = std::filesystem::path(f.context().file).parent_path() / path;
  spec.path = path.lexically_normal().string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(spec.path, ec))
    f.fail("file",
           "\"" + shown(file.get<std::string>()) + "\" is not a readable file (looked for " +
               shown(std::filesystem::absolute(spec.path, ec).lexically_normal().string(), 300) + ")");
  if (f.take("format")) {
    spec.format = f.enumeration("format", io::VolumeFormat::Binvox, &io::parseVolumeFormat);
  } else {
    try {
      spec.format = io::volumeFormatFromPath(spec.path);
    } catch (const InputError& e) {
      f.fail("file", e.what());
    }
  }
  const io::VolumeFormat format = *spec.format;
  const std::string name = io::volumeFormatName(format);
  const bool grey =
      format == io::VolumeFormat::Nrrd || format == io::VolumeFormat::Nifti || format == io::VolumeFormat::Raw;
  const bool mesh = io::isMeshFormat(format);
  const std::string greyOnly =
      "only grey-level formats (nrrd, nifti, raw) take it; " + name + " files are binary already";
  if (!grey) {
    f.forbid("threshold", greyOnly);
    f.forbid("range", greyOnly);
    f.forbid("labels", "only grey-level formats (nrrd, nifti, raw) hold labels; " + name + " files are binary");
  }
  if (const json* l = f.take("labels")) {
    if (!l->is_boolean()) f.failWrongType("labels", *l, "true or false");
    spec.grey.labels = l->get<bool>();
    if (spec.grey.labels)
      for (const char* key : {"threshold", "range"})
        f.forbid(key, "\"labels\": true keeps every value as a label (0 empty); no threshold or range");
  }
  spec.grey.threshold = f.optNumber("threshold", kAny, "");
  if (const json* r = f.take("range")) {
    const std::string expected = "2 numbers [lo, hi] with lo <= hi";
    if (!r->is_array() || r->size() != 2 || !(*r)[0].is_number() || !(*r)[1].is_number())
      f.failWrongType("range", *r, expected);
    const Real lo = (*r)[0].get<Real>(), hi = (*r)[1].get<Real>();
    if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi)
      f.fail("range", r->dump() + " is out of range (expected " + expected + ")");
    if (spec.grey.threshold) f.fail("range", "not allowed here: give \"threshold\" or \"range\", not both");
    spec.grey.rangeLo = lo;
    spec.grey.rangeHi = hi;
  }
  if (mesh) {
    if (dim == 2) f.fail("file", "a mesh is voxelised in 3D only (expected a voxel format in a 2D scene)");
    spec.resolution = f.optInteger("resolution", 1, 1024).value_or(spec.resolution);
  } else {
    f.forbid("resolution", "only meshes (obj, stl, ply) are voxelised at a resolution");
  }
  if (format == io::VolumeFormat::Vox)
    spec.model = f.optInteger("model", 0, 1 << 20).value_or(spec.model);
  else
    f.forbid("model", "only .vox files hold several models");
  if (format == io::VolumeFormat::Raw) {
    const std::array<int, 3> dims = f.requireIntVec("dims", 1, kMaxGridEdge);
    spec.raw.dims = {dims[0], dims[1], dims[2]};
    f.require("type", "a sample type");
    spec.raw.samples.type = f.enumeration("type", io::ScalarType::UInt8, &io::parseScalarType);
    spec.raw.samples.bigEndian = f.choice("endian", {"little", "big"}, 0) == 1;
    spec.raw.headerBytes = uint64_t(f.optInteger("header_bytes", 0, std::numeric_limits<int>::max()).value_or(0));
  } else {
    for (const char* key : {"dims", "type", "endian", "header_bytes"})
      f.forbid(key, "only raw files need their layout described (the " + name + " header has it)");
  }
  f.finish();
  return io::openVolume(spec);
}

// A body's keys (`body`, or an entry of `bodies`, whose material and name readBodies reads).
void readBody(Fields& f, int dim, BodySettings& body) {
  if (auto source = f.optObject("source")) {
    for (const char* key : {"shape", "size", "grid", "primitives"})
      f.forbid(key, "a body with \"source\" takes its volume from the file");
    body.shape.voxelSize = f.number("voxel_size", body.shape.voxelSize, kVoxelSize, "m");
    body.source = readSource(*source, dim, body.shape.voxelSize);
    body.sizeKey = f.keyPath("source");
  } else {
    const int shape = f.choice("shape", {"box", "sphere", "cylinder", "union"});
    const Real voxelSize = f.number("voxel_size", body.shape.voxelSize, kVoxelSize, "m");
    if (shape == 3) {
      f.forbid("size", "\"size\" is for the presets box, sphere and cylinder; a union takes \"grid\"");
      ShapeSpec spec;
      spec.dim = dim;
      spec.voxelSize = voxelSize;
      spec.dims = f.requireIntVec("grid", 1, kMaxGridEdge);
      body.sizeKey = f.keyPath("grid");
      std::vector<Fields> prims = f.objectArray("primitives", true);
      if (prims.empty()) f.fail("primitives", "empty (expected at least one primitive)");
      for (Fields& pf : prims) spec.primitives.push_back(readPrimitive(pf));
      body.shape = spec;
    } else {
      f.forbid("grid", "\"grid\" is only for shape \"union\"");
      f.forbid("primitives", "\"primitives\" is only for shape \"union\"");
      const int size = f.requireInteger("size", 1, kMaxGridEdge);
      body.sizeKey = f.keyPath("size");
      if (shape == 2 && dim == 2)
        f.fail("shape", "\"cylinder\" is 3D only (expected \"box\", \"sphere\" or \"union\" in a 2D scene)");
      static const char* kNames[] = {"box", "sphere", "cylinder"};
      try {
        body.shape = presetShape(kNames[shape], size, dim, voxelSize);
      } catch (const InputError& e) {
        f.fail("shape", e.what());
      }
    }
  }
  body.layout = f.enumeration("layout", body.layout, &parseLayoutKind);
  {
    const Real reach = kMaxPositionVoxels * body.shape.voxelSize;
    body.position = f.optVec("position", Bound{-reach, reach, false, false}, "m").value_or(body.position);
  }
  body.velocity = f.vec("velocity", body.velocity, "m/s");
  if (dim == 2) body.position.z() = 0, body.velocity.z() = 0;
}

// The core's own check of a settings type (settings_check.h: the same one World and the Python
// module use), after the reader's per-key checks: its "field: what" is reported at that key of
// this object, with the file and key path.
template <class Check>
void coreCheck(const Fields& f, Check check) {
  try {
    check();
  } catch (const InputError& e) {
    const std::string m = e.what();
    const size_t colon = m.find(": ");
    if (colon == std::string::npos) f.fail("", m);
    f.fail(m.substr(0, colon), m.substr(colon + 2));
  }
}

void readMaterial(Fields f, MaterialSettings& m) {
  m.scaling = f.enumeration("scaling", m.scaling, &parseScaling);
  m.youngsModulus = f.number("youngs_modulus", m.youngsModulus, kPositive, "Pa");
  m.density = f.number("density", m.density, kPositive, "kg/m^3");
  m.paperK = f.number("k", m.paperK, kPositive, "N");
  // Per-label materials; a field an entry leaves out is the body's (read above).
  std::vector<Fields> regions = f.objectArray("regions", false);
  for (size_t i = 0; i < regions.size(); ++i) {
    Fields& rf = regions[i];
    RegionMaterial r;
    r.label = uint16_t(rf.requireInteger("label", 1, 65535));
    for (size_t j = 0; j < i; ++j)
      if (m.regions[j].label == r.label)
        rf.fail("label", std::to_string(r.label) + " appears twice (also in regions[" + std::to_string(j) +
                             "]; expected one entry per label)");
    r.youngsModulus = rf.number("youngs_modulus", m.youngsModulus, kPositive, "Pa");
    r.density = rf.number("density", m.density, kPositive, "kg/m^3");
    r.paperK = rf.number("k", m.paperK, kPositive, "N");
    r.damping = rf.optNumber("damping", kNonNegative, "1/s");
    rf.finish();
    m.regions.push_back(r);
  }
  coreCheck(f, [&] { validate(m); });
  f.finish();
}

// `bodies`: several bodies, each with its own material and an output name (default "body<i>").
void readBodies(Fields& top, Scene& scene) {
  std::vector<Fields> entries = top.objectArray("bodies", true);
  if (entries.empty()) top.fail("bodies", "empty (expected at least one body)");
  std::vector<BodySettings> bodies(entries.size());
  for (size_t i = 0; i < entries.size(); ++i) {
    Fields& f = entries[i];
    BodySettings& b = bodies[i];
    b.name = "body" + std::to_string(i);
    if (auto name = f.optString("name")) {
      if (!isSafeName(*name))
        f.fail("name",
               "\"" + shown(*name) +
                   "\" is not usable in a file name (expected 1-100 of A-Z a-z 0-9 _ - ., not starting with .)");
      for (size_t j = 0; j < i; ++j)
        if (bodies[j].name == *name)
          f.fail("name", "\"" + shown(*name) + "\" is the name of bodies[" + std::to_string(j) +
                             "] too (expected a name of its own)");
      b.name = *name;
    }
    readBody(f, scene.dim, b);
    if (auto m = f.optObject("material")) readMaterial(*m, b.material);
    f.finish();
  }
  scene.bodies = std::move(bodies);
}

void readSimulation(Fields f, Scene& scene) {
  SimulationSettings& s = scene.simulation;
  s.integrator = f.enumeration("integrator", s.integrator, &parseIntegratorKind);
  if (const json* dt = f.take("dt")) {
    if (dt->is_string()) {
      if (dt->get<std::string>() != "auto")
        f.fail("dt", "unknown value " + shown(dt->dump()) + " (expected \"auto\" or a number > 0 [s])");
      s.dt = 0;  // auto: dt_fraction of the smallest period, see dt_period (integrator.h)
    } else if (!dt->is_number()) {
      f.failWrongType("dt", *dt, "\"auto\" or a number > 0 [s]");
    } else {
      s.dt = dt->get<Real>();
      if (!std::isfinite(s.dt)) f.fail("dt", "not a finite number (expected \"auto\" or a number > 0 [s])");
      if (!(s.dt > 0)) f.fail("dt", dt->dump() + " is out of range (expected \"auto\" or a number > 0 [s])");
    }
  }
  s.dtPeriod = f.enumeration("dt_period", s.dtPeriod, &parsePeriodRule);
  // Without dt_fraction the rule's own default applies (0; integrator.h): "element" is the
  // paper's 0.1. The range is where symplectic Euler is stable with a margin (docs/scenes.md):
  // omega_max dt < 2, i.e. 1/pi = 0.318 of the operator's period; measured, the vertex rule holds
  // at 0.3 and diverges at 0.33, the element rule holds at 0.12 and diverges at 0.15.
  s.dtFraction = f.number("dt_fraction", s.dtFraction, Bound{0, maxDtFraction(s.dtPeriod), true, false}, "");
  s.damping = f.number("damping", s.damping, kNonNegative, "1/s");
  s.gravity = f.vec("gravity", s.gravity, "m/s^2");  // World projects it into a 2D body's plane
  scene.output.duration = f.number("duration", scene.output.duration, kPositive, "s");
  scene.output.frameInterval = f.number("frame_interval", scene.output.frameInterval, kPositive, "s");
  s.threads = f.optInteger("threads", 1, 1024).value_or(s.threads);
  s.implicitIterations = f.optInteger("implicit_iterations", 1, 1000).value_or(s.implicitIterations);
  s.largeStepPasses = f.optInteger("large_step_passes", 1, 1000).value_or(s.largeStepPasses);
  s.largeStepSubsteps = f.optInteger("large_step_substeps", 1, 64).value_or(s.largeStepSubsteps);
  s.largeStepCoarseNodes = f.optInteger("large_step_coarse_nodes", 0, 512).value_or(s.largeStepCoarseNodes);
  coreCheck(f, [&] { validate(s); });
  f.finish();
}

void readDomain(Fields f, Scene& scene) {
  DomainSettings& d = scene.domain;
  d.enabled = true;  // a "domain" object means walls
  d.min = f.vec("min", d.min, "m");
  d.max = f.vec("max", d.max, "m");
  if (scene.dim == 2) {
    // z is unused in 2D; a non-empty z range keeps the z = 0 plane inside the box.
    d.min.z() = -1;
    d.max.z() = 1;
  }
  checkMaxAboveMin(f, d.min, d.max);
  d.restitution = f.number("restitution", d.restitution, kUnit, "");
  d.friction = f.number("friction", d.friction, kNonNegative, "");
  coreCheck(f, [&] { validate(d, scene.dim); });
  f.finish();
}

void readBodyContact(Fields f, Scene& scene) {
  BodyContactSettings& c = scene.bodyContact;
  c.restitution = f.number("restitution", c.restitution, kUnit, "");
  c.friction = f.number("friction", c.friction, kNonNegative, "");
  c.selfContact = f.optBool("self_contact", c.selfContact);
  if (scene.dim != 3) f.fail("self_contact", "contact between bodies needs 3D bodies");
  coreCheck(f, [&] { validate(c); });
  f.finish();
}

Keyframe readKeyframe(Fields& f) {
  Keyframe k;
  k.time = f.requireNumber("t", kNonNegative, "s");
  k.position = f.requireVec("position", kAny, "m");
  k.velocity = f.optVec("velocity", kAny, "m/s");
  f.finish();
  return k;
}

// A path of keyframes with strictly increasing times.
Path readPath(Fields& f) {
  Path path;
  std::vector<Fields> keys = f.objectArray("path", false);
  for (size_t i = 0; i < keys.size(); ++i) {
    Keyframe k = readKeyframe(keys[i]);
    if (i > 0 && !(k.time > path.keys.back().time))
      keys[i].fail("t", numberText(k.time) + " is not after the previous key's t = " +
                            numberText(path.keys.back().time) + " (expected strictly increasing times [s])");
    path.keys.push_back(k);
  }
  return path;
}

// A pinned box or voxel mask of one body (`body`, default 0); its path's positions are offsets
// from rest (pins.h). A mask lives on its body's lattice: mask voxel (i, j, k) is body voxel
// offset + (i, j, k).
PinSettings readPin(Fields& f, const Scene& scene) {
  const int dim = scene.dim;
  PinSettings p;
  p.body = uint32_t(f.optInteger("body", 0, int(scene.numBodies()) - 1).value_or(0));
  const BodySettings& body = scene.bodies[p.body];
  if (auto mf = f.optObject("mask")) {
    f.forbid("min", "a pin takes a box (\"min\", \"max\") or a \"mask\", not both");
    f.forbid("max", "a pin takes a box (\"min\", \"max\") or a \"mask\", not both");
    auto mask = std::make_shared<PinMask>();
    mask->voxelSize = body.shape.voxelSize;
    Vec3 offset = Vec3::Zero();
    if (mf->take("offset")) {
      const std::array<int, 3> o = mf->requireIntVec("offset", -kMaxGridEdge, kMaxGridEdge);
      offset = Vec3(o[0], o[1], dim == 3 ? o[2] : 0);
    }
    Vec3 origin = body.position;
    if (dim == 2) origin.z() = 0;
    mask->origin = origin + offset * mask->voxelSize;
    for (Fields& bf : mf->objectArray("boxes", false)) {
      const std::array<int, 3> lo = bf.requireIntVec("min", 0, kMaxGridEdge),
                               hi = bf.requireIntVec("max", 0, kMaxGridEdge);
      for (int a = 0; a < dim; ++a)
        if (hi[a] < lo[a])
          bf.fail("max", "is below \"min\" on axis " + std::to_string(a) +
                             " (expected max >= min; both inclusive voxel indices)");
      bf.finish();
      mask->boxes.push_back({Int3(lo[0], lo[1], dim == 3 ? lo[2] : 0), Int3(hi[0], hi[1], dim == 3 ? hi[2] : 0)});
    }
    if (mf->take("file")) {
      mask->source = readSource(*mf, dim, mask->voxelSize);  // also finishes mf; read by buildScene
    } else {
      if (mask->boxes.empty()) mf->fail("file", "missing (expected a volume file, or \"boxes\": voxel index boxes)");
      mf->finish();
    }
    p.mask = mask;
  } else {
    p.min = f.requireVec("min", kAny, "m");
    p.max = f.requireVec("max", kAny, "m");
    if (dim == 2) {
      p.min.z() = -1;  // the z = 0 plane is inside, as for the domain
      p.max.z() = 1;
    }
    checkMaxAboveMin(f, p.min, p.max);
  }
  p.path = readPath(f);
  f.finish();
  return p;
}

ManipulatorSettings readManipulator(Fields& f, int dim) {
  ManipulatorSettings m;
  f.require("type", dim == 3 ? "\"sphere\" or \"cylinder\"" : "\"circle\" or \"sphere\"");
  m.shape = f.enumeration("type", m.shape, &parseManipulatorShape);
  if (m.shape == ManipulatorShape::Cylinder && dim == 2)
    f.fail("type", "\"cylinder\" is 3D only (expected \"circle\" in a 2D scene)");
  if (m.shape == ManipulatorShape::Circle && dim == 3)
    f.fail("type", "\"circle\" is 2D only (expected \"sphere\" or \"cylinder\" in a 3D scene)");
  m.radius = f.number("radius", m.radius, kPositive, "m");
  if (m.shape == ManipulatorShape::Cylinder) {
    m.halfLength = f.number("half_length", m.halfLength, kPositive, "m");
    // "x", "y", "z" as a union primitive's axis, or a direction vector.
    const json* a = f.take("axis");
    if (a && a->is_string()) {
      const int k = f.choice("axis", {"x", "y", "z"}, 2);
      m.axis = Vec3::Unit(k);
    } else if (const auto axis = f.optVec("axis", kAny, "")) {
      if (!(axis->norm() > 0)) f.fail("axis", "is the zero vector (expected a non-zero direction)");
      m.axis = *axis;
    }
  } else {
    f.forbid("half_length", "only a cylinder manipulator takes \"half_length\"");
    f.forbid("axis", "only a cylinder manipulator takes \"axis\"");
  }
  m.restitution = f.number("restitution", m.restitution, kUnit, "");
  m.friction = f.number("friction", m.friction, kNonNegative, "");
  m.path = readPath(f);
  coreCheck(f, [&] { validate(m); });
  f.finish();
  return m;
}

}  // namespace

Scene parseScene(const std::string& jsonText, const std::string& sourceName) {
  Context ctx;
  ctx.file = sourceName;
  const json root = parseStrict(jsonText, ctx);
  if (!root.is_object()) failAt(ctx, "", "got " + describeValue(root) + " at the top level (expected an object)");

  Scene scene;
  Fields top(root, "", ctx);
  // dim first: every vector below has `dim` components.
  scene.dim = top.optInteger("dim", 2, 3).value_or(scene.dim);
  ctx.dim = scene.dim;

  scene.name = defaultName(sourceName);
  if (auto name = top.optString("name")) {
    if (!isSafeName(*name))
      top.fail("name",
               "\"" + shown(*name) +
                   "\" is not usable as a directory name (expected 1-100 of A-Z a-z 0-9 _ - ., not starting with .)");
    scene.name = *name;
  }
  top.optString("description");  // free text for people; ignored

  // `body` (+ top-level `material`) is the one-body shorthand of `bodies`.
  if (top.take("bodies")) {
    top.forbid("body", "give \"body\" (one body) or \"bodies\" (a list), not both");
    top.forbid("material", "with \"bodies\", each body's \"material\" goes inside its entry");
    readBodies(top, scene);
  } else {
    Fields body = top.requireObject("body");
    readBody(body, scene.dim, scene.bodies[0]);
    body.finish();
    if (auto m = top.optObject("material")) readMaterial(*m, scene.bodies[0].material);
  }
  if (auto s = top.optObject("simulation")) readSimulation(*s, scene);
  if (auto d = top.optObject("domain")) readDomain(*d, scene);
  if (auto c = top.optObject("body_contact")) readBodyContact(*c, scene);
  for (Fields& mf : top.objectArray("manipulators", false))
    scene.manipulators.push_back(readManipulator(mf, scene.dim));
  for (Fields& pf : top.objectArray("pins", false)) scene.pins.push_back(readPin(pf, scene));
  top.finish();

  // A union's labels need materials (a volume file's labels are checked when it is read).
  for (const BodySettings& body : scene.bodies) {
    if (body.source) continue;
    // The body's key path ("body" or "bodies[k]"), from the key that set its grid.
    const std::string key = body.sizeKey.substr(0, body.sizeKey.rfind('.'));
    const auto& prims = body.shape.primitives;
    for (size_t i = 0; i < prims.size(); ++i) {
      try {
        (void)regionMaterial(body.material, prims[i].label);
      } catch (const InputError&) {
        failAt(ctx, key + ".primitives[" + std::to_string(i) + "].label",
               std::to_string(prims[i].label) + " has no material (expected an entry with \"label\": " +
                   std::to_string(prims[i].label) + " in material.regions)");
      }
    }
  }
  return scene;
}

Scene loadScene(const std::string& path) {
  // C stdio rather than iostreams: errno then names the reason ("No such file or directory",
  // "Is a directory", "Permission denied").
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw InputError(path + ": cannot read: " + std::strerror(errno));
  std::string text;
  char buf[65536];
  size_t n = 0;
  errno = 0;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) {
    text.append(buf, n);
    if (text.size() > kMaxSceneBytes) {
      std::fclose(f);
      throw InputError(path + ": cannot read: larger than 16 MiB (not a scene file?)");
    }
  }
  const bool failed = std::ferror(f);
  const int err = errno;
  std::fclose(f);
  if (failed) throw InputError(path + ": cannot read: " + std::strerror(err ? err : EIO));
  return parseScene(text, path);
}

}  // namespace gradel
