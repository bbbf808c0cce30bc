// The explicit step's stability limit, measured on the body itself: the highest angular frequency
// of its small vibrations about the rest shape, omega_max = sqrt(lambda_max(M^-1 K)), with K the
// assembled stiffness of every element at rest (element_stiffness.h: the Hessian of element.h's
// energy, rotations as null modes), M the lumped masses, hanging vertices and per-region
// stiffness and masses included as the model holds them.
//
// Symplectic Euler is stable on a mode of frequency omega while omega dt < 2, so the fastest mode
// sets dt: dt = dt_fraction * 2 pi / omega_max (dt_period "operator", integrator.h), stable for
// dt_fraction < 1/pi. The per-vertex rule (RestModel::smallestVertexPeriod) is a Gershgorin-type
// upper bound on omega_max (K <= diag(sum_{e at i} k_e), since every element's K_e <= k_e I):
// within 4 % of it on uniform spheres and boxes, further above where vertices sit between a
// stiff and a soft region.
//
// The estimate: Lanczos on the symmetric M^-1/2 K M^-1/2 from a fixed pseudo-random start
// (deterministic), the largest Ritz value theta plus its residual |beta_k s_k| (an eigenvalue lies
// within it), capped by the Gershgorin bound. Cost: one stiffness product per iteration (about
// the work of three explicit steps), 48 iterations by default.
#pragma once

#include <vector>

#include "gradel/model.h"

namespace gradel {

class ThreadTeam;

struct FrequencyEstimate {
  double omega = 0;       ///< [rad/s] the estimate used: sqrt(min(theta + residual, gershgorin^2)).
  double ritz = 0;        ///< [rad/s] sqrt(theta): Lanczos's value, a lower bound of omega_max.
  double gershgorin = 0;  ///< [rad/s] max_i sqrt(sum_{e at i} k_e / m_i): an upper bound of omega_max.
  int iterations = 0;     ///< Lanczos iterations run (fewer when the Krylov space closed).
};

/// omega_max of the model at rest (all bodies: the largest over them). A model with no element
/// gives 0 everywhere. `ritzVector` (optional): the Ritz vector of the largest Ritz value (unit
/// length to single precision; the estimate's bits do not depend on asking for it), the start of
/// the next estimate after a change of the model (stability_warm.h). `team` (optional, the
/// engine's own): the products and vector updates on its members; the same bits at any count.
FrequencyEstimate highestFrequency(const RestModel& model, int iterations = 48, std::vector<Vec3>* ritzVector = nullptr,
                                   ThreadTeam* team = nullptr);

/// The same estimate from a given start (one entry per vertex, normalised here; z dropped in 2D)
/// instead of the fixed pseudo-random one, with the cheaper operator (the frames at rest, each
/// product one element pass and one vertex pass: the same operator to rounding, ~1.5x faster).
/// A zero start falls back to highestFrequency.
/// std::invalid_argument when the start's size is not the model's vertex count.
FrequencyEstimate highestFrequencyFrom(const RestModel& model, std::vector<Vec3> start, int iterations,
                                       std::vector<Vec3>* ritzVector = nullptr, ThreadTeam* team = nullptr);

}  // namespace gradel
