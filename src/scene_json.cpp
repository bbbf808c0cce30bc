// The strict JSON reader under the scene files (scene_json.h): messages, the duplicate-key
// parse and the checks every section shares.
#include "scene_json.h"

#include <algorithm>
#include <charconv>
#include <cstdio>

#include "gradel/settings_check.h"

namespace gradel::scene_json {

// User text as it appears in a message: control characters (a NUL would end the message
// early) written as \u00XX, cut to kShownChars bytes (never inside a UTF-8 sequence) with "...".
std::string shown(std::string_view text, size_t maxBytes) {
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

[[noreturn]] void failAt(const Context& ctx, const std::string& path, const std::string& what) {
  throw InputError(ctx.file, path, what);
}

namespace {

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

}  // namespace

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
    throw InputError(ctx.file, "", "invalid JSON: " + shown(msg, 200));
  }
}

bool isNameChar(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' || c == '.';
}
bool isSafeName(const std::string& s) {
  return !s.empty() && s.size() <= 100 && s[0] != '.' && std::all_of(s.begin(), s.end(), isNameChar);
}

void checkMaxAboveMin(const Fields& f, const Vec3& min, const Vec3& max) {
  for (int i = 0; i < f.context().dim; ++i)
    if (!(max[i] > min[i]))
      f.fail("max", "max[" + std::to_string(i) + "] = " + numberText(max[i]) + " is not above min[" +
                        std::to_string(i) + "] = " + numberText(min[i]) + " (expected max > min on every axis)");
}

}  // namespace gradel::scene_json
