// The body-contact stage's energy cap (body_contact_energy.h).
#include "body_contact_energy.h"

#include <algorithm>
#include <cmath>

#include "gradel/element.h"

namespace gradel {

void ContactEnergyLimiter::prepare(const RestModel& m) {
  const size_t V = m.numVertices(), E = m.numElements();
  if (model_ == &m && vertexStart_.size() == V + 1 && elementMark_.size() == E &&
      vertexElements_.size() == m.elemVerts.size())
    return;
  model_ = &m;
  vertexStart_.assign(V + 1, 0);
  for (uint32_t u : m.elemVerts) ++vertexStart_[u + 1];
  for (size_t i = 0; i < V; ++i) vertexStart_[i + 1] += vertexStart_[i];
  vertexElements_.assign(m.elemVerts.size(), 0);
  std::vector<uint32_t> at(vertexStart_.begin(), vertexStart_.end() - 1);
  for (uint32_t e = 0; e < E; ++e)
    for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1]; ++p) vertexElements_[at[m.elemVerts[p]]++] = e;
  elementMark_.assign(E, 0), vertexMark_.assign(V, 0), slot_.assign(V, 0);
  mark_ = 0;
}

// The elements holding any of `verts`, ascending (marks elementMark_ with mark_).
void ContactEnergyLimiter::elementsOf(const std::vector<uint32_t>& verts, std::vector<uint32_t>& out) {
  out.clear();
  for (uint32_t u : verts)
    for (uint32_t j = vertexStart_[u]; j < vertexStart_[u + 1]; ++j) {
      const uint32_t e = vertexElements_[j];
      if (elementMark_[e] != mark_) elementMark_[e] = mark_, out.push_back(e);
    }
  std::sort(out.begin(), out.end());
}

// The elastic energy of inner_ and the kinetic energy of ring_ at w = v + a dt / 2, a from the
// forces of outer_ (every element of a ring vertex) and gravity; w per ring vertex into `w`.
Real ContactEnergyLimiter::measure(const RestModel& m, const ContactEnergyInput& in, const Vec3* x, const Vec3* v,
                                   std::vector<Vec3>& w) {
  Real elastic = 0;
  std::fill(force_.begin(), force_.end(), Vec3::Zero());
  for (size_t k = 0; k < outer_.size(); ++k) {
    const uint32_t e = outer_[k], b = m.elemStart[e], n = m.elemStart[e + 1] - b;
    f_.assign(n, Vec3::Zero());
    Quat q = in.rotations[e];
    const Vec3* R0 = m.restOffsets(e, offsets_);
    Real energy = elementForces(m.dim, x, &m.elemVerts[b], R0, int(n), m.stiffness[e], q, f_.data(), 20).energy;
    if (m.hasVolumeTerm() && m.volumeStiffness[e] > 0)
      energy += elementVolumeForces(m.dim, x, &m.elemVerts[b], R0, int(n), q, m.volumeStiffness[e], f_.data());
    if (isInner_[k]) elastic += energy;
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t u = m.elemVerts[b + i];
      if (vertexMark_[u] == mark_) force_[slot_[u]] += f_[i];
    }
  }
  Real kinetic = 0;
  w.resize(ring_.size());
  for (size_t i = 0; i < ring_.size(); ++i) {
    const uint32_t u = ring_[i];
    w[i] = v[u] + Real(0.5) * in.dt * (force_[i] * m.invMass[u] + in.gravity);
    kinetic += Real(0.5) * m.mass[u] * w[i].squaredNorm();
  }
  return elastic + kinetic;
}

// The bodies the stage's contacts link (a pair of balls, every body of a touching stack) as one
// group each, on its own: one mean over every touched vertex of the stage would move momentum
// between two hits far apart. (Groups of contacts sharing a vertex instead split one hit into
// patches whose elements overlap: the 1 m/s pair of the header peaked at 1.049x.)
ContactEnergyCap ContactEnergyLimiter::apply(const RestModel& m, const ContactEnergyInput& in, Vec3* x, Vec3* v) {
  ContactEnergyCap cap;
  const std::vector<uint32_t>& T = *in.touched;
  if (T.empty() || !(in.dt > 0)) return cap;
  prepare(m);
  // Union-find over the bodies, linked by each contact's vertex and face corners; a group is
  // numbered by its lowest body.
  parent_.resize(m.numBodies());
  for (size_t b = 0; b < parent_.size(); ++b) parent_[b] = uint32_t(b);
  auto find = [&](uint32_t b) {
    while (parent_[b] != b) b = parent_[b] = parent_[parent_[b]];
    return b;
  };
  for (const BodyContacts::Contact& c : *in.contacts) {
    const uint32_t a = find(m.bodyOfVertex(c.vertex));
    for (uint32_t u : c.face) {
      const uint32_t b = find(m.bodyOfVertex(u));
      if (a != b) parent_[std::max(a, b)] = std::min(a, b);
    }
  }
  order_.resize(T.size()), group_.resize(T.size());
  for (size_t i = 0; i < T.size(); ++i) order_[i] = uint32_t(i), group_[i] = find(uint32_t(m.bodyOfVertex(T[i])));
  std::stable_sort(order_.begin(), order_.end(), [&](uint32_t a, uint32_t b) { return group_[a] < group_[b]; });
  for (size_t k = 0; k < order_.size();) {  // the groups in order, each's vertices in T's order
    groupT_.clear(), groupX0_.clear(), groupV0_.clear();
    const uint32_t root = group_[order_[k]];
    for (; k < order_.size() && group_[order_[k]] == root; ++k) {
      const uint32_t j = order_[k];
      groupT_.push_back(T[j]), groupX0_.push_back((*in.startPositions)[j]), groupV0_.push_back((*in.startVelocities)[j]);
    }
    const ContactEnergyCap g = capGroup(m, in, x, v);
    cap.excess += g.excess, cap.removed += g.removed, cap.scale = std::max(cap.scale, g.scale);
  }
  return cap;
}

// One group (groupT_, where and how fast its vertices were when the stage began: groupX0_, groupV0_).
ContactEnergyCap ContactEnergyLimiter::capGroup(const RestModel& m, const ContactEnergyInput& in, Vec3* x, Vec3* v) {
  ContactEnergyCap cap;
  const std::vector<uint32_t>& T = groupT_;
  ++mark_;
  elementsOf(T, inner_);
  ring_.clear();
  for (uint32_t e : inner_)
    for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1]; ++p) {
      const uint32_t u = m.elemVerts[p];
      if (vertexMark_[u] != mark_) vertexMark_[u] = mark_, slot_[u] = uint32_t(ring_.size()), ring_.push_back(u);
    }
  ++mark_;  // a fresh element mark for outer_ (vertexMark_ keeps the ring's: measure() reads it with mark_ - 1)
  elementsOf(ring_, outer_);
  isInner_.resize(outer_.size());
  for (size_t k = 0; k < outer_.size(); ++k) isInner_[k] = std::binary_search(inner_.begin(), inner_.end(), outer_[k]);
  for (uint32_t u : ring_) vertexMark_[u] = mark_;
  force_.resize(ring_.size());
  const Real after = measure(m, in, x, v, wAfter_);
  // The same measure with the touched vertices where and how fast they were when the stage began.
  const std::vector<Vec3>& X0 = groupX0_;
  const std::vector<Vec3>& V0 = groupV0_;
  start_.resize(T.size()), vNow_.resize(T.size());
  for (size_t i = 0; i < T.size(); ++i) start_[i] = x[T[i]], vNow_[i] = v[T[i]], x[T[i]] = X0[i], v[T[i]] = V0[i];
  const Real before = measure(m, in, x, v, wBefore_);
  for (size_t i = 0; i < T.size(); ++i) x[T[i]] = start_[i], v[T[i]] = vNow_[i];
  cap.excess = after - before;
  if (!(cap.excess > 0)) return cap;
  // Out of the touched vertices' motion relative to their mass-weighted mean. (Out of every vertex
  // of their elements instead: the 1 m/s pair above ended at 0.905x, not 0.979x, and the stiff
  // 9^3 ball into the soft 6^3 one still peaked at 1.11x.)
  Real mass = 0, relative = 0;
  Vec3 mean = Vec3::Zero();
  for (uint32_t u : T)
    if (in.movable[u] > 0) mean += m.mass[u] * wAfter_[slot_[u]], mass += m.mass[u];
  if (!(mass > 0)) return cap;
  mean /= mass;
  for (uint32_t u : T)
    if (in.movable[u] > 0) relative += Real(0.5) * m.mass[u] * (wAfter_[slot_[u]] - mean).squaredNorm();
  if (!(relative > 0)) return cap;
  cap.scale = cap.excess >= relative ? Real(1) : 1 - std::sqrt(1 - cap.excess / relative);
  cap.removed = relative * cap.scale * (2 - cap.scale);
  for (uint32_t u : T)
    if (in.movable[u] > 0) v[u] -= cap.scale * (wAfter_[slot_[u]] - mean);
  return cap;
}

}  // namespace gradel
