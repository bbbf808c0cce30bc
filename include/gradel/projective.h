// The implicit integrator: projective dynamics (Bouaziz, Martin, Liu, Kavan, Pauly 2014) on the
// shape-matching element energy of element.h, E_e = k_e/2 sum_i |M_e R0_i - (x_i - c_e)|^2.
//
// One step minimises  1/(2 dt^2) |x - y|_M^2 + sum_e E_e(x),  y = x_n + dt v_n + dt^2 g
// (backward Euler with the same element energy), by alternating
//   local:  M_e = best-fit rotation of element e at the current x (eq. 1, rotation_fit.h,
//           warm-started from the previous one);
//   global: (M/dt^2 + sum_e k_e G_e^T G_e) x = M/dt^2 y + sum_e k_e G_e^T (M_e R0),
// where G_e = I - 11^T/n maps the element's vertices to their offsets from the centroid.
// Poisson's ratio (material.h, an element with kappa_e > 0): a volume constraint per element,
// w_e/2 sum_i |T_e R0_i - F_e R0_i|^2 with F_e = A S_e^-1 (element.h), whose local step T_e is the
// matrix of determinant 1 nearest F_e (SVD, the signs of an inverted F_e in its smallest singular
// value, Bouaziz et al. 2014) and whose global term is w_e B_e, B_e(i, k) = R0_i^T S_e^-1 R0_k, in
// the factored matrix, w_e T_e R0_i on the right-hand side. w_e = D^2 kappa_e / tr S_e (D = 3, or 2
// in 2D) gives it the small-strain energy kappa_e/2 tr(eps)^2 of the explicit step's corotated
// kappa_e/2 e_v^2 (element.h); at large strain the two differ (a distance to det F = 1). Measured
// (tests/test_poisson.cpp, a box pressed 2 % between frictionless walls): lateral / axial strain
// 0.302 / 0.456 / 0.497 at nu = 0.3 / 0.45 / 0.49 (the explicit step: 0.300 / 0.450 / 0.490). The
// matrix is constant (dt, stiffness and pins fixed): it is factored once (sparse LDL^T) and the
// three coordinates, which decouple, are three right-hand sides of one V x V system. Pinned
// vertices are eliminated: their prescribed positions move to the right-hand side.
// Contacts (held vertices): a vertex a contact pass found inside a surface can be held at its
// projected position for a second solve of the step. The global solve with held vertices is a
// filtered PCG (Baraff and Witkin 1998) on the other rows, preconditioned by the factor with the
// held rows zeroed and warm-started from the last pass: a held vertex costs nothing per
// iteration (the exact capacitance matrix E^T A^-1 E cost one back-solve per held vertex and a
// dense |held|^2 matrix, ~1.3 GB for the 64-voxel box on the floor). With the contact normals
// given, the holds are one-sided, an active set over the step's passes: after each pass a held
// vertex whose hold pulls it into the surface (the reaction A x - b on its row points inwards) is
// let go, and one let go earlier that is now behind its surface's plane is held again (the
// reactions come from a few PCG iterations: let go for good on an early pass's, a block resting on
// the floor fell through it for the rest of the step, issue 26).
// Without that a stiff ball resting on the floor at dt = 1/30 s was crushed: every vertex within
// one step's fall (dt^2 g = 1.1 cm, a voxel) of the floor ended below it in the free solve and
// was held flat on the floor. A hold on a frictionless surface (given the surfaces' friction)
// holds its vertex along the normal only: the filter removes the normal part of its rows, not the
// whole row, and the solve is one CG over the three coordinates. Held in all three (a sticking hold),
// the vertices a strike pushed into a ball were also held sideways, in the dent the striker made:
// at E x1000 and dt = 1/60 s the step ended with 162 J of elastic energy, 57x the explicit run's
// peak (issue 26); sliding, the ball moves off the striker instead (0.70 J).
// A hold on a surface with friction mu sticks at its target (its anchor) while its tangential
// reaction f_t stays within Coulomb's cone, |f_t| <= mu f_n, and slips otherwise: after each pass
// a return mapping on z = f_t - k s (s its slip from the anchor, k the row's diagonal, which
// overestimates how fast its reaction changes with its slip and so never overshoots): inside
// the cone s = 0, outside s = -(|z| - mu f_n) z / (k |z|), where the reaction is mu f_n against
// the slip. The slip is recomputed from the anchor each pass, so what an early pass's inexact
// reactions asked for is taken back (kept, the side holds of a ball grasped against a wall at
// dt = 1/30 s slipped down a little every step and the ball sank 2 mm into the floor). Without the
// cone the squeezed ball of a grasp could not spread along the surfaces as the explicit run's
// friction lets it. The slip of a whole body (a box sliding down a floor tilted past its
// friction angle, where k is ~1000x the stiffness of that motion) would take ~1000 passes: a body
// whose holds all lie on one plane (and that is in no pair constraint) first slips as a whole, the
// same return mapping on the sums of its holds' reactions with k = its mass / dt^2 (its common
// slip carries the holds' anchors), and
// the first guess (heldSlip) carries the last step's sliding over.
// Velocities are (x_{n+1} - x_n) / dt. The scheme is unconditionally stable and dissipative
// (numerical damping grows with omega dt); it is what lets a stiff body run at dt = 1/60 s.
// Contacts between bodies (pair constraints): a vertex p near a face of another body, the face's
// point at barycentric weights w (sum 1), normal n: n . (x_p - sum_k w_k x_k) >= gap. They enter
// the solve as an augmented Lagrangian (one-sided): the energy 1/(2 k) max(0, lambda + k (gap - c(x)))^2
// adds k J^T J to the matrix of the filtered PCG (J the constraint's row: n on p, -w_k n on the
// face's corners) and J^T (lambda + k gap) to its right-hand side; after each local/global pass
// lambda <- max(0, lambda + k (gap - c(x))). The force J^T lambda has zero sum (sum_k w_k = 1):
// equal and opposite on the two bodies, so the step keeps linear momentum (the PCG keeps the
// residual's sum at zero when the warm start has it, and the warm start is shifted so). k is ten
// times the pair's effective mass over dt^2, 10 / (dt^2 (1/m_p + sum_k w_k^2 / m_k)): the PCG,
// preconditioned by the factor of the matrix without the contacts, stays well conditioned (8
// iterations), while a contact vertex held by a stiff body, whose inertia rather than its own mass
// resists the push, still closes most of its violation in a step's passes (at 1x the effective
// mass the two balls of two-balls.json ended their first contact step 8 mm inside each other);
// and at least 0.1 / (J D^-1 J^T), D the matrix's diagonal (the elements' stiffness): a stiff body
// squeezed against another by a tool needs the pair to carry the push (issue 26; projective.cpp).
// lambda [N] is warm-started by the caller (a resting contact carries its load from the first pass).
#pragma once

#include <array>
#include <memory>
#include <vector>

#include "gradel/model.h"

namespace gradel {

class ThreadTeam;

/// One contact between bodies in the solve (see above).
struct PairConstraint {
  uint32_t vertex;               ///< The vertex p.
  std::array<uint32_t, 3> face;  ///< The face's corners.
  std::array<Real, 3> w;         ///< Barycentric weights of the face's point (sum 1).
  Vec3 n;                        ///< Unit normal out of the face's body.
  Real gap = 0;                  ///< [m] the least n . (x_p - sum w_k x_k).
  Real lambda = 0;               ///< [N] multiplier: warm start in, the last pass's out.
};

class ProjectiveSolver {
 public:
  /// Factors the global matrix for `model` at time step dt [s] with the vertices `pinned`
  /// (ascending ids) eliminated. The model must outlive the solver.
  ProjectiveSolver(const RestModel& model, Real dt, const std::vector<uint32_t>& pinned);
  ~ProjectiveSolver();
  ProjectiveSolver(const ProjectiveSolver&) = delete;
  ProjectiveSolver& operator=(const ProjectiveSolver&) = delete;

  /// One step of dt: x, v (per vertex) and q (per element, warm start) in/out. `pinTargets` are
  /// the pinned vertices' positions at the end of the step (order of `pinned`); their velocities
  /// are set to the displacement over dt. Velocities are scaled by 1 / (1 + c dt) as in the
  /// explicit integrators, c = model.vertexDamping(i, damping) (the regions' rates, model.h).
  /// `iterations` local/global passes (>= 1).
  /// `held` / `heldTargets`: free vertices held at given positions during this step (contacts);
  /// `heldNormals` (empty, or one per held vertex): the surfaces' outward normals, which make the
  /// holds one-sided (see above). `heldForces`, when given, gets the force [N] that held each of
  /// them in the last pass (the hold's reaction A x - b on its row; 0 for a pinned or released
  /// one): the contact forces' share of a held solve. `pairs` (in/out): contacts between bodies
  /// (see above), their multipliers updated. `heldFriction` (empty, or one per held vertex, with
  /// the normals): the Coulomb coefficient of the surface holding each; a hold on a frictionless
  /// surface holds its vertex along the normal only (it slides; see above). Empty: every hold sticks.
  /// A hold with (finite) friction sticks at its target (its anchor) until its tangential reaction
  /// leaves Coulomb's cone, then slips (see above); with an infinite one it sticks without limit. `heldLetGo` (empty, or one per held vertex): the holds
  /// that start let go (held once their vertex goes behind their plane). `heldSlip` (empty, or one
  /// per held vertex): a first guess of each hold's slip from its anchor (e.g. its sliding over
  /// the last step), in its surface's tangent plane.
  void step(std::vector<Vec3>& x, std::vector<Vec3>& v, std::vector<Quat>& q, const Vec3& gravity, Real damping,
            int iterations, const std::vector<Vec3>& pinTargets, int rotationIterations = 4,
            const std::vector<uint32_t>& held = {}, const std::vector<Vec3>& heldTargets = {},
            const std::vector<Vec3>& heldNormals = {}, std::vector<Vec3>* heldForces = nullptr,
            std::vector<PairConstraint>* pairs = nullptr, const std::vector<Real>& heldFriction = {},
            const std::vector<char>& heldLetGo = {}, const std::vector<Vec3>& heldSlip = {});

  /// Static equilibrium under gravity with the pins at `pinTargets`: the same local/global
  /// iteration with the inertia term dropped (needs at least one pin per body). Runs until the
  /// largest position change of a pass is below `tolerance` [m] or `maxIterations`; returns the
  /// number of passes. Requires a solver built with `dt` = 0 (static).
  int solveStatic(std::vector<Vec3>& x, std::vector<Quat>& q, const Vec3& gravity, const std::vector<Vec3>& pinTargets,
                  int maxIterations, Real tolerance);

  /// z = A^-1 r on the free vertices (A the factored global matrix), pinned entries 0.
  void applyInverse(const std::vector<Vec3>& r, std::vector<Vec3>& z) const;

  /// Threads for the factor's solves (null: this thread only). Any team gives the same result bit
  /// for bit: the solve is split along the factor's elimination tree in the same way at any count
  /// (src/factor_solve.h).
  void setTeam(ThreadTeam* team);

  /// The global matrix's diagonal entry of a free vertex [N/m].
  Real diagonal(uint32_t vertex) const;

  Real dt() const;
  bool isFree(uint32_t vertex) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace gradel
