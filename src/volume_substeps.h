// The volumetric term in substeps of the explicit step (multiple time stepping, issue 29 item 2).
//
// The volumetric force (element.h, elementVolumeForces) with F_e = (A_e / h) shape_e
// (element_stage.h ElementVolumeGroup: shape = h V_e, h (D / tr S_e) I when isotropic):
// e_v = tr(M^T F_e) - D and f_v = H_e (X_v - C_e - mean R0) with H_e = -(kappa_e / h) e_v M shape_e.
// A substep takes M from the step's fit (M of A, or M_F) refreshed by one Newton step of the polar
// fit of F_e (computeVolumeFrames): no full rotation fit, and the forces keep zero torque to second
// order in the rotation since the fit (with M frozen instead, a spinning body lost 1e-3 of its
// angular momentum per second). The step (impulse form) then is
//   v += dt a_rest(x0) + (dt / n) a_vol(x0);  x += (dt / n) v      (the step's own passes)
//   n - 1 times: v += (dt / n) a_vol(x);  x += (dt / n) v           (computeVolumeFrames + gather)
// so the rotation fits and the shape-matching frames run once per step at the dt of the
// operator without the volumetric term, and only the volumetric part runs at its own, shorter,
// limit. A substep needs no rotation fit: the moments' gather (as pass 1), ~30 flops per element
// and the vertex gather of pass 2.
#pragma once

#include <cstddef>

#include "element_stage.h"

namespace gradel {

/// The rotation of four consecutive elements' volumetric term (lanes as ElementVolumeGroup: M,
/// or M_F for an anisotropic lane), written by pass 1 when the step splits the volumetric term
/// off: M(r, c) at [3 r + c]. A group whose four kappa are zero is not written (and not read).
struct alignas(32) VolumeBasisGroup {
  Real M[9][4];
};

/// Pass 1's share of the split (computeElementFrames): the volumetric force enters the step's own
/// frames scaled by `scale` (1 / n) and its rotation is stored in basis[group].
struct VolumeSplit {
  Real scale = 1;
  VolumeBasisGroup* basis = nullptr;
};

/// A substep's frames for elements [begin, end) (begin a multiple of 4): the volumetric force
/// alone, with the refreshed rotation, as ElementFrame columns H_e and t = (-H_e (C_e + mean R0), 0), so that
/// gatherVertexForces yields f_v = H_e X_v + t.
void computeVolumeFrames(const RestModel& model, const ElementStageRest& rest, const VolumeBasisGroup* basis,
                         size_t begin, size_t end, const Vec3* positions, ElementFrame* frames);

}  // namespace gradel
