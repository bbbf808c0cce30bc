// Grey-level readers (NRRD, NIfTI-1/2, raw): sample types, byte orders, encodings, the
// threshold / range rule, scaling, and clear errors for malformed, truncated and hostile headers.
#include <gtest/gtest.h>

#include <cstring>

#include "gradel/io/nifti.h"
#include "gradel/io/nrrd.h"
#include "gradel/io/raw_volume.h"
#include "test_io_support.h"

namespace gradel {
namespace {

using test::Bytes;
using test::errorOf;
using test::stream;

// Values 0, 100, 200, ... of a 4 x 3 x 2 volume, x fastest, as int16.
Bytes int16Samples(bool bigEndian) {
  Bytes b;
  for (int i = 0; i < 24; ++i)
    bigEndian ? test::putBE(b, uint16_t(int16_t(i * 100 - 1000)), 2)
              : test::putLE(b, uint16_t(int16_t(i * 100 - 1000)), 2);
  return b;
}

Bytes nrrd(const std::string& fields, const Bytes& data) {
  return "NRRD0004\n# test\nkey:=value\n" + fields + "\n" + data;
}

io::GreyRule threshold(double t) {
  io::GreyRule r;
  r.threshold = t;
  return r;
}

TEST(Nrrd, ReadNrrdRawGzipAsciiAndBothByteOrdersAgree) {
  const std::string head = "type: short\ndimension: 3\nsizes: 4 3 2\nspacings: 1 1 2\n";
  const Bytes files[] = {
      nrrd(head + "encoding: raw\nendian: little\n", int16Samples(false)),
      nrrd(head + "encoding: raw\nendian: big\n", int16Samples(true)),
      nrrd(head + "encoding: gzip\nendian: little\n", test::gzipped(int16Samples(false))),
      nrrd(head + "encoding: ascii\n",
           [] {
             std::string t;
             for (int i = 0; i < 24; ++i) t += std::to_string(i * 100 - 1000) + (i % 4 == 3 ? "\n" : " ");
             return t;
           }()),
  };
  for (const Bytes& f : files) {
    auto in = stream(f);
    const VoxelVolume v = io::readNrrd(*in, threshold(300), 0.01);
    ASSERT_EQ(v.dims(), (std::array<int, 3>{4, 3, 2}));
    for (int i = 0; i < 24; ++i) EXPECT_EQ(v.data()[i], i * 100 - 1000 >= 300 ? 1 : 0) << i;
  }
}

TEST(Nrrd, ReadNrrdRangeAndDefaultNonZeroRules) {
  const Bytes f = nrrd("type: short\ndimension: 3\nsizes: 4 3 2\nencoding: raw\nendian: little\n", int16Samples(false));
  io::GreyRule range;
  range.rangeLo = -200;
  range.rangeHi = 200;
  auto a = stream(f);
  EXPECT_EQ(io::readNrrd(*a, range, 0.01).countFilled(), 5u);  // -200 .. 200
  auto b = stream(f);
  EXPECT_EQ(io::readNrrd(*b, {}, 0.01).countFilled(), 23u);  // all but the 0
}

TEST(Nrrd, ReadNrrd2dImageIsOneSliceAndTypeAliasesWork) {
  const Bytes f = nrrd("type: unsigned char\ndimension: 2\nsizes: 3 2\nencoding: raw\n", Bytes("\0\1\2\0\5\0", 6));
  auto in = stream(f);
  const VoxelVolume v = io::readNrrd(*in, {}, 0.01);
  EXPECT_EQ(v.dims(), (std::array<int, 3>{3, 2, 1}));
  EXPECT_EQ(v.countFilled(), 3u);
}

TEST(Nrrd, ReadNrrdEmptyResultNamesTheValueRange) {
  const Bytes f = nrrd("type: short\ndimension: 3\nsizes: 4 3 2\nencoding: raw\nendian: little\n", int16Samples(false));
  auto in = stream(f, "ct.nrrd");
  EXPECT_EQ(errorOf([&] { io::readNrrd(*in, threshold(5000), 0.01); }),
            "ct.nrrd: the volume is empty: no voxel passes the threshold 5000 (values range from -1000 to 1300)");
}

TEST(Nrrd, ReadNrrdRejectsMalformedFiles) {
  const std::string ok = "type: short\ndimension: 3\nsizes: 4 3 2\nencoding: raw\nendian: little\n";
  const Bytes data = int16Samples(false);
  struct Case {
    Bytes file;
    std::string message;
  };
  const Case cases[] = {
      {"NRRD", "not a NRRD file"},
      {"NRRD0009\n", "not a NRRD file"},
      {"NRRD0004\ntype: short\n", "header ends without the blank line"},
      {nrrd("type: short\ndimension: 3\nencoding: raw\nendian: little\n", data), "required field 'sizes' is missing"},
      {nrrd("type: block\ndimension: 3\nsizes: 4 3 2\nencoding: raw\n", data), "unsupported type 'block'"},
      {nrrd("type: short\ndimension: 4\nsizes: 4 3 2 1\nencoding: raw\nendian: little\n", data), "dimension: 4"},
      {nrrd("type: short\ndimension: 3\nsizes: 4 3\nencoding: raw\nendian: little\n", data),
       "2 values for dimension 3"},
      {nrrd("type: short\ndimension: 3\nsizes: 4 -3 2\nencoding: raw\nendian: little\n", data), "4 x -3 x 2"},
      {nrrd("type: short\ndimension: 3\nsizes: 4096 4096 4096\nencoding: raw\nendian: little\n", data),
       "more than the limit"},
      {nrrd("type: short\ndimension: 3\nsizes: 4 3 2\nencoding: raw\n", data), "required field 'endian' is missing"},
      {nrrd("type: short\ndimension: 3\nsizes: 4 3 2\nencoding: bzip2\nendian: little\n", data),
       "'bzip2' is not supported"},
      {nrrd(ok, data.substr(0, 40)), "truncated"},
      {nrrd(ok, data + "xx"), "2 bytes more than"},
      {nrrd(ok + "data file: ct.raw\n", ""), "detached data is not supported"},
      {nrrd(ok + "byte skip: -1\n", data), "negative skips are not supported"},
      {nrrd(ok + "type: float\n", data), "field 'type' given twice"},
      {nrrd(ok + "this line has no colon\n", data), "is not 'field: value'"},
      {nrrd("type: short\ndimension: 3\nsizes: 4 3 2\nencoding: gzip\nendian: little\n", data), "gzip:"},
      {nrrd("type: short\ndimension: 3\nsizes: 4 3 2\nencoding: ascii\n", "1 2 3 x"), "'x' is not a number"},
      {nrrd("type: short\ndimension: 3\nsizes: 4 3 2\nencoding: ascii\n", "1 2 3"), "expected 24 ascii samples, got 3"},
  };
  for (const Case& c : cases) {
    auto in = stream(c.file, "v.nrrd");
    const std::string e = errorOf([&] { io::readNrrd(*in, {}, 0.01); });
    EXPECT_EQ(e.rfind("v.nrrd: ", 0), 0u) << e;
    EXPECT_NE(e.find(c.message), std::string::npos) << "got: " << e << "\nexpected: " << c.message;
  }
}

// ---- NIfTI ------------------------------------------------------------------------

// A NIfTI-1 .nii of 4 x 3 x 2 uint16 samples 0, 1, ..., 23 (+ 1000), slope 1, inter -1000.
Bytes nifti1(bool bigEndian, int16_t datatype = 512, float voxOffset = 352, int16_t dim0 = 3) {
  Bytes h(348, '\0');
  auto put = [&](size_t at, uint64_t v, int n) {
    Bytes b;
    bigEndian ? test::putBE(b, v, n) : test::putLE(b, v, n);
    std::memcpy(&h[at], b.data(), size_t(n));
  };
  auto putF = [&](size_t at, float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    put(at, u, 4);
  };
  put(0, 348, 4);
  const int16_t dims[8] = {dim0, 4, 3, 2, 1, 1, 1, 1};
  for (int i = 0; i < 8; ++i) put(40 + 2 * size_t(i), uint16_t(dims[i]), 2);
  put(70, uint16_t(datatype), 2);
  put(72, 16, 2);
  putF(108, voxOffset);
  putF(112, 1.0f);
  putF(116, -1000.0f);
  std::memcpy(&h[344], "n+1", 4);
  Bytes b = h + Bytes(4, '\0');
  for (int i = 0; i < 24; ++i)
    bigEndian ? test::putBE(b, uint16_t(1000 + i), 2) : test::putLE(b, uint16_t(1000 + i), 2);
  return b;
}

Bytes nifti2() {
  Bytes h(540, '\0');
  auto put = [&](size_t at, uint64_t v, int n) {
    Bytes b;
    test::putLE(b, v, n);
    std::memcpy(&h[at], b.data(), size_t(n));
  };
  put(0, 540, 4);
  std::memcpy(&h[4], "n+2\0\r\n\032\n", 8);
  put(12, 2, 2);  // uint8
  put(14, 8, 2);
  const int64_t dims[8] = {3, 4, 3, 2, 1, 1, 1, 1};
  for (int i = 0; i < 8; ++i) put(16 + 8 * size_t(i), uint64_t(dims[i]), 8);
  put(168, 544, 8);
  Bytes b = h + Bytes(4, '\0');
  for (int i = 0; i < 24; ++i) b.push_back(char(i));
  return b;
}

TEST(Nifti, ReadNiftiAppliesSclSlopeAndInterInEitherByteOrder) {
  for (bool big : {false, true}) {
    auto in = stream(nifti1(big));
    const VoxelVolume v = io::readNifti(*in, threshold(20), 0.01);  // value = stored - 1000
    ASSERT_EQ(v.dims(), (std::array<int, 3>{4, 3, 2}));
    EXPECT_EQ(v.countFilled(), 4u) << big;  // 20, 21, 22, 23
    EXPECT_TRUE(v.at(3, 2, 1));
  }
}

TEST(Nifti, ReadNiftiReadsNifti2AndGzippedFiles) {
  auto in = stream(nifti2());
  EXPECT_EQ(io::readNifti(*in, threshold(12), 0.01).countFilled(), 12u);
  auto z = io::gzipStream(stream(test::gzipped(nifti1(false))));
  EXPECT_EQ(io::readNifti(*z, threshold(0), 0.01).countFilled(), 24u);
}

TEST(Nifti, ReadNiftiRejectsMalformedFiles) {
  Bytes badSize = nifti1(false);
  badSize[0] = 7;
  Bytes pair = nifti1(false);
  std::memcpy(&pair[344], "ni1", 4);
  Bytes bigDim = nifti1(false);
  bigDim[42] = char(0xff), bigDim[43] = char(0x7f);  // dim[1] = 32767
  bigDim[44] = char(0xff), bigDim[45] = char(0x7f);
  bigDim[46] = char(0xff), bigDim[47] = char(0x7f);
  Bytes negDim = nifti1(false);
  negDim[44] = char(0xfe), negDim[45] = char(0xff);  // dim[2] = -2
  struct Case {
    Bytes file;
    std::string message;
  };
  const Case cases[] = {
      {Bytes(100, '\0'), "truncated"},
      {badSize, "sizeof_hdr is"},
      {pair, "two-file (.hdr/.img) NIfTI pair is not supported"},
      {nifti1(false, 32), "datatype 32 is not supported"},
      {nifti1(false, 512, 100), "vox_offset 100"},
      {nifti1(false, 512, 352.5f), "vox_offset 352.5"},
      {nifti1(false, 512, 1e30f), "vox_offset"},
      {nifti1(false, 512, 352, 9), "dim[0] is 9"},
      {bigDim, "expected every size in [1, 4096]"},
      {negDim, "4 x -2 x 2"},
      {nifti1(false).substr(0, 380), "truncated"},
  };
  for (const Case& c : cases) {
    auto in = stream(c.file, "b.nii");
    const std::string e = errorOf([&] { io::readNifti(*in, {}, 0.01); });
    EXPECT_EQ(e.rfind("b.nii: ", 0), 0u) << e;
    EXPECT_NE(e.find(c.message), std::string::npos) << "got: " << e << "\nexpected: " << c.message;
  }
}

// ---- raw ------------------------------------------------------------------------

TEST(Raw, ReadRawVolumeReadsTheGivenLayoutAndChecksTheFileSize) {
  io::RawLayout layout;
  layout.dims = {4, 3, 2};
  layout.samples.type = io::ScalarType::Int16;
  layout.samples.bigEndian = true;
  layout.headerBytes = 5;
  auto in = stream("HEAD!" + int16Samples(true));
  EXPECT_EQ(io::readRawVolume(*in, layout, threshold(0), 0.01).countFilled(), 14u);

  auto wrong = stream("HEAD!" + int16Samples(true) + "x", "r.raw");
  EXPECT_EQ(
      errorOf([&] { io::readRawVolume(*wrong, layout, {}, 0.01); }),
      "r.raw: size: the file has 54 bytes; header_bytes 5 + 4 x 3 x 2 int16 samples need 53 (check dims and type)");
  layout.dims = {0, 3, 2};
  auto zero = stream("x", "r.raw");
  EXPECT_NE(errorOf([&] { io::readRawVolume(*zero, layout, {}, 0.01); }).find("dims: 0 x 3 x 2"), std::string::npos);
}

TEST(GreyLevels, NanSamplesAreEmptyAndFloatTypesWork) {
  Bytes b;
  for (float f : {1.0f, std::numeric_limits<float>::quiet_NaN(), -2.0f, 0.0f}) test::putFloatLE(b, f);
  io::RawLayout layout;
  layout.dims = {4, 1, 1};
  layout.samples.type = io::ScalarType::Float32;
  auto in = stream(b);
  const VoxelVolume v = io::readRawVolume(*in, layout, {}, 0.01);
  EXPECT_EQ(v.countFilled(), 2u);
  EXPECT_FALSE(v.at(1, 0, 0));
  EXPECT_NE(errorOf([] { io::parseScalarType("half"); }).find("unknown sample type 'half'"), std::string::npos);
}

}  // namespace
}  // namespace gradel
