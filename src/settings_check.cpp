#include "gradel/settings_check.h"

#include <cmath>
#include <sstream>
#include <string>

namespace gradel {

namespace {
std::string num(Real x) {
  std::ostringstream o;
  o << x;
  return o.str();
}
[[noreturn]] void fail(const char* field, const std::string& what, Real got) {
  throw InputError("", field, what + " (got " + num(got) + ")");
}
void unit(const char* field, Real x) {
  if (!(x >= 0 && x <= 1)) fail(field, "must be in [0, 1]", x);
}
void nonNegative(const char* field, Real x) {
  if (!(x >= 0) || !std::isfinite(x)) fail(field, "must be a finite number >= 0", x);
}
void positive(const char* field, Real x) {
  if (!(x > 0) || !std::isfinite(x)) fail(field, "must be a finite number > 0", x);
}
// Poisson's ratio (material.h): 0.5 is incompressible, which the volumetric term cannot represent.
void poisson(const char* field, Real x) {
  if (!(x >= 0 && x < 0.5)) fail(field, "must be in [0, 0.5) (0.5, incompressible, is refused)", x);
}
}  // namespace

void validate(const SimulationSettings& s) {
  if (!(s.dt >= 0) || !std::isfinite(s.dt)) fail("dt", "must be 0 (auto) or a finite number of seconds > 0", s.dt);
  if (!(s.dtFraction >= 0 && s.dtFraction <= 1))
    fail("dt_fraction", "must be in [0, 1] (0: the dt_period rule's default)", s.dtFraction);
  nonNegative("damping", s.damping);
  if (!s.gravity.allFinite()) throw InputError("", "gravity", "must be finite");
  if (s.threads < 1 || s.threads > kMaxThreads)
    fail("threads", "must be an integer in [1, " + std::to_string(kMaxThreads) + "]", s.threads);
  if (s.rotationIterations < 1) fail("rotation_iterations", "must be >= 1", s.rotationIterations);
  if (s.implicitIterations < 1) fail("implicit_iterations", "must be >= 1", s.implicitIterations);
  if (s.largeStepPasses < 1) fail("large_step_passes", "must be >= 1", s.largeStepPasses);
  if (s.largeStepCoarseNodes < 0 || s.largeStepCoarseNodes > 512)
    fail("large_step_coarse_nodes", "must be in [0, 512]", s.largeStepCoarseNodes);
  if (s.largeStepSubsteps < 1 || s.largeStepSubsteps > 64)
    fail("large_step_substeps", "must be in [1, 64]", s.largeStepSubsteps);
  // Forward Euler multiplies a vibration's energy by (1 + (omega dt)^2) / (1 + damping dt) every
  // step: without damping no dt is stable, so "auto" has nothing to pick (World, docs/scenes.md).
  if (s.integrator == IntegratorKind::ForwardEuler && s.dt == 0 && !(s.damping > 0))
    throw InputError(
        "", "integrator",
        "forward_euler is unstable at every dt without damping (each step multiplies a "
        "vibration's energy by 1 + (omega dt)^2); give damping > 0 (dt auto is then damping / (2 omega^2)), "
        "an explicit dt, or use symplectic");
}

void validate(const ManipulatorSettings& s) {
  if (!s.carveLabels.empty() && !s.carve)
    throw InputError("", "carve_labels", "only a carving tool (\"carve\": true) takes \"carve_labels\"");
  for (size_t i = 0; i < s.carveLabels.size(); ++i) {
    if (s.carveLabels[i] == 0) throw InputError("", "carve_labels", "0 is not a region label (1 .. 65535)");
    if (i > 0 && s.carveLabels[i - 1] == s.carveLabels[i])
      throw InputError("", "carve_labels", "lists label " + std::to_string(s.carveLabels[i]) + " twice");
    if (i > 0 && s.carveLabels[i - 1] > s.carveLabels[i])
      throw InputError("", "carve_labels", "must be in ascending order");
  }
  if (s.shape == ManipulatorShape::Blade) {  // a rectangle: its axes and half extents, no radius
    for (const Vec3* a : {&s.axis, &s.widthAxis})
      if (!(a->norm() > 0) || !a->allFinite()) throw InputError("", "axes", "must be finite non-zero directions");
    if (std::abs(s.axis.normalized().dot(s.widthAxis.normalized())) > 1e-6)
      throw InputError("", "axes", "must be perpendicular (the blade is a rectangle)");
    positive("half_extents", s.halfLength);
    positive("half_extents", s.halfWidth);
    unit("restitution", s.restitution);
    nonNegative("friction", s.friction);
    return;
  }
  positive("radius", s.radius);
  if (s.shape == ManipulatorShape::Cylinder) {
    positive("half_length", s.halfLength);
    if (!(s.axis.norm() > 0) || !s.axis.allFinite())
      throw InputError("", "axis", "must be a finite non-zero direction");
  }
  unit("restitution", s.restitution);
  nonNegative("friction", s.friction);
}

void validate(const DomainSettings& s, int dim) {
  if (!s.enabled) return;
  if (!s.min.allFinite() || !s.max.allFinite()) throw InputError("", "min, max", "must be finite");
  for (int a = 0; a < dim; ++a)
    if (!(s.min[a] < s.max[a]))
      throw InputError("", "max",
                       "must exceed min on every axis (axis " + std::to_string(a) + ": min " + num(s.min[a]) +
                           ", max " + num(s.max[a]) + ")");
  unit("restitution", s.restitution);
  nonNegative("friction", s.friction);
}

void validate(const MaterialSettings& s) {
  positive("youngs_modulus", s.youngsModulus);
  positive("density", s.density);
  positive("k", s.paperK);
  poisson("poisson_ratio", s.poissonRatio);
  for (size_t i = 0; i < s.regions.size(); ++i) {
    const RegionMaterial& r = s.regions[i];
    const std::string at = "regions[" + std::to_string(i) + "].";
    if (r.label == 0) fail((at + "label").c_str(), "must be in [1, 65535] (0 is empty space)", 0);
    for (size_t j = 0; j < i; ++j)
      if (s.regions[j].label == r.label)
        fail((at + "label").c_str(), "appears twice (also regions[" + std::to_string(j) + "])", r.label);
    positive((at + "youngs_modulus").c_str(), r.youngsModulus);
    positive((at + "density").c_str(), r.density);
    positive((at + "k").c_str(), r.paperK);
    poisson((at + "poisson_ratio").c_str(), r.poissonRatio);
    if (r.damping) nonNegative((at + "damping").c_str(), *r.damping);
  }
  if (s.damping) nonNegative("damping", *s.damping);
}

}  // namespace gradel
