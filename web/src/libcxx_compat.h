// Force-included into every source of the WebAssembly build (web/CMakeLists.txt, -include).
// Debian's emscripten 3.1.6 ships a libc++ without four C++20 / C++17 library pieces that the
// core uses: std::bit_cast, std::make_unique_for_overwrite, and std::to_chars / std::from_chars for floating point.
// Provided here only when the library lacks them (its <version> leaves the feature macros undefined), so a newer
// emscripten uses its own. Same results as the standard ones for what gradel does with them: shortest round-trip
// output; input in the "general" format only (no leading whitespace,
// '+' or hex prefix, which strtod would accept).
#pragma once

#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <system_error>
#include <type_traits>
#include <version>

namespace std {

#ifndef __cpp_lib_bit_cast
template <class To, class From>
requires(sizeof(To) == sizeof(From) && is_trivially_copyable_v<To> && is_trivially_copyable_v<From>) To
    bit_cast(const From& from)
noexcept {
  To to;
  std::memcpy(&to, &from, sizeof to);
  return to;
}
#endif

#ifndef __cpp_lib_smart_ptr_for_overwrite
template <class T>
requires is_unbounded_array_v<T> unique_ptr<T> make_unique_for_overwrite(size_t n) {
  return unique_ptr<T>(new remove_extent_t<T>[n]);
}
#endif

#ifndef __cpp_lib_to_chars
namespace gradel_compat {
template <class F>
to_chars_result toChars(char* first, char* last, F value) {
  char buf[64];
  int n = 0;
  for (int precision = 1; precision <= 17; ++precision) {  // the shortest text that reads back exactly
    n = std::snprintf(buf, sizeof buf, "%.*g", precision, double(value));
    if (F(std::strtod(buf, nullptr)) == value) break;
  }
  if (n < 0 || n > last - first) return {last, errc::value_too_large};
  std::memcpy(first, buf, size_t(n));
  return {first + n, errc{}};
}

template <class F>
from_chars_result fromChars(const char* first, const char* last, F& value) {
  const char* p = first;
  if (p != last && *p == '-') ++p;
  const bool hex = last - p >= 2 && p[0] == '0' && (p[1] == 'x' || p[1] == 'X');
  if (p == last || hex ||
      !(std::isdigit(static_cast<unsigned char>(*p)) || *p == '.' || *p == 'i' || *p == 'I' || *p == 'n' || *p == 'N'))
    return {first, errc::invalid_argument};
  const std::string text(first, last);  // strtod needs a terminated string
  char* end = nullptr;
  errno = 0;
  const double d = std::strtod(text.c_str(), &end);
  if (end == text.c_str()) return {first, errc::invalid_argument};
  const char* stop = first + (end - text.c_str());
  if (errno == ERANGE || (is_same_v<F, float> && d != 0 && (d > 3.4028234663852886e38 || d < -3.4028234663852886e38)))
    return {stop, errc::result_out_of_range};
  value = F(d);
  return {stop, errc{}};
}
}  // namespace gradel_compat

inline to_chars_result to_chars(char* first, char* last, double value) {
  return gradel_compat::toChars(first, last, value);
}
inline to_chars_result to_chars(char* first, char* last, float value) {
  return gradel_compat::toChars(first, last, value);
}
inline from_chars_result from_chars(const char* first, const char* last, double& value) {
  return gradel_compat::fromChars(first, last, value);
}
inline from_chars_result from_chars(const char* first, const char* last, float& value) {
  return gradel_compat::fromChars(first, last, value);
}
#endif

}  // namespace std
