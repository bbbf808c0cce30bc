// Several bodies in one world (bodies.h): the combined rest model is the bodies' models side by
// side, and bodies that do not touch move exactly as each would alone.
#include <gtest/gtest.h>

#include <cstring>

#include "gradel/bodies.h"
#include "test_support.h"

using namespace gradel;
using namespace gradel::test;

namespace {

bool sameBits(const Vec3& a, const Vec3& b) { return std::memcmp(a.data(), b.data(), sizeof(Vec3)) == 0; }

MaterialSettings material(Real E, Real rho) {
  MaterialSettings m;
  m.youngsModulus = E, m.density = rho;
  return m;
}

}  // namespace

TEST(Bodies, CombinedModelIsTheModelsSideBySide) {
  const Body a = makeBody("sphere", 8, 3, LayoutKind::Gradational, material(1e5, 1000), 0.01);
  const Body b = makeBody("box", 5, 3, LayoutKind::Voxel, material(3e5, 500), 0.02, Vec3(1, 0, 0));
  const RestModel c = combineRestModels({a.model, b.model});
  const RestModel &A = *a.model, &B = *b.model;
  const size_t VA = A.numVertices(), EA = A.numElements(), PA = A.numPairs();
  ASSERT_EQ(c.numVertices(), VA + B.numVertices());
  ASSERT_EQ(c.numElements(), EA + B.numElements());
  ASSERT_EQ(c.numPairs(), PA + B.numPairs());
  ASSERT_EQ(c.bodies.size(), 2u);
  EXPECT_EQ(c.bodies[0].vertexBegin, 0u);
  EXPECT_EQ(c.bodies[0].vertexEnd, VA);
  EXPECT_EQ(c.bodies[1].vertexBegin, VA);
  EXPECT_EQ(c.bodies[1].vertexEnd, c.numVertices());
  EXPECT_EQ(c.bodies[1].elementBegin, EA);
  EXPECT_EQ(c.bodies[1].elementEnd, c.numElements());
  EXPECT_EQ(c.bodies[1].voxelSize, 0.02);
  EXPECT_EQ(c.bodies[1].material.youngsModulus, 3e5);
  EXPECT_EQ(c.bodies[1].origin, Vec3(1, 0, 0));
  EXPECT_EQ(c.voxelSize, 0.01);  // body 0's
  for (size_t v = 0; v < c.numVertices(); ++v) {
    const RestModel& m = v < VA ? A : B;
    const size_t i = v < VA ? v : v - VA;
    ASSERT_EQ(c.restPositions[v], m.restPositions[i]);
    ASSERT_EQ(c.mass[v], m.mass[i]);
    ASSERT_EQ(c.invMass[v], m.invMass[i]);
    ASSERT_EQ(c.onSurface[v], m.onSurface[i]);
    ASSERT_EQ(c.bodyOfVertex(v), v < VA ? 0u : 1u);
  }
  for (size_t e = 0; e < c.numElements(); ++e) {
    const RestModel& m = e < EA ? A : B;
    const size_t k = e < EA ? e : e - EA;
    ASSERT_EQ(c.stiffness[e], m.stiffness[k]);
    ASSERT_EQ(c.size[e], m.size[k]);
    ASSERT_EQ(c.level[e], m.level[k]);
    ASSERT_EQ(c.elemStart[e + 1] - c.elemStart[e], m.elemStart[k + 1] - m.elemStart[k]);
    for (uint32_t p = 0; p < m.elemStart[k + 1] - m.elemStart[k]; ++p) {
      const uint32_t cp = c.elemStart[e] + p, mp = m.elemStart[k] + p;
      ASSERT_EQ(c.elemVerts[cp], m.elemVerts[mp] + (e < EA ? 0 : VA));
      ASSERT_EQ(c.restOffsets[cp], m.restOffsets[mp]);
    }
  }
  EXPECT_DOUBLE_EQ(c.totalMass, A.totalMass + B.totalMass);
  EXPECT_EQ(c.smallestPeriod, std::min(A.smallestPeriod, B.smallestPeriod));
  EXPECT_EQ(c.smallestVertexPeriod, std::min(A.smallestVertexPeriod, B.smallestVertexPeriod));
  // One model: a copy of it, totals and all.
  const RestModel one = combineRestModels({a.model});
  EXPECT_EQ(one.totalMass, A.totalMass);
  EXPECT_EQ(one.elemVerts, A.elemVerts);
  ASSERT_EQ(one.bodies.size(), 1u);
  EXPECT_EQ(one.bodies[0].vertexEnd, VA);
}

TEST(Bodies, CombineRefusesMixedDimensionsAndNoModels) {
  const Body a = makeBody("sphere", 6, 3, LayoutKind::Gradational);
  const Body b = makeBody("sphere", 6, 2, LayoutKind::Gradational);
  EXPECT_THROW(combineRestModels({a.model, b.model}), std::invalid_argument);
  EXPECT_THROW(combineRestModels({}), std::invalid_argument);
}

// Two bodies that never touch, with different voxel sizes, materials and layouts, in one world
// with walls, gravity, damping and a manipulator striking the first: each evolves bit for bit as
// it does alone in a world of its own (same dt), at one thread and at two.
TEST(Bodies, SeparatedBodiesEvolveBitIdenticallyToEachAlone) {
  const Body a = makeBody("sphere", 16, 3, LayoutKind::Gradational, material(1e5, 1000), 0.01, Vec3(0, 0.05, 0));
  const Body b = makeBody("box", 7, 3, LayoutKind::Voxel, material(4e5, 700), 0.013, Vec3(0.4, 0.02, 0));
  auto combined = std::make_shared<RestModel>(combineRestModels({a.model, b.model}));
  SimulationSettings sim;
  sim.dt = 2e-4;
  sim.damping = 0.5;
  DomainSettings domain;
  domain.enabled = true;
  domain.min = Vec3(-1, 0, -1), domain.max = Vec3(1, 1, 1);
  ManipulatorSettings strike;
  strike.radius = 0.03;
  strike.path.keys = {{0, Vec3(-0.15, 0.1, 0.06), {}}, {0.04, Vec3(0.1, 0.1, 0.06), {}}};
  for (int threads : {1, 2}) {
    sim.threads = threads;
    World wa(a.model, sim, domain, {strike}), wb(b.model, sim, domain, {strike});
    World both(combined, sim, domain, {strike});
    perturb(wa, 1e-4, 0.05, 1), perturb(wb, 1e-4, 0.05, 2);
    const size_t VA = a.model->numVertices();
    for (size_t i = 0; i < VA; ++i)
      both.state().positions[i] = wa.state().positions[i], both.state().velocities[i] = wa.state().velocities[i];
    for (size_t i = 0; i < b.model->numVertices(); ++i)
      both.state().positions[VA + i] = wb.state().positions[i],
                              both.state().velocities[VA + i] = wb.state().velocities[i];
    for (int s = 0; s < 300; ++s) wa.step(), wb.step(), both.step();
    EXPECT_GT(both.metrics().maxContactDepth + wa.state().velocities[0].norm(), 0);  // it moved
    size_t differ = 0;
    for (size_t i = 0; i < VA; ++i)
      differ += !sameBits(both.state().positions[i], wa.state().positions[i]) ||
                !sameBits(both.state().velocities[i], wa.state().velocities[i]);
    for (size_t i = 0; i < b.model->numVertices(); ++i)
      differ += !sameBits(both.state().positions[VA + i], wb.state().positions[i]) ||
                !sameBits(both.state().velocities[VA + i], wb.state().velocities[i]);
    EXPECT_EQ(differ, 0u) << "threads " << threads;
    // Per-body metrics are each body's own; the world's are their sum.
    const std::vector<Metrics> each = both.bodyMetrics();
    ASSERT_EQ(each.size(), 2u);
    EXPECT_EQ(each[0].kineticEnergy, wa.metrics().kineticEnergy);
    EXPECT_EQ(each[1].elasticEnergy, wb.metrics().elasticEnergy);
    EXPECT_EQ(each[1].linearMomentum, wb.metrics().linearMomentum);
    EXPECT_EQ(both.metrics().kineticEnergy, each[0].kineticEnergy + each[1].kineticEnergy);
    // The strike moved the sphere, not the box: the comparison is not between two resting bodies.
    EXPECT_GT(each[0].linearMomentum.x(), 1e-3);
  }
}

TEST(Bodies, PinsSelectOnlyTheirBodysVertices) {
  const Body a = makeBody("box", 4, 3, LayoutKind::Voxel, {}, 0.01);
  const Body b = makeBody("box", 4, 3, LayoutKind::Voxel, {}, 0.01);  // the same place: boxes overlap
  auto combined = std::make_shared<RestModel>(combineRestModels({a.model, b.model}));
  World w(combined, isolated(), {}, {});
  PinSettings p;
  p.min = Vec3(-1, -1, -1), p.max = Vec3(1, 1, 1);  // every vertex of both
  p.body = 1;
  w.setPins({p});
  const size_t VA = a.model->numVertices();
  ASSERT_EQ(w.pinned().vertices.size(), b.model->numVertices());
  EXPECT_EQ(w.pinned().vertices.front(), VA);
  p.body = 2;
  try {
    w.setPins({p});
    FAIL() << "no body 2";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("pins[0].body"), std::string::npos) << e.what();
  }
}
