// A selective carving tool (ManipulatorSettings::carveLabels, scene key "carve_labels"): it removes
// only voxels of the listed regions of a label map. scenes/phantom-resect.json: a burr that takes
// the phantom's soft tissue (label 1) goes down onto its stiff inclusion (label 2) and uncovers it
// without removing any of it; the same burr without the key removes inclusion voxels too (so the
// key is what spares them). Also the key's errors.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "gradel/carve_scene.h"
#include "gradel/scene.h"
#include "test_support.h"

using namespace gradel;
using namespace gradel::test;

namespace {

struct LabelCounts {
  size_t soft = 0, stiff = 0;
};

LabelCounts countLabels(const VoxelVolume& v) {
  LabelCounts c;
  for (int k = 0; k < v.nz(); ++k)
    for (int j = 0; j < v.ny(); ++j)
      for (int i = 0; i < v.nx(); ++i) {
        const uint16_t l = v.label(i, j, k);
        c.soft += l == 1, c.stiff += l == 2;
      }
  return c;
}

struct Resection {
  LabelCounts before, after;
  size_t removed = 0;
  Real removedMass = 0, mass0 = 0, mass1 = 0, voxelVolume = 0;
  bool finite = true;
};

// Runs the phantom-resect scene to `until` [s], carving after every 1/60 s (as gradel run's chunks).
Resection runResection(bool selective, Real until) {
  Scene scene = loadScene(std::string(GRADEL_SOURCE_DIR) + "/scenes/phantom-resect.json");
  if (!selective) scene.manipulators[0].carveLabels.clear();
  auto b = std::make_unique<BuiltScene>(buildScene(scene));
  Resection r;
  r.before = countLabels(b->bodies[0].volume);
  r.mass0 = b->world->model().totalMass;
  r.voxelVolume = std::pow(b->bodies[0].volume.voxelSize(), 3);
  std::vector<Vec3> previous;
  while (b->world->time() < until) {
    b->world->advanceTo(b->world->time() + 1.0 / 60);
    for (const CarveEvent& e : carveWithManipulators(*b, previous)) r.removed += e.removedVoxels, r.removedMass += e.removedMass;
  }
  r.after = countLabels(b->bodies[0].volume);
  r.mass1 = b->world->model().totalMass;
  for (const Vec3& x : b->world->state().positions) r.finite = r.finite && x.allFinite();
  return r;
}

}  // namespace

TEST(CarveLabels, SelectiveBurrUncoversTheInclusionWithoutRemovingIt) {
  const Resection r = runResection(true, 0.8);  // down onto the inclusion and held there
  ASSERT_TRUE(r.finite);
  EXPECT_GT(r.removed, 20u);
  EXPECT_EQ(r.after.stiff, r.before.stiff);             // not one voxel of the inclusion
  EXPECT_EQ(r.after.soft + r.removed, r.before.soft);  // every removed voxel was soft tissue
  // The mass left with soft tissue's density (1000 kg/m^3), not the inclusion's (1200).
  EXPECT_NEAR(r.removedMass, r.removed * 1000 * r.voxelVolume, 1e-12);
  EXPECT_NEAR(r.mass0 - r.mass1, r.removedMass, 1e-12 * r.mass0);
}

TEST(CarveLabels, TheSameBurrWithoutTheKeyTakesTheInclusionToo) {
  const Resection r = runResection(false, 0.8);
  ASSERT_TRUE(r.finite);
  EXPECT_LT(r.after.stiff, r.before.stiff);
  EXPECT_EQ(r.after.soft + r.after.stiff + r.removed, r.before.soft + r.before.stiff);
  const size_t stiffRemoved = r.before.stiff - r.after.stiff;
  EXPECT_NEAR(r.removedMass, (r.removed - stiffRemoved) * 1000 * r.voxelVolume + stiffRemoved * 1200 * r.voxelVolume,
              1e-12);
}

TEST(CarveLabels, SceneKeyAndItsErrors) {
  const std::string body = R"("body": {"shape": "box", "size": 6}, )";
  const Scene s = parseScene(
      "{" + body + R"("manipulators": [{"type": "sphere", "carve": true, "carve_labels": [3, 1]}]})", "x.json");
  EXPECT_EQ(s.manipulators[0].carveLabels, (std::vector<uint16_t>{1, 3}));  // sorted
  const std::pair<std::string, std::string> bad[] = {
      {R"({"type": "sphere", "carve_labels": [1]})", "manipulators[0].carve_labels"},  // not a carving tool
      {R"({"type": "sphere", "carve": true, "carve_labels": []})", "manipulators[0].carve_labels"},
      {R"({"type": "sphere", "carve": true, "carve_labels": 1})", "manipulators[0].carve_labels"},
      {R"({"type": "sphere", "carve": true, "carve_labels": [0]})", "manipulators[0].carve_labels[0]"},
      {R"({"type": "sphere", "carve": true, "carve_labels": [1, 70000]})", "manipulators[0].carve_labels[1]"},
      {R"({"type": "sphere", "carve": true, "carve_labels": [1.5]})", "manipulators[0].carve_labels[0]"},
      {R"({"type": "sphere", "carve": true, "carve_labels": [2, 2]})", "manipulators[0].carve_labels"},
  };
  for (const auto& [tool, key] : bad) {
    const std::string msg = sceneErrorOf("{" + body + R"("manipulators": [)" + tool + "]}", "x.json");
    EXPECT_EQ(msg.rfind("x.json: ", 0), 0u) << tool << " -> " << msg;
    EXPECT_NE(msg.find(key), std::string::npos) << tool << " -> " << msg;
  }
}
