// Carving (carve.h, carve_scene.h): the event's counts on a hand-checked layout, what it keeps
// (surviving vertices bit for bit, mass and momentum less exactly the removed voxels'), what it
// must not create (energy, inverted elements), the tool's voxel set, and carving in a world.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <vector>

#include "gradel/carve.h"
#include "gradel/carve_scene.h"
#include "test_support.h"

using namespace gradel;
using namespace gradel::test;

namespace {

bool sameBits(const Vec3& a, const Vec3& b) { return std::memcmp(a.data(), b.data(), sizeof(Vec3)) == 0; }

// A body in a bare world (for its metrics: kinetic and elastic energy, the smallest determinant).
struct Held {
  Body body;
  std::unique_ptr<World> world;
};

Held held(Body b) {
  Held h{std::move(b), nullptr};
  h.world = std::make_unique<World>(h.body.model, isolated(), DomainSettings{}, std::vector<ManipulatorSettings>{});
  return h;
}

CarveInput inputOf(const Held& h) {
  CarveInput in;
  in.volume = &h.body.volume, in.layout = &h.body.layout, in.model = h.body.model.get();
  in.positions = h.world->state().positions.data(), in.velocities = h.world->state().velocities.data();
  in.rotations = h.world->state().rotations.data();
  return in;
}

Metrics metricsOf(const CarvedBody& c) {
  World w(c.model, isolated(), DomainSettings{}, {});
  w.state().positions = c.positions, w.state().velocities = c.velocities;
  return w.metrics();
}

Vec3 momentumOf(const RestModel& m, const std::vector<Vec3>& v) {
  Vec3 p = Vec3::Zero();
  for (size_t i = 0; i < m.numVertices(); ++i) p += m.mass[i] * v[i];
  return p;
}

// A moving, deformed body: a smooth stretch and shear, a spin and a drift, velocity noise.
Held movingBody(const std::string& shape, int size, LayoutKind kind) {
  Held h = held(makeBody(shape, size, 3, kind));
  deformSmoothly(*h.world, 0.05);
  const Vec3 omega(0.3, -1.0, 0.7), drift(0.2, -0.1, 0.05);
  std::vector<Vec3>& v = h.world->state().velocities;
  for (size_t i = 0; i < v.size(); ++i) v[i] = drift + omega.cross(h.world->state().positions[i]);
  perturb(*h.world, 0, 0.02, 7);
  return h;
}

std::vector<uint8_t> ballMask(const VoxelVolume& vol, const Vec3& c, Real r) {
  std::vector<uint8_t> m(vol.size(), 0);
  for (int k = 0; k < vol.nz(); ++k)
    for (int j = 0; j < vol.ny(); ++j)
      for (int i = 0; i < vol.nx(); ++i)
        if ((Vec3(i + 0.5, j + 0.5, k + 0.5) - c).norm() <= r) m[vol.index(i, j, k)] = 1;
  return m;
}

}  // namespace

// A 4^3 box, gradational: 8 full level-0 elements, vertices on the even lattice points (27).
// Removing corner voxel (0,0,0) leaves its group incomplete (7 unit cells: all 27 points of
// [0,2]^3 but the corner) and the 7 others full: 8 elements, 27 - 1 + 19 = 45 vertices, 19 new.
TEST(Carve, CornerVoxelOfA4BoxHandChecked) {
  const Held h = held(makeBody("box", 4, 3, LayoutKind::Gradational));
  ASSERT_EQ(h.body.layout.numElements(), 8u);
  ASSERT_EQ(h.body.layout.numVertices(), 27u);
  std::vector<uint8_t> mask(h.body.volume.size(), 0);
  mask[h.body.volume.index(0, 0, 0)] = 1;
  const CarvedBody c = carveBody(inputOf(h), mask);
  EXPECT_EQ(c.removedVoxels, 1u);
  EXPECT_EQ(c.layout.numElements(), 8u);
  EXPECT_EQ(c.layout.numVertices(), 45u);
  EXPECT_EQ(c.newVertices, 19u);
  EXPECT_EQ(c.volume.countFilled(), 63u);
  EXPECT_EQ(c.layout.vertexAt(Int3(0, 0, 0)), Layout::kNoVertex);
  const Real voxelMass = 1000.0 * std::pow(0.01, 3);
  EXPECT_NEAR(c.removedMass, voxelMass, 1e-18);
  EXPECT_NEAR(h.body.model->totalMass - c.model->totalMass, voxelMass, 1e-15);
  // At rest, every new vertex lies at its rest position.
  for (size_t v = 0; v < c.layout.numVertices(); ++v)
    EXPECT_LT((c.positions[v] - c.model->restPositions[v]).norm(), 1e-15);
}

TEST(Carve, MassMomentumAndSurvivorsOfAMovingDeformedBody) {
  for (LayoutKind kind : {LayoutKind::Gradational, LayoutKind::Voxel}) {
    const Held h = movingBody("sphere", 16, kind);
    const std::vector<uint8_t> mask = ballMask(h.body.volume, Vec3(13, 9, 8), 4.5);
    const CarvedBody c = carveBody(inputOf(h), mask);
    ASSERT_GT(c.removedVoxels, 50u);
    // The voxel layout has a vertex at every voxel corner: removing voxels adds none.
    if (kind == LayoutKind::Gradational) ASSERT_GT(c.newVertices, 0u);
    if (kind == LayoutKind::Voxel) ASSERT_EQ(c.newVertices, 0u);
    const RestModel& before = *h.body.model;
    // Mass: less exactly the removed voxels' (rho h^3 each).
    EXPECT_NEAR(c.removedMass, Real(c.removedVoxels) * 1000.0 * 1e-6, 1e-15);
    EXPECT_NEAR(before.totalMass - c.model->totalMass, c.removedMass, 1e-12 * before.totalMass);
    // Momentum: less exactly the removed material's.
    const Vec3 p0 = momentumOf(before, h.world->state().velocities), p1 = momentumOf(*c.model, c.velocities);
    const Real scale = before.totalMass * 1.0;
    EXPECT_LT((p0 - c.removedMomentum - p1).norm(), 1e-12 * scale) << layoutKindName(kind);
    EXPECT_GT(c.removedMomentum.norm(), 1e-3 * p0.norm());
    // The correction over the new vertices is small (hanging survivors only).
    EXPECT_LT(c.momentumCorrection.norm(), 0.05) << layoutKindName(kind);
    // Survivors keep their position and velocity bit for bit.
    size_t kept = 0;
    for (size_t v = 0; v < c.layout.numVertices(); ++v) {
      if (c.fromVertex[v] == Layout::kNoVertex) continue;
      ++kept;
      ASSERT_TRUE(sameBits(c.positions[v], h.world->state().positions[c.fromVertex[v]]));
      ASSERT_TRUE(sameBits(c.velocities[v], h.world->state().velocities[c.fromVertex[v]]));
      ASSERT_EQ(h.body.layout.vertices[c.fromVertex[v]], c.layout.vertices[v]);
    }
    EXPECT_EQ(kept + c.newVertices, c.layout.numVertices());
    // No energy from the event (kinetic + elastic; the removed part takes its own), no inversion.
    const Metrics m0 = h.world->metrics(), m1 = metricsOf(c);
    EXPECT_LE(m1.kineticEnergy + m1.elasticEnergy, m0.kineticEnergy + m0.elasticEnergy - c.removedKineticEnergy +
                                                       1e-9 * (m0.kineticEnergy + m0.elasticEnergy))
        << layoutKindName(kind) << " KE " << m0.kineticEnergy << " -> " << m1.kineticEnergy << " EE "
        << m0.elasticEnergy << " -> " << m1.elasticEnergy << " removed KE " << c.removedKineticEnergy;
    ASSERT_GT(m0.minElementDet, 0);
    EXPECT_GT(m1.minElementDet, 0);
  }
}

TEST(Carve, RemovingNothingOrEverythingChangesNothing) {
  const Held h = held(makeBody("box", 4, 3, LayoutKind::Gradational));
  const CarvedBody none = carveBody(inputOf(h), std::vector<uint8_t>(h.body.volume.size(), 0));
  EXPECT_EQ(none.removedVoxels, 0u);
  EXPECT_EQ(none.layout.numVertices(), 27u);
  const CarvedBody all = carveBody(inputOf(h), std::vector<uint8_t>(h.body.volume.size(), 1));
  EXPECT_TRUE(all.emptied);
  EXPECT_EQ(all.removedVoxels, 0u);
  EXPECT_EQ(all.volume.countFilled(), 64u);
  EXPECT_THROW(carveBody(inputOf(h), std::vector<uint8_t>(3, 0)), std::invalid_argument);
}

// The tool's voxels: a body moved rigidly by d, a sphere at c + d takes the voxels whose rest
// centres lie within r of c (counted directly).
TEST(Carve, SphereTakesTheVoxelsWhoseDeformedCentresItHolds) {
  Held h = held(makeBody("box", 12, 3, LayoutKind::Gradational));
  const Vec3 d(0.3, -0.2, 0.1);
  for (Vec3& x : h.world->state().positions) x += d;
  const Real hv = 0.01;
  const Vec3 c(0.02, 0.05, 0.06);
  size_t n = 0;
  const std::vector<uint8_t> got = voxelsInSphere(inputOf(h), c + d, 0.035, &n);
  const std::vector<uint8_t> want = ballMask(h.body.volume, c / hv, 0.035 / hv);
  size_t expected = 0;
  for (size_t q = 0; q < want.size(); ++q) {
    expected += want[q];
    EXPECT_EQ(got[q], want[q]) << q;
  }
  EXPECT_EQ(n, expected);
  EXPECT_GT(n, 20u);
}

// In a world: a drill (a carving sphere) moving into a block removes voxels every chunk; the
// world steps on with the carved body, finite, the same bits at 1 and 2 threads.
TEST(Carve, DrillInAWorldIsDeterministicAndKeepsMass) {
  uint64_t hashes[2] = {0, 0};
  for (int threads : {1, 2}) {
    Scene scene;
    scene.bodies[0].shape = presetShape("box", 12, 3, 0.01);
    scene.simulation.gravity = Vec3::Zero();
    scene.simulation.threads = threads;
    scene.domain.enabled = true, scene.domain.min = Vec3(-1, 0, -1), scene.domain.max = Vec3(1, 1, 1);
    ManipulatorSettings burr;
    burr.radius = 0.025, burr.carve = true, burr.restitution = 0;
    burr.path.keys = {{0.0, Vec3(0.06, 0.16, 0.06), std::nullopt}, {0.1, Vec3(0.06, 0.06, 0.06), std::nullopt}};
    scene.manipulators = {burr};
    BuiltScene b = buildScene(scene);
    std::vector<Vec3> previous;
    size_t removed = 0;
    Real removedMass = 0;
    const Real mass0 = b.world->model().totalMass;
    while (b.world->time() < 0.11) {
      b.world->advanceTo(b.world->time() + 16 * b.world->dt());
      for (const CarveEvent& e : carveWithManipulators(b, previous)) removed += e.removedVoxels, removedMass += e.removedMass;
      ASSERT_TRUE(b.world->state().positions.size() == b.world->model().numVertices());
      // No vertex inside the tool after an event (the reach of one voxel keeps new ones out).
      for (const Vec3& x : b.world->state().positions)
        ASSERT_GE((x - b.world->manipulators()[0].position).norm(), burr.radius * (1 - 1e-9));
    }
    EXPECT_GT(removed, 100u);
    EXPECT_EQ(b.bodies[0].volume.countFilled() + removed, 12u * 12u * 12u);
    EXPECT_NEAR(mass0 - b.world->model().totalMass, removedMass, 1e-12 * mass0);
    for (const Vec3& x : b.world->state().positions) ASSERT_TRUE(x.allFinite());
    EXPECT_GT(b.world->metrics().minElementDet, 0);
    hashes[threads - 1] = b.world->stateHash();
  }
  EXPECT_EQ(hashes[0], hashes[1]);
}

TEST(Carve, DrillSceneRuns) {
  auto b = std::make_unique<BuiltScene>(buildScene(loadScene(std::string(GRADEL_SOURCE_DIR) + "/scenes/drill.json")));
  std::vector<Vec3> previous;
  size_t removed = 0;
  const size_t before = b->bodies[0].volume.countFilled();
  while (b->world->time() < 1.0) {
    b->world->advanceTo(b->world->time() + 1.0 / 60);
    for (const CarveEvent& e : carveWithManipulators(*b, previous)) removed += e.removedVoxels;
  }
  EXPECT_GT(removed, 50u);
  EXPECT_EQ(b->bodies[0].volume.countFilled() + removed, before);
  for (const Vec3& x : b->world->state().positions) ASSERT_TRUE(x.allFinite());
}
