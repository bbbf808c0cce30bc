#include "gradel/io/mesh_file.h"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <memory>
#include <vector>

namespace gradel::io {

namespace {

// Buffered byte-at-a-time access for text formats (ByteStream::read is a virtual call).
class TextReader {
 public:
  explicit TextReader(ByteStream& in) : in_(in), buf_(std::make_unique_for_overwrite<uint8_t[]>(kBufferSize)) {}
  int get() {
    if (pos_ == len_) {
      len_ = in_.read(buf_.get(), kBufferSize);
      pos_ = 0;
      if (len_ == 0) return -1;
    }
    return buf_[pos_++];
  }
  /// Next line (without "\r\n"); false at the end. Lines over 1 MiB are an error.
  bool line(std::string& out) {
    out.clear();
    int c = get();
    if (c < 0) return false;
    ++lineNo_;
    for (; c >= 0 && c != '\n'; c = get()) {
      if (out.size() >= (1u << 20))
        in_.fail("line " + std::to_string(lineNo_) + ": longer than 1 MiB (not a text file?)");
      out.push_back(char(c));
    }
    if (!out.empty() && out.back() == '\r') out.pop_back();
    return true;
  }
  /// Next whitespace-separated token; empty at the end. Tokens over 256 bytes are an error.
  std::string token() {
    std::string t;
    int c = get();
    while (c == ' ' || c == '\t' || c == '\r' || c == '\n') {
      if (c == '\n') ++lineNo_;
      c = get();
    }
    for (; c >= 0 && c != ' ' && c != '\t' && c != '\r' && c != '\n'; c = get()) {
      if (t.size() >= 256)
        in_.fail("line " + std::to_string(lineNo_ + 1) + ": token longer than 256 bytes (not a text file?)");
      t.push_back(char(c));
    }
    if (c == '\n') ++lineNo_;
    return t;
  }
  /// Hands back the bytes read into the buffer but not consumed (PLY: binary data after a text header).
  size_t takeBuffered(uint8_t* dst, size_t n) {
    const size_t k = std::min(n, len_ - pos_);
    std::memcpy(dst, buf_.get() + pos_, k);
    pos_ += k;
    return k;
  }
  size_t lineNo() const { return lineNo_; }
  ByteStream& stream() { return in_; }

 private:
  ByteStream& in_;
  static constexpr size_t kBufferSize = size_t(1) << 16;
  std::unique_ptr<uint8_t[]> buf_;  // not zeroed: only bytes read into it are looked at
  size_t pos_ = 0, len_ = 0;
  size_t lineNo_ = 0;
};

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
    size_t j = i;
    while (j < s.size() && s[j] != ' ' && s[j] != '\t') ++j;
    if (j > i) out.push_back(s.substr(i, j - i));
    i = j;
  }
  return out;
}

double number(const ByteStream& in, const std::string& t, const std::string& where) {
  return parseNumberToken(in, t, where);
}

void checkCount(const ByteStream& in, uint64_t n, const ReadLimits& limits, const std::string& what) {
  if (n > limits.maxMeshElements) in.fail(what + ": more than the limit of " + std::to_string(limits.maxMeshElements));
}

// Fans polygon `poly` (>= 3 vertex ids) into triangles.
void addPolygon(TriangleMesh& m, const std::vector<uint32_t>& poly) {
  for (size_t i = 1; i + 1 < poly.size(); ++i) m.triangles.push_back({poly[0], poly[i], poly[i + 1]});
}

}  // namespace

// ---- OBJ ------------------------------------------------------------------------

TriangleMesh readObj(ByteStream& in, const ReadLimits& limits) {
  TextReader r(in);
  TriangleMesh m;
  std::string line;
  std::vector<int64_t> ids;  // 1-based, resolved against the final vertex count at the end
  std::vector<uint32_t> poly;
  std::vector<size_t> faceLine;  // the line of each triangle's face, for index errors
  std::vector<std::array<int64_t, 3>> raw;
  while (r.line(line)) {
    const std::string where = "line " + std::to_string(r.lineNo());
    if (line.size() < 2 || line[0] == '#') continue;
    if (line[0] == 'v' && (line[1] == ' ' || line[1] == '\t')) {
      const std::vector<std::string> t = split(line);
      if (t.size() < 4) in.fail(where + ": 'v' needs x y z");
      checkCount(in, m.vertices.size() + 1, limits, where + ": vertex count");
      m.vertices.emplace_back(number(in, t[1], where + ": v x"), number(in, t[2], where + ": v y"),
                              number(in, t[3], where + ": v z"));
    } else if (line[0] == 'f' && (line[1] == ' ' || line[1] == '\t')) {
      const std::vector<std::string> t = split(line);
      if (t.size() < 4) in.fail(where + ": 'f' needs at least 3 vertices");
      ids.clear();
      for (size_t i = 1; i < t.size(); ++i) {
        const std::string v = t[i].substr(0, t[i].find('/'));
        int64_t id = parseIntegerToken(in, v, where + ": f vertex " + std::to_string(i));
        if (id == 0) in.fail(where + ": f vertex " + std::to_string(i) + ": index 0 (OBJ indices start at 1)");
        if (id < 0) {
          // Relative to the vertices read so far: -1 is the last one.
          if (-id > int64_t(m.vertices.size()))
            in.fail(where + ": f vertex " + std::to_string(i) + ": index " + std::to_string(id) +
                    " reaches before the first vertex");
          id = int64_t(m.vertices.size()) + id + 1;
        }
        ids.push_back(id);
      }
      for (size_t i = 1; i + 1 < ids.size(); ++i) {
        checkCount(in, raw.size() + 1, limits, where + ": triangle count");
        raw.push_back({ids[0], ids[i], ids[i + 1]});
        faceLine.push_back(r.lineNo());
      }
    }
  }
  for (size_t f = 0; f < raw.size(); ++f) {
    std::array<uint32_t, 3> tri;
    for (int k = 0; k < 3; ++k) {
      if (raw[f][k] > int64_t(m.vertices.size()))
        in.fail("line " + std::to_string(faceLine[f]) + ": f index " + std::to_string(raw[f][k]) +
                " but the file has " + std::to_string(m.vertices.size()) + " vertices");
      tri[k] = uint32_t(raw[f][k] - 1);
    }
    m.triangles.push_back(tri);
  }
  if (m.triangles.empty()) in.fail("no faces ('f' lines)");
  return m;
}

// ---- STL ------------------------------------------------------------------------

namespace {

float leFloat(const uint8_t* p) {
  uint32_t u = uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
  return std::bit_cast<float>(u);
}

TriangleMesh readStlBinary(ByteStream& in, uint32_t count, const ReadLimits& limits) {
  checkCount(in, count, limits, "binary STL: triangle count " + std::to_string(count));
  TriangleMesh m;
  m.vertices.reserve(size_t(count) * 3);
  m.triangles.reserve(count);
  uint8_t rec[50];
  for (uint32_t t = 0; t < count; ++t) {
    in.readExact(rec, 50, "triangle " + std::to_string(t) + " of " + std::to_string(count));
    const uint32_t base = uint32_t(m.vertices.size());
    for (int v = 0; v < 3; ++v) {
      const uint8_t* p = rec + 12 + 12 * v;  // after the 12-byte normal
      const Vec3 x(leFloat(p), leFloat(p + 4), leFloat(p + 8));
      if (!x.allFinite()) in.fail("triangle " + std::to_string(t) + ": vertex " + std::to_string(v) + " is not finite");
      m.vertices.push_back(x);
    }
    m.triangles.push_back({base, base + 1, base + 2});
  }
  return m;
}

TriangleMesh readStlAscii(TextReader& r, const ReadLimits& limits) {
  ByteStream& in = r.stream();
  TriangleMesh m;
  std::vector<uint32_t> loop;
  bool inLoop = false;
  for (std::string t = r.token(); !t.empty(); t = r.token()) {
    const std::string where = "line " + std::to_string(r.lineNo());
    if (t == "outer") {
      if (inLoop) in.fail(where + ": 'outer loop' inside a loop");
      inLoop = true;
      loop.clear();
    } else if (t == "vertex") {
      if (!inLoop) in.fail(where + ": 'vertex' outside 'outer loop' ... 'endloop'");
      Vec3 x;
      for (int k = 0; k < 3; ++k) x[k] = number(in, r.token(), where + ": vertex coordinate");
      checkCount(in, m.vertices.size() + 1, limits, where + ": vertex count");
      loop.push_back(uint32_t(m.vertices.size()));
      m.vertices.push_back(x);
    } else if (t == "endloop") {
      if (!inLoop) in.fail(where + ": 'endloop' without 'outer loop'");
      if (loop.size() < 3) in.fail(where + ": a facet with " + std::to_string(loop.size()) + " vertices (expected 3)");
      addPolygon(m, loop);
      inLoop = false;
    }
  }
  if (inLoop) in.fail("truncated: the file ends inside a facet");
  if (m.triangles.empty()) in.fail("no facets");
  return m;
}

}  // namespace

TriangleMesh readStl(ByteStream& in, const ReadLimits& limits) {
  uint8_t head[84];
  const size_t got = in.read(head, 84);
  const bool startsSolid = got >= 5 && std::memcmp(head, "solid", 5) == 0;
  if (got == 84) {
    const uint32_t count =
        uint32_t(head[80]) | uint32_t(head[81]) << 8 | uint32_t(head[82]) << 16 | uint32_t(head[83]) << 24;
    const auto left = in.remaining();
    // Binary when the size matches exactly (or, without a known size, when it is not "solid").
    if ((left && *left == uint64_t(count) * 50) || (!left && !startsSolid)) return readStlBinary(in, count, limits);
    if (!startsSolid)
      in.fail("binary STL: " + std::to_string(count) + " triangles need " + std::to_string(uint64_t(count) * 50 + 84) +
              " bytes, the file has " + std::to_string(84 + (left ? *left : 0)) + " (truncated or not an STL file)");
  } else if (!startsSolid) {
    in.fail("truncated: " + std::to_string(got) + " bytes, shorter than a binary STL header (84 bytes)");
  }
  // ASCII: re-read the bytes already taken through a reader that sees them first.
  auto prefixed = memoryStream(head, got, in.name());
  struct Chain final : ByteStream {
    Chain(ByteStream& a, ByteStream& b) : ByteStream(a.name()), a_(a), b_(b) {}
    size_t read(void* dst, size_t n) override {
      size_t k = a_.read(dst, n);
      if (k < n) k += b_.read(static_cast<uint8_t*>(dst) + k, n - k);
      offset_ += k;
      return k;
    }
    std::optional<uint64_t> remaining() const override { return std::nullopt; }
    ByteStream& a_;
    ByteStream& b_;
  } chain(*prefixed, in);
  TextReader r(chain);
  return readStlAscii(r, limits);
}

// ---- PLY ------------------------------------------------------------------------

namespace {

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool plyType(const std::string& s, PlyType& t) {
  static const std::pair<const char*, PlyType> kNames[] = {
      {"char", PlyType::Int8},       {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},
      {"uint8", PlyType::UInt8},     {"short", PlyType::Int16},     {"int16", PlyType::Int16},
      {"ushort", PlyType::UInt16},   {"uint16", PlyType::UInt16},   {"int", PlyType::Int32},
      {"int32", PlyType::Int32},     {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
      {"float", PlyType::Float32},   {"float32", PlyType::Float32}, {"double", PlyType::Float64},
      {"float64", PlyType::Float64},
  };
  for (const auto& [name, type] : kNames)
    if (s == name) return t = type, true;
  return false;
}

size_t plyBytes(PlyType t) {
  switch (t) {
    case PlyType::Int8:
    case PlyType::UInt8: return 1;
    case PlyType::Int16:
    case PlyType::UInt16: return 2;
    case PlyType::Int32:
    case PlyType::UInt32:
    case PlyType::Float32: return 4;
    case PlyType::Float64: return 8;
  }
  return 1;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::Float32;
  bool list = false;
  PlyType countType = PlyType::UInt8;
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> props;
};

// Names a value of the PLY body in messages ("element 'face' 12 list entry"). Built only when a
// message needs it: a row costs a few bytes of input, so a string per row would dominate.
struct PlyWhere {
  const std::string& element;
  uint64_t row;
  const char* part;  // "", " list count", " list entry"
  std::string str() const { return "element '" + element.substr(0, 30) + "' " + std::to_string(row) + part; }
};

// Reads values of a PLY body: text tokens, or binary in either byte order.
class PlyValues {
 public:
  PlyValues(TextReader& r, int format) : r_(r), format_(format) {}
  double next(PlyType t, const PlyWhere& where) {
    ByteStream& in = r_.stream();
    if (format_ == 0) {
      const std::string tok = r_.token();
      if (tok.empty()) in.fail("truncated: the data ends in " + where.str());
      double v = 0;
      const char* end = tok.data() + tok.size();
      const auto res = std::from_chars(tok.data(), end, v);
      if (res.ec == std::errc() && res.ptr == end && std::isfinite(v)) return v;
      return number(in, tok, where.str());  // the same rule, with its message
    }
    uint8_t b[8];
    const size_t n = plyBytes(t);
    size_t got = r_.takeBuffered(b, n);
    if (got < n) got += in.read(b + got, n - got);
    if (got < n) in.fail("truncated: the data ends in " + where.str());
    if ((format_ == 2) != (std::endian::native == std::endian::big)) std::reverse(b, b + n);
    switch (t) {
      case PlyType::Int8: return double(std::bit_cast<int8_t>(b[0]));
      case PlyType::UInt8: return double(b[0]);
      case PlyType::Int16: {
        int16_t v;
        std::memcpy(&v, b, 2);
        return v;
      }
      case PlyType::UInt16: {
        uint16_t v;
        std::memcpy(&v, b, 2);
        return v;
      }
      case PlyType::Int32: {
        int32_t v;
        std::memcpy(&v, b, 4);
        return v;
      }
      case PlyType::UInt32: {
        uint32_t v;
        std::memcpy(&v, b, 4);
        return v;
      }
      case PlyType::Float32: {
        float v;
        std::memcpy(&v, b, 4);
        return v;
      }
      case PlyType::Float64: {
        double v;
        std::memcpy(&v, b, 8);
        return v;
      }
    }
    return 0;
  }

 private:
  TextReader& r_;
  int format_;  // 0 ascii, 1 little endian, 2 big endian
};

}  // namespace

TriangleMesh readPly(ByteStream& in, const ReadLimits& limits) {
  TextReader r(in);
  std::string line;
  if (!r.line(line) || line != "ply") in.fail("not a PLY file (expected 'ply' on the first line)");
  int format = -1;
  std::vector<PlyElement> elements;
  for (;;) {
    if (!r.line(line)) in.fail("truncated: header ends without 'end_header'");
    if (r.lineNo() > 10000) in.fail("header: more than 10000 lines");
    const std::string where = "header line " + std::to_string(r.lineNo());
    const std::vector<std::string> t = split(line);
    if (t.empty() || t[0] == "comment" || t[0] == "obj_info") continue;
    if (t[0] == "end_header") break;
    if (t[0] == "format") {
      if (t.size() != 3) in.fail(where + ": 'format' needs a type and a version");
      if (t[1] == "ascii")
        format = 0;
      else if (t[1] == "binary_little_endian")
        format = 1;
      else if (t[1] == "binary_big_endian")
        format = 2;
      else
        in.fail(where + ": unknown format '" + t[1].substr(0, 30) + "'");
    } else if (t[0] == "element") {
      if (t.size() != 3) in.fail(where + ": 'element' needs a name and a count");
      const int64_t n = parseIntegerToken(in, t[2], where + ": element count");
      if (n < 0) in.fail(where + ": element count " + std::to_string(n) + " is negative");
      checkCount(in, uint64_t(n), limits, where + ": element '" + t[1].substr(0, 30) + "' count " + std::to_string(n));
      elements.push_back({t[1], uint64_t(n), {}});
    } else if (t[0] == "property") {
      if (elements.empty()) in.fail(where + ": 'property' before any 'element'");
      PlyProperty p;
      if (t.size() == 5 && t[1] == "list") {
        p.list = true;
        if (!plyType(t[2], p.countType) || !plyType(t[3], p.type)) in.fail(where + ": unknown list types");
        if (p.countType == PlyType::Float32 || p.countType == PlyType::Float64)
          in.fail(where + ": a list count must be an integer type");
        p.name = t[4];
      } else if (t.size() == 3) {
        if (!plyType(t[1], p.type)) in.fail(where + ": unknown property type '" + t[1].substr(0, 30) + "'");
        p.name = t[2];
      } else {
        in.fail(where + ": 'property' needs a type and a name");
      }
      elements.back().props.push_back(p);
    } else {
      in.fail(where + ": unknown header keyword '" + t[0].substr(0, 30) + "'");
    }
  }
  if (format < 0) in.fail("header: no 'format' line");

  TriangleMesh m;
  PlyValues values(r, format);
  std::vector<uint32_t> poly;
  bool haveFaces = false;
  for (const PlyElement& e : elements) {
    const bool isVertex = e.name == "vertex", isFace = e.name == "face";
    int xyz[3] = {-1, -1, -1};
    int indices = -1;
    for (size_t i = 0; i < e.props.size(); ++i) {
      const PlyProperty& p = e.props[i];
      if (isVertex && !p.list && (p.name == "x" || p.name == "y" || p.name == "z")) xyz[p.name[0] - 'x'] = int(i);
      if (isFace && p.list && (p.name == "vertex_indices" || p.name == "vertex_index")) indices = int(i);
    }
    if (isVertex && (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0))
      in.fail("header: element 'vertex' lacks property x, y or z");
    if (isFace) {
      if (indices < 0) in.fail("header: element 'face' lacks list property 'vertex_indices'");
      haveFaces = true;
    }
    // Rows of an element without properties hold no data: nothing to read, however many.
    if (e.props.empty()) continue;
    // A header's count is only a claim until the rows arrive: reserve a little, grow as read.
    if (isVertex) m.vertices.reserve(size_t(std::min<uint64_t>(e.count, 1u << 12)));
    for (uint64_t k = 0; k < e.count; ++k) {
      const PlyWhere row{e.name, k, ""}, listCount{e.name, k, " list count"}, listEntry{e.name, k, " list entry"};
      auto what = [&] { return row.str(); };
      Vec3 x(0, 0, 0);
      poly.clear();
      for (size_t i = 0; i < e.props.size(); ++i) {
        const PlyProperty& p = e.props[i];
        if (!p.list) {
          const double v = values.next(p.type, row);
          if (isVertex)
            for (int c = 0; c < 3; ++c)
              if (xyz[c] == int(i)) x[c] = v;
          continue;
        }
        const double n = values.next(p.countType, listCount);
        // A polygon of more than 2^16 corners is not a mesh face; the cap bounds the work.
        if (!(n >= 0 && n <= 65536) || n != std::floor(n))
          in.fail(what() + ": list count " + std::to_string(n) + " (expected 0 to 65536)");
        for (int64_t j = 0; j < int64_t(n); ++j) {
          const double id = values.next(p.type, listEntry);
          if (isFace && int(i) == indices) {
            if (!(id >= 0 && id < double(m.vertices.size())) || id != std::floor(id))
              in.fail(what() + ": vertex index " + std::to_string(id) + " (the file has " +
                      std::to_string(m.vertices.size()) + " vertices before its faces)");
            poly.push_back(uint32_t(id));
          }
        }
      }
      if (isVertex) {
        if (!x.allFinite()) in.fail(what() + ": coordinates are not finite");
        m.vertices.push_back(x);
      }
      if (isFace) {
        if (poly.size() < 3)
          in.fail(what() + ": a face with " + std::to_string(poly.size()) + " vertices (expected at least 3)");
        const uint64_t triangles = m.triangles.size() + poly.size() - 2;
        if (triangles > limits.maxMeshElements) checkCount(in, triangles, limits, what() + ": triangle count");
        addPolygon(m, poly);
      }
    }
  }
  if (!haveFaces || m.triangles.empty()) in.fail("no faces (element 'face')");
  return m;
}

}  // namespace gradel::io
