// factor_solve: the factor's solve split along the elimination tree equals Eigen's LDL^T solve to
// rounding, and gives the same bits on one thread and on two.
#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>

#include "factor_solve.h"
#include "thread_team.h"

using namespace gradel;

namespace {

using SpMat = Eigen::SparseMatrix<Real>;

// A grid Laplacian plus a mass term (SPD), on `pieces` disconnected n x n x n grids: the shape of
// the projective matrix of one or several bodies.
SpMat gridMatrix(int n, int pieces) {
  std::vector<Eigen::Triplet<Real>> t;
  const int N = n * n * n;
  auto id = [&](int p, int i, int j, int k) { return p * N + i + n * (j + n * k); };
  for (int p = 0; p < pieces; ++p)
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          const int a = id(p, i, j, k);
          t.emplace_back(a, a, 0.5 + 0.01 * (a % 7));
          const int nb[3][3] = {{i + 1, j, k}, {i, j + 1, k}, {i, j, k + 1}};
          for (const auto& q : nb) {
            if (q[0] >= n || q[1] >= n || q[2] >= n) continue;
            const int b = id(p, q[0], q[1], q[2]);
            t.emplace_back(a, a, 1.0), t.emplace_back(b, b, 1.0), t.emplace_back(a, b, -1.0),
                t.emplace_back(b, a, -1.0);
          }
        }
  SpMat A(pieces * N, pieces * N);
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

void expectSolves(const SpMat& A, bool expectTwoSets) {
  Eigen::SimplicialLDLT<SpMat> ldlt(A);
  ASSERT_EQ(ldlt.info(), Eigen::Success);
  const SplitFactor f = SplitFactor::fromLdlt(ldlt);
  const auto parts = f.entriesPerPart();
  EXPECT_EQ(parts[0] + parts[1] + parts[2], f.nonZeros());
  if (expectTwoSets) {
    EXPECT_GT(parts[1], 0u);
    EXPECT_GT(parts[1], parts[0] / 4) << "the two threads' shares are far apart";
  }
  const size_t n = f.size();
  std::vector<Vec3> b(n), one(n), two(n);
  for (size_t i = 0; i < n; ++i) b[i] = Vec3(std::sin(0.3 * Real(i)), std::cos(0.7 * Real(i)), Real(i % 5) - 2);
  f.solve(b.data(), one.data(), nullptr);
  ThreadTeam team(2);
  f.solve(b.data(), two.data(), &team);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(one[i], two[i]) << "row " << i;  // bit for bit
  for (int c = 0; c < 3; ++c) {
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(Eigen::Index(n)), x;
    for (size_t i = 0; i < n; ++i) rhs(Eigen::Index(i)) = b[i][c];
    x = ldlt.solve(rhs);
    for (size_t i = 0; i < n; ++i)
      EXPECT_NEAR(one[i][c], x(Eigen::Index(i)), 1e-12 * (1 + std::abs(x(Eigen::Index(i)))));
    // And it solves A x = b.
    Eigen::VectorXd mine = Eigen::VectorXd::Zero(Eigen::Index(n));
    for (size_t i = 0; i < n; ++i) mine(Eigen::Index(i)) = one[i][c];
    EXPECT_LT((A * mine - rhs).norm(), 1e-10 * rhs.norm());
  }
  // In place (x aliases b).
  std::vector<Vec3> inPlace = b;
  f.solve(inPlace.data(), inPlace.data(), &team);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(inPlace[i], one[i]);
}

TEST(FactorSolve, OneGridSplitsBelowTheTopSeparatorAndSolvesExactly) { expectSolves(gridMatrix(9, 1), true); }

TEST(FactorSolve, SeveralBodiesAreSeveralTreesSharedBetweenTheThreads) { expectSolves(gridMatrix(6, 3), true); }

TEST(FactorSolve, APathHasOnlyAChainAndStillSolves) {
  // Tridiagonal: every column's parent is the next one, no node has two children.
  const int n = 50;
  std::vector<Eigen::Triplet<Real>> t;
  for (int i = 0; i < n; ++i) {
    t.emplace_back(i, i, 3.0);
    if (i + 1 < n) t.emplace_back(i, i + 1, -1.0), t.emplace_back(i + 1, i, -1.0);
  }
  SpMat A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  expectSolves(A, false);
}

}  // namespace
