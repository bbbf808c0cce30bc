// The committed samples (samples/make_samples.py) through readVolumeFile, and scenes whose body
// comes from a file: formats agree with each other where they hold the same data, the CT
// threshold matters, and scene files naming sources are parsed strictly.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "gradel/io/volume_file.h"
#include "gradel/scene.h"
#include "test_io_support.h"

namespace gradel {
namespace {

namespace fs = std::filesystem;
using test::errorOf;

std::string sample(const std::string& name) { return std::string(GRADEL_SOURCE_DIR) + "/samples/" + name; }

io::VolumeFileSpec spec(const std::string& name) {
  io::VolumeFileSpec s;
  s.path = sample(name);
  return s;
}

TEST(Samples, CtThresholdSelectsBoneOrLimbAndFormatsAgree) {
  io::VolumeFileSpec bone = spec("ct.nrrd");
  bone.grey.threshold = 300;
  io::VolumeFileSpec limb = spec("ct.nrrd");
  limb.grey.threshold = -300;
  const VoxelVolume b = io::readVolumeFile(bone), l = io::readVolumeFile(limb);
  EXPECT_EQ(b.dims(), (std::array<int, 3>{40, 40, 40}));
  EXPECT_GT(b.countFilled(), 2000u);
  EXPECT_GT(l.countFilled(), 3 * b.countFilled());  // the threshold choice matters

  io::VolumeFileSpec nii = spec("ct.nii.gz");  // uint16 + scl_inter -1024: same Hounsfield units
  nii.grey.threshold = 300;
  EXPECT_EQ(io::readVolumeFile(nii).data(), b.data());
  io::VolumeFileSpec raw = spec("ct.raw");  // the bone mask at 300 HU
  raw.raw.dims = {40, 40, 40};
  EXPECT_EQ(io::readVolumeFile(raw).data(), b.data());
}

TEST(Samples, MeshesVoxeliseAndMatchTheBinvox) {
  io::VolumeFileSpec obj = spec("torus.obj"), stl = spec("torus.stl");
  obj.resolution = stl.resolution = 24;
  const VoxelVolume o = io::readVolumeFile(obj), s = io::readVolumeFile(stl);
  EXPECT_EQ(o.data(), s.data());
  const VoxelVolume bv = io::readVolumeFile(spec("torus.binvox"));
  ASSERT_EQ(o.dims(), bv.dims());  // 24 x 7 x 24
  size_t diff = 0;
  for (size_t i = 0; i < o.size(); ++i) diff += o.data()[i] != bv.data()[i];
  // binvox is the analytic torus, the mesh a 32 x 16 faceting of it: only boundary voxels differ.
  EXPECT_LT(diff, o.countFilled() / 10);
  EXPECT_FALSE(o.at(12, 3, 12));  // the hole in the middle
  io::VolumeFileSpec pawn = spec("pawn.ply");
  pawn.resolution = 20;
  const VoxelVolume p = io::readVolumeFile(pawn);
  EXPECT_EQ(p.ny(), 20);  // tallest along y
  EXPECT_GT(p.countFilled(), 500u);
}

TEST(Samples, VoxModelStandsUp) {
  const VoxelVolume v = io::readVolumeFile(spec("mushroom.vox"));
  ASSERT_EQ(v.dims(), (std::array<int, 3>{16, 16, 16}));
  // The cap (wide) is on top (high j), the stalk (narrow) below.
  auto rowCount = [&](int j) {
    size_t n = 0;
    for (int k = 0; k < 16; ++k)
      for (int i = 0; i < 16; ++i) n += v.at(i, j, k);
    return n;
  };
  EXPECT_GT(rowCount(10), 3 * rowCount(3));
  EXPECT_GT(rowCount(3), 0u);
  EXPECT_EQ(rowCount(15), 0u);
}

TEST(Samples, ReadVolumeFileChecksFormatAndDimension) {
  io::VolumeFileSpec unknown = spec("make_samples.py");
  EXPECT_NE(errorOf([&] { io::readVolumeFile(unknown); }).find("cannot tell the format"), std::string::npos);
  io::VolumeFileSpec flat = spec("mushroom.vox");
  flat.dim = 2;
  EXPECT_NE(errorOf([&] { io::readVolumeFile(flat); }).find("nz = 16"), std::string::npos);
  io::VolumeFileSpec wrong = spec("ct.nrrd");
  wrong.format = io::VolumeFormat::Binvox;
  EXPECT_NE(errorOf([&] { io::readVolumeFile(wrong); }).find("not a binvox file"), std::string::npos);
}

// ---- scenes -------------------------------------------------------------------------

Scene parseIn(const std::string& body, int dim = 3) {
  // As if the scene file sat in scenes/ (sources are relative to the scene's folder).
  return parseScene("{\"dim\": " + std::to_string(dim) + ", \"body\": " + body + "}",
                    std::string(GRADEL_SOURCE_DIR) + "/scenes/test.json");
}

TEST(SceneSource, ParseSceneFileSourceBuildsTheBody) {
  const Scene s = parseIn(R"({"source": {"file": "../samples/ct.nrrd", "threshold": 300}, "voxel_size": 0.005})");
  ASSERT_TRUE(s.bodies[0].source);
  EXPECT_NE(s.bodies[0].source->describe().find("samples/ct.nrrd"), std::string::npos);
  const BuiltScene b = buildScene(s);
  EXPECT_EQ(b.bodies[0].volume.voxelSize(), 0.005);
  EXPECT_GT(b.world->state().positions.size(), 100u);
}

TEST(SceneSource, ParseScene2dSceneTakesAOneSliceVolume) {
  const fs::path dir = fs::temp_directory_path() / ("gradel-io-2d-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "img.nrrd", std::ios::binary)
      << "NRRD0004\ntype: uchar\ndimension: 2\nsizes: 6 5\nencoding: ascii\n\n"
      << "0 1 1 1 1 0\n1 1 1 1 1 1\n1 1 1 1 1 1\n1 1 1 1 1 1\n0 1 1 1 1 0\n";
  const Scene s =
      parseScene(R"({"dim": 2, "body": {"source": {"file": "img.nrrd", "range": [1, 1]}}})", (dir / "s.json").string());
  const BuiltScene b = buildScene(s);
  EXPECT_EQ(b.bodies[0].volume.dim(), 2);
  EXPECT_EQ(b.bodies[0].volume.countFilled(), 26u);
  fs::remove_all(dir);
}

TEST(SceneSource, ParseSceneRejectsBadSourcesNamingTheKey) {
  struct Case {
    std::string body;
    std::string message;
  };
  const Case cases[] = {
      {R"({"source": {"file": "../samples/nope.nrrd"}})",
       "body.source.file: \"../samples/nope.nrrd\" is not a readable file"},
      {R"({"source": {"file": "../samples/ct.nrrd", "treshold": 3}})",
       "body.source.treshold: unknown key (did you mean \"threshold\"?)"},
      {R"({"source": {"file": "../samples/torus.binvox", "threshold": 3}})",
       "body.source.threshold: not allowed here: only grey-level"},
      {R"({"source": {"file": "../samples/ct.nrrd", "threshold": 3, "range": [1, 2]}})",
       "give \"threshold\" or \"range\", not both"},
      {R"({"source": {"file": "../samples/ct.nrrd", "range": [5, 2]}})", "body.source.range: [5,2] is out of range"},
      {R"({"source": {"file": "../samples/ct.raw", "type": "uint8"}})", "body.source.dims: missing"},
      {R"({"source": {"file": "../samples/ct.raw", "dims": [40, 40, 40], "type": "uint9"}})",
       "body.source.type: unknown sample type 'uint9'"},
      {R"({"source": {"file": "../samples/ct.nrrd", "dims": [1, 1, 1]}})", "body.source.dims: not allowed here"},
      {R"({"source": {"file": "../samples/torus.obj", "resolution": 0}})", "body.source.resolution: 0 is out of range"},
      {R"({"source": {"file": "../samples/ct.nrrd", "resolution": 8}})", "body.source.resolution: not allowed here"},
      {R"({"source": {"file": "../samples/ct.nrrd", "format": "dicom"}})",
       "body.source.format: unknown format 'dicom'"},
      {R"({"source": {"file": "../samples/make_samples.py"}})", "body.source.file: "},
      {R"({"source": {"file": "../samples/ct.nrrd"}, "shape": "sphere"})", "body.shape: not allowed here"},
      {R"({"source": {}})", "body.source.file: missing"},
      {R"({"source": {"file": 3}})", "body.source.file: got number 3"},
  };
  for (const Case& c : cases) {
    const std::string e = errorOf([&] { parseIn(c.body); });
    EXPECT_NE(e.find(c.message), std::string::npos) << "got: " << e << "\nexpected: " << c.message;
  }
  EXPECT_NE(
      errorOf([&] { parseIn(R"({"source": {"file": "../samples/torus.obj"}})", 2); }).find("voxelised in 3D only"),
      std::string::npos);
}

TEST(SceneSource, CliMalformedSourceFileIsExitCode2) {
  const fs::path dir = fs::temp_directory_path() / ("gradel-io-cli-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "bad.binvox", std::ios::binary) << "#binvox 1\ndim 4 4 4\ndata\n\x01\x05";
  std::ofstream(dir / "s.json") << R"({"body": {"source": {"file": "bad.binvox"}}, "simulation": {"duration": 0.01}})";
  const std::string cmd =
      "cd '" + dir.string() + "' && '" + GRADEL_CLI_PATH + "' run s.json --out out > o.txt 2> e.txt";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  std::ifstream err(dir / "e.txt");
  const std::string line((std::istreambuf_iterator<char>(err)), std::istreambuf_iterator<char>());
  EXPECT_NE(line.find("bad.binvox: truncated: run-length data covers 5 of dim's 64 voxels"), std::string::npos) << line;
  EXPECT_FALSE(fs::exists(dir / "out"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace gradel
