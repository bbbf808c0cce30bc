// Mesh readers (OBJ, STL ASCII and binary, PLY ASCII and binary) and the voxeliser: closed
// meshes voxelise exactly, overlapping parts give their union, a hole or flipped orientation
// does not spoil the result, and malformed files are rejected with the line or element named.
#include <gtest/gtest.h>

#include <cstring>

#include "gradel/io/mesh_file.h"
#include "gradel/io/voxelize.h"
#include "test_io_support.h"

namespace gradel {
namespace {

using test::Bytes;
using test::errorOf;
using test::stream;

// An axis-aligned box [lo, hi] as 12 outward triangles.
TriangleMesh box(const Vec3& lo, const Vec3& hi) {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
  const uint32_t q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : q) {
    m.triangles.push_back({f[0], f[1], f[2]});
    m.triangles.push_back({f[0], f[2], f[3]});
  }
  return m;
}

TriangleMesh merge(TriangleMesh a, const TriangleMesh& b) {
  const uint32_t off = uint32_t(a.vertices.size());
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (auto t : b.triangles) a.triangles.push_back({t[0] + off, t[1] + off, t[2] + off});
  return a;
}

// A UV sphere of radius 1 (outward).
TriangleMesh sphere(int nu = 48, int nv = 24) {
  TriangleMesh m;
  m.vertices.emplace_back(0, -1, 0);
  for (int j = 1; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double th = M_PI * j / nv - M_PI / 2, ph = 2 * M_PI * i / nu;
      m.vertices.emplace_back(std::cos(th) * std::cos(ph), std::sin(th), std::cos(th) * std::sin(ph));
    }
  m.vertices.emplace_back(0, 1, 0);
  auto id = [&](int j, int i) { return uint32_t(1 + (j - 1) * nu + (i % nu)); };
  const uint32_t top = uint32_t(m.vertices.size() - 1);
  for (int i = 0; i < nu; ++i) {
    m.triangles.push_back({0, id(1, i), id(1, i + 1)});
    m.triangles.push_back({top, id(nv - 1, i + 1), id(nv - 1, i)});
    for (int j = 1; j < nv - 1; ++j) {
      m.triangles.push_back({id(j, i), id(j + 1, i), id(j + 1, i + 1)});
      m.triangles.push_back({id(j, i), id(j + 1, i + 1), id(j, i + 1)});
    }
  }
  return m;
}

// ---- voxeliser ------------------------------------------------------------------

TEST(Voxelize, VoxelizeClosedBoxFillsItsGridExactly) {
  const VoxelVolume v = io::voxelize(box({0, 0, 0}, {2, 1, 0.5}), {16, 0.01}, "box");
  EXPECT_EQ(v.dims(), (std::array<int, 3>{16, 8, 4}));
  EXPECT_EQ(v.countFilled(), 16u * 8u * 4u);
  EXPECT_EQ(v.voxelSize(), 0.01);
}

TEST(Voxelize, VoxelizeSphereMatchesTheBallWithinTheFacetingError) {
  const int n = 32;
  const VoxelVolume v = io::voxelize(sphere(), {n, 0.01}, "sphere");
  ASSERT_EQ(v.dims(), (std::array<int, 3>{n, n, n}));
  // Every voxel whose centre is clearly inside (r < 0.97, the faceting's inner radius) or
  // clearly outside (r > 1.01) must be classified so.
  size_t wrong = 0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double r = Vec3((i + 0.5) / n * 2 - 1, (j + 0.5) / n * 2 - 1, (k + 0.5) / n * 2 - 1).norm();
        if ((r < 0.97 && !v.at(i, j, k)) || (r > 1.01 && v.at(i, j, k))) ++wrong;
      }
  EXPECT_EQ(wrong, 0u);
}

TEST(Voxelize, VoxelizeOverlappingPartsGiveTheirUnion) {
  // Two boxes sharing the middle third: parity would leave the overlap empty.
  const TriangleMesh m = merge(box({0, 0, 0}, {2, 1, 1}), box({1, 0, 0}, {3, 1, 1}));
  const VoxelVolume v = io::voxelize(m, {12, 0.01}, "two boxes");
  EXPECT_EQ(v.countFilled(), size_t(v.size()));
}

TEST(Voxelize, VoxelizeToleratesAHoleAndInvertedOrientation) {
  TriangleMesh holed = sphere();
  holed.triangles.erase(holed.triangles.begin() + 200, holed.triangles.begin() + 204);  // a hole near the equator
  TriangleMesh inverted = sphere();
  for (auto& t : inverted.triangles) std::swap(t[1], t[2]);
  const VoxelVolume ref = io::voxelize(sphere(), {24, 0.01}, "ref");
  const VoxelVolume a = io::voxelize(holed, {24, 0.01}, "holed");
  const VoxelVolume b = io::voxelize(inverted, {24, 0.01}, "inverted");
  EXPECT_EQ(b.data(), ref.data());
  size_t diff = 0;
  for (size_t i = 0; i < ref.size(); ++i) diff += a.data()[i] != ref.data()[i];
  EXPECT_LE(diff, 2u) << "of " << ref.countFilled();
}

TEST(Voxelize, VoxelizeRejectsUnusableMeshes) {
  TriangleMesh sheet;
  sheet.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  sheet.triangles = {{0, 1, 2}};
  EXPECT_NE(errorOf([&] {
              io::voxelize(sheet, {8, 0.01}, "s.obj");
            }).find("s.obj: the voxelised volume is empty"),
            std::string::npos);
  TriangleMesh bad = sheet;
  bad.triangles = {{0, 1, 7}};
  EXPECT_NE(errorOf([&] { io::voxelize(bad, {8, 0.01}, "b"); }).find("index 7 out of range"), std::string::npos);
  TriangleMesh point = sheet;
  point.vertices = {{1, 1, 1}, {1, 1, 1}, {1, 1, 1}};
  EXPECT_NE(errorOf([&] {
              io::voxelize(point, {8, 0.01}, "p");
            }).find("not a finite, non-empty box"),
            std::string::npos);
  EXPECT_NE(errorOf([&] {
              io::voxelize(box({0, 0, 0}, {1, 1, 1}), {0, 0.01}, "r");
            }).find("resolution 0"),
            std::string::npos);
}

// ---- OBJ ------------------------------------------------------------------------

TEST(Obj, ReadObjReadsPolygonsAndNegativeIndices) {
  const Bytes f =
      "# quad and triangle\r\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0 1.0\nvn 0 0 1\nvt 0 0\ng part\n"
      "f 1/1/1 2/1/1 3/1/1 4//1\nf -1 -2 -3\nusemtl red\nl 1 2\n";
  auto in = stream(f);
  const TriangleMesh m = io::readObj(*in);
  EXPECT_EQ(m.vertices.size(), 4u);
  ASSERT_EQ(m.triangles.size(), 3u);
  EXPECT_EQ(m.triangles[1], (std::array<uint32_t, 3>{0, 2, 3}));
  EXPECT_EQ(m.triangles[2], (std::array<uint32_t, 3>{3, 2, 1}));
}

TEST(Obj, ReadObjRejectsMalformedFiles) {
  struct Case {
    Bytes file;
    std::string message;
  };
  const Case cases[] = {
      {"v 0 0 0\n", "no faces"},
      {"v 0 0\n", "line 1: 'v' needs x y z"},
      {"v 0 0 nan\n", "line 1: v z: 'nan' is not a finite number"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "line 4: f index 9 but the file has 3 vertices"},
      {"v 0 0 0\nf 1 2\n", "line 2: 'f' needs at least 3 vertices"},
      {"v 0 0 0\nf 0 1 1\n", "index 0"},
      {"v 0 0 0\nf -5 1 1\n", "reaches before the first vertex"},
      {"v 0 0 0\nf 1 a 1\n", "'a' is not an integer"},
      {"v 0 0 0\nf 1 1 99999999999999999999\n", "out of range"},
  };
  for (const Case& c : cases) {
    auto in = stream(c.file, "m.obj");
    const std::string e = errorOf([&] { io::readObj(*in); });
    EXPECT_EQ(e.rfind("m.obj: ", 0), 0u) << e;
    EXPECT_NE(e.find(c.message), std::string::npos) << "got: " << e << "\nexpected: " << c.message;
  }
}

// ---- STL ------------------------------------------------------------------------

Bytes binaryStl(const TriangleMesh& m, const std::string& header) {
  Bytes b = header;
  b.resize(80, ' ');
  test::putLE(b, m.triangles.size(), 4);
  for (const auto& t : m.triangles) {
    for (int k = 0; k < 3; ++k) test::putFloatLE(b, 0);
    for (uint32_t id : t)
      for (int k = 0; k < 3; ++k) test::putFloatLE(b, float(m.vertices[id][k]));
    b += Bytes(2, '\0');
  }
  return b;
}

TEST(Stl, ReadStlBinaryEvenWhenTheHeaderSaysSolid) {
  const TriangleMesh cube = box({0, 0, 0}, {1, 1, 1});
  for (const std::string& header : {std::string("binary"), std::string("solid cube exported as binary")}) {
    auto in = stream(binaryStl(cube, header));
    const TriangleMesh m = io::readStl(*in);
    EXPECT_EQ(m.triangles.size(), 12u);
    EXPECT_EQ(io::voxelize(m, {4, 0.01}, "stl").countFilled(), 64u);
  }
}

TEST(Stl, ReadStlAscii) {
  const Bytes f =
      "solid t\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 1 0\n  endloop\n "
      "endfacet\n"
      " facet normal 0 0 1\n  outer loop\n   vertex 1 0 0\n   vertex 1 1 0\n   vertex 0 1 0\n  endloop\n "
      "endfacet\nendsolid t\n";
  auto in = stream(f);
  const TriangleMesh m = io::readStl(*in);
  EXPECT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.vertices[4], Vec3(1, 1, 0));
}

TEST(Stl, ReadStlRejectsMalformedFiles) {
  const Bytes good = binaryStl(box({0, 0, 0}, {1, 1, 1}), "binary");
  Bytes huge = good.substr(0, 80);
  test::putLE(huge, 0xffffffffu, 4);
  Bytes nan = good;
  std::memset(&nan[84 + 12], 0xff, 4);
  struct Case {
    Bytes file;
    std::string message;
  };
  const Case cases[] = {
      {"", "shorter than a binary STL header"},
      {good.substr(0, good.size() - 10), "truncated or not an STL file"},
      {huge, "4294967295 triangles need"},
      {nan, "triangle 0: vertex 0 is not finite"},
      {"solid x\n facet normal 0 0 1\n outer loop\n vertex 0 0 0\n vertex 1 0 0\n endloop\n",
       "a facet with 2 vertices"},
      {"solid x\n facet normal 0 0 1\n outer loop\n vertex 0 0 zz\n", "'zz' is not a finite number"},
      {"solid x\n outer loop\n vertex 0 0 0\n", "ends inside a facet"},
      {"solid x\nendsolid x\n", "no facets"},
  };
  for (const Case& c : cases) {
    auto in = stream(c.file, "m.stl");
    const std::string e = errorOf([&] { io::readStl(*in); });
    EXPECT_EQ(e.rfind("m.stl: ", 0), 0u) << e;
    EXPECT_NE(e.find(c.message), std::string::npos) << "got: " << e << "\nexpected: " << c.message;
  }
}

// ---- PLY ------------------------------------------------------------------------

TEST(Ply, ReadPlyAsciiAndBigEndianBinaryWithExtraProperties) {
  const Bytes ascii =
      "ply\nformat ascii 1.0\ncomment x\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "property uchar red\nelement face 1\nproperty list uchar int vertex_indices\nproperty int flags\n"
      "element edge 1\nproperty int a\nproperty int b\nend_header\n0 0 0 255\n1 0 0 0\n1 1 0 0\n0 1 0 0\n4 0 1 2 3 "
      "7\n0 1\n";
  auto a = stream(ascii);
  const TriangleMesh m = io::readPly(*a);
  EXPECT_EQ(m.vertices.size(), 4u);
  EXPECT_EQ(m.triangles.size(), 2u);

  Bytes bin =
      "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
      "element face 1\nproperty list uchar uint vertex_index\nend_header\n";
  for (double x : {0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 2.0, 0.0}) {
    uint64_t u;
    std::memcpy(&u, &x, 8);
    test::putBE(bin, u, 8);
  }
  bin.push_back(3);
  for (int i : {0, 1, 2}) test::putBE(bin, uint32_t(i), 4);
  auto b = stream(bin);
  const TriangleMesh t = io::readPly(*b);
  ASSERT_EQ(t.vertices.size(), 3u);
  EXPECT_EQ(t.vertices[2], Vec3(0, 2, 0));
}

TEST(Ply, ReadPlyRejectsMalformedFiles) {
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
  struct Case {
    Bytes file;
    std::string message;
  };
  const Case cases[] = {
      {"plx\n", "not a PLY file"},
      {"ply\nformat ascii 1.0\n", "header ends without 'end_header'"},
      {"ply\nelement vertex 0\nend_header\n", "no 'format' line"},
      {"ply\nformat ascii 1.0\nelement vertex -3\nend_header\n", "element count -3 is negative"},
      {"ply\nformat ascii 1.0\nelement vertex 99999999999\nend_header\n", "more than the limit"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n", "lacks property x, y or z"},
      {"ply\nformat ascii 1.0\nproperty float x\n", "'property' before any 'element'"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\n", "unknown property type 'quad'"},
      {head + "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n",
       "vertex index 5"},
      {head + "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n-1 0 1 2\n",
       "list count -1"},
      {head + "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n", "truncated"},
      {head + "end_header\n0 0 0\n1 0 0\n0 1 0\n", "no faces"},
      {"ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
       "end_header\nabc",
       "truncated"},
  };
  for (const Case& c : cases) {
    auto in = stream(c.file, "m.ply");
    const std::string e = errorOf([&] { io::readPly(*in); });
    EXPECT_EQ(e.rfind("m.ply: ", 0), 0u) << e;
    EXPECT_NE(e.find(c.message), std::string::npos) << "got: " << e << "\nexpected: " << c.message;
  }
}

}  // namespace
}  // namespace gradel

namespace gradel {
namespace {

// Inputs that once cost the fuzz_ply target seconds per execution (fuzz/fuzz_reader.cpp): they
// still read and voxelise right, and the crossing cap is a clear InputError.
std::string tetraPlyHeader(const std::string& before, int faces, const std::string& listTypes) {
  return "ply\nformat binary_little_endian 1.0\n" + before +
         "element vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face " +
         std::to_string(faces) + "\nproperty list " + listTypes + " vertex_indices\nend_header\n";
}
std::string tetraVertices() {
  const float v[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  return std::string(reinterpret_cast<const char*>(v), sizeof v);
}
TriangleMesh readPlyText(const std::string& text) {
  auto in = io::memoryStream(reinterpret_cast<const uint8_t*>(text.data()), text.size(), "t.ply");
  return io::readPly(*in);
}

TEST(PlySpeed, RowsWithoutPropertiesAreSkippedWhateverTheirCount) {
  const std::string faces = std::string("\x03\x00\x02\x01\x03\x00\x01\x03\x03\x00\x03\x02\x03\x01\x02\x03", 16);
  const TriangleMesh m =
      readPlyText(tetraPlyHeader("element junk 65536\n", 4, "uchar uchar") + tetraVertices() + faces);
  EXPECT_EQ(m.vertices.size(), 4u);
  EXPECT_EQ(m.triangles.size(), 4u);
  // A row-less element still counts against the limit.
  io::ReadLimits small;
  small.maxMeshElements = 1000;
  const std::string text = tetraPlyHeader("element junk 65536\n", 4, "uchar uchar") + tetraVertices() + faces;
  auto in2 = io::memoryStream(reinterpret_cast<const uint8_t*>(text.data()), text.size(), "t.ply");
  EXPECT_NE(errorOf([&] { io::readPly(*in2, small); }).find("element 'junk' count 65536: more than the limit of 1000"),
            std::string::npos);
}

TEST(PlySpeed, RepeatedFacesHitTheCrossingCapAndFewCopiesGiveTheShell) {
  // 16000 copies of the tetrahedron's faces: 1.0e6 crossings per axis at resolution 16.
  std::string faces;
  const uint8_t tet[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  for (int i = 0; i < 16000; ++i)
    faces += std::string{char(3), char(tet[i % 4][0]), char(tet[i % 4][1]), char(tet[i % 4][2])};
  const TriangleMesh many = readPlyText(tetraPlyHeader("", 16000, "uchar uchar") + tetraVertices() + faces);
  ASSERT_EQ(many.triangles.size(), 16000u);
  io::VoxelizeSettings s{16, 0.01};
  s.minCrossingCap = 1 << 14;
  EXPECT_NE(errorOf([&] { io::voxelize(many, s, "t.ply"); }).find("t.ply: more than 16384 ray crossings"),
            std::string::npos);
  // Four copies only: the tetrahedron, the same voxels as one copy (a union of identical shells).
  TriangleMesh one = many, four = many;
  one.triangles.resize(4);
  four.triangles.resize(16);
  const VoxelVolume a = io::voxelize(one, s, "one"), b = io::voxelize(four, s, "four");
  EXPECT_GT(a.countFilled(), 100u);
  EXPECT_EQ(a.data(), b.data());
}

TEST(Voxelize, ThinTrianglesAcrossTheGridCrossOnlyTheirRays) {
  // A closed sliver prism along the grid's diagonal: the per-row span must not drop any ray.
  const Real w = 0.037;
  const Vec3 A(0, 0.0031, 0), B(1, 1, 0), C(w, 0, 0);
  TriangleMesh m;
  m.vertices = {A, B, C, A + Vec3(0, 0, 1), B + Vec3(0, 0, 1), C + Vec3(0, 0, 1)};
  m.triangles = {{0, 1, 2}, {3, 5, 4}, {0, 2, 5}, {0, 5, 3}, {2, 1, 4}, {2, 4, 5}, {1, 0, 3}, {1, 3, 4}};
  auto side = [](const Vec3& a, const Vec3& b, Real x, Real y) {
    return (b.x() - a.x()) * (y - a.y()) - (b.y() - a.y()) * (x - a.x());
  };
  for (int res : {16, 64, 200}) {
    const VoxelVolume v = io::voxelize(m, {res, 0.01}, "sliver");
    ASSERT_EQ(v.nx(), res);
    ASSERT_EQ(v.ny(), res);
    const Real h = 1.0 / res;
    size_t expected = 0, got = 0;
    for (int j = 0; j < v.ny(); ++j)
      for (int i = 0; i < v.nx(); ++i) {
        const Real x = (i + 0.5) * h, y = (j + 0.5) * h;
        const Real s0 = side(A, B, x, y), s1 = side(B, C, x, y), s2 = side(C, A, x, y);
        const bool inside = (s0 > 0 && s1 > 0 && s2 > 0) || (s0 < 0 && s1 < 0 && s2 < 0);
        expected += inside;
        got += v.at(i, j, v.nz() / 2);
        EXPECT_EQ(v.at(i, j, v.nz() / 2), inside) << "resolution " << res << " voxel " << i << ", " << j;
      }
    EXPECT_GT(expected, size_t(res / 3)) << "resolution " << res;
  }
}

}  // namespace
}  // namespace gradel
