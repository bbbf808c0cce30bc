// Carving: the event (carveBody) and the voxel sets of a tool (voxelsInSphere, voxelsInCapsule,
// voxelsInCylinder).
// carve.h says what is kept and why.
#include "gradel/carve.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <vector>

#include "gradel/material.h"
#include "carve_cells.h"

namespace gradel {

namespace {

using namespace carve_cells;

// Voxel mass [kg] of each label's material (consistent scaling: rho h^3; paper: the same voxel mass).
Real voxelMass(const RestModel& m, uint16_t label, Real h, int dim) {
  size_t i = 0;
  while (i + 1 < m.materialLabel.size() && m.materialLabel[i] != label) ++i;
  return cellCornerMass(m.materials[i], h, 1, dim) * cornerCount(dim);
}

Real boxDistance(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  return (p - p.cwiseMax(lo).cwiseMin(hi)).norm();
}

}  // namespace

CarvedBody carveBody(const CarveInput& b, const std::vector<uint8_t>& remove) {
  checkInput(b);
  const VoxelVolume& old = *b.volume;
  const Layout& oldLayout = *b.layout;
  const RestModel& oldModel = *b.model;
  if (remove.size() != old.size()) throw std::invalid_argument("carve: the mask's size is not the volume's");
  const int D = oldLayout.dim;
  const Real h = oldLayout.voxelSize;
  CarvedBody out;
  out.volume = old;
  const std::vector<int32_t> owner = voxelOwners(oldLayout, old);

  // What leaves: each removed voxel's mass and its momentum at its centre.
  const auto& n = old.dims();
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        const size_t q = old.index(i, j, k);
        if (!remove[q] || !old.at(i, j, k)) continue;
        const Real m = voxelMass(oldModel, old.label(i, j, k), h, D);
        const MassCell c = cellOfVoxel(oldLayout, size_t(owner[q]), Int3(i, j, k));
        const Vec3 centre(i + 0.5, j + 0.5, D == 3 ? k + 0.5 : 0.0);
        const Vec3 v = interpolate(c, trilinear(localPoint(c, centre), D), b.velocities);
        out.removedMass += m, out.removedMomentum += m * v, out.removedKineticEnergy += 0.5 * m * v.squaredNorm();
        out.volume.set(i, j, k, false);
        ++out.removedVoxels;
      }
  if (out.removedVoxels == old.countFilled()) {
    out.emptied = true;
    out.removedVoxels = 0, out.removedMass = 0, out.removedMomentum.setZero(), out.removedKineticEnergy = 0;
    out.volume = old;
  }
  out.removedVolume = Real(out.removedVoxels) * h * h * h;
  if (out.removedVoxels == 0) {
    out.layout = oldLayout;
    out.model = std::make_shared<const RestModel>(oldModel);
    out.positions.assign(b.positions, b.positions + oldModel.numVertices());
    out.velocities.assign(b.velocities, b.velocities + oldModel.numVertices());
    if (b.rotations)
      out.rotations.assign(b.rotations, b.rotations + oldModel.numElements());
    else
      out.rotations.assign(oldModel.numElements(), Quat::Identity());
    out.fromVertex.resize(oldModel.numVertices());
    for (uint32_t v = 0; v < out.fromVertex.size(); ++v) out.fromVertex[v] = v;
    return out;
  }

  // The new body: a full re-layout by the body's own rule and its rest model.
  out.layout = buildLayout(out.volume, oldLayout.kind);
  auto model = std::make_shared<RestModel>(buildRestModel(out.layout, out.volume, oldModel.material, oldModel.origin));
  Vec3 before = Vec3::Zero();
  for (size_t v = 0; v < oldModel.numVertices(); ++v) before += oldModel.mass[v] * b.velocities[v];
  Transferred t = transferState(oldLayout, owner, old, b.positions, b.velocities, b.rotations, out.volume, out.layout,
                                *model, before - out.removedMomentum);
  takeTransferred(out, std::move(t));
  out.model = std::move(model);
  return out;
}

std::vector<uint8_t> voxelsInSphere(const CarveInput& body, const Vec3& centre, Real radius, size_t* count) {
  return voxelsWhere(
      body, [&](const Vec3& lo, const Vec3& hi) { return boxDistance(centre, lo, hi) <= radius; },
      [&](const Vec3& x) { return (x - centre).squaredNorm() <= radius * radius; }, count);
}

std::vector<uint8_t> voxelsInCapsule(const CarveInput& body, const Vec3& from, const Vec3& to, Real radius,
                                     size_t* count) {
  const Vec3 d = to - from;
  const Real len2 = d.squaredNorm();
  auto distance = [&](const Vec3& x) {
    const Real t = len2 > 0 ? std::clamp((x - from).dot(d) / len2, Real(0), Real(1)) : Real(0);
    return (x - (from + t * d)).norm();
  };
  const Vec3 lo = from.cwiseMin(to), hi = from.cwiseMax(to);
  return voxelsWhere(
      body,
      [&](const Vec3& bmin, const Vec3& bmax) {
        return ((bmin - hi).cwiseMax(lo - bmax).cwiseMax(Vec3::Zero())).norm() <= radius;
      },
      [&](const Vec3& x) { return distance(x) <= radius; }, count);
}

std::vector<uint8_t> voxelsInCylinder(const CarveInput& body, const Vec3& from, const Vec3& to, const Vec3& axis,
                                      Real radius, Real halfLength, size_t* count) {
  if (!(axis.norm() > 0) || !axis.allFinite()) throw std::invalid_argument("carve: the cylinder's axis is zero");
  const Vec3 a = axis.normalized(), d = to - from;
  const Real along = d.dot(a);
  const Vec3 across = d - along * a;  // the move across the axis: the disc sweeps a stadium
  const Real across2 = across.squaredNorm();
  const Real zLo = std::min(Real(0), along) - halfLength, zHi = std::max(Real(0), along) + halfLength;
  auto inside = [&](const Vec3& x) {
    const Vec3 y = x - from;
    const Real z = y.dot(a);
    if (z < zLo || z > zHi) return false;
    const Vec3 p = y - z * a;
    const Real t = across2 > 0 ? std::clamp(p.dot(across) / across2, Real(0), Real(1)) : Real(0);
    return (p - t * across).squaredNorm() <= radius * radius;
  };
  // The cylinder's box (half extents per axis), at both ends of the move.
  Vec3 e;
  for (int k = 0; k < 3; ++k) e[k] = halfLength * std::abs(a[k]) + radius * std::sqrt(std::max(Real(0), 1 - a[k] * a[k]));
  const Vec3 lo = from.cwiseMin(to) - e, hi = from.cwiseMax(to) + e;
  return voxelsWhere(
      body, [&](const Vec3& bmin, const Vec3& bmax) { return (bmin.array() <= hi.array()).all() && (lo.array() <= bmax.array()).all(); },
      inside, count);
}

}  // namespace gradel
