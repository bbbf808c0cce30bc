// Boundary conditions (pins.h): selection, explicit integrators holding pinned vertices on their
// prescribed path, and the scene keys.
#include <gtest/gtest.h>

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

TEST(Pins, selectPins_boxHoldsExactlyTheVerticesInside) {
  const std::vector<Vec3> rest = {{0, 0, 0}, {0.01, 0, 0}, {0.02, 0, 0}, {0.01, 0.01, 0}};
  PinSettings p;
  p.min = Vec3(0.005, -1, -1);
  p.max = Vec3(0.01, 1, 1);  // closed: x = 0.01 is inside
  const PinSet s = selectPins({p}, rest);
  EXPECT_EQ(s.vertices, (std::vector<uint32_t>{1, 3}));
  EXPECT_EQ(s.pinOf, (std::vector<uint32_t>{0, 0}));
}

TEST(Pins, selectPins_emptyBox_isInputError) {
  PinSettings p;
  p.min = Vec3(5, 5, 5);
  p.max = Vec3(6, 6, 6);
  EXPECT_THROW(selectPins({p}, {Vec3::Zero()}), InputError);
}

TEST(Pins, explicitClampedBar_pinnedVerticesStayAtRestAndTipSags) {
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

TEST(Pins, movingPin_followsItsPathOffset) {
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

TEST(Pins, parseScene_pinsReadBoxAndPath) {
  const Scene s = parseScene(kPinScene, "pins.json");
  ASSERT_EQ(s.pins.size(), 1u);
  EXPECT_EQ(s.pins[0].max, Vec3(0.001, 0.041, 0.041));
  ASSERT_EQ(s.pins[0].path.keys.size(), 2u);
  EXPECT_EQ(s.pins[0].path.position(0.5), Vec3(0, 0.005, 0));
  BuiltScene b = buildScene(s);
  EXPECT_EQ(b.world->pinned().vertices.size(), 9u);  // 3 x 3 block corners (2-voxel blocks)
}

TEST(Pins, parseScene_unknownKeyInPin_namesItsPath) {
  std::string text = kPinScene;
  text.replace(text.find("\"min\""), 5, "\"mni\"");
  try {
    parseScene(text, "pins.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("pins[0]"), std::string::npos) << e.what();
  }
}

TEST(Pins, buildScene_pinHoldingNoVertex_isInputError) {
  std::string text = kPinScene;
  text.replace(text.find("[-0.001, -0.001, -0.001]"), 24, "[ 0.5,    0.5,    0.5  ]");
  text.replace(text.find("[0.001, 0.041, 0.041]"), 21, "[0.6,   0.6,   0.6  ]");
  EXPECT_THROW(buildScene(parseScene(text, "pins.json")), InputError);
}

}  // namespace
}  // namespace gradel
