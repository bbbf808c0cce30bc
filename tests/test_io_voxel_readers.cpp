// Voxel-grid readers (binvox, MagicaVoxel .vox) and the byte streams under every reader:
// axis conventions on hand-made files, and clear errors for malformed, truncated and hostile
// input (absurd or negative sizes, counts that do not fit).
#include <gtest/gtest.h>

#include "gradel/io/binvox.h"
#include "gradel/io/byte_stream.h"
#include "gradel/io/vox.h"
#include "test_io_support.h"

namespace gradel {
namespace {

using test::Bytes;
using test::errorOf;
using test::stream;

// ---- byte streams ---------------------------------------------------------------

TEST(ByteStream, GzipRoundTripsAndRejectsTruncatedOrTrailingData) {
  Bytes data;
  for (int i = 0; i < 300000; ++i) data.push_back(char(i * 7 % 251));
  const Bytes z = test::gzipped(data);
  auto in = io::gzipStream(stream(z));
  Bytes back(data.size(), '\0');
  in->readExact(back.data(), back.size(), "data");
  EXPECT_EQ(back, data);
  char c;
  EXPECT_EQ(in->read(&c, 1), 0u);

  const std::string cut = errorOf([&] {
    auto t = io::gzipStream(stream(z.substr(0, z.size() / 2), "half.gz"));
    Bytes b(data.size(), '\0');
    t->readExact(b.data(), b.size(), "data");
  });
  EXPECT_NE(cut.find("half.gz: gzip: compressed data ends early"), std::string::npos) << cut;

  const std::string trailing = errorOf([&] {
    auto t = io::gzipStream(stream(z + "junk"));
    Bytes b(data.size() + 1, '\0');
    t->read(b.data(), b.size());
  });
  EXPECT_NE(trailing.find("unexpected bytes after the compressed data"), std::string::npos) << trailing;

  const std::string corrupt = errorOf([&] {
    Bytes bad = z;
    for (size_t i = 20; i < 60; ++i) bad[i] = char(0xff);
    auto t = io::gzipStream(stream(bad));
    Bytes b(data.size(), '\0');
    t->read(b.data(), b.size());
  });
  EXPECT_NE(corrupt.find("gzip:"), std::string::npos) << corrupt;
}

TEST(ByteStream, GzipSmallReadsDrainOutputZlibHeldBack) {
  // One byte at a time: zlib consumes the whole input while output is still pending, which must
  // not be mistaken for a truncated stream.
  const Bytes data(5000, 'a');
  auto in = io::gzipStream(stream(test::gzipped(data)));
  Bytes back;
  char c;
  while (in->read(&c, 1) == 1) back.push_back(c);
  EXPECT_EQ(back, data);
}

TEST(ByteStream, OpenFileStreamNamesTheReasonAFileCannotBeRead) {
  const std::string e = errorOf([] { io::openFileStream("/nonexistent/gradel.nrrd"); });
  EXPECT_EQ(e, "/nonexistent/gradel.nrrd: cannot read: No such file or directory");
}

// ---- binvox -----------------------------------------------------------------------

// A D x H x W binvox whose voxel (x, y, z) is filled when f(x, y, z); file order x, z, y.
template <class F>
Bytes binvox(int d, int h, int w, F f) {
  Bytes b = "#binvox 1\ndim " + std::to_string(d) + " " + std::to_string(h) + " " + std::to_string(w) +
            "\ntranslate 0 0 0\nscale 1\ndata\n";
  for (int x = 0; x < d; ++x)
    for (int z = 0; z < h; ++z)
      for (int y = 0; y < w; ++y) b += std::string{char(f(x, y, z) ? 1 : 0), char(1)};
  return b;
}

TEST(Binvox, ReadBinvoxMapsFileAxesToGradelAxes) {
  // dim D H W = 2 3 4: nx = 2, nz = 3, ny = 4 (x slowest, z, y fastest).
  auto filled = [](int x, int y, int z) { return (x + 2 * y + 3 * z) % 5 == 0; };
  auto in = stream(binvox(2, 3, 4, filled));
  const VoxelVolume v = io::readBinvox(*in, 0.02);
  ASSERT_EQ(v.dims(), (std::array<int, 3>{2, 4, 3}));
  EXPECT_EQ(v.voxelSize(), 0.02);
  for (int x = 0; x < 2; ++x)
    for (int y = 0; y < 4; ++y)
      for (int z = 0; z < 3; ++z) EXPECT_EQ(v.at(x, y, z), filled(x, y, z)) << x << y << z;
}

TEST(Binvox, ReadBinvoxLongRunsSpanRows) {
  Bytes b = "#binvox 1\ndim 8 8 8\ndata\n";
  b += std::string{char(1), char(255)} + std::string{char(1), char(1)} + std::string{char(0), char(255)} +
       std::string{char(0), char(1)};
  auto in = stream(b);
  EXPECT_EQ(io::readBinvox(*in, 0.01).countFilled(), 256u);
}

TEST(Binvox, ReadBinvoxRejectsMalformedFiles) {
  const Bytes ok = binvox(2, 2, 2, [](int, int, int) { return true; });
  struct Case {
    Bytes file;
    std::string message;
  };
  const Case cases[] = {
      {"", "not a binvox file"},
      {"#binvox 1\n", "header ends before the 'data' line"},
      {"#binvox 1\ndata\n", "no 'dim' line"},
      {"#binvox 1\ndim 2 2\ndata\n", "'dim' needs 3 integers"},
      {"#binvox 1\ndim -2 2 2\ndata\n", "header: dim: -2 x 2 x 2 (expected every size in [1, 4096])"},
      {"#binvox 1\ndim 99999999999999999999 2 2\ndata\n", "out of range"},
      {"#binvox 1\ndim 4096 4096 4096\ndata\n", "more than the limit"},
      {"#binvox 1\ndim 2 2 x\ndata\n", "'x' is not an integer"},
      {"#binvox 1\ndim 2 2 2\nfrobnicate\ndata\n", "unknown line 'frobnicate'"},
      {"#binvox 1\ndim 2 2 2\nscale nan\ndata\n", "not a finite number"},
      {ok.substr(0, ok.size() - 2), "covers 7 of dim's 8 voxels"},
      {ok.substr(0, ok.size() - 1), "in the middle of a (value, count) pair"},
      {ok + std::string{char(1), char(1)}, "unexpected bytes after the last run"},
      {"#binvox 1\ndim 2 2 2\ndata\n" + std::string{char(1), char(9)}, "runs cover more than dim's 8 voxels"},
      {"#binvox 1\n" + std::string(300, 'a'), "longer than 256 bytes"},
  };
  for (const Case& c : cases) {
    auto in = stream(c.file, "x.binvox");
    const std::string e = errorOf([&] { io::readBinvox(*in, 0.01); });
    EXPECT_EQ(e.rfind("x.binvox: ", 0), 0u) << e;
    EXPECT_NE(e.find(c.message), std::string::npos) << "got: " << e << "\nexpected: " << c.message;
  }
}

// ---- MagicaVoxel .vox -------------------------------------------------------------

Bytes chunk(const std::string& id, const Bytes& content, const Bytes& children = "") {
  Bytes b = id;
  test::putLE(b, content.size(), 4);
  test::putLE(b, children.size(), 4);
  return b + content + children;
}

Bytes sizeChunk(int x, int y, int z) {
  Bytes c;
  test::putLE(c, uint32_t(x), 4), test::putLE(c, uint32_t(y), 4), test::putLE(c, uint32_t(z), 4);
  return chunk("SIZE", c);
}

Bytes xyziChunk(const std::vector<std::array<int, 3>>& pts) {
  Bytes c;
  test::putLE(c, pts.size(), 4);
  for (const auto& p : pts) c += std::string{char(p[0]), char(p[1]), char(p[2]), char(1)};
  return chunk("XYZI", c);
}

Bytes voxFile(const Bytes& children) {
  Bytes b = "VOX ";
  test::putLE(b, 150, 4);
  return b + chunk("MAIN", "", children);
}

TEST(Vox, ReadVoxTurnsZUpIntoYUp) {
  // A 3 x 4 x 5 model (x, y, z; z up) with voxels at (0,0,0) and (2,3,4).
  const Bytes f = voxFile(sizeChunk(3, 4, 5) + xyziChunk({{0, 0, 0}, {2, 3, 4}}) + chunk("RGBA", Bytes(1024, '\x7f')));
  auto in = stream(f);
  const VoxelVolume v = io::readVox(*in, 0.01);
  ASSERT_EQ(v.dims(), (std::array<int, 3>{3, 5, 4}));  // gradel (i, j, k) = (x, z, 3 - y)
  EXPECT_EQ(v.countFilled(), 2u);
  EXPECT_TRUE(v.at(0, 0, 3));
  EXPECT_TRUE(v.at(2, 4, 0));
}

TEST(Vox, ReadVoxPicksTheRequestedModelAndSkipsUnknownChunks) {
  Bytes pack;
  test::putLE(pack, 2, 4);
  const Bytes f =
      voxFile(chunk("PACK", pack) + sizeChunk(1, 1, 1) + xyziChunk({{0, 0, 0}}) + chunk("nTRN", "abcdefgh") +
              sizeChunk(2, 2, 2) + xyziChunk({{0, 0, 0}, {1, 1, 1}, {1, 0, 1}}));
  auto first = stream(f);
  EXPECT_EQ(io::readVox(*first, 0.01, 0).countFilled(), 1u);
  auto second = stream(f);
  EXPECT_EQ(io::readVox(*second, 0.01, 1).countFilled(), 3u);
  auto third = stream(f);
  EXPECT_NE(errorOf([&] { io::readVox(*third, 0.01, 2); }).find("model 2 requested, the file has 2"),
            std::string::npos);
}

TEST(Vox, ReadVoxRejectsMalformedFiles) {
  Bytes negative = "VOX ";
  test::putLE(negative, 150, 4);
  negative += "MAIN";
  test::putLE(negative, 0, 4);
  test::putLE(negative, uint32_t(-5), 4);
  Bytes hugeCount;
  test::putLE(hugeCount, 0x7fffffff, 4);
  struct Case {
    Bytes file;
    std::string message;
  };
  const Case cases[] = {
      {"VOX", "truncated"},
      {Bytes("RIFF\x96\0\0\0", 8), "not a MagicaVoxel file"},
      {negative, "negative size"},
      {voxFile(sizeChunk(2, 2, 2)).substr(0, 30), "do not fit in the 10 bytes left"},
      {voxFile(sizeChunk(2, 2, 2) + chunk("XYZI", hugeCount)), "voxel count 2147483647 does not fit"},
      {voxFile(xyziChunk({{0, 0, 0}})), "XYZI chunk without a SIZE chunk"},
      {voxFile(sizeChunk(2, 2, 2) + xyziChunk({{0, 5, 0}})), "lies outside the model's SIZE"},
      {voxFile(sizeChunk(0, 2, 2) + xyziChunk({})), "expected every size in [1, 4096]"},
      {voxFile(sizeChunk(-3, 2, 2) + xyziChunk({})), "-3"},
      {voxFile(sizeChunk(2, 2, 2) + xyziChunk({})), "has no voxels"},
      {voxFile(""), "no model"},
      {voxFile(chunk("SIZE", "abc")), "SIZE chunk: 3 bytes"},
  };
  for (const Case& c : cases) {
    auto in = stream(c.file, "m.vox");
    const std::string e = errorOf([&] { io::readVox(*in, 0.01); });
    EXPECT_EQ(e.rfind("m.vox: ", 0), 0u) << e;
    EXPECT_NE(e.find(c.message), std::string::npos) << "got: " << e << "\nexpected: " << c.message;
  }
}

}  // namespace
}  // namespace gradel
