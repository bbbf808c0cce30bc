// The strict JSON reader under the scene files (docs/scenes.md): the parse that refuses
// duplicate keys, and `Fields`, one JSON object read key by key. Every problem a user can put in
// a file is an InputError of one line,
//   "FILE: KEY.PATH: what is wrong (expected ...)",
// so a typo never silently falls back to a default: every accessor validates its key the same
// way and finish() reports the keys nobody asked for. Private to the scene reader
// (scene_schema_*.cpp, scene_io.cpp); nlohmann_json is a private build dependency.
#pragma once

#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "gradel/types.h"

namespace gradel::scene_json {

using nlohmann::json;

// ---- messages ---------------------------------------------------------------

// Longest piece of user text (a key, a string value) echoed in a message [bytes].
constexpr size_t kShownChars = 60;

// User text as it appears in a message: control characters (a NUL would end the message
// early) written as \u00XX, cut to kShownChars bytes (never inside a UTF-8 sequence) with "...".
std::string shown(std::string_view text, size_t maxBytes = kShownChars);
// One-line description of a JSON value for "got ..." messages; long values are cut.
std::string describeValue(const json& v);
// Edit distance counting a swap of neighbours as one edit (optimal string alignment), for
// "did you mean" on mistyped keys.
size_t editDistance(std::string_view a, std::string_view b);
// Is `typed` a plausible typo of `key`? One edit for short keys, two for longer ones, so that
// two real keys of one object (min / max) are never mistaken for each other.
bool isNearMiss(std::string_view typed, std::string_view key);
// Shortest text that reads back to x: "0", "0.01", "1e+05".
std::string numberText(Real x);

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

inline const Bound kAny{};
inline const Bound kPositive{0, std::numeric_limits<Real>::infinity(), true, false};
// A voxel edge from a nanometre to a kilometre: outside it the rest lattice (positions = origin +
// lattice x voxel_size) and the masses (density x voxel_size^3) lose their precision or underflow.
inline const Bound kVoxelSize{1e-9, 1e3, false, false};
// A body's position within 1e9 voxels of the origin: beyond it a voxel is below the rounding of
// the coordinates (the rest positions would leave the voxel lattice).
constexpr Real kMaxPositionVoxels = 1e9;
inline const Bound kNonNegative{0, std::numeric_limits<Real>::infinity(), false, false};
inline const Bound kUnit{0, 1, false, false};  // [0, 1]
inline const Bound kPoissonRatio{0, 0.5, false, true};  // [0, 0.5) (material.h)

// "a number in [lo, hi] [unit]".
std::string expectNumber(const Bound& b, const char* unit);
// "\"a\", \"b\" or \"c\"".
std::string quoteList(const std::vector<std::string>& names);

// What every reader shares: the file name for messages and the scene's dimension (vectors
// have `dim` components).
struct Context {
  std::string file;
  int dim = 3;
};
[[noreturn]] void failAt(const Context& ctx, const std::string& path, const std::string& what);

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
      // A parser may already name the key as its error's field; don't repeat it.
      fail(key, e.field() == key ? e.detail() : std::string(e.what()));
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
// nlohmann keeps the last of two equal keys silently; a strict scene file must not: a key seen
// twice in one object is an InputError naming its key path, as is invalid JSON (with its line
// and column).
json parseStrict(const std::string& text, const Context& ctx);

// A scene name becomes a directory name (out/<name>), so it is kept to safe characters.
bool isNameChar(char c);
bool isSafeName(const std::string& s);

// Boxes (primitives, the domain) must have a positive extent on every axis of the scene.
void checkMaxAboveMin(const Fields& f, const Vec3& min, const Vec3& max);

// The core's own check of a settings type (settings_check.h: the same one World and the Python
// module use), after the reader's per-key checks: its error's field is reported as that key of
// this object, with the file and key path.

template <class Check>
void coreCheck(const Fields& f, Check check) {
  try {
    check();
  } catch (const InputError& e) {
    f.fail(e.field(), e.detail());
  }
}

}  // namespace gradel::scene_json
