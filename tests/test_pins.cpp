// Boundary conditions (pins.h): selection, explicit integrators holding pinned vertices on their
// prescribed path, and the scene keys.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>

#include "gradel/pins.h"
#include "gradel/scene.h"
#include "gradel/validation.h"
#include "test_support.h"

namespace gradel {
namespace {

BarSpec smallBar() {
  BarSpec bar;
  bar.across = 2;
  bar.along = 8;
  bar.width = 0.02;
  bar.material.youngsModulus = 1e6;
  return bar;
}

TEST(Pins, SelectPinsBoxHoldsExactlyTheVerticesInside) {
  const std::vector<Vec3> rest = {{0, 0, 0}, {0.01, 0, 0}, {0.02, 0, 0}, {0.01, 0.01, 0}};
  PinSettings p;
  p.min = Vec3(0.005, -1, -1);
  p.max = Vec3(0.01, 1, 1);  // closed: x = 0.01 is inside
  const PinSet s = selectPins({p}, rest);
  EXPECT_EQ(s.vertices, (std::vector<uint32_t>{1, 3}));
  EXPECT_EQ(s.pinOf, (std::vector<uint32_t>{0, 0}));
}

TEST(Pins, SelectPinsEmptyBoxIsInputError) {
  PinSettings p;
  p.min = Vec3(5, 5, 5);
  p.max = Vec3(6, 6, 6);
  EXPECT_THROW(selectPins({p}, {Vec3::Zero()}), InputError);
}

TEST(Pins, ExplicitClampedBarPinnedVerticesStayAtRestAndTipSags) {
  SimulationSettings sim;
  BuiltScene b = buildScene(barScene(smallBar(), sim));
  World& w = *b.world;
  ASSERT_EQ(w.pinned().vertices.size(), 4u);  // the 2 x 2 block corners of the x = 0 face
  for (int i = 0; i < 2000; ++i) w.step();
  for (uint32_t i : w.pinned().vertices) {
    EXPECT_EQ(w.state().positions[i], w.model().restPositions[i]);
    EXPECT_EQ(w.state().velocities[i], Vec3::Zero());
  }
  const std::vector<uint32_t> tip = tipVertices(w.model(), smallBar().length());
  EXPECT_LT(w.state().positions[tip[0]].y(), w.model().restPositions[tip[0]].y() - 1e-4);
}

TEST(Pins, MovingPinFollowsItsPathOffset) {
  SimulationSettings sim;
  sim.gravity.setZero();
  Scene scene = barScene(smallBar(), sim);
  scene.pins[0].path.keys = {Keyframe{0, Vec3::Zero(), std::nullopt}, Keyframe{0.01, Vec3(0, 0.002, 0), std::nullopt}};
  BuiltScene b = buildScene(scene);
  World& w = *b.world;
  w.advanceTo(0.02);
  for (uint32_t i : w.pinned().vertices)
    EXPECT_NEAR((w.state().positions[i] - w.model().restPositions[i] - Vec3(0, 0.002, 0)).norm(), 0, 1e-12);
  // The rest of the bar was dragged up with it.
  const std::vector<uint32_t> tip = tipVertices(w.model(), smallBar().length());
  EXPECT_GT(w.state().positions[tip[0]].y(), w.model().restPositions[tip[0]].y() + 1e-4);
}

const char* kPinScene = R"({
  "body": { "shape": "box", "size": 4, "voxel_size": 0.01 },
  "pins": [ { "min": [-0.001, -0.001, -0.001], "max": [0.001, 0.041, 0.041],
              "path": [ { "t": 0, "position": [0, 0, 0] }, { "t": 1, "position": [0, 0.01, 0] } ] } ]
})";

TEST(Pins, ParseScenePinsReadBoxAndPath) {
  const Scene s = parseScene(kPinScene, "pins.json");
  ASSERT_EQ(s.pins.size(), 1u);
  EXPECT_EQ(s.pins[0].max, Vec3(0.001, 0.041, 0.041));
  ASSERT_EQ(s.pins[0].path.keys.size(), 2u);
  EXPECT_EQ(s.pins[0].path.position(0.5), Vec3(0, 0.005, 0));
  BuiltScene b = buildScene(s);
  EXPECT_EQ(b.world->pinned().vertices.size(), 9u);  // 3 x 3 block corners (2-voxel blocks)
}

TEST(Pins, ParseSceneUnknownKeyInPinNamesItsPath) {
  std::string text = kPinScene;
  text.replace(text.find("\"min\""), 5, "\"mni\"");
  try {
    parseScene(text, "pins.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("pins[0]"), std::string::npos) << e.what();
  }
}

TEST(Pins, BuildScenePinHoldingNoVertexIsInputError) {
  std::string text = kPinScene;
  text.replace(text.find("[-0.001, -0.001, -0.001]"), 24, "[ 0.5,    0.5,    0.5  ]");
  text.replace(text.find("[0.001, 0.041, 0.041]"), 21, "[0.6,   0.6,   0.6  ]");
  EXPECT_THROW(buildScene(parseScene(text, "pins.json")), InputError);
}

// ---- voxel-mask pins ----

TEST(Pins, MaskBoxesSelectTheCornersOfTheirVoxelsAndFollowThePath) {
  // smallBar: 2 x 2 x 8 voxels, 2-voxel blocks, so vertices sit at even lattice coordinates.
  // Mask voxels x in [0, 2] hold the vertices with lattice x <= 3: the planes x = 0 and x = 2.
  SimulationSettings sim;
  sim.gravity.setZero();
  Scene scene = barScene(smallBar(), sim, false);
  auto mask = std::make_shared<PinMask>();
  mask->voxelSize = smallBar().voxelSize();
  mask->boxes = {{Int3(0, 0, 0), Int3(2, 1, 1)}};
  PinSettings pin;
  pin.mask = mask;
  pin.path.keys = {Keyframe{0, Vec3::Zero(), std::nullopt}, Keyframe{0.01, Vec3(0, 0.002, 0), std::nullopt}};
  scene.pins = {pin};
  BuiltScene b = buildScene(scene);
  World& w = *b.world;
  ASSERT_EQ(w.pinned().vertices.size(), 8u);
  const Real h = smallBar().voxelSize();
  for (uint32_t i : w.pinned().vertices) EXPECT_LT(w.model().restPositions[i].x(), 2.5 * h);
  for (size_t i = 0; i < w.model().numVertices(); ++i) {
    if (w.model().restPositions[i].x() < 2.5 * h) {
      EXPECT_TRUE(std::binary_search(w.pinned().vertices.begin(), w.pinned().vertices.end(), uint32_t(i)));
    }
  }
  w.advanceTo(0.02);
  for (uint32_t i : w.pinned().vertices)
    EXPECT_NEAR((w.state().positions[i] - w.model().restPositions[i] - Vec3(0, 0.002, 0)).norm(), 0, 1e-12);
  const std::vector<uint32_t> tip = tipVertices(w.model(), smallBar().length());
  EXPECT_GT(w.state().positions[tip[0]].y(), w.model().restPositions[tip[0]].y() + 1e-4);
}

// A label volume the size of the body (raw uint8, 4 x 4 x 4): the voxels with x index == slab.
std::string writeMask(const std::string& name, int slab) {
  const auto path = std::filesystem::temp_directory_path() / ("gradel-pins-" + std::to_string(::getpid()) + "-" + name);
  std::ofstream out(path, std::ios::binary);
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) out.put(char(i == slab ? 7 : 0));
  return path.string();
}

std::string maskScene(const std::string& maskFields) {
  return R"({ "body": { "shape": "box", "size": 4, "voxel_size": 0.01, "position": [1, 0, 0] },
             "simulation": { "gravity": [0, 0, 0] },
             "pins": [ { "mask": { )" +
         maskFields + R"( },
                         "path": [ { "t": 0, "position": [0, 0, 0] }, { "t": 0.01, "position": [0, 0, 0.003] } ] } ] })";
}

TEST(Pins, MaskFileOnTheBodyLatticePinsTheFilledVoxelsCornersWithOffset) {
  const std::string file = writeMask("slab0.raw", 0);
  const std::string raw = "\"file\": \"" + file + "\", \"dims\": [4, 4, 4], \"type\": \"uint8\"";
  for (int offset : {0, 2}) {
    const Scene s = parseScene(maskScene(raw + ", \"offset\": [" + std::to_string(offset) + ", 0, 0]"), "scene.json");
    BuiltScene b = buildScene(s);
    World& w = *b.world;
    // Mask voxels x = offset: the vertex plane x = offset (2-voxel blocks: 3 x 3 vertices).
    ASSERT_EQ(w.pinned().vertices.size(), 9u) << "offset " << offset;
    for (uint32_t i : w.pinned().vertices) EXPECT_NEAR(w.model().restPositions[i].x(), 1 + 0.01 * offset, 1e-12);
    w.advanceTo(0.02);
    for (uint32_t i : w.pinned().vertices)
      EXPECT_NEAR((w.state().positions[i] - w.model().restPositions[i] - Vec3(0, 0, 0.003)).norm(), 0, 1e-12);
  }
  std::filesystem::remove(file);
}

void expectInputError(const std::function<void()>& f, const std::vector<std::string>& needles) {
  try {
    f();
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    for (const std::string& n : needles) EXPECT_NE(std::string(e.what()).find(n), std::string::npos) << e.what();
  }
}

TEST(Pins, MaskErrorsNameTheFieldAndTheFile) {
  const std::string missing = "/nonexistent/gradel-mask.raw";
  expectInputError(
      [&] {
        parseScene(maskScene("\"file\": \"" + missing + "\", \"dims\": [4, 4, 4], \"type\": \"uint8\""), "s.json");
      },
      {"s.json", "pins[0].mask.file", "gradel-mask.raw"});
  expectInputError([&] { parseScene(maskScene("\"offset\": [0, 0, 0]"), "s.json"); }, {"pins[0].mask.file", "boxes"});
  expectInputError(
      [&] { parseScene(maskScene("\"boxes\": [ { \"min\": [2, 0, 0], \"max\": [1, 3, 3] } ]"), "s.json"); },
      {"pins[0].mask.boxes[0].max"});
  std::string both = maskScene("\"boxes\": [ { \"min\": [0, 0, 0], \"max\": [0, 3, 3] } ]");
  both.replace(both.find("\"mask\""), 6, "\"min\": [0, 0, 0], \"mask\"");
  expectInputError([&] { parseScene(both, "s.json"); }, {"pins[0].min", "not both"});
  // An empty label volume: read when the scene is built; the message names the pin and the file.
  const std::string empty = writeMask("empty.raw", 99);
  const Scene s =
      parseScene(maskScene("\"file\": \"" + empty + "\", \"dims\": [4, 4, 4], \"type\": \"uint8\""), "s.json");
  expectInputError([&] { buildScene(s); }, {"pins[0].mask", "empty.raw"});
  std::filesystem::remove(empty);
  // A mask outside the body.
  expectInputError(
      [&] {
        buildScene(parseScene(maskScene("\"boxes\": [ { \"min\": [10, 10, 10], \"max\": [11, 11, 11] } ]"), "s.json"));
      },
      {"pins[0]", "mask holds no vertex"});
}

}  // namespace
}  // namespace gradel
