#include "gradel/io/grey_levels.h"

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <vector>

namespace gradel::io {

namespace {
struct TypeInfo {
  ScalarType type;
  const char* name;
  size_t bytes;
};
constexpr TypeInfo kTypes[] = {
    {ScalarType::Int8, "int8", 1},       {ScalarType::UInt8, "uint8", 1},   {ScalarType::Int16, "int16", 2},
    {ScalarType::UInt16, "uint16", 2},   {ScalarType::Int32, "int32", 4},   {ScalarType::UInt32, "uint32", 4},
    {ScalarType::Int64, "int64", 8},     {ScalarType::UInt64, "uint64", 8}, {ScalarType::Float32, "float32", 4},
    {ScalarType::Float64, "float64", 8},
};

std::string numberText(double x) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, r.ptr);
}

template <class T>
double loadSample(const uint8_t* p, bool swap) {
  std::array<uint8_t, sizeof(T)> b;
  std::memcpy(b.data(), p, sizeof(T));
  if (swap) std::reverse(b.begin(), b.end());
  return double(std::bit_cast<T>(b));
}

// Applies the rule to one value and keeps the statistics; NaN (float data) is empty.
inline uint8_t classify(double v, const GreyRule& rule, SampleStats& s) {
  if (std::isnan(v)) return 0;
  if (!s.any) s.min = s.max = v, s.any = true;
  s.min = std::min(s.min, v);
  s.max = std::max(s.max, v);
  return rule.filled(v) ? 1 : 0;
}

// Converts n samples of type T at `in` into 0 / 1 at `out`; the type switch stays out of the
// per-sample loop.
template <class T>
void convertSlice(const uint8_t* in, size_t n, bool swap, const SampleLayout& layout, bool scaled, const GreyRule& rule,
                  SampleStats& stats, uint8_t* out) {
  for (size_t i = 0; i < n; ++i) {
    double v = loadSample<T>(in + i * sizeof(T), swap);
    if (scaled) v = layout.scale * v + layout.offset;
    out[i] = classify(v, rule, stats);
  }
}

// Labels: the value itself, which must be an integer in [0, 65535]; NaN is empty. Returns false
// (and writes 0) for any other value, which the caller reports with the sample's index.
inline bool labelOf(double v, SampleStats& s, uint16_t& label) {
  label = 0;
  if (std::isnan(v)) return true;
  if (!s.any) s.min = s.max = v, s.any = true;
  s.min = std::min(s.min, v);
  s.max = std::max(s.max, v);
  if (!(v >= 0 && v <= 65535) || v != std::floor(v)) return false;
  label = uint16_t(v);
  return true;
}

// Converts n samples of type T into labels at `lab` and fill bytes at `out`; returns the index
// of the first value that is no label (that value in `bad`), or n.
template <class T>
size_t convertLabels(const uint8_t* in, size_t n, bool swap, const SampleLayout& layout, bool scaled,
                     SampleStats& stats, uint8_t* out, uint16_t* lab, double& bad) {
  for (size_t i = 0; i < n; ++i) {
    double v = loadSample<T>(in + i * sizeof(T), swap);
    if (scaled) v = layout.scale * v + layout.offset;
    if (!labelOf(v, stats, lab[i])) return bad = v, i;
    out[i] = lab[i] != 0 ? 1 : 0;
  }
  return n;
}

// Calls f(T{}) with T the C++ type of `type`: the type switch stays out of the per-sample loops.
template <class F>
void withSampleType(ScalarType type, F&& f) {
  switch (type) {
    case ScalarType::Int8: return f(int8_t{});
    case ScalarType::UInt8: return f(uint8_t{});
    case ScalarType::Int16: return f(int16_t{});
    case ScalarType::UInt16: return f(uint16_t{});
    case ScalarType::Int32: return f(int32_t{});
    case ScalarType::UInt32: return f(uint32_t{});
    case ScalarType::Int64: return f(int64_t{});
    case ScalarType::UInt64: return f(uint64_t{});
    case ScalarType::Float32: return f(float{});
    case ScalarType::Float64: return f(double{});
  }
}

[[noreturn]] void failLabel(const ByteStream& in, size_t index, double v) {
  in.fail("labels: sample " + std::to_string(index) + " is " + numberText(v) +
          " (expected an integer label in [0, 65535]: 0 empty, 1..65535 a region)");
}

}  // namespace

ScalarType parseScalarType(const std::string& name) {
  for (const TypeInfo& t : kTypes)
    if (name == t.name) return t.type;
  throw InputError("unknown sample type '" + name +
                   "' (expected int8, uint8, int16, uint16, int32, uint32, int64, uint64, float32 or float64)");
}

const char* scalarTypeName(ScalarType t) {
  for (const TypeInfo& i : kTypes)
    if (i.type == t) return i.name;
  return "?";
}

size_t scalarTypeBytes(ScalarType t) {
  for (const TypeInfo& i : kTypes)
    if (i.type == t) return i.bytes;
  return 1;
}

std::string GreyRule::describe() const {
  if (labels) return "labels (non-zero)";
  if (threshold) return "threshold " + numberText(*threshold);
  if (rangeLo) return "range [" + numberText(*rangeLo) + ", " + numberText(*rangeHi) + "]";
  return "non-zero";
}

SampleStats readGreyLevels(ByteStream& in, const SampleLayout& layout, const GreyRule& rule, VoxelVolume& volume) {
  const size_t bytes = scalarTypeBytes(layout.type);
  const size_t count = volume.size();
  // Checked before reading, so a header that promises more than the file holds fails at once.
  if (const auto left = in.remaining(); left && *left / bytes < count)
    in.fail("truncated: " + std::to_string(count) + " " + scalarTypeName(layout.type) + " samples need " +
            std::to_string(uint64_t(count) * bytes) + " bytes, the file has " + std::to_string(*left));
  const bool swap = layout.bigEndian != (std::endian::native == std::endian::big);
  const bool scaled = layout.scale != 1.0 || layout.offset != 0.0;
  constexpr size_t kSlice = 1u << 20;  // bytes per read: small next to the volume, large for I/O
  // A slice, or the whole data when smaller (small volumes need no 1 MiB buffer).
  std::vector<uint8_t> buf(std::min<uint64_t>(kSlice - kSlice % bytes, uint64_t(count) * bytes));
  uint8_t* out = volume.data().data();
  uint16_t* lab = rule.labels ? volume.enableLabels().data() : nullptr;
  SampleStats stats;
  size_t done = 0;
  while (done < count) {
    const size_t n = std::min(count - done, buf.size() / bytes);
    in.readExact(buf.data(), n * bytes, "voxel data (" + std::to_string(count) + " samples)");
    const uint8_t* in8 = buf.data();
    uint8_t* o = out + done;
    size_t bad = n;
    double badValue = 0;
    withSampleType(layout.type, [&](auto tag) {
      using T = decltype(tag);
      if (lab)
        bad = convertLabels<T>(in8, n, swap, layout, scaled, stats, o, lab + done, badValue);
      else
        convertSlice<T>(in8, n, swap, layout, scaled, rule, stats, o);
    });
    if (bad < n) failLabel(in, done + bad, badValue);
    done += n;
  }
  return stats;
}

SampleStats readGreyLevelsText(ByteStream& in, const GreyRule& rule, VoxelVolume& volume) {
  const size_t count = volume.size();
  uint8_t* out = volume.data().data();
  uint16_t* lab = rule.labels ? volume.enableLabels().data() : nullptr;
  SampleStats stats;
  size_t done = 0;
  std::string token;
  char c = 0;
  auto flush = [&]() {
    if (token.empty()) return;
    if (done >= count) in.fail("more than " + std::to_string(count) + " ascii samples");
    double v = 0;
    const auto r = std::from_chars(token.data(), token.data() + token.size(), v);
    if (r.ec != std::errc() || r.ptr != token.data() + token.size())
      in.fail("ascii sample " + std::to_string(done) + ": '" + token.substr(0, 20) + "' is not a number");
    if (lab) {
      if (!labelOf(v, stats, lab[done])) failLabel(in, done, v);
      out[done] = lab[done] != 0 ? 1 : 0;
      ++done;
    } else {
      out[done++] = classify(v, rule, stats);
    }
    token.clear();
  };
  while (in.read(&c, 1) == 1) {
    if (c == ' ' || c == '\n' || c == '\r' || c == '\t' || c == ',') {
      flush();
    } else {
      if (token.size() >= 64) in.fail("ascii sample " + std::to_string(done) + ": token longer than 64 characters");
      token.push_back(c);
    }
  }
  flush();
  if (done != count)
    in.fail("truncated: expected " + std::to_string(count) + " ascii samples, got " + std::to_string(done));
  return stats;
}

void failNothingFilled(const std::string& name, const GreyRule& rule, const SampleStats& stats) {
  std::string what = name + ": the volume is empty: no voxel passes the " + rule.describe();
  if (stats.any) what += " (values range from " + numberText(stats.min) + " to " + numberText(stats.max) + ")";
  throw InputError(what);
}

}  // namespace gradel::io
