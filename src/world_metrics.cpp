// World's figures (world.h Metrics): energies, momenta, stress, strain, penetration, per body
// and combined, and the per-element and per-vertex stress and strain.
#include <algorithm>
#include <cmath>
#include <limits>

#include "gradel/element.h"
#include "gradel/element_strain.h"
#include "gradel/material.h"
#include "step_context.h"
#include "thread_team.h"

namespace gradel {

std::vector<Real> World::elementStress() const {
  return elementVonMisesStress(*model_, state_.positions, state_.rotations);
}

std::vector<Real> World::vertexStrain() const { return vertexStress(elementStrain()); }

std::vector<Real> World::elementStrain() const {
  const RestModel& m = *model_;
  std::vector<Real> s(m.numElements());
  std::vector<Vec3> f, offsets;
  for (size_t e = 0; e < m.numElements(); ++e) {
    const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
    f.resize(n);
    Quat q = state_.rotations[e];
    const ElementResult r = elementForces(m.dim, state_.positions.data(), &m.elemVerts[b], m.restOffsets(e, offsets), int(n),
                                          m.stiffness[e], q, f.data(), 20);
    s[e] = std::sqrt(r.sumSqDisp / n) / m.size[e];
  }
  return s;
}

std::vector<Real> World::vertexStress() const { return vertexStress(elementStress()); }

std::vector<Real> World::vertexStress(const std::vector<Real>& elementStress) const {
  const RestModel& m = *model_;
  // Mean over each vertex's elements, summed in element order (deterministic).
  std::vector<Real> sum(m.numVertices(), 0.0);
  std::vector<uint32_t> count(m.numVertices(), 0);
  for (size_t e = 0; e < m.numElements(); ++e)
    for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1]; ++p)
      sum[m.elemVerts[p]] += elementStress[e], ++count[m.elemVerts[p]];
  for (size_t i = 0; i < sum.size(); ++i) sum[i] = count[i] ? sum[i] / count[i] : 0;
  return sum;
}

Metrics World::metrics(std::vector<Real>* elementStress, std::vector<Real>* elementStrain) const {
  Metrics r = combineMetrics(bodyMetrics(elementStress, elementStrain));
  r.contactForces = averageContactForces();  // the world's: what all bodies exert together
  return r;
}

Metrics combineMetrics(const std::vector<Metrics>& each) {
  if (each.empty()) throw std::invalid_argument("combineMetrics: no bodies");
  Metrics r = each[0];
  for (size_t k = 1; k < each.size(); ++k) {
    const Metrics& b = each[k];
    r.kineticEnergy += b.kineticEnergy, r.elasticEnergy += b.elasticEnergy, r.gravityEnergy += b.gravityEnergy;
    r.shadowEnergy += b.shadowEnergy;
    r.linearMomentum += b.linearMomentum, r.angularMomentum += b.angularMomentum;
    r.maxStress = std::max(r.maxStress, b.maxStress), r.maxStrain = std::max(r.maxStrain, b.maxStrain);
    r.maxPenetration = std::max(r.maxPenetration, b.maxPenetration);
    r.minElementDet = std::min(r.minElementDet, b.minElementDet);
    r.removed.voxels += b.removed.voxels, r.removed.volume += b.removed.volume;
    r.removed.mass += b.removed.mass, r.removed.momentum += b.removed.momentum;
  }
  return r;
}

std::vector<Metrics> World::bodyMetrics(std::vector<Real>* elementStress, std::vector<Real>* elementStrain) const {
  if (elementStress) elementStress->assign(model_->numElements(), 0.0);
  if (elementStrain) elementStrain->assign(model_->numElements(), 0.0);
  std::vector<Metrics> r;
  for (const BodyRange& b : model_->bodies) r.push_back(metricsOf(b, elementStress, elementStrain));
  for (size_t b = 0; b < r.size() && b < removed_.size(); ++b) r[b].removed = removed_[b];
  return r;
}

Metrics World::metricsOf(const BodyRange& body, std::vector<Real>* elementStress,
                         std::vector<Real>* elementStrain) const {
  const RestModel& m = *model_;
  Metrics r;
  r.time = state_.time;
  const Vec3 g = sim_.gravity;
  const size_t v0 = body.vertexBegin;

  // Elastic forces and energy at the current positions (the body's elements touch only its
  // vertices): each element's figures and its vertices' forces on the team (`gradel run` asks
  // every frame: ~10 % of box-realtime's run on one thread), then summed here in element order,
  // the same sums at any thread count.
  struct ElementFigures {
    Real energy = 0, volumeEnergy = 0, strain = 0, stress = 0, det = 0;
  };
  const size_t e0 = body.elementBegin, ne = body.numElements();
  const uint32_t p0 = m.elemStart[e0];
  std::vector<ElementFigures> figures(ne);
  std::vector<Vec3> pairForce(m.elemStart[body.elementEnd] - p0);
  forEachInChunks(team_.get(), ne, 64, [&](size_t k) {
    const size_t e = e0 + k;
    const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
    Vec3* f = &pairForce[b - p0];
    Quat q = state_.rotations[e];
    ElementFigures& fig = figures[k];
    thread_local std::vector<Vec3> offsets;  // (its storage reused from element to element on each thread)
    const Vec3* R0 = m.restOffsets(e, offsets);
    const ElementResult er = elementForces(m.dim, state_.positions.data(), &m.elemVerts[b], R0, int(n),
                                           m.stiffness[e], q, f, 20);
    if (m.hasVolumeTerm() && m.volumeStiffness[e] > 0)  // Poisson's ratio > 0 (element.h)
      fig.volumeEnergy = elementVolumeForces(m.dim, state_.positions.data(), &m.elemVerts[b], R0,
                                             int(n), q, m.volumeStiffness[e], f);
    fig.energy = er.energy;
    fig.strain = std::sqrt(er.sumSqDisp / n) / m.size[e];
    // The strain and the determinant from one covariance and one rest moment (elementVonMises and
    // elementDeterminant form each once more, and fit again to the same A: the same values).
    const Mat3 A = elementCovariance(state_.positions.data(), &m.elemVerts[b], R0, int(n));
    const Mat3 S = restSecondMoment(R0, n);
    fig.stress = vonMisesStress(elementStrainOfFit(m.dim, A, q, restMomentInverse(m.dim, S)),
                                elementYoungsModulus(m, e), elementPoissonRatio(m, e));
    fig.det = deformationDeterminant(m.dim, A, S);
  });
  std::vector<Vec3> forces(body.numVertices(), Vec3::Zero());
  r.minElementDet = std::numeric_limits<Real>::infinity();
  for (size_t k = 0; k < ne; ++k) {
    const size_t e = e0 + k;
    const ElementFigures& fig = figures[k];
    r.elasticEnergy += fig.volumeEnergy;  // 0 without a volumetric term (adding it changes no bit)
    for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1]; ++p) forces[m.elemVerts[p] - v0] += pairForce[p - p0];
    r.elasticEnergy += fig.energy;
    if (elementStrain) (*elementStrain)[e] = fig.strain;
    r.maxStrain = std::max(r.maxStrain, fig.strain);
    if (elementStress) (*elementStress)[e] = fig.stress;
    r.maxStress = std::max(r.maxStress, fig.stress);
    r.minElementDet = std::min(r.minElementDet, fig.det);
  }

  // Symplectic Euler's stored velocity belongs half a step before its positions (it is the
  // leapfrog v_{n-1/2}); the kinetic energy at time t uses v + a(x) dt / 2, as Stormer-Verlet
  // does. This is what makes the measured energy of an undamped run flat to O(dt^2) rather
  // than swing by O(omega dt). Forward Euler's velocity is already synchronous.
  // The modified energy's term -dt^2/8 m |a|^2 (Metrics::shadowEnergy) makes the total the
  // quantity symplectic Euler keeps: 1/2 m v_{n-1/2} . v_{n+1/2} = 1/2 m |v_n|^2 - dt^2/8 m |a|^2.
  const bool staggered = sim_.integrator == IntegratorKind::SymplecticEuler;
  for (size_t i = body.vertexBegin; i < body.vertexEnd; ++i) {
    const Vec3& x = state_.positions[i];
    Vec3 v = state_.velocities[i];
    if (staggered) {
      const Vec3 a = forces[i - v0] * m.invMass[i] + g;
      v += 0.5 * dt_ * a;
      r.shadowEnergy -= 0.125 * dt_ * dt_ * m.mass[i] * a.squaredNorm();
    }
    r.kineticEnergy += 0.5 * m.mass[i] * v.squaredNorm();
    r.gravityEnergy -= m.mass[i] * g.dot(x);
    r.linearMomentum += m.mass[i] * v;
    r.angularMomentum += m.mass[i] * x.cross(v);
    Real pen = 0;
    for (const Manipulator& mp : manipulators_) pen = std::max(pen, -mp.signedDistance(x, nullptr));
    if (domain_.enabled)
      for (int a = 0; a < m.dim; ++a) pen = std::max({pen, domain_.min[a] - x[a], x[a] - domain_.max[a]});
    r.maxPenetration = std::max(r.maxPenetration, pen);
  }
  r.maxContactDepth = scratch_->maxContactDepth;
  return r;
}

}  // namespace gradel
