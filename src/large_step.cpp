#include "gradel/large_step.h"

#include <Eigen/Dense>
#include <cmath>

#include "gradel/coarse_space.h"
#include "gradel/element.h"
#include "gradel/element_stiffness.h"
#include "gradel/integration.h"
#include "thread_team.h"

namespace gradel {

namespace {

struct RigidFit {
  Vec3 centre = Vec3::Zero(), velocity = Vec3::Zero(), omega = Vec3::Zero(), momentum = Vec3::Zero();
  Mat3 inertia = Mat3::Zero();
};

// Centre of mass, its velocity, angular momentum about it, inertia tensor and angular velocity
// of the vertices [begin, end) (one body).
RigidFit rigidFit(const RestModel& m, const std::vector<Vec3>& x, const std::vector<Vec3>& v, size_t begin,
                  size_t end) {
  RigidFit r;
  Real mass = 0;
  for (size_t i = begin; i < end; ++i) mass += m.mass[i], r.centre += m.mass[i] * x[i], r.velocity += m.mass[i] * v[i];
  r.centre /= mass, r.velocity /= mass;
  for (size_t i = begin; i < end; ++i) {
    const Vec3 d = x[i] - r.centre;
    r.momentum += m.mass[i] * d.cross(v[i] - r.velocity);
    r.inertia += m.mass[i] * (d.squaredNorm() * Mat3::Identity() - d * d.transpose());
  }
  if (m.dim == 2) r.inertia(2, 2) = std::max(r.inertia(2, 2), Real(1e-300));
  const Eigen::FullPivLU<Mat3> lu(r.inertia);
  r.omega = lu.rank() == 3 ? Vec3(lu.solve(r.momentum)) : Vec3::Zero();
  if (m.dim == 2) r.omega.x() = r.omega.y() = 0;
  return r;
}

// The rigid motions the guards keep: one per body (a model made by hand without bodies is one),
// its vertices [begin, end); a body holding a pinned vertex has none.
struct GuardBody {
  uint32_t begin = 0, end = 0;
  bool pinned = false;
};
std::vector<GuardBody> guardBodies(const RestModel& m, const std::vector<uint32_t>& pinned) {
  std::vector<GuardBody> bodies;
  if (m.bodies.empty()) bodies.push_back({0, uint32_t(m.numVertices()), false});
  for (const BodyRange& b : m.bodies) bodies.push_back({b.vertexBegin, b.vertexEnd, false});
  for (uint32_t u : pinned)
    for (GuardBody& b : bodies) b.pinned = b.pinned || (u >= b.begin && u < b.end);
  return bodies;
}

// Runs perElement(begin, end) over element ranges, then (after a barrier) perVertex(begin, end)
// over vertex ranges, split between the team's members (or on this thread).
template <class PerElement, class PerVertex>
void elementsThenVertices(ThreadTeam* team, size_t E, size_t V, PerElement&& perElement, PerVertex&& perVertex) {
  if (!team || team->members() == 1) {
    perElement(size_t(0), E), perVertex(size_t(0), V);
    return;
  }
  team->run([&](int t) {
    const size_t T = size_t(team->members());
    perElement(E * size_t(t) / T, E * size_t(t + 1) / T);
    team->barrier();
    perVertex(V * size_t(t) / T, V * size_t(t + 1) / T);
  });
}

// Sums each vertex's pair slots in element order (pairStart / pairs: its pairs) into out[i],
// for the vertices [begin, end).
void gatherPairs(const std::vector<uint32_t>& pairStart, const std::vector<uint32_t>& pairs,
                 const std::vector<Vec3>& pair, size_t begin, size_t end, std::vector<Vec3>& out) {
  for (size_t i = begin; i < end; ++i) {
    Vec3 sum = Vec3::Zero();
    for (uint32_t k = pairStart[i]; k < pairStart[i + 1]; ++k) sum += pair[pairs[k]];
    out[i] = sum;
  }
}

}  // namespace

LargeStepSolver::LargeStepSolver(const RestModel& model, Real dt, const std::vector<uint32_t>& pinned, int coarseNodes)
    : model_(&model), dt_(dt), pinned_(pinned), half_(model, 0.5 * dt, pinned) {
  if (coarseNodes > 0) {
    std::vector<char> free(model.numVertices());
    for (size_t i = 0; i < free.size(); ++i) free[i] = half_.isFree(uint32_t(i));
    coarse_ = std::make_unique<CoarseSpace>(model, 0.5 * dt, free, coarseNodes);
  }
  acceleration_.assign(model.numVertices(), Vec3::Zero());
  restOffsets_ = model.pairRestOffsets();
  // Each vertex's element-vertex pairs in element order (a counting sort of the pairs by vertex).
  vertexPairStart_.assign(model.numVertices() + 1, 0);
  for (uint32_t v : model.elemVerts) ++vertexPairStart_[v + 1];
  for (size_t i = 0; i < model.numVertices(); ++i) vertexPairStart_[i + 1] += vertexPairStart_[i];
  vertexPairs_.resize(model.elemVerts.size());
  std::vector<uint32_t> next(vertexPairStart_.begin(), vertexPairStart_.end() - 1);
  for (uint32_t p = 0; p < model.elemVerts.size(); ++p) vertexPairs_[next[model.elemVerts[p]]++] = p;
}

LargeStepSolver::~LargeStepSolver() = default;

Real LargeStepSolver::energy(const std::vector<Vec3>& x, const std::vector<Vec3>& v, const std::vector<Quat>& q,
                             const Vec3& gravity) const {
  const RestModel& m = *model_;
  Real e = 0;
  std::vector<Vec3> f;
  for (size_t el = 0; el < m.numElements(); ++el) {
    const uint32_t b = m.elemStart[el], n = m.elemStart[el + 1] - b;
    f.resize(n);
    Quat r = q[el];
    e += elementForces(m.dim, x.data(), &m.elemVerts[b], &restOffsets_[b], int(n), m.stiffness[el], r, f.data(), 8)
             .energy;
    if (m.hasVolumeTerm() && m.volumeStiffness[el] > 0)
      e += elementVolumeForces(m.dim, x.data(), &m.elemVerts[b], &restOffsets_[b], int(n), r, m.volumeStiffness[el],
                               f.data());
  }
  for (size_t i = 0; i < x.size(); ++i) e += 0.5 * m.mass[i] * v[i].squaredNorm() - m.mass[i] * gravity.dot(x[i]);
  return e;
}

// Elastic forces [N] per vertex at x (rotations fitted, warm-started from q, written back): each
// element's forces into its own pair slots (elements split between the team's members), then
// per vertex the sum of its pairs in element order (vertices split): the same additions in the
// same order as one thread scattering element by element, so the same bits at any thread count.
void LargeStepSolver::forces(const std::vector<Vec3>& x, std::vector<Quat>& q, std::vector<Vec3>& f,
                             int iterations) const {
  const RestModel& m = *model_;
  f.resize(m.numVertices());
  std::vector<Vec3> pair(m.numPairs());
  elementsThenVertices(
      team_, m.numElements(), m.numVertices(),
      [&](size_t begin, size_t end) {
        for (size_t el = begin; el < end; ++el) {
          const uint32_t b = m.elemStart[el], n = m.elemStart[el + 1] - b;
          elementForces(m.dim, x.data(), &m.elemVerts[b], &restOffsets_[b], int(n), m.stiffness[el], q[el], &pair[b],
                        iterations);
          if (m.hasVolumeTerm() && m.volumeStiffness[el] > 0)  // Poisson's ratio (element.h)
            elementVolumeForces(m.dim, x.data(), &m.elemVerts[b], &restOffsets_[b], int(n), q[el],
                                m.volumeStiffness[el], &pair[b]);
        }
      },
      [&](size_t begin, size_t end) { gatherPairs(vertexPairStart_, vertexPairs_, pair, begin, end, f); });
}

// Newton on Phi(x) = 1/(2 h^2) |x - y|_M^2 + E(x): each Newton system
// (M / h^2 + K(x)) dx = -grad Phi is solved by conjugate gradients preconditioned with the
// projective-dynamics matrix (M / h^2 + sum_e k_e G_e^T G_e, factored once), K(x) p analytic
// (element_stiffness.h, each element's frame fitted once per Newton iteration). `passes` bounds
// the CG iterations of the step.
int LargeStepSolver::minimise(const ProjectiveSolver& pre, Real h, const std::vector<Vec3>& y,
                              const std::vector<char>& free, Real scale, int passes, int fitIterations, bool reform,
                              std::vector<Vec3>& x, std::vector<Quat>& q) const {
  const RestModel& m = *model_;
  const size_t V = m.numVertices();
  const Real invH2 = 1.0 / (h * h);
  int iterations = 0;
  // The preconditioner restricted to the free vertices: z = S P^-1 S r, S zeroing the others,
  // plus the coarse correction Q r (coarse_space.h; its rows of pinned vertices are zero).
  auto precondition = [&](const std::vector<Vec3>& r, std::vector<Vec3>& z) {
    pre.applyInverse(r, z);
    for (size_t i = 0; i < V; ++i)
      if (!free[i]) z[i].setZero();
    if (coarse_) coarse_->addCorrection(r, z);
  };
  std::vector<Vec3> f, Kp, r(V), z, p(V), Ap(V), dx(V), pair(m.numPairs());
  // K(x) p (element_stiffness.h): each element's frame at the Newton iterate, then per product
  // each element's K_e p into its pair slots and per vertex their sum (as forces(): the same bits
  // at any thread count).
  std::vector<StiffnessFrame> frames(m.numElements());
  // The volumetric term's Gauss-Newton Hessian kappa g g^T, g_i = (D / tr S) M R0_i = de_v/dx_i
  // (an anisotropic S: M_F V R0_i) at the iterate (element.h; positive semi-definite, as element_stiffness.h clamps the rotation
  // term's; the rotation's own change is left out): (D / tr S) M per element.
  std::vector<Mat3> volumeFrames(m.hasVolumeTerm() ? m.numElements() : 0);
  auto fitFrames = [&] {
    elementsThenVertices(
        team_, m.numElements(), 0,
        [&](size_t begin, size_t end) {
          for (size_t el = begin; el < end; ++el) {
            const uint32_t b = m.elemStart[el], n = m.elemStart[el + 1] - b;
            const Mat3 A = elementCovariance(x.data(), &m.elemVerts[b], &restOffsets_[b], int(n));
            frames[el] = elementStiffnessFrame(m.dim, A, q[el], &restOffsets_[b], int(n));
            if (!volumeFrames.empty() && m.volumeStiffness[el] > 0) {
              Mat3 V;  // an anisotropic S: M_F V (element.h), else (D / tr S) M
              if (volumeStrainMatrix(m.dim, &restOffsets_[b], int(n), V))
                volumeFrames[el] = fitAffineRotation(m.dim, A * V, q[el]) * V;
              else
                volumeFrames[el] = Real(m.dim == 2 ? 2 : 3) / restMomentTrace(&restOffsets_[b], int(n)) *
                                   q[el].toRotationMatrix();
            }
          }
        },
        [](size_t, size_t) {});
  };
  auto stiffness = [&](const std::vector<Vec3>& d, std::vector<Vec3>& out) {
    out.resize(V);
    elementsThenVertices(
        team_, m.numElements(), V,
        [&](size_t begin, size_t end) {
          for (size_t el = begin; el < end; ++el) {
            const uint32_t b = m.elemStart[el], n = m.elemStart[el + 1] - b;
            elementStiffnessProduct(frames[el], d.data(), &m.elemVerts[b], &restOffsets_[b], int(n), m.stiffness[el],
                                    &pair[b]);
            if (!volumeFrames.empty() && m.volumeStiffness[el] > 0) {
              const Mat3& D = volumeFrames[el];
              Real s = 0;
              for (uint32_t i = 0; i < n; ++i) s += (D * restOffsets_[b + i]).dot(d[m.elemVerts[b + i]]);
              s *= m.volumeStiffness[el];
              for (uint32_t i = 0; i < n; ++i) pair[b + i] += s * (D * restOffsets_[b + i]);
            }
          }
        },
        [&](size_t begin, size_t end) { gatherPairs(vertexPairStart_, vertexPairs_, pair, begin, end, out); });
  };
  auto applyA = [&](const std::vector<Vec3>& d, std::vector<Vec3>& out) {
    stiffness(d, Kp);
    for (size_t i = 0; i < V; ++i) out[i] = free[i] ? Vec3(m.mass[i] * invH2 * d[i] + Kp[i]) : Vec3::Zero();
  };
  auto dot = [&](const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
    Real sum = 0;
    for (size_t i = 0; i < V; ++i) sum += a[i].dot(b[i]);
    return sum;
  };
  // Inexact Newton with the two-level preconditioner: each system to 1e-2 in the preconditioned
  // residual norm (rz to 1e-4), so the budget spreads over the Newton iterations (to 1e-8, the
  // first took most of it and the bar's damping at 8-12 iterations jumped between 1 % and 40 %).
  const Real tolerance = coarse_ ? 1e-4 : 1e-8;
  int budget = std::max(passes, 1);
  for (int newton = 0; newton < 4 && budget > 0; ++newton) {
    forces(x, q, f, fitIterations);
    fitFrames();
    Real rNorm = 0;
    for (size_t i = 0; i < V; ++i) {
      r[i] = free[i] ? Vec3(f[i] - m.mass[i] * invH2 * (x[i] - y[i])) : Vec3::Zero();
      rNorm = std::max(rNorm, r[i].norm() * m.invMass[i]);
    }
    if (rNorm <= 1e-10 * std::max(scale, Real(1e-3)) * invH2 * h * h) break;
    std::fill(dx.begin(), dx.end(), Vec3::Zero());
    if (coarse_) {
      // Galerkin start dx = Q r: the coarse part of the solution before any CG iteration.
      if (newton == 0 && reform) coarse_->update(frames);
      coarse_->addCorrection(r, dx);
      applyA(dx, Ap);
      for (size_t i = 0; i < V; ++i) r[i] -= Ap[i];
    }
    precondition(r, z);
    p = z;
    Real rz = dot(r, z);
    const Real rz0 = rz;
    for (; budget > 0; --budget) {
      ++iterations;
      applyA(p, Ap);
      const Real pAp = dot(p, Ap);
      if (!(pAp > 0)) {
        if (newton == 0 && !coarse_ && dx[0].isZero() && iterations == 1) dx = z;  // no curvature: take the PD step
        break;
      }
      const Real alpha = rz / pAp;
      for (size_t i = 0; i < V; ++i) dx[i] += alpha * p[i], r[i] -= alpha * Ap[i];
      precondition(r, z);
      const Real rzNew = dot(r, z);
      if (rzNew <= tolerance * rz0) {
        --budget;
        break;
      }
      const Real beta = rzNew / rz;
      rz = rzNew;
      for (size_t i = 0; i < V; ++i) p[i] = z[i] + beta * p[i];
    }
    for (size_t i = 0; i < V; ++i) x[i] += dx[i];
  }
  return iterations;
}

LargeStepReport LargeStepSolver::step(std::vector<Vec3>& x, std::vector<Vec3>& v, std::vector<Quat>& q,
                                      const Vec3& gravity, Real damping, int passes, int rotationIterations,
                                      const std::vector<Vec3>& pinStart, const std::vector<Vec3>& pinEnd) {
  const RestModel& m = *model_;
  const size_t V = m.numVertices();
  const Real h = 0.5 * dt_, invH2 = 1.0 / (h * h);
  LargeStepReport report;
  const bool pinsMove = pinStart != pinEnd;
  if (pinsMove) budgetValid_ = false;
  if (!budgetValid_) budget_ = energy(x, v, q, gravity), budgetValid_ = true;
  const std::vector<GuardBody> guard = guardBodies(m, pinned_);
  std::vector<RigidFit> before(guard.size());
  for (size_t b = 0; b < guard.size(); ++b)
    if (!guard[b].pinned) before[b] = rigidFit(m, x, v, guard[b].begin, guard[b].end);
  const int fitIterations = std::max(rotationIterations, 20);

  const std::vector<Vec3> x0 = x;
  std::vector<Vec3> y(V);
  for (size_t i = 0; i < V; ++i) {
    y[i] = freeFlight(x0[i], v[i], h, 1, gravity);
    x[i] = x0[i] + h * v[i] + h * h * acceleration_[i];
  }
  for (size_t j = 0; j < pinned_.size(); ++j) y[pinned_[j]] = x[pinned_[j]] = 0.5 * (pinStart[j] + pinEnd[j]);

  std::vector<char> free(V);
  Real scale = 0;
  for (size_t i = 0; i < V; ++i)
    free[i] = half_.isFree(uint32_t(i)), scale = std::max(scale, (v[i].norm() / h + gravity.norm()));
  // The coarse operator is re-formed every second substep (once per step at 2 substeps): it
  // preconditions, so a frame of lag costs iterations, not accuracy (every substep cost the bar
  // 40 % more per step for the same amplitude).
  const bool reform = substeps_++ % 2 == 0;
  report.passes = minimise(half_, h, y, free, scale, passes, fitIterations, reform, x, q);
  for (size_t i = 0; i < V; ++i) {
    const Vec3 d = x[i] - x0[i];
    if (half_.isFree(uint32_t(i))) acceleration_[i] = (d - h * v[i]) * invH2;
    v[i] = 2 * d / h - v[i];
    x[i] = x0[i] + 2 * d;
  }
  for (size_t j = 0; j < pinned_.size(); ++j)
    x[pinned_[j]] = pinEnd[j], v[pinned_[j]] = (pinEnd[j] - pinStart[j]) / dt_;
  // The momentum guard, per free body (each keeps its own angular momentum about its centre).
  for (size_t b = 0; b < guard.size(); ++b) {
    if (guard[b].pinned) continue;
    const RigidFit after = rigidFit(m, x, v, guard[b].begin, guard[b].end);
    const Eigen::FullPivLU<Mat3> lu(after.inertia);
    if (lu.rank() == 3 || m.dim == 2) {
      Vec3 dOmega = m.dim == 2 ? Vec3(0, 0, (before[b].momentum.z() - after.momentum.z()) / after.inertia(2, 2))
                               : Vec3(lu.solve(before[b].momentum - after.momentum));
      for (size_t i = guard[b].begin; i < guard[b].end; ++i) v[i] += dOmega.cross(x[i] - after.centre);
      report.momentumKept = true;
    }
  }
  if (damping > 0 || m.hasRegionDamping()) {
    Real removed = 0;
    for (size_t i = 0; i < V; ++i) {
      const Real damp = dampingFactor(m.vertexDamping(i, damping), dt_);  // integration.h; per region: model.h
      removed += 0.5 * m.mass[i] * v[i].squaredNorm() * (1 - damp * damp), v[i] *= damp;
    }
    budget_ -= removed;
  }
  const Real e = energy(x, v, q, gravity);
  if (e > budget_) {
    // Each body's rigid fit (a pinned body has no free rigid motion: all its velocity is deformation).
    std::vector<RigidFit> rigid(guard.size());
    for (size_t b = 0; b < guard.size(); ++b)
      if (!guard[b].pinned) rigid[b] = rigidFit(m, x, v, guard[b].begin, guard[b].end);
    auto rigidVelocity = [&](const RigidFit& r, size_t i) { return Vec3(r.velocity + r.omega.cross(x[i] - r.centre)); };
    Real kDef = 0;
    for (size_t b = 0; b < guard.size(); ++b)
      for (size_t i = guard[b].begin; i < guard[b].end; ++i)
        if (half_.isFree(uint32_t(i)))  // (as written: the same rounding as a single body's before)
          kDef += 0.5 * m.mass[i] * (v[i] - rigid[b].velocity - rigid[b].omega.cross(x[i] - rigid[b].centre)).squaredNorm();
    const Real excess = e - budget_;
    const Real s = kDef > 0 ? std::sqrt(std::max(Real(0), 1 - excess / kDef)) : 1;
    for (size_t b = 0; b < guard.size(); ++b)
      for (size_t i = guard[b].begin; i < guard[b].end; ++i) {
        if (!half_.isFree(uint32_t(i))) continue;
        const Vec3 r = rigidVelocity(rigid[b], i);
        v[i] = r + s * (v[i] - r);
      }
    report.energyRemoved = std::min(excess, kDef);
  }
  return report;
}

}  // namespace gradel
