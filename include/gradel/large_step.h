// The large-step integrator (issue 11): implicit midpoint on the shape-matching element energy
// of element.h, solved by the projective-dynamics local/global iteration (projective.h) with
// Chebyshev acceleration, contacts as constraints inside the iteration, and two guards that keep
// what the material and the rigid motion must keep.
//
// Implicit midpoint, x_{n+1} = x_n + dt (v_n + v_{n+1}) / 2, v_{n+1} = v_n + dt a(x_{n+1/2}), is
// one backward-Euler step of h = dt / 2 to the midpoint followed by a linear extrapolation:
//   x_m = argmin 1/(2 h^2) |x - (x_n + h v_n + h^2 g)|_M^2 + sum_e E_e(x)    (projective.h at h),
//   x_{n+1} = 2 x_m - x_n,   v_{n+1} = 2 (x_m - x_n) / h - v_n.
// Backward Euler damps a mode of frequency omega by a factor 1/(1 + (omega dt)^2)^(1/2) per step
// (40 % of the bar's 13 Hz mode per period at dt = 1/60 s) and its inertia term pulls a spinning
// body towards the chord of its arc (48 % of the angular momentum lost in 0.83 s). The midpoint
// is symplectic and A-stable: a linear mode keeps its amplitude exactly at any dt (its period is
// lengthened by 2 atan(omega dt / 2) / (omega dt): 12 % for 13 Hz at 1/60 s) and angular
// momentum is a quadratic invariant it conserves when the iteration has converged.
//
// The iteration (fixed count: bounded time per step):
//   start   x_m^0 = x_n + h v_n + h^2 a_{n-1}, the previous step's acceleration (warm start: a body
//           at rest starts at its equilibrium; rotations are warm-started from the previous fit);
//   pass k  x^ = local/global pass at x^k (ProjectiveSolver::pass), then Chebyshev (Wang 2015,
//           "A Chebyshev semi-iterative approach for accelerating projective and position-based
//           dynamics"): x^{k+1} = w_{k+1} (x^ - x^{k-1}) + x^{k-1} with w_1 = 1, w_2 = 2/(2 - rho^2),
//           w_{k+1} = 4 / (4 - rho^2 w_k); rho = 0 is the plain iteration.
//   contacts  a vertex whose end point 2 x_m - x_n lies inside a surface (signed distance d < 0
//           from the caller's function) gets a normal force lambda n on the right-hand side,
//           lambda <- max(0, lambda - m d / (2 h^2)) after every pass (projected Uzawa; the
//           matrix and its factor stay as they are: no back-solve per contact vertex). lambda is
//           kept across steps (a resting body starts with its support force).
// Guards, applied after the extrapolation:
//   momentum  with no pins and no contact force, the angular momentum about the centre of mass
//           is restored to its start-of-step value by a rigid rotation increment (uniform gravity
//           exerts no torque about it; an unconverged iteration does): rigid spin is kept.
//   energy    kinetic + elastic + gravity energy never exceeds the budget: the energy when the
//           budget was set (first step, or after contacts or moving pins did work), less what
//           velocity damping took out. An excess is taken from the deformation part of the
//           velocities (the velocities minus their rigid fit), which keeps linear and angular
//           momentum. The midpoint conserves a linear system's energy exactly; the guard removes
//           the O(dt^2) excursions of the corotated energy and of an unconverged iteration.
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include "gradel/model.h"
#include "gradel/projective.h"

namespace gradel {

/// Signed distance [m] of a point from the nearest contact surface (negative inside) and its
/// outward normal there.
using ContactGap = std::function<Real(const Vec3& p, Vec3* normal)>;

struct LargeStepReport {
  int passes = 0;            ///< Local/global passes run.
  int contactVertices = 0;   ///< Vertices with a contact force at the end of the step.
  bool momentumKept = false;  ///< The angular-momentum guard ran.
  Real energyRemoved = 0;    ///< [J] taken out by the energy guard.
};

class LargeStepSolver {
 public:
  /// Factors the midpoint system (h = dt / 2) with the vertices `pinned` eliminated.
  LargeStepSolver(const RestModel& model, Real dt, const std::vector<uint32_t>& pinned);

  /// One step of dt. pinStart / pinEnd: the pinned vertices' positions at the start and end of
  /// the step (order of `pinned`). `gap` (may be empty): the contact surfaces at the end of the
  /// step. passes >= 1: the conjugate-gradient iterations of the step (a bounded cost).
  LargeStepReport step(std::vector<Vec3>& x, std::vector<Vec3>& v, std::vector<Quat>& q, const Vec3& gravity,
                       Real damping, int passes, int rotationIterations, const std::vector<Vec3>& pinStart,
                       const std::vector<Vec3>& pinEnd, const ContactGap& gap);

  /// Kinetic + elastic + gravity energy [J] (rotations fitted at x, warm-started from a copy of q).
  Real energy(const std::vector<Vec3>& x, const std::vector<Vec3>& v, const std::vector<Quat>& q,
              const Vec3& gravity) const;
  /// Forget the energy budget (contacts or moving pins did work, or the state was set from
  /// outside): the next step sets it from its start state.
  void resetEnergyBudget() { budgetValid_ = false; }
  Real dt() const { return dt_; }

 private:
  void forces(const std::vector<Vec3>& x, std::vector<Quat>& q, std::vector<Vec3>& f, int iterations) const;

  const RestModel* model_;
  Real dt_;
  std::vector<uint32_t> pinned_;
  ProjectiveSolver half_;            ///< Backward Euler at h = dt / 2.
  std::vector<Vec3> acceleration_;   ///< [m/s^2] last step's, the warm start.
  std::vector<Real> contactForce_;   ///< [N] lambda per vertex (normal contact force).
  bool budgetValid_ = false;
  Real budget_ = 0;                  ///< [J]
};

}  // namespace gradel
