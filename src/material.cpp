// The material rules of material.h: lumped masses and per-element stiffness for the two scalings.
#include "gradel/material.h"

#include <cmath>
#include <numbers>

#include <Eigen/Eigenvalues>

namespace gradel {

Scaling parseScaling(const std::string& name) {
  if (name == "consistent") return Scaling::Consistent;
  if (name == "paper") return Scaling::Paper;
  throw InputError("unknown scaling '" + name + "' (expected consistent or paper)");
}

const char* scalingName(Scaling s) { return s == Scaling::Paper ? "paper" : "consistent"; }

MaterialSettings regionMaterial(const MaterialSettings& m, uint16_t label) {
  MaterialSettings out = m;
  out.regions.clear();
  for (const RegionMaterial& r : m.regions)
    if (r.label == label) {
      out.youngsModulus = r.youngsModulus;
      out.density = r.density;
      out.paperK = r.paperK;
      out.poissonRatio = r.poissonRatio;
      out.damping = r.damping;
      return out;
    }
  if (label == 1) return out;
  std::string known;
  for (const RegionMaterial& r : m.regions) known += (known.empty() ? "" : ", ") + std::to_string(r.label);
  throw InputError("", "regions",
                   "label " + std::to_string(label) + " of the volume has no entry (expected one with \"label\": " +
                       std::to_string(label) + "; the table has " + (known.empty() ? std::string("none") : known) +
                       ", and label 1 takes the body's own fields)");
}

// 2D bodies are slabs one voxel thick: a lattice voxel's volume is h^3 in both.
Real paperVertexMass(const MaterialSettings& m, Real h) {
  const Real voxelVolume = h * h * h;
  return m.density * voxelVolume;  // "reduced mass per voxel" (sec. 2.3)
}

Real cellCornerMass(const MaterialSettings& m, Real h, int cellEdge, int dim) {
  const Real voxelVolume = h * h * h;
  const Real cellMass = m.density * voxelVolume * std::pow(Real(cellEdge), dim);
  const int corners = dim == 3 ? 8 : 4;
  return cellMass / corners;
}

Mat3 restSecondMoment(const Vec3* r, size_t n) {
  Mat3 S = Mat3::Zero();
  for (size_t i = 0; i < n; ++i) S.noalias() += r[i] * r[i].transpose();
  return S;
}

namespace {

Real largestRestMoment(int dim, const Vec3* restOffsets, size_t n) {
  const Mat3 S = restSecondMoment(restOffsets, n);
  return dim == 3 ? Eigen::SelfAdjointEigenSolver<Mat3>(S, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff()
                  : Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(S.topLeftCorner<2, 2>(), Eigen::EigenvaluesOnly)
                        .eigenvalues()
                        .maxCoeff();
}

// k_e at nu = 0 (material.h).
Real shapeStiffness(const MaterialSettings& m, int dim, Real h, int64_t regionVoxels, Real elementSize,
                    const Vec3* restOffsets, size_t n) {
  if (m.scaling == Scaling::Paper) return m.paperK / elementSize;  // displacement / element size (sec. 2.2)
  // No direction stiffer than the continuum (material.h): k_e = E V_e / lambda_max(S),
  // S = sum R0_i R0_i^T. A complete element's S is isotropic and this is D E V_e / tr S.
  const Real voxelVolume = h * h * h;
  const Real regionVolume = Real(regionVoxels) * voxelVolume;
  return m.youngsModulus * regionVolume / largestRestMoment(dim, restOffsets, n);
}

}  // namespace

Real elementStiffness(const MaterialSettings& m, int dim, Real h, int64_t regionVoxels, Real elementSize,
                      const Vec3* restOffsets, size_t n) {
  const Real k = shapeStiffness(m, dim, h, regionVoxels, elementSize, restOffsets, n);
  // mu = E / (2 (1 + nu)); nu = 0 leaves k untouched (bit for bit).
  return m.poissonRatio > 0 ? k / (1 + m.poissonRatio) : k;
}

Real elementVolumeStiffness(const MaterialSettings& m, int dim, Real h, int64_t regionVoxels, Real elementSize,
                            const Vec3* restOffsets, size_t n) {
  const Real nu = m.poissonRatio;
  if (!(nu > 0)) return 0;
  // E V_e = k_e(nu = 0) lambda_max(S) (also `paper`'s equivalent modulus times V_e); kappa = lambda V_e.
  const Real EV = shapeStiffness(m, dim, h, regionVoxels, elementSize, restOffsets, n) *
                  largestRestMoment(dim, restOffsets, n);
  return EV * nu / ((1 + nu) * (1 - 2 * nu));
}

Real springPeriod(Real mass, Real stiffness) { return 2 * std::numbers::pi * std::sqrt(mass / stiffness); }

}  // namespace gradel
