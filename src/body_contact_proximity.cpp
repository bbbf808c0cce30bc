// The body contacts of the frame-size integrators (implicit, large_step): the step's broad phase
// (mayTouch) and the proximity list the solve carries as one-sided constraints (projective.h
// PairConstraint); resolve() runs after the step as the safety net.
#include <cmath>
#include <vector>

#include "body_contact_grid.h"
#include "gradel/body_contacts.h"
#include "pseudo_normal.h"

namespace gradel {

bool BodyContacts::mayTouch(const Vec3* x, const Vec3* xEnd, Real margin) const {
  std::vector<Box> box(bodies_.size());
  for (size_t b = 0; b < bodies_.size(); ++b)
    for (uint32_t u : bodies_[b].vertices) box[b].add(x[u]), box[b].add(xEnd[u]);
  for (size_t a = 0; a < box.size(); ++a)
    for (size_t b = a + 1; b < box.size(); ++b)
      if (((box[a].lo.array() - margin) <= box[b].hi.array()).all() &&
          ((box[b].lo.array() - margin) <= box[a].hi.array()).all())
        return true;
  return false;
}

void BodyContacts::proximity(const Vec3* x, Real margin, std::vector<Proximity>& out) {
  out.clear();
  const size_t B = bodies_.size();
  std::vector<Box> box(B);
  for (size_t b = 0; b < B; ++b)
    for (uint32_t u : bodies_[b].vertices) box[b].add(x[u]);
  for (size_t a = 0; a < B; ++a)
    for (size_t b = 0; b < B; ++b) {
      if (a == b) continue;
      const ContactBody& A = bodies_[a];
      const ContactBody& F = bodies_[b];
      const Box q{box[a].lo.cwiseMax(box[b].lo - Vec3::Constant(margin)),
                  box[a].hi.cwiseMin(box[b].hi + Vec3::Constant(margin))};
      if ((q.lo.array() > q.hi.array()).any()) continue;
      buildGrid(*grid_, F, {q.lo - Vec3::Constant(margin), q.hi + Vec3::Constant(margin)}, x, nullptr, margin, 0);
      if (grid_->count == 0) continue;
      for (uint32_t v : A.vertices) {
        const Vec3& p = x[v];
        if ((p.array() < q.lo.array()).any() || (p.array() > q.hi.array()).any()) continue;
        const Nearest near = nearestTriangle(*grid_, F, p, margin, x);
        if (near.tri == ContactBody::kNone) continue;
        const Real best = near.d2;
        const uint32_t bestTri = near.tri;
        const ClosestPoint bestCp = near.cp;
        const auto& tri = F.triangles[bestTri];
        const Vec3 c = bestCp.w[0] * x[tri[0]] + bestCp.w[1] * x[tri[1]] + bestCp.w[2] * x[tri[2]];
        const Vec3 pn = unit(pseudoNormal(F, bestTri, bestCp.feature, x));
        const Real dist = std::sqrt(best);
        const bool behind = (p - c).dot(pn) < 0;
        // Out of the face's body: along p - c in front, c - p behind; the pseudo-normal on the surface.
        Vec3 n = dist > 1e-9 * F.thickness ? Vec3((behind ? c - p : p - c) / dist) : pn;
        if (n.squaredNorm() == 0) continue;
        out.push_back({v, uint32_t(b), tri, bestCp.w, n, behind ? -dist : dist});
      }
    }
}

}  // namespace gradel
