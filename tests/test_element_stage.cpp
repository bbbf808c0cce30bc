// element_stage: the explicit step's data-parallel element pass and per-vertex gather compute the
// same element (eq. 1) as element.h's reference kernel, to rounding; the batched rotation fit
// follows fitRotation3 lane by lane.
#include <gtest/gtest.h>

#include <random>

#include "element_stage.h"
#include "gradel/element.h"
#include "gradel/rotation_fit.h"
#include "test_support.h"

using namespace gradel;
using namespace gradel::test;

namespace {

// Reference forces: element.h's kernel per element, summed per vertex.
std::vector<Vec3> referenceForces(const World& w, std::vector<Quat>& q) {
  const RestModel& m = w.model();
  std::vector<Vec3> forces(m.numVertices(), Vec3::Zero()), f;
  for (size_t e = 0; e < m.numElements(); ++e) {
    const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
    f.resize(n);
    elementForces(m.dim, w.state().positions.data(), &m.elemVerts[b], &m.restOffsets[b], int(n), m.stiffness[e], q[e],
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

// The element pass forms R0 = X - C from the rest positions instead of streaming restOffsets:
// that must reproduce the model's offsets bit for bit (else the two would drift apart).
TEST(ElementStageRest, RestCentroidsReproduceTheRestOffsetsExactly) {
  for (LayoutKind kind : {LayoutKind::Gradational, LayoutKind::Uniform, LayoutKind::Voxel}) {
    Body b = makeBody("sphere", 14, 3, kind, {}, 0.01, Vec3(0.3, -0.2, 0.7));
    const RestModel& m = *b.model;
    const ElementStageRest rest(m);
    size_t mismatches = 0;
    for (size_t e = 0; e < m.numElements(); ++e)
      for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1]; ++p)
        mismatches += (m.restPositions[m.elemVerts[p]] - rest.restCentroids[e]) != m.restOffsets[p];
    EXPECT_EQ(mismatches, 0u) << layoutKindName(kind);
  }
}
