// The large-step integrator (issue 11): implicit midpoint on the shape-matching element energy
// of element.h, each step's system solved by Newton's method with conjugate gradients
// preconditioned by the projective-dynamics matrix (projective.h, factored once), and two guards
// that keep what the material and the rigid motion must keep.
//
// Implicit midpoint, x_{n+1} = x_n + dt (v_n + v_{n+1}) / 2, v_{n+1} = v_n + dt a(x_{n+1/2}), is
// one backward-Euler step of h = dt / 2 to the midpoint followed by a linear extrapolation:
//   x_m = argmin Phi(x) = 1/(2 h^2) |x - (x_n + h v_n + h^2 g)|_M^2 + sum_e E_e(x),
//   x_{n+1} = 2 x_m - x_n,   v_{n+1} = 2 (x_m - x_n) / h - v_n.
// Backward Euler damps a mode by 1/(1 + (omega dt)^2)^(1/2) per step (the bar's 13 Hz mode loses
// 52 % per period at dt = 1/60 s) and its inertia term pulls a spinning body onto the chord of
// its arc (a third of the angular momentum lost in 0.83 s). The midpoint is symplectic and
// A-stable: a linear mode keeps its amplitude at any dt, its period lengthened by
// omega dt / (2 atan(omega dt / 2)) (12 % for 13 Hz at 1/60 s, 3 % at 1/120 s: World runs
// large_step_substeps = 2 midpoint steps per step), and angular momentum is a quadratic
// invariant it keeps when the system is solved.
//
// The solve. The projective-dynamics local/global iteration (projective.h) converges far too
// slowly on bending to serve the midpoint: its error is doubled by the extrapolation, and 300
// passes still left the clamped bar unstable (measured). Here each Newton system
// (M / h^2 + K(x)) dx = -grad Phi(x) is solved by preconditioned conjugate gradients: K(x) p is
// analytic (element_stiffness.h, clamped to >= 0 per element; a forward difference of the forces
// blew up the 8-across bar). The preconditioner has two levels: the projective matrix
// M / h^2 + sum k_e G_e^T G_e (factored once; one back-solve, 3 coordinates per sweep of L,
// docs/speed.md, per CG iteration), which penalises element rotations like stretch and so leaves
// the smooth bending modes badly conditioned (alone it needed 50-60 iterations per substep on the
// 8-across bar), plus the coarse correction of coarse_space.h (smooth affine motions on a grid of
// at most `coarseNodes` nodes per body, its operator Z^T A Z of the true Newton matrix, re-formed
// once every second substep), which also gives each Newton iteration its Galerkin start. Each
// system is solved to 1e-2 in the preconditioned residual norm (inexact Newton). `passes` bounds
// the CG iterations of a step (bounded time); up to 4 Newton iterations share them. Warm start:
// x_m^0 = x_n + h v_n + h^2 a_{n-1} (the last step's acceleration: a body at rest starts at its
// equilibrium); the rotations are warm-started from the last fit.
// Guards, after the extrapolation:
//   momentum  per body without pins (RestModel::bodies: bodies apart exert nothing on each other), the
//           angular momentum about its centre of mass is restored to its
//           start-of-step value by a rigid rotation increment (uniform gravity exerts no torque
//           about it; an unconverged solve does): the free spin keeps it to 1e-4.
//   energy    kinetic + elastic + gravity energy never exceeds the budget: the energy when the
//           budget was set (first step, or after contacts or moving pins did work, reset by the
//           caller), less what velocity damping took out. An excess is taken from the
//           deformation part of the velocities (for a free body the velocities minus its own rigid
//           fit, which keeps each body's linear and angular momentum; for a pinned body all of them). At a
//           turning point (no such velocity) the excess waits for the next step.
// Contacts are not in this solve: World::stepLargeStep runs a step that could touch anything as
// a projective-dynamics (backward Euler) step with held contacts (stepImplicit, see step_implicit.cpp and
// projective.h: the held vertices are constraints of a filtered PCG there, no back-solve each).
// So does a step in which two bodies may touch (body_contacts.h, BodyContacts::mayTouch): their
// contacts are pair constraints of that solve (projective.h, PairConstraint).
#pragma once

#include <memory>
#include <vector>

#include "gradel/model.h"
#include "gradel/projective.h"

namespace gradel {

class ThreadTeam;
class CoarseSpace;

struct LargeStepReport {
  int passes = 0;             ///< Conjugate-gradient iterations run.
  bool momentumKept = false;  ///< The angular-momentum guard ran.
  Real energyRemoved = 0;     ///< [J] taken out by the energy guard.
};

class LargeStepSolver {
 public:
  /// Factors the midpoint system (h = dt / 2) with the vertices `pinned` eliminated; coarseNodes > 0:
  /// the coarse correction with at most that many grid nodes per body (coarse_space.h).
  LargeStepSolver(const RestModel& model, Real dt, const std::vector<uint32_t>& pinned, int coarseNodes = 0);
  ~LargeStepSolver();

  /// One step of dt: x, v (per vertex), q (per element, warm start) in/out. pinStart / pinEnd:
  /// the pinned vertices' positions at the start and end of the step (order of `pinned`).
  /// passes >= 1: the conjugate-gradient iterations of the step (a bounded cost). Velocities
  /// are damped per vertex by 1 / (1 + c dt), c = model.vertexDamping(i, damping) (model.h).
  LargeStepReport step(std::vector<Vec3>& x, std::vector<Vec3>& v, std::vector<Quat>& q, const Vec3& gravity,
                       Real damping, int passes, int rotationIterations, const std::vector<Vec3>& pinStart,
                       const std::vector<Vec3>& pinEnd);

  /// Kinetic + elastic + gravity energy [J] (rotations fitted at x, warm-started from a copy of q).
  Real energy(const std::vector<Vec3>& x, const std::vector<Vec3>& v, const std::vector<Quat>& q,
              const Vec3& gravity) const;
  /// Forget the energy budget (contacts or moving pins did work, or the state was set from
  /// outside): the next step sets it from its start state.
  void resetEnergyBudget() { budgetValid_ = false; }
  Real dt() const { return dt_; }
  /// Threads for the solve's element forces (null: this thread only). Any team gives the same
  /// result bit for bit: each element's forces go to its own slots, summed per vertex in element
  /// order, as on one thread.
  void setTeam(ThreadTeam* team) { team_ = team, half_.setTeam(team); }

 private:
  void forces(const std::vector<Vec3>& x, std::vector<Quat>& q, std::vector<Vec3>& f, int iterations) const;
  /// Newton-PCG on 1/(2 h^2) |x - y|_M^2 + E(x) over the vertices with free[i] != 0 (x in/out,
  /// the others kept), preconditioned by `pre` (factored at h); returns the CG iterations run.
  int minimise(const ProjectiveSolver& pre, Real h, const std::vector<Vec3>& y, const std::vector<char>& free,
               Real scale, int passes, int fitIterations, bool reform, std::vector<Vec3>& x,
               std::vector<Quat>& q) const;

  const RestModel* model_;
  ThreadTeam* team_ = nullptr;
  std::vector<uint32_t> vertexPairStart_, vertexPairs_;  ///< Per vertex: its element-vertex pairs, in element order.
  std::vector<Vec3> restOffsets_;  ///< R0 per pair (RestModel::pairRestOffsets): read in every product.
  Real dt_;
  std::vector<uint32_t> pinned_;
  ProjectiveSolver half_;  ///< Backward Euler at h = dt / 2.
  std::unique_ptr<CoarseSpace> coarse_;
  uint64_t substeps_ = 0;           ///< Substeps run (the coarse operator is re-formed every second).
  std::vector<Vec3> acceleration_;  ///< [m/s^2] last step's, the warm start.
  bool budgetValid_ = false;
  Real budget_ = 0;  ///< [J]
};

}  // namespace gradel
