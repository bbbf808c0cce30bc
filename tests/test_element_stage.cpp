// element_stage: the explicit step's data-parallel element pass and per-vertex gather compute the
// same element (eq. 1) as element.h's reference kernel, to rounding; the batched rotation fit
// follows fitRotation3 lane by lane.
#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "element_stage.h"
#include "gradel/element.h"
#include "gradel/rotation_fit.h"
#include "gradel/shared/scene_presets.h"
#include "test_support.h"

using namespace gradel;
using namespace gradel::test;

namespace {

// Reference forces: element.h's kernel per element, summed per vertex.
std::vector<Vec3> referenceForces(const World& w, std::vector<Quat>& q) {
  const RestModel& m = w.model();
  std::vector<Vec3> forces(m.numVertices(), Vec3::Zero()), f, R0;
  for (size_t e = 0; e < m.numElements(); ++e) {
    const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
    f.resize(n);
    elementForces(m.dim, w.state().positions.data(), &m.elemVerts[b], m.restOffsets(e, R0), int(n), m.stiffness[e], q[e],
                  f.data(), 4);
    for (uint32_t i = 0; i < n; ++i) forces[m.elemVerts[b + i]] += f[i];
  }
  return forces;
}

struct StageCase {
  const char* shape;
  int size, dim;
  LayoutKind kind;
};

class ElementStage : public testing::TestWithParam<StageCase> {};

}  // namespace

// One symplectic step from rest velocity with no gravity or damping gives v = dt f / m exactly
// the stage's forces; they must equal the reference kernel's, and so must the fitted rotations.
TEST_P(ElementStage, ForcesAndRotationsMatchTheReferenceKernel) {
  const StageCase c = GetParam();
  Body b = makeBody(c.shape, c.size, c.dim, c.kind);
  World w(b.model, isolated(), {}, {});
  deformSmoothly(w, 0.05);
  perturb(w, 0.2 * b.model->voxelSize, 0.0, 3);
  // Rotate the whole body by a large angle as well: the warm start (identity) is far off.
  const Quat spin(Eigen::AngleAxisd(0.4, Vec3(1, 2, 3).normalized()));
  for (Vec3& x : w.state().positions) x = spin * x;
  std::vector<Quat> q = w.state().rotations;
  const std::vector<Vec3> ref = referenceForces(w, q);
  Real scale = 0;
  for (const Vec3& f : ref) scale = std::max(scale, f.norm());
  ASSERT_GT(scale, 0);

  w.step();
  const RestModel& m = w.model();
  Real worst = 0;
  for (size_t i = 0; i < m.numVertices(); ++i) {
    const Vec3 f = w.state().velocities[i] * m.mass[i] / w.dt();
    worst = std::max(worst, (f - ref[i]).norm() / scale);
  }
  EXPECT_LT(worst, 1e-9);
  Real rotWorst = 0;
  for (size_t e = 0; e < m.numElements(); ++e)
    rotWorst = std::max(rotWorst, (w.state().rotations[e].toRotationMatrix() - q[e].toRotationMatrix()).norm());
  EXPECT_LT(rotWorst, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(Shapes, ElementStage,
                         testing::Values(StageCase{"sphere", 16, 3, LayoutKind::Gradational},
                                         StageCase{"box", 12, 3, LayoutKind::Uniform},
                                         StageCase{"sphere", 8, 3, LayoutKind::Voxel},
                                         StageCase{"sphere", 20, 2, LayoutKind::Gradational}),
                         [](const testing::TestParamInfo<StageCase>& i) {
                           return std::string(i.param.shape) + std::to_string(i.param.size) + "_" +
                                  std::to_string(i.param.dim) + "d_" + layoutKindName(i.param.kind);
                         });

// Every lane of the batched fit does what fitRotation3 does on its own: random, flat and
// inverted matrices, warm starts near and far, lanes that stop at different iterations.
TEST(RotationFitBatch, EachLaneMatchesTheScalarFit) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<Real> u(-1, 1);
  for (int trial = 0; trial < 300; ++trial) {
    RotationBatch batch;
    Mat3 A[kRotationLanes];
    Quat q[kRotationLanes];
    for (int l = 0; l < kRotationLanes; ++l) {
      for (int k = 0; k < 9; ++k) A[l].data()[k] = u(rng);
      if (trial % 5 == 1) A[l].col(2).setZero();  // flat element
      if (trial % 5 == 2) A[l].col(0) *= -1;      // inverted element
      if (trial % 5 == 3)
        A[l] = Quat(Eigen::AngleAxisd(u(rng), Vec3(u(rng), u(rng), 1).normalized())).toRotationMatrix();
      q[l] = Quat(Eigen::AngleAxisd(trial % 2 ? 0.01 * u(rng) : 3 * u(rng), Vec3(u(rng), 1, u(rng)).normalized()));
      for (int k = 0; k < 9; ++k) batch.A[k][l] = A[l](k / 3, k % 3);
      batch.q[0][l] = q[l].w(), batch.q[1][l] = q[l].x(), batch.q[2][l] = q[l].y(), batch.q[3][l] = q[l].z();
    }
    fitRotation3Batch(batch, 20, 1e-12);
    for (int l = 0; l < kRotationLanes; ++l) {
      Quat ref = q[l];
      fitRotation3(A[l], ref, 20, 1e-12);
      const Quat got(batch.q[0][l], batch.q[1][l], batch.q[2][l], batch.q[3][l]);
      EXPECT_LT((got.toRotationMatrix() - ref.toRotationMatrix()).norm(), 1e-9) << "trial " << trial << " lane " << l;
      EXPECT_NEAR(got.norm(), 1.0, 1e-12);
      Mat3 M;
      for (int k = 0; k < 9; ++k) M(k / 3, k % 3) = batch.M[k][l];
      EXPECT_LT((M - got.toRotationMatrix()).norm(), 1e-12);
    }
  }
}

// The element pass forms R0 = X - C from the rest positions (pass 2) and from lattice offsets
// (pass 1, R0 = h (P - mean P)): both must reproduce the model's offsets, X - C bit for bit.
TEST(ElementStageRest, RestCentroidsAndLatticeOffsetsReproduceTheRestOffsets) {
  for (LayoutKind kind : {LayoutKind::Gradational, LayoutKind::Uniform, LayoutKind::Voxel}) {
    Body b = makeBody("sphere", 14, 3, kind, {}, 0.01, Vec3(0.3, -0.2, 0.7));
    const RestModel& m = *b.model;
    const ElementStageRest rest(m);
    size_t mismatches = 0;
    Real worst = 0;
    for (size_t e = 0; e < m.numElements(); ++e) {
      const ElementConstants k = rest.constants(m, e);
      const Vec3 C(k.restCentroid[0], k.restCentroid[1], k.restCentroid[2]);
      const Vec3 meanP = Vec3(k.sumLattice[0], k.sumLattice[1], k.sumLattice[2]) * k.invCount;
      EXPECT_EQ(k.stiffness, m.stiffness[e]);
      for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1]; ++p) {
        mismatches += (m.restPositions[m.elemVerts[p]] - C) != m.restOffset(e, p);
        int P[4];
        rest.lattice(p, P);
        ASSERT_EQ(P[3], 1);
        const Vec3 R0 = m.voxelSize * (Vec3(P[0], P[1], P[2]) - meanP);
        worst = std::max(worst, (R0 - m.restOffset(e, p)).norm() / m.voxelSize);
      }
    }
    EXPECT_EQ(mismatches, 0u) << layoutKindName(kind);
    EXPECT_LT(worst, 1e-12) << layoutKindName(kind);
  }
}

// The pair records are one byte a coordinate when every lattice offset fits, else int16: both
// give the same frames and rotations bit for bit (here the narrow records of a sphere widened by
// hand), over the whole model and over a range ending inside a batch of four.
TEST(ElementStageRest, NarrowAndWidePairRecordsGiveTheSameFrames) {
  Body b = makeBody("sphere", 14, 3, LayoutKind::Gradational);
  World w(b.model, isolated(), {}, {});
  deformSmoothly(w, 0.05);
  perturb(w, 0.2 * b.model->voxelSize, 0.0, 5);
  const RestModel& m = *b.model;
  const ElementStageRest narrow(m);
  ASSERT_FALSE(narrow.lattice8.empty());
  ASSERT_TRUE(narrow.lattice16.empty());
  ElementStageRest wide = narrow;
  wide.lattice16.assign(narrow.lattice8.begin(), narrow.lattice8.end());
  wide.lattice8.clear();
  const size_t E = m.numElements();
  ASSERT_NE(E % 4, 0u);  // the model's last batch is a partial one
  for (size_t end : {E, size_t(E / 8 * 4 + 2)}) {
    std::vector<Quat> q8(E, Quat::Identity()), q16 = q8;
    std::vector<ElementFrame> f8(E), f16(E);
    computeElementFrames(m, narrow, 0, end, w.state().positions.data(), q8.data(), f8.data(), 20);
    computeElementFrames(m, wide, 0, end, w.state().positions.data(), q16.data(), f16.data(), 20);
    EXPECT_EQ(std::memcmp(f8.data(), f16.data(), end * sizeof(ElementFrame)), 0) << end;
    EXPECT_EQ(std::memcmp(q8.data(), q16.data(), E * sizeof(Quat)), 0) << end;
  }
}

// A vertex of no element (not made by buildRestModel, but a RestModel may hold one) gets zero
// force, and the other vertices' forces are those of the model without it, bit for bit.
TEST(ElementStageRest, AVertexOfNoElementGetsNoForce) {
  Body b = makeBody("sphere", 10, 3, LayoutKind::Gradational);
  World w(b.model, isolated(), {}, {});
  deformSmoothly(w, 0.05);
  const RestModel& m = *b.model;
  const size_t lone = m.numVertices() / 2, V = m.numVertices(), E = m.numElements();
  RestModel withLone = m;
  withLone.restPositions.insert(withLone.restPositions.begin() + long(lone), m.restPositions[lone]);
  for (uint32_t& v : withLone.elemVerts) v += v >= lone ? 1 : 0;
  for (BodyRange& r : withLone.bodies) r.vertexEnd += 1;
  std::vector<Vec3> x = w.state().positions;
  x.insert(x.begin() + long(lone), Vec3(1, 2, 3));
  const ElementStageRest rest(m), restLone(withLone);
  ASSERT_TRUE(rest.everyVertexInAnElement);
  ASSERT_FALSE(restLone.everyVertexInAnElement);
  auto forces = [&](const RestModel& model, const ElementStageRest& r, const std::vector<Vec3>& pos) {
    std::vector<Quat> q(E, Quat::Identity());
    std::vector<ElementFrame> frames(E);
    computeElementFrames(model, r, 0, E, pos.data(), q.data(), frames.data(), 20);
    std::vector<Vec3> f(model.numVertices());
    gatherVertexForces(model, r, frames.data(), 0, model.numVertices(), [&](size_t v, simd::d4 partial, Real k) {
      const simd::d4 force = partial - k * simd::loadVec3(pos[v]);
      f[v] = Vec3(force[0], force[1], force[2]);
    });
    return f;
  };
  const std::vector<Vec3> f = forces(m, rest, w.state().positions), g = forces(withLone, restLone, x);
  EXPECT_EQ(g[lone], Vec3::Zero());
  size_t differ = 0;
  for (size_t v = 0; v < V; ++v) differ += f[v] != g[v + (v >= lone ? 1 : 0)];
  EXPECT_EQ(differ, 0u);
}

// A rest position off the voxel lattice cannot be streamed as lattice offsets: refused loudly.
TEST(ElementStageRest, RefusesRestPositionsOffTheLattice) {
  Body b = makeBody("sphere", 6, 3, LayoutKind::Gradational);
  RestModel m = *b.model;
  m.restPositions[3].x() += 0.3 * m.voxelSize;
  EXPECT_THROW(ElementStageRest{m}, std::logic_error);
}

// The step fits rotations to kFrameRotationTolerance, warm-started from the last step's fit: over
// a run of the paper's setting (a 3 % stretch and shear ringing undamped, elements turning 1e-3 to
// 1e-2 rad a step), every stored rotation stays within a few times that tolerance (and the
// rounding of the stage's A / h) of the scalar fit to 1e-12 from the same warm start, so the
// step's fit does not accumulate error.
TEST(ElementStageRotations, StayWithinTheStepToleranceOfTheTightFit) {
  BuiltScene b = buildScene(paperBenchScene("sphere", 12, LayoutKind::Gradational));
  World& w = *b.world;
  preparePaperBench(w);
  const RestModel& m = w.model();
  std::vector<Quat> tight(m.numElements());
  const std::vector<Vec3> R0 = m.pairRestOffsets();
  Real worst = 0, moved = 0;
  for (int s = 0; s < 200; ++s) {
    for (size_t e = 0; e < m.numElements(); ++e) {
      const uint32_t first = m.elemStart[e], n = m.elemStart[e + 1] - first;
      const Mat3 A = elementCovariance(w.state().positions.data(), &m.elemVerts[first], &R0[first], int(n));
      tight[e] = w.state().rotations[e];
      fitRotation3(A, tight[e], 20, 1e-12);
      moved = std::max(moved, 2 * (w.state().rotations[e].conjugate() * tight[e]).vec().norm());
    }
    w.step();
    for (size_t e = 0; e < m.numElements(); ++e)
      worst = std::max(worst, 2 * (tight[e].conjugate() * w.state().rotations[e]).vec().norm());
  }
  EXPECT_GT(moved, 1e-3);  // the elements do turn: the warm start is not already the answer
  EXPECT_LT(worst, std::max<Real>(3 * kFrameRotationTolerance, 1e-10));
}
