// The large step's coarse space (large_step.h): smooth affine motions per node of a coarse
// regular grid, the second level of its two-level preconditioner.
//
// Why. The Newton matrix of a midpoint substep is A = M / h^2 + K(x), and K (element_stiffness.h)
// is the projective-dynamics matrix's elastic part less a rank-3 rotation term per element:
//   A = P - sum_e k_e B_e^T T'_e^-1 B_e,   P = M / h^2 + sum_e k_e G_e^T G_e,
// B_e p = b_e(p) = sum_i R0'_i x (M_e^T p_i) (the element's linearised rotation). The factored P
// preconditions stretch well but penalises element rotations like stretch: bending, which is
// mostly element rotation, is far stiffer in P than in A, so P^-1 A has many small eigenvalues
// on the smooth bending modes, exactly the slow modes the midpoint must keep (the 8-across bar
// needed 50-60 CG iterations per substep). A coarse space that represents smooth rotation
// fields takes them out.
//
// The space. Per body, a regular grid of spacing H over the free vertices' rest box (H the
// smallest for which the grid has at most `maxNodes` nodes); node c's trilinear hat phi_c
// (a partition of unity) times the 12 affine motions about the node, Y = (X - X_c) / H:
//   Z column (c, d, g): vertex i moves phi_c(X_i) g(Y_i) along axis d, g in {1, Y_x, Y_y, Y_z}.
// Sums of hat-weighted affine motions represent smoothly varying rotations and stretches (a bent
// bar) with a few nodes. Pinned vertices have no rows (they do not move).
//
// The coarse operator E = Z^T A Z (m x m, m = 12 nodes, dense) from the structure of A:
//   Z^T P Z is constant (formed once, per element from the hat-weighted basis);
//   B_e Z for column (c, d, g) is mu_{e,c,g} x (M_e^T e_d), mu_{e,c,g} = sum_{i in e}
//   phi_c(X_i) g(Y_i) R0'_i (rest moments, 4 vectors per element and node, formed once), so each
//   update subtracts per element k_e (B_e Z)^T T'^-1 (B_e Z) at the current frames: no products
//   with A, cost ~ (12 nodes per element)^2 per element, then a dense Cholesky of E.
// Used by large_step.cpp as a Galerkin start and an additive coarse correction, z = P^-1 r + Q r,
// Q = Z E^-1 Z^T (exact on the coarse space: Q A Z = Z).
#pragma once

#include <Eigen/Dense>
#include <array>
#include <vector>

#include "gradel/element_stiffness.h"
#include "gradel/model.h"

namespace gradel {

///
/// Same bits on every machine: Eigen sizes its dense products' blocks (which order each sum) from
/// the CPU's cache sizes; CoarseSpace sets them to fixed values (Eigen::setCpuCacheSizes, process-
/// wide) before it factors or solves. A program that sets other sizes meanwhile gets them back.
class CoarseSpace {
 public:
  /// The grids (at most maxNodes nodes per body, >= 2 per axis where the body has extent) and
  /// Z^T P Z for the substep h [s]; free[i] != 0 for the vertices that move.
  CoarseSpace(const RestModel& model, Real h, const std::vector<char>& free, int maxNodes);

  /// E = Z^T (M / h^2 + K(x)) Z at the elements' frames (element_stiffness.h), factored.
  void update(const std::vector<StiffnessFrame>& frames);
  /// z += Q r = Z E^-1 Z^T r (the last update's E).
  void addCorrection(const std::vector<Vec3>& r, std::vector<Vec3>& z) const;

  size_t size() const { return size_t(E0_.rows()); }
  /// Z^T r and Z c (the coarse vector's layout: node * 12 + axis * 4 + g).
  Eigen::VectorXd restrictTo(const std::vector<Vec3>& r) const;
  void prolongAdd(const Eigen::VectorXd& c, std::vector<Vec3>& z) const;
  /// The last update's E (for tests).
  Eigen::MatrixXd matrix() const { return E_.selfadjointView<Eigen::Lower>(); }

 private:
  struct Weight {
    uint32_t node;
    Real phi;               ///< The hat's value at the vertex.
    Vec3 y;                 ///< (X - X_node) / H.
    std::array<Real, 4> f;  ///< phi g(y), g = 1, y_x, y_y, y_z.
  };
  const RestModel* model_;
  std::vector<uint32_t> weightStart_;  ///< Per vertex: its hat weights (free vertices only).
  std::vector<Weight> weights_;
  std::vector<uint32_t> momentStart_;  ///< Per element: its nodes' rest moments.
  std::vector<uint32_t> momentNode_;
  std::vector<std::array<Vec3, 4>> moments_;  ///< mu_{e,c,g}, g = 1, Y_x, Y_y, Y_z.
  Eigen::MatrixXd E0_;                        ///< Z^T P Z.
  Eigen::MatrixXd E_;
  Eigen::LLT<Eigen::MatrixXd> factor_;
  bool valid_ = true;  ///< The factor succeeded (else no correction: P^-1 alone).
};

}  // namespace gradel
