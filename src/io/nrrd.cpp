#include "gradel/io/nrrd.h"

#include <algorithm>
#include <map>
#include <sstream>
#include <vector>

namespace gradel::io {

namespace {

std::string trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t");
  if (a == std::string::npos) return "";
  const size_t b = s.find_last_not_of(" \t");
  return s.substr(a, b - a + 1);
}

std::vector<std::string> words(const std::string& s) {
  std::istringstream in(s);
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

// NRRD's type names (format.html, "type") and their gradel ScalarType.
ScalarType nrrdType(const ByteStream& in, const std::string& name) {
  static const std::map<std::string, ScalarType> kNames = {
      {"signed char", ScalarType::Int8},
      {"int8", ScalarType::Int8},
      {"int8_t", ScalarType::Int8},
      {"uchar", ScalarType::UInt8},
      {"unsigned char", ScalarType::UInt8},
      {"uint8", ScalarType::UInt8},
      {"uint8_t", ScalarType::UInt8},
      {"short", ScalarType::Int16},
      {"short int", ScalarType::Int16},
      {"signed short", ScalarType::Int16},
      {"signed short int", ScalarType::Int16},
      {"int16", ScalarType::Int16},
      {"int16_t", ScalarType::Int16},
      {"ushort", ScalarType::UInt16},
      {"unsigned short", ScalarType::UInt16},
      {"unsigned short int", ScalarType::UInt16},
      {"uint16", ScalarType::UInt16},
      {"uint16_t", ScalarType::UInt16},
      {"int", ScalarType::Int32},
      {"signed int", ScalarType::Int32},
      {"int32", ScalarType::Int32},
      {"int32_t", ScalarType::Int32},
      {"uint", ScalarType::UInt32},
      {"unsigned int", ScalarType::UInt32},
      {"uint32", ScalarType::UInt32},
      {"uint32_t", ScalarType::UInt32},
      {"longlong", ScalarType::Int64},
      {"long long", ScalarType::Int64},
      {"long long int", ScalarType::Int64},
      {"signed long long", ScalarType::Int64},
      {"signed long long int", ScalarType::Int64},
      {"int64", ScalarType::Int64},
      {"int64_t", ScalarType::Int64},
      {"ulonglong", ScalarType::UInt64},
      {"unsigned long long", ScalarType::UInt64},
      {"unsigned long long int", ScalarType::UInt64},
      {"uint64", ScalarType::UInt64},
      {"uint64_t", ScalarType::UInt64},
      {"float", ScalarType::Float32},
      {"double", ScalarType::Float64},
  };
  const auto it = kNames.find(name);
  if (it == kNames.end())
    in.fail("header: type: unsupported type '" + name.substr(0, 40) + "' (block types are not voxels)");
  return it->second;
}

}  // namespace

VoxelVolume readNrrd(ByteStream& in, const GreyRule& rule, Real voxelSize, const ReadLimits& limits) {
  constexpr size_t kMaxLine = 4096;  // long "space directions" lines fit; binary data does not
  const auto magic = in.readLine(kMaxLine, "header");
  if (!magic || magic->size() != 8 || magic->rfind("NRRD000", 0) != 0 || (*magic)[7] < '1' || (*magic)[7] > '5')
    in.fail("not a NRRD file (expected 'NRRD0001' to 'NRRD0005' on the first line)");

  std::map<std::string, std::string> fields;
  for (int lines = 0;; ++lines) {
    if (lines > 1000) in.fail("header: more than 1000 lines");
    const auto line = in.readLine(kMaxLine, "header");
    if (!line) in.fail("truncated: header ends without the blank line before the data");
    if (line->empty()) break;
    if ((*line)[0] == '#') continue;
    if (line->find(":=") != std::string::npos && line->find(":=") < line->find(": ")) continue;  // key/value pair
    const size_t colon = line->find(": ");
    if (colon == std::string::npos) in.fail("header: line '" + line->substr(0, 60) + "' is not 'field: value'");
    std::string key = line->substr(0, colon);
    std::transform(key.begin(), key.end(), key.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    if (!fields.emplace(key, trim(line->substr(colon + 2))).second) in.fail("header: field '" + key + "' given twice");
  }
  auto field = [&](const std::string& key) -> const std::string* {
    const auto it = fields.find(key);
    return it == fields.end() ? nullptr : &it->second;
  };
  auto require = [&](const std::string& key) -> const std::string& {
    const std::string* v = field(key);
    if (!v) in.fail("header: required field '" + key + "' is missing");
    return *v;
  };

  if (field("data file") || field("datafile"))
    in.fail("header: 'data file': detached data is not supported (save the NRRD with an attached header, .nrrd)");
  const ScalarType type = nrrdType(in, require("type"));
  const int64_t dimension = parseIntegerToken(in, require("dimension"), "header: dimension");
  if (dimension != 2 && dimension != 3)
    in.fail("header: dimension: " + std::to_string(dimension) + " (expected 2 or 3)");
  const std::vector<std::string> sizeWords = words(require("sizes"));
  if (int64_t(sizeWords.size()) != dimension)
    in.fail("header: sizes: " + std::to_string(sizeWords.size()) + " values for dimension " +
            std::to_string(dimension));
  std::array<int64_t, 3> dims{1, 1, 1};
  for (size_t i = 0; i < sizeWords.size(); ++i)
    dims[i] = parseIntegerToken(in, sizeWords[i], "header: sizes[" + std::to_string(i) + "]");

  const std::string encoding = require("encoding");
  enum { Raw, Gzip, Ascii } enc;
  if (encoding == "raw")
    enc = Raw;
  else if (encoding == "gzip" || encoding == "gz")
    enc = Gzip;
  else if (encoding == "ascii" || encoding == "text" || encoding == "txt")
    enc = Ascii;
  else
    in.fail("header: encoding: '" + encoding.substr(0, 20) + "' is not supported (expected raw, gzip or ascii)");

  SampleLayout layout;
  layout.type = type;
  if (const std::string* e = field("endian")) {
    if (*e == "big")
      layout.bigEndian = true;
    else if (*e != "little")
      in.fail("header: endian: '" + e->substr(0, 20) + "' (expected little or big)");
  } else if (scalarTypeBytes(type) > 1 && enc != Ascii) {
    in.fail("header: required field 'endian' is missing (needed for " + std::string(scalarTypeName(type)) +
            " samples)");
  }
  for (const char* key : {"line skip", "lineskip"})
    if (const std::string* s = field(key))
      for (int64_t n = parseIntegerToken(in, *s, std::string("header: ") + key), i = 0; i < n; ++i)
        if (!in.readLine(1u << 20, "line skip")) in.fail("truncated: data ends within 'line skip'");
  int64_t byteSkip = 0;
  for (const char* key : {"byte skip", "byteskip"})
    if (const std::string* s = field(key)) byteSkip = parseIntegerToken(in, *s, std::string("header: ") + key);
  if (byteSkip < 0) in.fail("header: byte skip: " + std::to_string(byteSkip) + " (negative skips are not supported)");
  for (const char* key : {"spacings", "spacing"})
    if (const std::string* s = field(key))
      for (const std::string& w : words(*s))
        if (w != "nan" && w != "NaN") parseNumberToken(in, w, std::string("header: ") + key);

  VoxelVolume v = allocateVolume(in, dims, voxelSize, limits, "header: sizes");
  SampleStats stats;
  if (enc == Ascii) {
    stats = readGreyLevelsText(in, rule, v);
  } else if (enc == Gzip) {
    std::unique_ptr<ByteStream> z = gzipStream(in);
    z->skip(uint64_t(byteSkip), "byte skip");
    stats = readGreyLevels(*z, layout, rule, v);
    uint8_t extra;
    if (z->read(&extra, 1) != 0) in.fail("gzip data: more bytes than 'sizes' and 'type' describe");
  } else {
    in.skip(uint64_t(byteSkip), "byte skip");
    stats = readGreyLevels(in, layout, rule, v);
    if (const auto left = in.remaining(); left && *left > 0)
      in.fail("raw data: " + std::to_string(*left) + " bytes more than 'sizes' and 'type' describe");
  }
  if (v.countFilled() == 0) failNothingFilled(in.name(), rule, stats);
  return v;
}

}  // namespace gradel::io
