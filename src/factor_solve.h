// Solves with a sparse LDL^T factor (A = P^T L D L^T P) for three right-hand sides at once, split
// between two threads along the factor's elimination tree. Private to the implicit solvers
// (projective.cpp), whose steps are bound by these solves (docs/speed.md, "Large step").
//
// Column j of L holds entries only in rows that are ancestors of j in the elimination tree
// (parent(j) = the first row below the diagonal of column j). Below the first node with two or
// more children (nested dissection's top separator, or the virtual root of several bodies' trees)
// the children's subtrees share no row: they are put in two sets of about equal entries, and each
// set is swept by one thread. The nodes above, the "chain", are swept by one thread after (forward)
// or before (backward) the sets:
//   forward  a set's column j updates the rows below it: rows of its own set directly, rows of the
//            chain into that set's own accumulator; the chain's rows then take set 0's, then set
//            1's accumulator, and the chain is swept;
//   backward the chain first, then each set reads only its own rows and the chain's.
// The same operations in the same order whatever the thread count (one thread sweeps set 0, then
// set 1, with the same accumulators): the result is bit for bit the same at one and two threads.
#pragma once

#include <array>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "gradel/types.h"

namespace gradel {

class ThreadTeam;

class SplitFactor {
 public:
  SplitFactor() = default;
  /// From the factor in compressed columns: L strictly lower (unit diagonal implied; colStart n + 1
  /// entries, rows / values per entry), d the diagonal of D (n), perm with (P b)_perm[i] = b_i.
  SplitFactor(std::vector<int32_t> colStart, std::vector<int32_t> rows, std::vector<Real> values, std::vector<Real> d,
              std::vector<int32_t> perm);

  /// x = A^-1 b for the three columns of b (n rows each), on `team`'s first two members when given
  /// (null or one member: this thread). x may alias b.
  void solve(const Vec3* b, Vec3* x, ThreadTeam* team) const;

  /// From an Eigen SimplicialLDLT (matrixL(), vectorD(), permutationP()) that succeeded.
  template <class Ldlt>
  static SplitFactor fromLdlt(const Ldlt& ldlt);

  size_t size() const { return invD_.size(); }
  size_t nonZeros() const { return rows_.size(); }
  /// Entries of L in each set (set 0, set 1) and in the chain: how evenly the two threads share.
  std::array<size_t, 3> entriesPerPart() const;

 private:
  void forwardSet(int set, std::vector<Vec3>& y, std::vector<Vec3>& acc) const;
  void backwardSet(int set, std::vector<Vec3>& y) const;

  std::vector<int32_t> colStart_, rows_;
  std::vector<Real> values_, invD_;
  std::vector<int32_t> perm_;
  std::vector<int32_t> set_[2];       ///< Columns of each set, ascending.
  std::vector<int32_t> chain_;        ///< Columns of the chain, ascending.
  std::vector<int32_t> chainIndex_;   ///< Per column: its index in chain_, or -1.
  std::vector<int32_t> chainStart_;   ///< Per set column: its first entry in a chain row; chain column: its end.
  mutable std::vector<Vec3> y_;       ///< Scratch (n).
  mutable std::vector<Vec3> acc_[2];  ///< Scratch: per set, its updates of the chain's rows.
};

template <class Ldlt>
SplitFactor SplitFactor::fromLdlt(const Ldlt& ldlt) {
  const auto& L = ldlt.matrixL().nestedExpression();  // strictly lower, unit diagonal implied
  using Matrix = std::decay_t<decltype(L)>;
  const size_t n = size_t(L.cols());
  std::vector<int32_t> colStart(n + 1, 0), rows, perm(n, 0);
  std::vector<Real> values, d(n, 0.0);
  rows.reserve(size_t(L.nonZeros())), values.reserve(size_t(L.nonZeros()));
  for (size_t j = 0; j < n; ++j) {
    for (typename Matrix::InnerIterator it(L, Eigen::Index(j)); it; ++it)
      rows.push_back(int32_t(it.index())), values.push_back(it.value());
    colStart[j + 1] = int32_t(rows.size());
    d[j] = ldlt.vectorD()(Eigen::Index(j));
    perm[j] = int32_t(ldlt.permutationP().indices()(Eigen::Index(j)));
  }
  return SplitFactor(std::move(colStart), std::move(rows), std::move(values), std::move(d), std::move(perm));
}

}  // namespace gradel
