// The operator rule's estimate after a change of the model (carving, carve_scene.h), warm
// started instead of from scratch (stability.h: 48 Lanczos products from a pseudo-random start).
//
// A carving event changes the body near the removed voxels only; elsewhere the stiffness and the
// masses are the old ones, and so are their vibrations. The start is the previous estimate's Ritz
// vector (its fastest mode) carried onto the new vertices (a surviving vertex keeps its entry,
// a new one starts at 0) plus, with the same norm, a pseudo-random vector on the changed region
// (the new vertices, the vertices whose lumped mass changed, and every vertex of an element that
// holds one of them): the Krylov space holds the old fastest mode and every mode of the changed
// region from the first products, so a few iterations find either (the new fastest mode is
// usually at the new surface's small cells, or the old one). The estimate is read as before:
// theta + |beta_k s_k| capped by the Gershgorin bound; fewer iterations leave a larger residual,
// so dt errs short. What this does not see: a mode away from the change that the old estimate
// had not found either.
#pragma once

#include <cstdint>
#include <vector>

#include "gradel/model.h"

namespace gradel {

/// Lanczos products of the warm-started estimate (measured: docs/carving.md, "Cost").
constexpr int kWarmStartIterations = 16;

/// The warm start on `newModel`: per vertex, oldRitz at fromVertex[i] (an old vertex id of
/// `oldModel`, or UINT32_MAX for a new vertex: 0), normalised, plus the changed region's
/// pseudo-random vector of the same norm (above; a fixed LCG: the same start on every run).
/// std::invalid_argument when the sizes do not match.
std::vector<Vec3> stabilityWarmStart(const RestModel& oldModel, const RestModel& newModel,
                                     const std::vector<Vec3>& oldRitz, const std::vector<uint32_t>& fromVertex);

}  // namespace gradel
