// Carving (carve.h, carve_scene.h): the event's counts on a hand-checked layout, what it keeps
// (surviving vertices bit for bit, mass and momentum less exactly the removed voxels'), what it
// must not create (energy, inverted elements), the tool's voxel set, and carving in a world.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <cstring>
#include <memory>
#include <vector>

#include "gradel/carve.h"
#include "gradel/stability.h"
#include "gradel/stability_warm.h"
#include "gradel/carve_scene.h"
#include "gradel/output.h"
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

// The cylinder tool's voxels (a rod, axis z, radius 2.4 voxels, half length 3 voxels) on a 12^3
// box of 1 cm voxels moved rigidly by d, counted by hand in voxel units about the rod's centre
// (6, 6, 6): parked, the columns with |dx|, |dy| in {0.5, 1.5} (16; 2.5^2 + 0.5^2 > 2.4^2) over
// the 6 layers with |dz| <= 3 (96). Swept by (2, 0, 1): the stadium from (6, 6) to (8, 6) holds
// 8 columns at x = 6.5, 7.5 and 4 at each of x = 4.5, 5.5, 8.5, 9.5 (24), over the layers with
// z in [3, 10] (7): 168.
TEST(Carve, CylinderTakesTheVoxelsItSweepsHandChecked) {
  Held h = held(makeBody("box", 12, 3, LayoutKind::Gradational));
  const Vec3 d(0.3, -0.2, 0.1);
  for (Vec3& x : h.world->state().positions) x += d;
  const Vec3 c = Vec3(0.06, 0.06, 0.06) + d, axis(0, 0, 2);  // the axis need not be a unit vector
  size_t n = 0;
  const std::vector<uint8_t> parked = voxelsInCylinder(inputOf(h), c, c, axis, 0.024, 0.03, &n);
  EXPECT_EQ(n, 96u);
  const std::vector<uint8_t> swept = voxelsInCylinder(inputOf(h), c, c + Vec3(0.02, 0, 0.01), axis, 0.024, 0.03, &n);
  EXPECT_EQ(n, 168u);
  // Voxel by voxel: the rest centres by the same rule in voxel units.
  const VoxelVolume& vol = h.body.volume;
  for (int k = 0; k < vol.nz(); ++k)
    for (int j = 0; j < vol.ny(); ++j)
      for (int i = 0; i < vol.nx(); ++i) {
        const Real x = i + 0.5, y = j + 0.5, z = k + 0.5;
        const Real dx = x < 6 ? x - 6 : x > 8 ? x - 8 : 0, dy = y - 6;
        const bool inParked = (x - 6) * (x - 6) + dy * dy <= 2.4 * 2.4 && std::abs(z - 6) <= 3;
        const bool inSwept = dx * dx + dy * dy <= 2.4 * 2.4 && z >= 3 && z <= 10;
        EXPECT_EQ(parked[vol.index(i, j, k)] != 0, inParked) << i << " " << j << " " << k;
        EXPECT_EQ(swept[vol.index(i, j, k)] != 0, inSwept) << i << " " << j << " " << k;
      }
  // A tilted rod, parked: the same voxels as the rule in rest coordinates.
  const Vec3 tilt = Vec3(1, 1, 0).normalized();
  const std::vector<uint8_t> tilted = voxelsInCylinder(inputOf(h), c, c, tilt, 0.016, 0.045, &n);
  size_t expected = 0;
  for (int k = 0; k < vol.nz(); ++k)
    for (int j = 0; j < vol.ny(); ++j)
      for (int i = 0; i < vol.nx(); ++i) {
        const Vec3 y = Vec3(i + 0.5, j + 0.5, k + 0.5) - Vec3(6, 6, 6);
        const Real along = y.dot(tilt);
        const bool in = std::abs(along) <= 4.5 && (y - along * tilt).norm() <= 1.6;  // no ties
        expected += in;
        EXPECT_EQ(tilted[vol.index(i, j, k)] != 0, in) << i << " " << j << " " << k;
      }
  EXPECT_EQ(n, expected);
  EXPECT_GT(n, 40u);
  EXPECT_THROW(voxelsInCylinder(inputOf(h), c, c, Vec3::Zero(), 0.01, 0.01), std::invalid_argument);
}

namespace {

Vec3 worldMomentum(const World& w) {
  Vec3 p = Vec3::Zero();
  for (size_t i = 0; i < w.model().numVertices(); ++i) p += w.model().mass[i] * w.state().velocities[i];
  return p;
}

bool sameForces(const ContactForces& a, const ContactForces& b) {
  if (a.manipulators.size() != b.manipulators.size()) return false;
  auto same = [](const ContactForce& x, const ContactForce& y) {
    return sameBits(x.force, y.force) && sameBits(x.torque, y.torque);
  };
  for (size_t k = 0; k < a.manipulators.size(); ++k)
    if (!same(a.manipulators[k], b.manipulators[k])) return false;
  for (int w = 0; w < kWalls; ++w)
    if (!same(a.wall[w], b.wall[w])) return false;
  return same(a.walls, b.walls);
}

// A tool drilling down into a 12^3 block of voxels h = 2^-7 m (h^3 and rho h^3 exact in binary,
// so the ledger's sums are exact) without gravity. After every event: the ledger (World::
// removedMaterial, Metrics::removed) holds exactly the voxels gone from the volume, their volume
// n h^3 and the mass the model lost, bit for bit; momentum leaves only with the removed material;
// the frame's force average is what it was before the event. Returns the voxels removed.
size_t drillAndCheckTheLedger(ManipulatorSettings tool, bool expectPush) {
  const Real h = 0.0078125;
  Scene scene;
  scene.bodies[0].shape = presetShape("box", 12, 3, h);
  scene.simulation.gravity = Vec3::Zero();
  scene.domain.enabled = true, scene.domain.min = Vec3(-1, 0, -1), scene.domain.max = Vec3(1, 1, 1);
  tool.carve = true, tool.restitution = 0, tool.friction = 0.3;
  const Real top = 12 * h, mid = 6 * h;
  tool.path.keys = {{0.0, Vec3(mid, top + 0.02, mid), std::nullopt}, {0.1, Vec3(mid, top - 0.04, mid), std::nullopt}};
  scene.manipulators = {tool};
  BuiltScene b = buildScene(scene);
  World& w = *b.world;
  const Real mass0 = w.model().totalMass;
  const size_t voxels0 = b.bodies[0].volume.countFilled();
  std::vector<Vec3> previous;
  size_t removed = 0, events = 0;
  Vec3 momentumLeft = Vec3::Zero();
  bool pushedWhileCarving = false;
  while (w.time() < 0.1) {
    w.advanceTo(w.time() + 16 * w.dt());
    const ContactForces force = w.averageContactForces();
    const Real forceTime = w.forceAverageTime();
    const Vec3 p0 = worldMomentum(w);
    const std::vector<CarveEvent> e = carveWithManipulators(b, previous);
    EXPECT_LE(e.size(), 1u);
    if (e.empty()) continue;
    ++events, removed += e[0].removedVoxels, momentumLeft += e[0].removedMomentum;
    EXPECT_EQ(e[0].removedVolume, Real(e[0].removedVoxels) * h * h * h);
    EXPECT_LT((p0 - e[0].removedMomentum - worldMomentum(w)).norm(), 1e-12 * mass0);
    EXPECT_TRUE(sameForces(force, w.averageContactForces()));  // the frame's average survives the event
    EXPECT_EQ(forceTime, w.forceAverageTime());
    // dt = auto is the carved body's own (operator rule, estimated again: warm started from the
    // first event on in a world with a carving tool, stability_warm.h), not shrunk per event: at
    // or above the fastest mode the estimate from scratch finds (its Ritz value), and within
    // 10 % of that estimate.
    const FrequencyEstimate full = highestFrequency(w.model());
    EXPECT_EQ(w.dt(), defaultDtFraction(PeriodRule::Operator) * (2 * M_PI / w.stabilityEstimate().omega));
    EXPECT_GE(w.stabilityEstimate().omega, full.ritz);
    EXPECT_LE(w.stabilityEstimate().omega, 1.1 * full.omega);
    EXPECT_EQ(w.stabilityEstimate().iterations, kWarmStartIterations);  // a carving tool: every event warm
    pushedWhileCarving |= force.manipulators[0].force.y() > 0;  // the block pushes the tool up
    const RemovedMaterial& r = w.removedMaterial().at(0);
    EXPECT_EQ(r.voxels, removed);
    EXPECT_EQ(r.voxels, voxels0 - b.bodies[0].volume.countFilled());
    EXPECT_EQ(r.volume, Real(removed) * h * h * h);
    EXPECT_EQ(r.mass, mass0 - w.model().totalMass);
    EXPECT_EQ(r.mass, Real(removed) * 1000 * h * h * h);
    EXPECT_TRUE(sameBits(r.momentum, momentumLeft));
    size_t inside = 0;  // the reach of one voxel leaves no vertex inside the tool
    for (const Vec3& x : w.state().positions) inside += w.manipulators()[0].signedDistance(x, nullptr) < -1e-9 * tool.radius;
    EXPECT_EQ(inside, 0u);
    const Metrics m = w.metrics();
    EXPECT_EQ(m.removed.voxels, r.voxels);
    EXPECT_EQ(m.removed.volume, r.volume);
    EXPECT_EQ(m.removed.mass, r.mass);
  }
  EXPECT_GT(events, 3u);
  EXPECT_EQ(pushedWhileCarving, expectPush);
  EXPECT_GT(w.metrics().minElementDet, 0);
  return removed;
}

}  // namespace

TEST(Carve, LedgerHoldsExactlyTheRemovedVolumeMassAndMomentum) {
  ManipulatorSettings burr;
  burr.radius = 0.02;
  EXPECT_GT(drillAndCheckTheLedger(burr, true), 100u);
}

// A rod (cylinder, axis x) pressed down into the block carves a slot: the same ledger checks,
// and no vertex is left inside the rod after an event. Moving less than a voxel per chunk, it
// takes the voxels within a voxel of its path before it reaches them: it never touches the
// block, so its force stays zero (docs/carving.md, "Feedback"; the sphere's round front meets
// the corners of the voxels it leaves).
TEST(Carve, CylinderRodCarvesInAWorld) {
  ManipulatorSettings rod;
  rod.shape = ManipulatorShape::Cylinder, rod.axis = Vec3(1, 0, 0), rod.radius = 0.01, rod.halfLength = 0.03;
  EXPECT_GT(drillAndCheckTheLedger(rod, false), 150u);
}

// metrics.csv's carving columns: after max_strain, only when asked; a body's row carries its own.
TEST(Carve, MetricsCsvCarvingColumns) {
  EXPECT_EQ(MetricsCsv::header(0).find("removed"), std::string::npos);
  const std::string h = MetricsCsv::header(1, true, true);
  const std::string tail = ",max_strain,removed_voxels,removed_volume,removed_mass";
  EXPECT_EQ(h.substr(h.size() - tail.size()), tail);
  EXPECT_EQ(h.rfind(MetricsCsv::header(1, true) + ",", 0), 0u);  // the columns before kept their places
  Metrics m;
  m.contactForces.manipulators.resize(1);
  m.removed.voxels = 37, m.removed.volume = 37 * 1e-6, m.removed.mass = 0.037;
  const std::string row = MetricsCsv::row("a", m, 1, /*forces=*/false, /*carving=*/true);
  EXPECT_EQ(row.substr(row.size() - 17), ",37,3.7e-05,0.037");
  EXPECT_EQ(std::count(row.begin(), row.end(), ','), std::count(h.begin(), h.end(), ','));
  // Bodies' ledgers add up on the "all" row.
  Metrics other = m;
  other.removed.voxels = 3, other.removed.mass = 0.003;
  EXPECT_EQ(combineMetrics({m, other}).removed.voxels, 40u);
  EXPECT_EQ(combineMetrics({m, other}).removed.mass, 0.037 + 0.003);
}

// Scene keys: `"carve": true` on a cylinder is read with its axis and sizes; on a 2D circle it is
// refused, naming the key.
TEST(Carve, SceneCarveKeyOnCylinderAndCircle) {
  const Scene s = parseScene(R"({"body": {"shape": "box", "size": 4},
    "manipulators": [{"type": "cylinder", "radius": 0.01, "half_length": 0.04, "axis": "x", "carve": true}]})",
                             "rod.json");
  ASSERT_EQ(s.manipulators.size(), 1u);
  EXPECT_TRUE(s.manipulators[0].carve);
  EXPECT_EQ(s.manipulators[0].shape, ManipulatorShape::Cylinder);
  EXPECT_EQ(s.manipulators[0].axis, Vec3(1, 0, 0));
  const std::string msg = test::sceneErrorOf(R"({"dim": 2, "body": {"shape": "box", "size": 4},
    "manipulators": [{"type": "circle", "carve": true}]})",
                                             "disc.json");
  EXPECT_EQ(msg.rfind("disc.json: ", 0), 0u) << msg;
  EXPECT_NE(msg.find("manipulators[0].carve"), std::string::npos) << msg;
}
