// Small builders shared by the tests (the CLI and benchmarks use scene.h's buildScene).
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <random>

#include "gradel/bodies.h"
#include "gradel/body_contacts.h"
#include "gradel/layout.h"
#include "gradel/model.h"
#include "gradel/scene.h"
#include "gradel/shapes.h"
#include "gradel/world.h"

namespace gradel::test {

struct Body {
  VoxelVolume volume;
  Layout layout;
  std::shared_ptr<const RestModel> model;
};

inline Body makeBody(const std::string& shape, int size, int dim, LayoutKind kind, MaterialSettings material = {},
                     Real voxelSize = 0.01, Vec3 origin = Vec3::Zero()) {
  Body b;
  b.volume = rasterize(presetShape(shape, size, dim, voxelSize));
  b.layout = buildLayout(b.volume, kind);
  b.model = std::make_shared<RestModel>(buildRestModel(b.layout, b.volume, material, origin));
  return b;
}

/// Boundary vertices of any body of `w` inside any other body: inside the other's closed contact
/// surface by its winding number and more than 1e-12 m from it (soft-soft contact tests).
inline size_t verticesInsideOtherBodies(const World& w) {
  const auto& bodies = w.bodyContacts()->bodies();
  const Vec3* x = w.state().positions.data();
  size_t n = 0;
  for (size_t a = 0; a < bodies.size(); ++a)
    for (size_t b = 0; b < bodies.size(); ++b) {
      if (a == b) continue;
      Vec3 lo = Vec3::Constant(1e300), hi = -lo;
      for (uint32_t u : bodies[b].vertices) lo = lo.cwiseMin(x[u]), hi = hi.cwiseMax(x[u]);
      for (uint32_t u : bodies[a].vertices) {
        if ((x[u].array() < lo.array()).any() || (x[u].array() > hi.array()).any()) continue;
        if (windingNumber(x[u], bodies[b].triangles, x) <= 0.5) continue;
        Real d = std::numeric_limits<Real>::infinity();
        for (const auto& t : bodies[b].triangles) {
          const ClosestPoint cp = closestPointOnTriangle(x[u], x[t[0]], x[t[1]], x[t[2]]);
          d = std::min(d, (x[u] - (cp.w[0] * x[t[0]] + cp.w[1] * x[t[1]] + cp.w[2] * x[t[2]])).norm());
        }
        if (d > 1e-12) ++n;
      }
    }
  return n;
}

// The InputError message of parsing scene `text` as file `file`, or "" if it parsed.
inline std::string sceneErrorOf(const std::string& text, const char* file) {
  try {
    parseScene(text, file);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

/// Settings with no gravity and no damping: an isolated body.
inline SimulationSettings isolated() {
  SimulationSettings s;
  s.gravity = Vec3::Zero();
  s.damping = 0;
  return s;
}

/// Settings of a frame-size step with `kind` (an implicit integrator): dt = 1/60 s unless given,
/// no damping, gravity on.
inline SimulationSettings frameStep(IntegratorKind kind, Real dt = 1.0 / 60.0) {
  SimulationSettings s;
  s.integrator = kind;
  s.dt = dt;
  s.damping = 0;
  return s;
}

/// Perturbs positions and velocities with a seeded RNG (a deformed, moving, spinning body).
inline void perturb(World& w, Real posAmp, Real velAmp, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<Real> u(-1, 1);
  const int dim = w.model().dim;
  for (size_t i = 0; i < w.state().positions.size(); ++i)
    for (int a = 0; a < dim; ++a) {
      w.state().positions[i][a] += posAmp * u(rng);
      w.state().velocities[i][a] += velAmp * u(rng);
    }
}

/// Applies a smooth deformation x <- c + (I + eps)(x - c) about the body's centre: a stretch
/// and a shear of `strain`, exciting mostly the body's low modes (as a real load would).
inline void deformSmoothly(World& w, Real strain) {
  Vec3 c = Vec3::Zero();
  for (const Vec3& x : w.state().positions) c += x;
  c /= Real(w.state().positions.size());
  Mat3 eps = Mat3::Zero();
  eps(0, 0) = strain, eps(1, 1) = -0.5 * strain, eps(0, 1) = 0.5 * strain;
  if (w.model().dim == 3) eps(2, 2) = 0.5 * strain, eps(1, 2) = 0.5 * strain;
  for (Vec3& x : w.state().positions) x = c + (Mat3::Identity() + eps) * (x - c);
}

/// A world whose steps split across threads and touch everything: the body (>= 2048 vertices)
/// perturbed, damped, between walls, with a sphere (of the given friction) sweeping through it.
inline World sweptWorld(const Body& b, int threads, Real friction = 0) {
  SimulationSettings s;
  s.threads = threads;
  s.damping = 1.0;
  DomainSettings d;
  d.enabled = true;
  d.min = Vec3(-0.1, 0.0, -0.1), d.max = Vec3(0.4, 0.4, 0.4);
  ManipulatorSettings mp;
  mp.radius = 0.05;
  mp.friction = friction;
  mp.path.keys = {{0.0, Vec3(-0.05, 0.14, 0.14), std::nullopt}, {0.05, Vec3(0.1, 0.14, 0.14), std::nullopt}};
  World w(b.model, s, d, {mp});
  perturb(w, 0.1 * b.model->voxelSize, 0.05, 21);
  return w;
}

/// Kinetic + elastic + gravity + symplectic Euler's modified-energy term (Metrics::totalEnergy):
/// flat on undamped, contact-free runs at any stable dt.
inline Real totalEnergy(const World& w) { return w.metrics().totalEnergy(); }

}  // namespace gradel::test

namespace gradel::test {

inline Vec3 centreOfMass(const World& w) {
  Vec3 c = Vec3::Zero();
  for (size_t i = 0; i < w.model().numVertices(); ++i) c += w.model().mass[i] * w.state().positions[i];
  return c / w.model().totalMass;
}

// Bodies side by side in one world (combineRestModels), each body's vertices at its velocity,
// with soft-soft contact between them.
inline std::unique_ptr<World> worldOfBodies(const std::vector<Body>& parts, const std::vector<Vec3>& velocities,
                                            const SimulationSettings& sim, const BodyContactSettings& contact,
                                            const DomainSettings& domain = {}) {
  std::vector<std::shared_ptr<const RestModel>> models;
  std::vector<const Layout*> layouts;
  std::vector<const VoxelVolume*> volumes;
  for (const Body& b : parts) models.push_back(b.model), layouts.push_back(&b.layout), volumes.push_back(&b.volume);
  auto m = std::make_shared<RestModel>(combineRestModels(models));
  auto world = std::make_unique<World>(m, sim, domain, std::vector<ManipulatorSettings>{});
  for (size_t i = 0; i < parts.size(); ++i)
    for (uint32_t u = m->bodies[i].vertexBegin; u < m->bodies[i].vertexEnd; ++u) world->state().velocities[u] = velocities[i];
  world->setBodyContacts(buildContactBodies(*m, layouts, volumes), contact);
  return world;
}

// Linear momentum of every vertex, and its scale (sum of |m v|) for relative tolerances.
inline Vec3 momentum(const World& w) {
  Vec3 p = Vec3::Zero();
  for (size_t u = 0; u < w.model().numVertices(); ++u) p += w.model().mass[u] * w.state().velocities[u];
  return p;
}

inline Real momentumScale(const World& w) {
  Real s = 0;
  for (size_t u = 0; u < w.model().numVertices(); ++u) s += w.model().mass[u] * w.state().velocities[u].norm();
  return s;
}

inline Vec3 centreOfMassVelocity(const World& w) {
  Vec3 c = Vec3::Zero();
  for (size_t i = 0; i < w.model().numVertices(); ++i) c += w.model().mass[i] * w.state().velocities[i];
  return c / w.model().totalMass;
}

inline Vec3 centroid(const World& w) {
  Vec3 c = Vec3::Zero();
  for (const Vec3& x : w.state().positions) c += x;
  return c / Real(w.state().positions.size());
}

/// A shipped scene with E x eScale, run with `kind` at `dt` for `duration`: every step finite, no
/// vertex inside anything, no energy from nowhere (a 0.9 kg ball moved at manipulator speeds,
/// ~1 m/s, holds well under 2 J), and no inverted element at the end. Returns the world for
/// scene-specific outcome checks.
inline std::unique_ptr<BuiltScene> runStiffScene(const std::string& file, Real duration, IntegratorKind kind,
                                                 Real eScale, Real dt) {
  Scene scene = loadScene(std::string(GRADEL_SOURCE_DIR) + "/scenes/" + file);
  scene.bodies[0].material.youngsModulus *= eScale;
  scene.simulation.integrator = kind;
  scene.simulation.dt = dt;
  auto b = std::make_unique<BuiltScene>(buildScene(scene));
  World& w = *b->world;
  while (w.time() < duration) {
    w.step();
    const Metrics m = w.metrics();
    EXPECT_TRUE(std::isfinite(m.kineticEnergy) && std::isfinite(m.elasticEnergy)) << file << " t=" << w.time();
    EXPECT_LE(m.maxPenetration, 1e-9) << file << " t=" << w.time();
    EXPECT_LT(m.kineticEnergy, 2.0) << file << " t=" << w.time();
    if (::testing::Test::HasFailure()) break;
  }
  EXPECT_GT(w.metrics().minElementDet, 0.3) << file;
  return b;
}

}  // namespace gradel::test
