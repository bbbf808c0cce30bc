#include "gradel/shared/validation.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>

#include "gradel/element.h"
#include "gradel/layout.h"
#include "gradel/projective.h"
#include "gradel/shapes.h"
#include "gradel/world.h"

namespace gradel {

PinSettings barFacePin(const BarSpec& bar, Real x0) {
  const Real h = bar.voxelSize();
  PinSettings p;
  p.min = Vec3(x0 - 0.25 * h, -0.25 * h, -0.25 * h);
  p.max = Vec3(x0 + 0.25 * h, bar.width + 0.25 * h, bar.width + 0.25 * h);
  return p;
}

Scene barScene(const BarSpec& bar, const SimulationSettings& sim, bool clamped) {
  Scene s;
  s.name = "bar";
  s.dim = 3;
  ShapeSpec& shape = s.bodies[0].shape;
  shape.dim = 3;
  shape.dims = {bar.along, bar.across, bar.across};
  shape.voxelSize = bar.voxelSize();
  Primitive box;
  box.kind = PrimitiveKind::Box;
  box.min = Vec3::Zero();
  box.max = Vec3(bar.along, bar.across, bar.across);
  shape.primitives = {box};
  if (bar.split != BarSplit::None) {
    Primitive second = box;  // painted over the first half's label 1 (shapes.h: later primitives win)
    if (bar.split == BarSplit::Series)
      second.min.x() = bar.along / 2;
    else
      second.min.y() = bar.across / 2;
    second.label = 2;
    shape.primitives.push_back(second);
  }
  s.bodies[0].layout = bar.layout;
  s.bodies[0].material = bar.material;
  s.simulation = sim;
  if (clamped) s.pins = {barFacePin(bar, 0)};
  return s;
}

Real mixtureModulus(BarSplit split, Real E1, Real E2) {
  switch (split) {
    case BarSplit::Series: return 2 / (1 / E1 + 1 / E2);
    case BarSplit::Parallel: return (E1 + E2) / 2;
    case BarSplit::None: break;
  }
  return E1;
}

Real beamTipSag(Real L, Real a, Real rho, Real E, Real g) {
  const Real A = a * a, I = a * a * a * a / 12;
  return rho * g * A * std::pow(L, 4) / (8 * E * I);
}

Real beamFrequency(Real L, Real a, Real rho, Real E) {
  const Real A = a * a, I = a * a * a * a / 12;
  return 1.875104 * 1.875104 / (2 * std::numbers::pi * L * L) * std::sqrt(E * I / (rho * A));
}

std::vector<uint32_t> tipVertices(const RestModel& model, Real length) {
  std::vector<uint32_t> ids;
  const Real tol = 1e-6 * length;
  for (size_t i = 0; i < model.numVertices(); ++i)
    if (std::abs(model.restPositions[i].x() - length) < tol) ids.push_back(uint32_t(i));
  return ids;
}

Real stretchModulus(const BarSpec& bar, Real strain) {
  SimulationSettings sim;
  sim.gravity.setZero();
  Scene scene = barScene(bar, sim, true);
  const Real L = bar.length(), dL = strain * L;
  PinSettings far = barFacePin(bar, L);
  far.path.keys = {Keyframe{0, Vec3(dL, 0, 0), std::nullopt}};
  scene.pins.push_back(far);
  BuiltScene b = buildScene(scene);
  World& w = *b.world;
  const RestModel& m = w.model();
  const PinSet& pins = w.pinned();
  std::vector<Vec3> targets;
  for (uint32_t i : pins.vertices) targets.push_back(w.state().positions[i]);
  // Start from the affine stretch: the static solve then only removes its small non-affine part.
  for (Vec3& x : w.state().positions) x.x() *= 1 + strain;
  ProjectiveSolver solver(m, 0, pins.vertices);
  solver.solveStatic(w.state().positions, w.state().rotations, Vec3::Zero(), targets, 20000, 1e-14 * L);
  // Elastic force on the moved face (pin index 1): the reaction pulling it back.
  std::vector<Vec3> force(m.numVertices(), Vec3::Zero()), f, offsets;
  for (size_t e = 0; e < m.numElements(); ++e) {
    const uint32_t s = m.elemStart[e], n = m.elemStart[e + 1] - s;
    f.resize(n);
    Quat q = w.state().rotations[e];
    elementForces(3, w.state().positions.data(), &m.elemVerts[s], m.restOffsets(e, offsets), int(n), m.stiffness[e], q,
                  f.data(), 20);
    for (uint32_t i = 0; i < n; ++i) force[m.elemVerts[s + i]] += f[i];
  }
  Real F = 0;
  for (size_t j = 0; j < pins.vertices.size(); ++j)
    if (pins.pinOf[j] == 1) F -= force[pins.vertices[j]].x();
  return F * L / (bar.width * bar.width * dL);
}

SagResult staticTipSag(const BarSpec& bar, size_t maxSteps, Real tolerance) {
  SimulationSettings sim;
  sim.damping = 0;
  // Kinetic damping (velocities zeroed at a peak of the kinetic energy) needs the small steps of
  // the vertex rule: zeroing symplectic Euler's staggered velocity where v_{n-1/2} . v_{n+1/2} < 0
  // raises the energy it keeps by up to (omega dt / 2)^2 of a mode's, and at the operator rule's
  // omega_max dt = 1.26 the paper-scaled 2-across bar's relaxation grew to a sag of 2e151 m
  // within 2e6 steps (0.00048 m at the vertex rule). The static sag does not depend on dt.
  sim.dtPeriod = PeriodRule::Vertex;
  BuiltScene b = buildScene(barScene(bar, sim, true));
  World& w = *b.world;
  const RestModel& m = w.model();
  const std::vector<uint32_t> tip = tipVertices(m, bar.length());
  auto sag = [&] {
    Real s = 0;
    for (uint32_t i : tip) s += m.restPositions[i].y() - w.state().positions[i].y();
    return s / Real(tip.size());
  };
  SagResult r;
  r.elements = m.numElements();
  r.vertices = m.numVertices();
  Real previousKE = 0, lastSag = -1;
  int calm = 0;
  for (r.steps = 0; r.steps < maxSteps; ++r.steps) {
    w.step();
    Real ke = 0;
    for (size_t i = 0; i < m.numVertices(); ++i) ke += m.mass[i] * w.state().velocities[i].squaredNorm();
    if (ke < previousKE) {
      for (Vec3& v : w.state().velocities) v.setZero();
      previousKE = 0;
      const Real s = sag();
      calm = std::abs(s - lastSag) < tolerance * std::abs(s) ? calm + 1 : 0;
      lastSag = s;
      if (calm >= 3) break;
    } else {
      previousKE = ke;
    }
  }
  r.sag = sag();
  return r;
}

Real dominantFrequency(const std::vector<Real>& signal, Real sampleInterval) {
  const size_t N = signal.size();
  if (N < 4) return 0;
  Real mean = 0;
  for (Real s : signal) mean += s;
  mean /= Real(N);
  std::vector<Real> w(N);
  for (size_t i = 0; i < N; ++i)
    w[i] = (signal[i] - mean) * (0.5 - 0.5 * std::cos(2 * std::numbers::pi * Real(i) / Real(N - 1)));
  auto power = [&](Real f) {
    Real re = 0, im = 0;
    for (size_t i = 0; i < N; ++i) {
      const Real ph = 2 * std::numbers::pi * f * Real(i) * sampleInterval;
      re += w[i] * std::cos(ph), im += w[i] * std::sin(ph);
    }
    return re * re + im * im;
  };
  // Coarse scan on the FFT bins (skipping DC), then a fine scan around the best bin.
  const Real df = 1.0 / (Real(N) * sampleInterval), fMax = 0.5 / sampleInterval;
  Real best = df, bestP = -1;
  for (Real f = df; f < fMax; f += df)
    if (const Real p = power(f); p > bestP) bestP = p, best = f;
  const Real lo = std::max(best - df, 0.0), hi = best + df;
  for (int i = 0; i <= 200; ++i) {
    const Real f = lo + (hi - lo) * i / 200.0;
    if (const Real p = power(f); p > bestP) bestP = p, best = f;
  }
  return best;
}

Real enclosedVolume(const DisplaySurface& surface, const std::vector<Vec3>& positions) {
  Real v = 0;
  for (const auto& t : surface.triangles) {
    const Vec3& a = positions[surface.modelVertex[t[0]]];
    const Vec3& b = positions[surface.modelVertex[t[1]]];
    const Vec3& c = positions[surface.modelVertex[t[2]]];
    v += a.dot(b.cross(c));
  }
  return v / 6;
}

namespace {

// A preset shape of `size` voxels of edge h, laid out, with its rest model and voxel surface.
struct Specimen {
  VoxelVolume volume;
  Layout layout;
  std::shared_ptr<const RestModel> model;
  DisplaySurface surface;
  Real restVolume = 0;
};
Specimen specimen(const ShapeSpec& shape, LayoutKind layout, const MaterialSettings& m) {
  Specimen s;
  s.volume = rasterize(shape);
  s.layout = buildLayout(s.volume, layout);
  s.model = std::make_shared<RestModel>(buildRestModel(s.layout, s.volume, m, Vec3::Zero()));
  s.surface = buildDisplaySurface(s.layout, s.volume, SurfaceKind::Voxel);
  s.restVolume = enclosedVolume(s.surface, s.model->restPositions);
  return s;
}

// The axis-aligned bounds of a set of positions [m]: lo and hi per axis.
struct Bounds {
  Vec3 lo = Vec3::Constant(1e300), hi = -lo;
  Vec3 extent() const { return hi - lo; }
  Vec3 centre() const { return 0.5 * (lo + hi); }
};
Bounds bounds(const std::vector<Vec3>& x) {
  Bounds b;
  for (const Vec3& p : x) b.lo = b.lo.cwiseMin(p), b.hi = b.hi.cwiseMax(p);
  return b;
}

// The segments where the surface's triangles cross the plane z = z0, relative to (cx, cy).
std::vector<std::array<Real, 4>> sectionAt(const DisplaySurface& surface, const std::vector<Vec3>& x, Real z0, Real cx,
                                           Real cy) {
  std::vector<std::array<Real, 4>> out;
  for (const auto& t : surface.triangles) {
    std::array<Vec3, 3> p;
    for (int k = 0; k < 3; ++k) p[k] = x[surface.modelVertex[t[k]]];
    std::vector<Vec3> hits;
    for (int k = 0; k < 3; ++k) {
      const Vec3 &a = p[k], &b = p[(k + 1) % 3];
      const Real da = a.z() - z0, db = b.z() - z0;
      if ((da < 0) != (db < 0)) hits.push_back(a + (b - a) * (da / (da - db)));
    }
    if (hits.size() == 2)
      out.push_back({hits[0].x() - cx, hits[0].y() - cy, hits[1].x() - cx, hits[1].y() - cy});
  }
  return out;
}

}  // namespace

UniaxialResult compressBetweenWalls(const MaterialSettings& m, LayoutKind layout, int n, Real strain,
                                    IntegratorKind integrator, int steps, Real h) {
  const Real L = n * h;
  const Specimen b = specimen(presetShape("box", n, 3, h), layout, m);
  SimulationSettings s;
  s.gravity.setZero();
  s.damping = 60;
  if (integrator != IntegratorKind::SymplecticEuler) s.integrator = integrator, s.dt = 1.0 / 60;
  DomainSettings d;
  d.enabled = true, d.friction = 0, d.restitution = 0;
  const Vec3 ext0 = bounds(b.model->restPositions).extent();
  const Real cx = 0.5 * ext0.x();  // the box spans [0, L] at rest
  d.min = Vec3(cx - 0.5 * L * (1 - strain), -1, -1), d.max = Vec3(cx + 0.5 * L * (1 - strain), 1, 1);
  World w(b.model, s, d, {});
  for (Vec3& x : w.state().positions) x.x() = cx + (x.x() - cx) * (1 - strain);  // start inside the walls
  for (int i = 0; i < steps; ++i) w.step();
  const Vec3 ext = bounds(w.state().positions).extent();
  UniaxialResult r;
  r.axial = ext.x() / L - 1;
  r.lateral = 0.5 * (ext.y() + ext.z()) / L - 1;
  r.volume = enclosedVolume(b.surface, w.state().positions) / b.restVolume;
  r.vertices = b.model->numVertices(), r.elements = b.model->numElements();
  return r;
}

UniaxialResult stretchBetweenGrips(const MaterialSettings& m, LayoutKind layout, int across, Real strain,
                                   Real duration) {
  const Real h = 0.02 / across;
  ShapeSpec shape = presetShape("box", across, 3, h);
  shape.dims = {4 * across, across, across};
  shape.primitives.front().max.x() = 4 * across;
  const Specimen b = specimen(shape, layout, m);
  const RestModel& model = *b.model;
  const Real L = 4 * across * h, a = across * h, tol = 1e-6 * L;
  SimulationSettings s;
  s.gravity.setZero();
  s.damping = 100;
  World w(b.model, s, DomainSettings{}, {});
  // Start from the stretch alone (no lateral strain): the settling finds the lateral strain.
  std::vector<uint32_t> gripped, middle;
  for (size_t i = 0; i < model.numVertices(); ++i) {
    const Vec3& r = model.restPositions[i];
    w.state().positions[i].x() = r.x() * (1 + strain);
    if (r.x() < tol || r.x() > L - tol) gripped.push_back(uint32_t(i));
    if (std::abs(r.x() - L / 2) < tol) middle.push_back(uint32_t(i));
  }
  const size_t steps = size_t(std::ceil(duration / w.dt()));
  for (size_t k = 0; k < steps; ++k) {
    w.step();
    for (uint32_t i : gripped) {  // frictionless grips: x prescribed, y and z free
      w.state().positions[i].x() = model.restPositions[i].x() * (1 + strain);
      w.state().velocities[i].x() = 0;
    }
  }
  std::vector<Vec3> mid;
  for (uint32_t i : middle) mid.push_back(w.state().positions[i]);
  const Vec3 ext = bounds(mid).extent();
  UniaxialResult r;
  r.axial = strain;
  r.lateral = 0.5 * (ext.y() + ext.z()) / a - 1;
  r.volume = enclosedVolume(b.surface, w.state().positions) / b.restVolume;
  r.modulus = 2 * w.metrics().elasticEnergy / (L * a * a * strain * strain);
  r.vertices = model.numVertices(), r.elements = model.numElements();
  return r;
}

BallSqueeze squeezeBall(const MaterialSettings& m, int size, Real squeeze) {
  const Real h = 0.005;
  const Specimen b = specimen(presetShape("sphere", size, 3, h), LayoutKind::Gradational, m);
  const Bounds rest = bounds(b.model->restPositions);
  const Vec3 c = rest.centre(), restExtent = rest.extent();
  BallSqueeze r;
  r.ballRadius = 0.5 * restExtent.x();
  r.toolRadius = 2 * r.ballRadius;
  const Real start = r.ballRadius + r.toolRadius + 0.5 * h, end = r.ballRadius * (1 - squeeze) + r.toolRadius;
  r.toolX = end;
  std::vector<ManipulatorSettings> tools;
  for (Real side : {-1.0, 1.0}) {
    ManipulatorSettings t;
    t.radius = r.toolRadius;
    t.restitution = 0;
    t.friction = 0;
    t.path.keys = {Keyframe{0, c + Vec3(side * start, 0, 0), std::nullopt},
                   Keyframe{0.15, c + Vec3(side * end, 0, 0), std::nullopt}};
    tools.push_back(t);
  }
  SimulationSettings s;
  s.gravity.setZero();
  s.damping = 30;
  World w(b.model, s, DomainSettings{}, tools);
  const size_t steps = size_t(std::ceil(0.5 / w.dt()));
  for (size_t k = 0; k < steps; ++k) w.step();
  r.volume = enclosedVolume(b.surface, w.state().positions) / b.restVolume;
  r.widthY = bounds(w.state().positions).extent().y() / restExtent.y();
  r.restSection = sectionAt(b.surface, b.model->restPositions, c.z() + 0.25 * h, c.x(), c.y());
  r.endSection = sectionAt(b.surface, w.state().positions, c.z() + 0.25 * h, c.x(), c.y());
  return r;
}

}  // namespace gradel
