// The blade (carve.h voxelsAlongBlade, contacts.h ManipulatorShape::Blade): its kerf counted by
// hand on a small box (one voxel layer for an axis-aligned blade, the rectangle's edge exact, a
// tilted blade's separating layer), its scene keys and their errors, that it never pushes, and
// scenes/cut.json: a blade cutting a held bar in two, the halves separate bodies.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "gradel/carve.h"
#include "gradel/carve_scene.h"
#include "gradel/pieces.h"
#include "test_support.h"

using namespace gradel;
using namespace gradel::test;

namespace {

constexpr Real kH = 0.0078125;  // 2^-7 m: lattice positions exact

struct AtRest {
  Body body;
  std::vector<Vec3> x, v;
  CarveInput in() const {
    CarveInput c;
    c.volume = &body.volume, c.layout = &body.layout, c.model = body.model.get();
    c.positions = x.data(), c.velocities = v.data();
    return c;
  }
};

AtRest box8() {
  AtRest a{makeBody("box", 8, 3, LayoutKind::Gradational, {}, kH), {}, {}};
  a.x = a.body.model->restPositions;
  a.v.assign(a.x.size(), Vec3::Zero());
  return a;
}

size_t countWhere(const VoxelVolume& v, const std::vector<uint8_t>& m, bool (*f)(int, int, int)) {
  size_t n = 0;
  for (int k = 0; k < v.nz(); ++k)
    for (int j = 0; j < v.ny(); ++j)
      for (int i = 0; i < v.nx(); ++i) n += m[v.index(i, j, k)] && f(i, j, k);
  return n;
}

}  // namespace

// An 8^3 box of voxels h at rest. A blade with normal x in the plane x = 4h (a voxel boundary:
// the centres at 3.5h and 4.5h are both h/2 away; the half-open slab takes the +x one) swept
// down through the whole box takes the layer i = 4: 64 voxels. Stopped with its lower edge at
// y = 4.75h it takes the rows j = 5, 6, 7 of that layer: 24. Parked in the plane x = 4.5h (the
// centres' plane of layer 4) it takes the same 64.
TEST(Blade, KerfOfAnAxisAlignedBladeHandChecked) {
  const AtRest a = box8();
  BladeSweep s;
  s.axis = Vec3(0, 0, 1), s.widthAxis = Vec3(0, 1, 0);  // normal z x y = -x
  s.halfLength = 1.0, s.halfWidth = 1.5 * kH;
  s.from = Vec3(4 * kH, 20 * kH, 4 * kH), s.to = Vec3(4 * kH, -4 * kH, 4 * kH);
  size_t n = 0;
  std::vector<uint8_t> m = voxelsAlongBlade(a.in(), s, &n);
  EXPECT_EQ(n, 64u);
  // normal -x: the slab (-h/2, h/2] along -x holds the centre at 3.5h (offset +h/2): layer 3.
  EXPECT_EQ(countWhere(a.body.volume, m, [](int i, int, int) { return i == 3; }), 64u);
  s.axis = Vec3(0, 1, 0), s.widthAxis = Vec3(0, 0, 1);  // normal +x: layer 4
  s.halfLength = 1.5 * kH, s.halfWidth = 1.0;
  m = voxelsAlongBlade(a.in(), s, &n);
  EXPECT_EQ(n, 64u);
  EXPECT_EQ(countWhere(a.body.volume, m, [](int i, int, int) { return i == 4; }), 64u);
  s.halfLength = 1.25 * kH, s.to = Vec3(4 * kH, 6 * kH, 4 * kH);  // lower edge at 4.75h
  m = voxelsAlongBlade(a.in(), s, &n);
  EXPECT_EQ(n, 24u);
  EXPECT_EQ(countWhere(a.body.volume, m, [](int i, int j, int) { return i == 4 && j >= 5; }), 24u);
  s.from = s.to = Vec3(4.5 * kH, 4 * kH, 4 * kH), s.halfLength = 1.0;
  m = voxelsAlongBlade(a.in(), s, &n);
  EXPECT_EQ(n, 64u);
  EXPECT_EQ(countWhere(a.body.volume, m, [](int i, int, int) { return i == 4; }), 64u);
  // Moved rigidly, the same voxels.
  AtRest moved = box8();
  const Vec3 d(0.25, -0.5, 0.125);
  for (Vec3& x : moved.x) x += d;
  s.from += d, s.to += d;
  EXPECT_EQ(voxelsAlongBlade(moved.in(), s), m);
}

// A blade at 45 degrees (normal (1, 1, 0)/sqrt 2) through the plane where (x + y)/h = 8.5: the
// centres' offsets are (i + j - 7.5) h / sqrt 2 and the kerf's half width h/2 (|n_x| + |n_y|) =
// h / sqrt 2, so it takes i + j in {7, 8}: 8 + 7 = 15 per z layer, 120 voxels. The box falls
// into i + j <= 6 (28 per layer, 224) and i + j >= 9 (21 per layer, 168). One diagonal alone
// (i + j = 7, what a slab of width h would take) leaves voxels touching at an edge across it: one piece.
TEST(Blade, TiltedBladeTakesTheThinnestSeparatingLayer) {
  const AtRest a = box8();
  BladeSweep s;
  s.axis = Vec3(0, 0, 1), s.widthAxis = Vec3(-1, 1, 0);  // normal (1, 1, 0)/sqrt 2 after normalising
  s.halfLength = s.halfWidth = 1.0;
  s.from = s.to = Vec3(4.25 * kH, 4.25 * kH, 0);
  size_t n = 0;
  const std::vector<uint8_t> m = voxelsAlongBlade(a.in(), s, &n);
  EXPECT_EQ(n, 120u);
  EXPECT_EQ(countWhere(a.body.volume, m, [](int i, int j, int) { return i + j == 7 || i + j == 8; }), 120u);
  const CarvedBody c = carveBody(a.in(), m);
  const BodyPieces p = findPieces(c.layout, c.volume);
  ASSERT_EQ(p.count(), 2u);
  EXPECT_EQ(p.voxels[0], 224u);
  EXPECT_EQ(p.voxels[1], 168u);
  std::vector<uint8_t> one(m.size(), 0);
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 8; ++i) one[a.body.volume.index(i, j, k)] = i + j == 7;
  const CarvedBody c1 = carveBody(a.in(), one);
  EXPECT_EQ(findPieces(c1.layout, c1.volume).count(), 1u);
}

TEST(Blade, BadInputIsRefused) {
  const AtRest a = box8();
  BladeSweep s;
  s.axis = Vec3(1, 0, 0), s.widthAxis = Vec3(1, 1, 0), s.halfLength = s.halfWidth = 0.1;
  EXPECT_THROW(voxelsAlongBlade(a.in(), s), std::invalid_argument);
  s.widthAxis = Vec3::Zero();
  EXPECT_THROW(voxelsAlongBlade(a.in(), s), std::invalid_argument);
}

// Scene keys: "axes" and "half_extents" read; each bad key refused naming it.
TEST(Blade, SceneKeysAndTheirErrors) {
  const std::string body = R"("body": {"shape": "box", "size": 4}, )";
  const Scene s = parseScene("{" + body + R"("manipulators": [{"type": "blade", "axes": ["z", [0, 2, 0]],
      "half_extents": [0.05, 0.02], "path": [{"t": 0, "position": [0, 0.1, 0]}]}]})",
                             "cut.json");
  ASSERT_EQ(s.manipulators.size(), 1u);
  const ManipulatorSettings& m = s.manipulators[0];
  EXPECT_EQ(m.shape, ManipulatorShape::Blade);
  EXPECT_TRUE(m.carve);
  EXPECT_EQ(m.axis, Vec3(0, 0, 1));
  EXPECT_EQ(m.widthAxis, Vec3(0, 2, 0));
  EXPECT_EQ(m.halfLength, 0.05);
  EXPECT_EQ(m.halfWidth, 0.02);
  const std::pair<std::string, std::string> bad[] = {
      {R"({"type": "blade", "half_extents": [0.05, 0.02]})", "manipulators[0].axes"},
      {R"({"type": "blade", "axes": ["x", "y"]})", "manipulators[0].half_extents"},
      {R"({"type": "blade", "axes": ["x", [1, 1, 0]], "half_extents": [0.05, 0.02]})", "manipulators[0].axes"},
      {R"({"type": "blade", "axes": ["x", "w"], "half_extents": [0.05, 0.02]})", "manipulators[0].axes[1]"},
      {R"({"type": "blade", "axes": ["x"], "half_extents": [0.05, 0.02]})", "manipulators[0].axes"},
      {R"({"type": "blade", "axes": ["x", "y"], "half_extents": [0.05, -1]})", "manipulators[0].half_extents[1]"},
      {R"({"type": "blade", "axes": ["x", "y"], "half_extents": [0.05, 0.02], "radius": 0.01})",
       "manipulators[0].radius"},
      {R"({"type": "blade", "axes": ["x", "y"], "half_extents": [0.05, 0.02], "carve": false})",
       "manipulators[0].carve"},
      {R"({"type": "blade", "axes": ["x", "y"], "half_extents": [0.05, 0.02], "friction": 0.3})",
       "manipulators[0].friction"},
      {R"({"type": "sphere", "axes": ["x", "y"]})", "manipulators[0].axes"},
  };
  for (const auto& [tool, key] : bad) {
    const std::string msg = sceneErrorOf("{" + body + R"("manipulators": [)" + tool + "]}", "cut.json");
    EXPECT_EQ(msg.rfind("cut.json: ", 0), 0u) << msg;
    EXPECT_NE(msg.find(key), std::string::npos) << tool << " -> " << msg;
  }
  const std::string flat = sceneErrorOf(R"({"dim": 2, "body": {"shape": "box", "size": 4},
    "manipulators": [{"type": "blade", "axes": ["x", "y"], "half_extents": [0.05, 0.02]}]})",
                                        "cut.json");
  EXPECT_NE(flat.find("manipulators[0].type"), std::string::npos) << flat;
}

// A blade never pushes: a world with a blade moving through the body steps exactly as one
// without it (until it cuts), and its contact force is zero.
TEST(Blade, NeverPushes) {
  uint64_t hashes[2];
  for (int with = 0; with < 2; ++with) {
    Scene scene;
    scene.bodies[0].shape = presetShape("box", 8, 3, 0.01);
    scene.domain.enabled = true, scene.domain.min = Vec3(-1, 0, -1), scene.domain.max = Vec3(1, 1, 1);
    if (with) {
      ManipulatorSettings blade;
      blade.shape = ManipulatorShape::Blade, blade.carve = true;
      blade.axis = Vec3(0, 1, 0), blade.widthAxis = Vec3(0, 0, 1), blade.halfLength = 0.02, blade.halfWidth = 0.1;
      blade.path.keys = {{0.0, Vec3(0.04, 0.1, 0.04), std::nullopt}, {0.05, Vec3(0.04, 0.0, 0.04), std::nullopt}};
      scene.manipulators = {blade};
    }
    BuiltScene b = buildScene(scene);
    b.world->advanceTo(0.05);
    hashes[with] = b.world->stateHash();
    if (with) {
      EXPECT_EQ(b.world->stepContactForces().manipulators[0].force, Vec3::Zero());
      EXPECT_EQ(b.world->metrics().maxPenetration, 0);
    }
  }
  EXPECT_EQ(hashes[0], hashes[1]);
}

// scenes/cut.json, the first 0.7 s: a blade comes down through a bar held at its left end and
// cuts it in two; the right half falls as a body of its own. After the cut: two bodies, the
// mass of the bar less the kerf's exactly, no vertex of one inside the other, the ledger's kerf
// one voxel layer (6 x 6 voxels).
TEST(Blade, CutSceneSplitsTheBarInTwo) {
  auto b = std::make_unique<BuiltScene>(buildScene(loadScene(std::string(GRADEL_SOURCE_DIR) + "/scenes/cut.json")));
  World& w = *b->world;
  const Real mass0 = w.model().totalMass;
  const size_t voxels0 = b->bodies[0].volume.countFilled();
  std::vector<Vec3> previous;
  size_t removed = 0, split = 0;
  Real removedMass = 0;
  while (w.time() < 0.7) {
    w.advanceTo(w.time() + 1.0 / 60);
    for (const CarveEvent& e : carveWithManipulators(*b, previous)) {
      removed += e.removedVoxels, removedMass += e.removedMass;
      split += e.pieces.size() > 1;
    }
    if (w.bodyContacts()) {
      ASSERT_EQ(verticesInsideOtherBodies(w), 0u) << "t = " << w.time();
    }
  }
  EXPECT_EQ(split, 1u);
  ASSERT_EQ(b->numBodies(), 2u);
  EXPECT_EQ(b->bodies[1].name, "bar-2");
  EXPECT_EQ(removed, 36u);
  EXPECT_EQ(b->bodies[0].volume.countFilled() + b->bodies[1].volume.countFilled() + removed, voxels0);
  EXPECT_NEAR(w.model().totalMass, mass0 - removedMass, 1e-12 * mass0);
  EXPECT_EQ(w.removedMaterial()[0].voxels, removed);
  EXPECT_EQ(verticesInsideOtherBodies(w), 0u);
  // The held half keeps the pin; the other one has fallen towards the floor.
  ASSERT_EQ(w.pins().size(), 1u);
  EXPECT_EQ(w.pins()[0].body, 0u);
  const BodyRange& r = b->range(1);
  Real lowest = 1;
  for (uint32_t u = r.vertexBegin; u < r.vertexEnd; ++u) lowest = std::min(lowest, w.state().positions[u].y());
  EXPECT_LT(lowest, 0.005);
}

// The same cut at 1 and 2 threads: the same events, bodies and state, bit for bit.
TEST(Blade, CutSceneIsTheSameAtOneAndTwoThreads) {
  uint64_t hashes[2] = {0, 0};
  size_t bodies[2] = {0, 0};
  for (int threads : {1, 2}) {
    Scene scene = loadScene(std::string(GRADEL_SOURCE_DIR) + "/scenes/cut.json");
    scene.simulation.threads = threads;
    BuiltScene b = buildScene(scene);
    std::vector<Vec3> previous;
    while (b.world->time() < 0.5) {
      b.world->advanceTo(b.world->time() + 1.0 / 60);
      carveWithManipulators(b, previous);
    }
    hashes[threads - 1] = b.world->stateHash(), bodies[threads - 1] = b.numBodies();
  }
  EXPECT_EQ(bodies[0], 2u);
  EXPECT_EQ(bodies[1], 2u);
  EXPECT_EQ(hashes[0], hashes[1]);
}
