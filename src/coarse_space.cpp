#include "gradel/coarse_space.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace gradel {

namespace {

// The four scalar functions of a node's affine motions at Y.
inline std::array<Real, 4> affine(const Vec3& y) { return {1, y.x(), y.y(), y.z()}; }

// Eigen sizes the blocks of its dense products and of LLT's blocked rank updates from the CPU's
// cache sizes, read at run time, and the blocks decide the order of each sum: two CI machines of
// the same flavour gave the large step different bits (tests/golden). Before every dense
// product and factorisation the coarse space sets the sizes Eigen reads on the project's 2-core
// machines (AMD EPYC: 32 KiB, 512 KiB, 256 MiB), so its results are the same on every machine.
// Process-wide, and written only when they differ (coarse_space.h).
void pinEigenBlocking() {
  constexpr std::ptrdiff_t l1 = std::ptrdiff_t(32) << 10, l2 = std::ptrdiff_t(512) << 10, l3 = std::ptrdiff_t(256) << 20;
  if (Eigen::l1CacheSize() != l1 || Eigen::l2CacheSize() != l2 || Eigen::l3CacheSize() != l3)
    Eigen::setCpuCacheSizes(l1, l2, l3);
}

}  // namespace

CoarseSpace::CoarseSpace(const RestModel& m, Real h, const std::vector<char>& free, int maxNodes) : model_(&m) {
  pinEigenBlocking();
  const size_t V = m.numVertices();
  weightStart_.assign(V + 1, 0);
  uint32_t nodes = 0;
  std::vector<BodyRange> bodies = m.bodies;
  if (bodies.empty()) {
    BodyRange all;
    all.vertexEnd = uint32_t(V), all.elementEnd = uint32_t(m.numElements());
    bodies.push_back(all);
  }
  std::vector<std::vector<Weight>> perVertex(V);
  for (const BodyRange& body : bodies) {
    Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
    for (uint32_t i = body.vertexBegin; i < body.vertexEnd; ++i)
      if (free[i]) lo = lo.cwiseMin(m.restPositions[i]), hi = hi.cwiseMax(m.restPositions[i]);
    if (!(lo.x() <= hi.x())) continue;  // nothing free
    const Vec3 extent = hi - lo;
    const Real longest = extent.maxCoeff();
    if (!(longest > 0)) continue;
    // Nodes per axis at spacing H: ceil(extent / H) + 1 (1 on an axis without extent).
    auto count = [&](Real H, std::array<int, 3>& n) {
      long total = 1;
      for (int a = 0; a < 3; ++a) {
        n[a] = extent[a] > 1e-12 * longest ? int(std::ceil(extent[a] / H - 1e-9)) + 1 : 1;
        total *= n[a];
      }
      return total;
    };
    // The smallest spacing longest / k (k = 1, 2, ...) within the node budget.
    std::array<int, 3> n{};
    Real H = longest;
    count(H, n);
    for (int k = 2; k < 4096; ++k) {
      std::array<int, 3> nk{};
      if (count(longest / k, nk) > maxNodes) break;
      H = longest / k, n = nk;
    }
    for (uint32_t i = body.vertexBegin; i < body.vertexEnd; ++i) {
      if (!free[i]) continue;
      const Vec3 t = (m.restPositions[i] - lo) / H;
      std::array<int, 3> cell{};
      Vec3 frac;
      for (int a = 0; a < 3; ++a) {
        cell[a] = n[a] > 1 ? std::clamp(int(std::floor(t[a])), 0, n[a] - 2) : 0;
        frac[a] = n[a] > 1 ? std::clamp(t[a] - cell[a], Real(0), Real(1)) : 0;
      }
      for (int corner = 0; corner < 8; ++corner) {
        Real phi = 1;
        std::array<int, 3> c{};
        bool valid = true;
        for (int a = 0; a < 3; ++a) {
          const int bit = (corner >> a) & 1;
          if (n[a] == 1 && bit) valid = false;
          c[a] = cell[a] + bit;
          phi *= n[a] == 1 ? 1 : (bit ? frac[a] : 1 - frac[a]);
        }
        if (!valid || phi <= 0) continue;
        const uint32_t node = nodes + uint32_t((c[2] * n[1] + c[1]) * n[0] + c[0]);
        const Vec3 nodePos = lo + H * Vec3(c[0], c[1], c[2]);
        const Vec3 y = (m.restPositions[i] - nodePos) / H;
        perVertex[i].push_back({node, phi, y, {phi, phi * y.x(), phi * y.y(), phi * y.z()}});
      }
    }
    nodes += uint32_t(n[0] * n[1] * n[2]);
  }
  for (size_t i = 0; i < V; ++i) {
    weightStart_[i + 1] = weightStart_[i] + uint32_t(perVertex[i].size());
    weights_.insert(weights_.end(), perVertex[i].begin(), perVertex[i].end());
  }
  const Eigen::Index dofs = Eigen::Index(12) * nodes;
  E0_.setZero(dofs, dofs);
  // Mass part: sum_i m_i / h^2 Z_i^T Z_i.
  const Real invH2 = 1 / (h * h);
  for (size_t i = 0; i < V; ++i)
    for (uint32_t a = weightStart_[i]; a < weightStart_[i + 1]; ++a)
      for (uint32_t b = weightStart_[i]; b < weightStart_[i + 1]; ++b) {
        const Weight &wa = weights_[a], &wb = weights_[b];
        const auto ga = affine(wa.y), gb = affine(wb.y);
        for (int g = 0; g < 4; ++g)
          for (int g2 = 0; g2 < 4; ++g2) {
            const Real v = m.mass[i] * invH2 * wa.phi * ga[g] * wb.phi * gb[g2];
            for (int d = 0; d < 3; ++d) E0_(wa.node * 12 + d * 4 + g, wb.node * 12 + d * 4 + g2) += v;
          }
      }
  // Elastic part and rest moments per element: Phi_e (n x 4 nodes_e, the hat-weighted scalar
  // basis on the element's vertices), k_e (Phi_e^T Phi_e - s s^T / n), s its column sums.
  momentStart_.assign(m.numElements() + 1, 0);
  std::vector<uint32_t> local;
  Eigen::MatrixXd Phi;
  for (size_t el = 0; el < m.numElements(); ++el) {
    const uint32_t b0 = m.elemStart[el], n = m.elemStart[el + 1] - b0;
    local.clear();
    for (uint32_t p = b0; p < b0 + n; ++p) {
      const uint32_t i = m.elemVerts[p];
      for (uint32_t a = weightStart_[i]; a < weightStart_[i + 1]; ++a)
        if (std::find(local.begin(), local.end(), weights_[a].node) == local.end()) local.push_back(weights_[a].node);
    }
    std::sort(local.begin(), local.end());
    Vec3 mean = Vec3::Zero();
    for (uint32_t p = b0; p < b0 + n; ++p) mean += m.restOffset(el, p);
    mean /= Real(n);
    Phi.setZero(n, Eigen::Index(4 * local.size()));
    std::vector<std::array<Vec3, 4>> mu(local.size(), {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()});
    for (uint32_t p = b0; p < b0 + n; ++p) {
      const uint32_t i = m.elemVerts[p];
      const Vec3 r0 = m.restOffset(el, p) - mean;
      for (uint32_t a = weightStart_[i]; a < weightStart_[i + 1]; ++a) {
        const Weight& w = weights_[a];
        const size_t c = size_t(std::lower_bound(local.begin(), local.end(), w.node) - local.begin());
        const auto g = affine(w.y);
        for (int k = 0; k < 4; ++k) Phi(p - b0, Eigen::Index(4 * c + k)) += w.phi * g[k], mu[c][k] += w.phi * g[k] * r0;
      }
    }
    const Eigen::RowVectorXd s = Phi.colwise().sum();
    const Eigen::MatrixXd G = m.stiffness[el] * (Phi.transpose() * Phi - s.transpose() * s / Real(n));
    for (size_t c = 0; c < local.size(); ++c)
      for (size_t c2 = 0; c2 < local.size(); ++c2)
        for (int g = 0; g < 4; ++g)
          for (int g2 = 0; g2 < 4; ++g2)
            for (int d = 0; d < 3; ++d)
              E0_(local[c] * 12 + d * 4 + g, local[c2] * 12 + d * 4 + g2) +=
                  G(Eigen::Index(4 * c + g), Eigen::Index(4 * c2 + g2));
    momentNode_.insert(momentNode_.end(), local.begin(), local.end());
    moments_.insert(moments_.end(), mu.begin(), mu.end());
    momentStart_[el + 1] = uint32_t(momentNode_.size());
  }
  // Columns without support (an axis without extent, a node with no free vertex) get a unit
  // diagonal; the others a relative 1e-10 (columns dependent on few vertices).
  const Real maxDiag = dofs ? E0_.diagonal().maxCoeff() : 0;
  for (Eigen::Index j = 0; j < dofs; ++j) {
    if (E0_(j, j) <= 1e-14 * maxDiag) {
      E0_.row(j).setZero(), E0_.col(j).setZero();
      E0_(j, j) = 1;
    } else {
      E0_(j, j) *= 1 + 1e-10;
    }
  }
  E_ = E0_;
  factor_.compute(E_);
}

void CoarseSpace::update(const std::vector<StiffnessFrame>& frames) {
  const RestModel& m = *model_;
  pinEigenBlocking();
  E_ = E0_;
  using Block = Eigen::Matrix<Real, 3, 12>;
  std::vector<Block> B, WB;
  for (size_t el = 0; el < m.numElements(); ++el) {
    const uint32_t a = momentStart_[el], nodes = momentStart_[el + 1] - a;
    if (!nodes) continue;
    const StiffnessFrame& f = frames[el];
    const Mat3 W = m.stiffness[el] * f.Tinv;
    B.resize(nodes), WB.resize(nodes);
    for (uint32_t c = 0; c < nodes; ++c) {
      for (int d = 0; d < 3; ++d) {
        const Vec3 u = f.M.row(d).transpose();  // M^T e_d
        for (int g = 0; g < 4; ++g) B[c].col(4 * d + g) = moments_[a + c][g].cross(u);
      }
      WB[c].noalias() = W.lazyProduct(B[c]);
    }
    // The lower block triangle only (local nodes ascend; the factor reads the lower triangle).
    for (uint32_t c = 0; c < nodes; ++c)
      for (uint32_t c2 = 0; c2 <= c; ++c2)
        E_.block<12, 12>(Eigen::Index(momentNode_[a + c]) * 12, Eigen::Index(momentNode_[a + c2]) * 12) -=
            B[c].transpose().lazyProduct(WB[c2]);
  }
  factor_.compute(E_);
  valid_ = factor_.info() == Eigen::Success;
}

Eigen::VectorXd CoarseSpace::restrictTo(const std::vector<Vec3>& r) const {
  Eigen::VectorXd c = Eigen::VectorXd::Zero(E0_.rows());
  for (size_t i = 0; i + 1 < weightStart_.size(); ++i)
    for (uint32_t a = weightStart_[i]; a < weightStart_[i + 1]; ++a) {
      const Weight& w = weights_[a];
      const Eigen::Map<const Eigen::Vector4d> f(w.f.data());
      Eigen::Map<Eigen::Matrix<Real, 4, 3>> out(c.data() + w.node * 12);
      out.noalias() += f * r[i].transpose();
    }
  return c;
}

void CoarseSpace::prolongAdd(const Eigen::VectorXd& c, std::vector<Vec3>& z) const {
  for (size_t i = 0; i + 1 < weightStart_.size(); ++i) {
    Vec3 sum = Vec3::Zero();
    for (uint32_t a = weightStart_[i]; a < weightStart_[i + 1]; ++a) {
      const Weight& w = weights_[a];
      const Eigen::Map<const Eigen::Vector4d> f(w.f.data());
      const Eigen::Map<const Eigen::Matrix<Real, 4, 3>> in(c.data() + w.node * 12);
      sum.noalias() += in.transpose() * f;
    }
    z[i] += sum;
  }
}

void CoarseSpace::addCorrection(const std::vector<Vec3>& r, std::vector<Vec3>& z) const {
  if (!size() || !valid_) return;
  pinEigenBlocking();
  prolongAdd(factor_.solve(restrictTo(r)), z);
}

}  // namespace gradel
