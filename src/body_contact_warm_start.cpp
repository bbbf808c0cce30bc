// The body contacts' one cache (body_contacts.h Cache): the explicit stage's warm start (the
// last stage's contacts, found inside their plane again, are round 0's: applyWarm; keepWarm keeps
// this stage's for the next) and the frame-size steps' multipliers. docs/speed.md, "Body
// contacts: the stage".
#include <algorithm>

#include "body_contact_kernels.h"
#include "body_contact_tuning.h"
#include "gradel/body_contacts.h"

namespace gradel {

// The warm start (header): the last stage's contacts whose vertex and face corners start this
// step where that stage left them, in a small step of their pair (a face that moved less than a
// quarter voxel is still the surface there), are round 0's contacts where the vertex now lies
// behind the contact's plane as it was found (its normal, its point at weights w on the face now).
// The detection rounds then check every candidate as ever. Measured (two 64^3 balls pressed, 400
// steps, every contact kept): the plane as found beats the face's plane now (545 lookups a step
// against 745) and one contact per vertex (724): a vertex carried against two faces stays out of both.
bool BodyContacts::applyWarm(const BodyContactState& s, BodyContactStats& stats) {
  if (!warmStart_ || cache_.contacts.empty()) return false;
  const Vec3* x = s.positions;
  const Vec3* x0 = s.previousPositions;
  for (size_t k = 0; k < cache_.contacts.size(); ++k) {
    const Contact& c = cache_.contacts[k];
    const Vec3* at = &cache_.at[4 * k];
    if (x0[c.vertex] != at[0] || x0[c.face[0]] != at[1] || x0[c.face[1]] != at[2] || x0[c.face[2]] != at[3])
      continue;  // moved since (walls, or a state set from outside)
    const uint32_t a = bodyOf_[c.vertex], b = bodyOf_[c.face[0]];
    if (!(movedStart_[a] + movedStart_[b] <= kSmallStep * std::max(bodies_[a].thickness, bodies_[b].thickness)))
      continue;
    const Real gap = c.n.dot(relative(c, x));
    if (!(gap < 0)) continue;
    round_.push_back(c);
    round_.back().depth = -gap;
  }
  cache_.contacts.clear(), cache_.at.clear();
  stats.warm = round_.size();
  return !round_.empty();
}

// What the next stage's warm start reads: this stage's body-body contacts (after the last resort
// too: dropping them there left a generic build's pressed balls in it for many steps), one per vertex and face, the
// first in the stage's order (a contact carried over from the last stage comes first: its plane as first found, kept
// while the vertex is behind it), and where its vertex and face corners end the stage. Measured (two 64^3 balls
// pressed, 1,500 steps, the whole collision): all of them, a vertex-face pair found again each step adding one, grew to
// 6,000 contacts a step for 1,300 vertices (2,191 a step on average against 516), for the same lookups and no faster;
// the last one found per pair is not behind its plane in the next step (its bounce moves it away), which leaves no warm
// start (891 lookups a step at 400 steps, against 971 without one).
void BodyContacts::keepWarm(const Vec3* x) {
  cache_.contacts.clear(), cache_.at.clear();
  if (!warmStart_) return;
  warmKeys_.clear();
  for (uint32_t k = 0; k < contacts_.size(); ++k) {
    const Contact& c = contacts_[k];
    if (bodyOf_[c.vertex] != bodyOf_[c.face[0]])  // (self-contact: found by its own rule)
      warmKeys_.push_back({{c.vertex, c.face[0], c.face[1], c.face[2]}, k});
  }
  std::stable_sort(warmKeys_.begin(), warmKeys_.end(), [](const auto& l, const auto& r) { return l.first < r.first; });
  warmKeys_.erase(
      std::unique(warmKeys_.begin(), warmKeys_.end(), [](const auto& l, const auto& r) { return l.first == r.first; }),
      warmKeys_.end());  // (the first of each run of equal keys stays)
  std::sort(warmKeys_.begin(), warmKeys_.end(), [](const auto& l, const auto& r) { return l.second < r.second; });
  for (const auto& key : warmKeys_) {
    const Contact& c = contacts_[key.second];
    cache_.contacts.push_back(c);
    cache_.at.insert(cache_.at.end(), {x[c.vertex], x[c.face[0]], x[c.face[1]], x[c.face[2]]});
  }
}

// The frame-size steps' side of the cache (World::bodyPairConstraints reads it, stepImplicit keeps it).
Real BodyContacts::Cache::multiplier(uint32_t vertex, uint32_t faceBody) const {
  const uint64_t k = key(vertex, faceBody);
  auto it = std::lower_bound(multipliers.begin(), multipliers.end(), std::make_pair(k, Real(0)),
                             [](const auto& a, const auto& b) { return a.first < b.first; });
  return it != multipliers.end() && it->first == k ? it->second : 0;
}

void BodyContacts::Cache::keepMultipliers(const std::vector<uint64_t>& keys, const std::vector<Real>& lambdas) {
  multipliers.clear();
  for (size_t j = 0; j < keys.size(); ++j)
    if (lambdas[j] > 0) multipliers.push_back({keys[j], lambdas[j]});
  std::sort(multipliers.begin(), multipliers.end());  // proximity lists by vertex within a pair of bodies
}

}  // namespace gradel
