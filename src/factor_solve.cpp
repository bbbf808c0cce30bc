#include "factor_solve.h"

#include <algorithm>

#include "thread_team.h"

namespace gradel {

SplitFactor::SplitFactor(std::vector<int32_t> colStart, std::vector<int32_t> rows, std::vector<Real> values,
                         std::vector<Real> d, std::vector<int32_t> perm)
    : colStart_(std::move(colStart)), rows_(std::move(rows)), values_(std::move(values)), perm_(std::move(perm)) {
  const int32_t n = int32_t(d.size());
  // Each column's entries by ascending row (the split below relies on it).
  std::vector<std::pair<int32_t, Real>> column;
  for (int32_t j = 0; j < n; ++j) {
    const int32_t b = colStart_[size_t(j)], e = colStart_[size_t(j) + 1];
    column.clear();
    for (int32_t k = b; k < e; ++k) column.emplace_back(rows_[size_t(k)], values_[size_t(k)]);
    std::sort(column.begin(), column.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    for (int32_t k = b; k < e; ++k)
      rows_[size_t(k)] = column[size_t(k - b)].first, values_[size_t(k)] = column[size_t(k - b)].second;
  }
  invD_.resize(size_t(n));
  for (int32_t j = 0; j < n; ++j) invD_[size_t(j)] = Real(1) / d[size_t(j)];
  // Elimination tree: parent(j) = the first row below the diagonal in column j (-1: a root).
  std::vector<int32_t> parent(size_t(n), -1);
  std::vector<size_t> entries(size_t(n), 0);  // in the subtree of j
  for (int32_t j = 0; j < n; ++j) {
    if (colStart_[size_t(j)] < colStart_[size_t(j) + 1]) parent[size_t(j)] = rows_[size_t(colStart_[size_t(j)])];
    entries[size_t(j)] += size_t(colStart_[size_t(j) + 1] - colStart_[size_t(j)]) + 1;
    if (parent[size_t(j)] >= 0) entries[size_t(parent[size_t(j)])] += entries[size_t(j)];
  }
  std::vector<std::vector<int32_t>> children(size_t(n) + 1);  // index n: the virtual root
  for (int32_t j = 0; j < n; ++j) children[parent[size_t(j)] < 0 ? size_t(n) : size_t(parent[size_t(j)])].push_back(j);
  // Down from the virtual root while a node has one child: those nodes are the chain.
  std::vector<int32_t> label(size_t(n), -1);  // -1 chain, else the set
  std::vector<char> onChain(size_t(n), 0);
  int32_t node = n;
  while (children[size_t(node)].size() == 1) node = children[size_t(node)][0], onChain[size_t(node)] = 1;
  // `node` and its ancestors are the chain; its children's subtrees (the frontier) go to the two
  // sets, largest first into the lighter one (ties: set 0). While the heavier set holds more than
  // 55 % of the frontier's entries, the largest frontier subtree's root joins the chain and its
  // children the frontier (an unbalanced tree, e.g. an AMD ordering, is split further down).
  std::vector<int32_t> split = children[size_t(node)];
  size_t load[2] = {0, 0};
  for (int round = 0; round < 64; ++round) {
    std::stable_sort(split.begin(), split.end(),
                     [&](int32_t a, int32_t b) { return entries[size_t(a)] > entries[size_t(b)]; });
    load[0] = load[1] = 0;
    for (int32_t c : split) {
      const int s = load[1] < load[0] ? 1 : 0;
      label[size_t(c)] = s, load[s] += entries[size_t(c)];
    }
    const size_t total = load[0] + load[1];
    if (split.empty() || 20 * std::max(load[0], load[1]) <= 11 * total || children[size_t(split[0])].empty()) break;
    const int32_t root = split[0];  // the largest: into the chain
    label[size_t(root)] = -1, onChain[size_t(root)] = 1;
    split.erase(split.begin());
    split.insert(split.end(), children[size_t(root)].begin(), children[size_t(root)].end());
  }
  std::vector<char> isSplitChild(size_t(n), 0);
  for (int32_t c : split) isSplitChild[size_t(c)] = 1;
  // The chain: `node`, its ancestors and the frontier's former roots; a child of one of them is on
  // the chain or a frontier root, so every other node takes its parent's set (parents first:
  // parent(j) > j).
  for (int32_t j = n - 1; j >= 0; --j)
    if (!onChain[size_t(j)] && !isSplitChild[size_t(j)]) label[size_t(j)] = label[size_t(parent[size_t(j)])];
  chainIndex_.assign(size_t(n), -1);
  for (int32_t j = 0; j < n; ++j) {
    if (label[size_t(j)] < 0)
      chainIndex_[size_t(j)] = int32_t(chain_.size()), chain_.push_back(j);
    else
      set_[label[size_t(j)]].push_back(j);
  }
  // A set's column holds its own rows first, then the chain's (its ancestors: up its subtree to the
  // frontier root, then on the chain, with rising ids): where the chain's begin.
  chainStart_.assign(size_t(n), 0);
  for (int32_t j = 0; j < n; ++j) {
    int32_t k = colStart_[size_t(j)];
    const int32_t end = colStart_[size_t(j) + 1];
    if (chainIndex_[size_t(j)] >= 0) k = end;  // a chain column: all its rows are the chain's, updated directly
    while (k < end && chainIndex_[size_t(rows_[size_t(k)])] < 0) ++k;
    chainStart_[size_t(j)] = k;
  }
  y_.resize(size_t(n));
  for (auto& a : acc_) a.resize(chain_.size());
}

std::array<size_t, 3> SplitFactor::entriesPerPart() const {
  std::array<size_t, 3> e{0, 0, 0};
  auto count = [&](const std::vector<int32_t>& cols) {
    size_t c = 0;
    for (int32_t j : cols) c += size_t(colStart_[size_t(j) + 1] - colStart_[size_t(j)]);
    return c;
  };
  e[0] = count(set_[0]), e[1] = count(set_[1]), e[2] = count(chain_);
  return e;
}

namespace {

// The sweeps over a list of columns, on raw arrays (the compiler then keeps L's pointers in
// registers; through the members it reloaded them after every store into y: 1.3x slower).
// Forward, fused with the scaling by D^-1 (a column is final when reached): entries before
// chainStart[j] update y, the others acc (the chain's rows, through chainIndex).
void forwardSweep(const int32_t* cols, size_t count, const int32_t* colStart, const int32_t* chainStart,
                  const int32_t* rows, const Real* values, const Real* invD, const int32_t* chainIndex,
                  Vec3* __restrict y, Vec3* __restrict acc) {
  for (size_t c = 0; c < count; ++c) {
    const int32_t j = cols[c], chain = chainStart[j], end = colStart[j + 1];
    const Vec3 yj = y[j];
    for (int32_t k = colStart[j]; k < chain; ++k) y[rows[k]] -= values[k] * yj;
    for (int32_t k = chain; k < end; ++k) acc[chainIndex[rows[k]]] -= values[k] * yj;
    y[j] = yj * invD[j];
  }
}

// Backward, the columns in reverse: y_j -= sum L_ij y_i over the rows below (already final).
void backwardSweep(const int32_t* cols, size_t count, const int32_t* colStart, const int32_t* rows, const Real* values,
                   Vec3* __restrict y) {
  for (size_t c = count; c-- > 0;) {
    const int32_t j = cols[c], end = colStart[j + 1];
    Vec3 s = y[j];
    for (int32_t k = colStart[j]; k < end; ++k) s -= values[k] * y[rows[k]];
    y[j] = s;
  }
}

}  // namespace

void SplitFactor::forwardSet(int set, std::vector<Vec3>& y, std::vector<Vec3>& acc) const {
  std::fill(acc.begin(), acc.end(), Vec3::Zero());
  forwardSweep(set_[set].data(), set_[set].size(), colStart_.data(), chainStart_.data(), rows_.data(), values_.data(),
               invD_.data(), chainIndex_.data(), y.data(), acc.data());
}

void SplitFactor::backwardSet(int set, std::vector<Vec3>& y) const {
  backwardSweep(set_[set].data(), set_[set].size(), colStart_.data(), rows_.data(), values_.data(), y.data());
}

void SplitFactor::solve(const Vec3* b, Vec3* x, ThreadTeam* team) const {
  const size_t n = invD_.size();
  std::vector<Vec3>& y = y_;
  for (size_t i = 0; i < n; ++i) y[size_t(perm_[i])] = b[i];
  // Both sets, on two members or one after the other (the same operations either way).
  auto bothSets = [&](auto&& perSet) {
    if (team && team->members() >= 2 && !set_[1].empty())
      team->run([&](int t) {
        if (t < 2) perSet(t);
      });
    else
      perSet(0), perSet(1);
  };
  bothSets([&](int s) { forwardSet(s, y, acc_[s]); });
  for (size_t c = 0; c < chain_.size(); ++c) y[size_t(chain_[c])] += acc_[0][c], y[size_t(chain_[c])] += acc_[1][c];
  // The chain's columns update only the chain's rows: chainStart is their end (no accumulator).
  forwardSweep(chain_.data(), chain_.size(), colStart_.data(), chainStart_.data(), rows_.data(), values_.data(),
               invD_.data(), chainIndex_.data(), y.data(), nullptr);
  backwardSweep(chain_.data(), chain_.size(), colStart_.data(), rows_.data(), values_.data(), y.data());
  bothSets([&](int s) { backwardSet(s, y); });
  for (size_t i = 0; i < n; ++i) x[i] = y[size_t(perm_[i])];
}

}  // namespace gradel
