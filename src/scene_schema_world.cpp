// The scene file's world sections (scene_schema.h): `simulation`, `domain`, `body_contact`,
// `pins` and `manipulators` (with their keyframe paths).
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "gradel/settings_check.h"
#include "scene_schema.h"

namespace gradel::scene_json {

void readSimulation(Fields f, Scene& scene) {
  SimulationSettings& s = scene.simulation;
  s.integrator = f.enumeration("integrator", s.integrator, &parseIntegratorKind);
  if (const json* dt = f.take("dt")) {
    if (dt->is_string()) {
      if (dt->get<std::string>() != "auto")
        f.fail("dt", "unknown value " + shown(dt->dump()) + " (expected \"auto\" or a number > 0 [s])");
      s.dt = 0;  // auto: dt_fraction of the smallest period, see dt_period (integrator.h)
    } else if (!dt->is_number()) {
      f.failWrongType("dt", *dt, "\"auto\" or a number > 0 [s]");
    } else {
      s.dt = dt->get<Real>();
      if (!std::isfinite(s.dt)) f.fail("dt", "not a finite number (expected \"auto\" or a number > 0 [s])");
      if (!(s.dt > 0)) f.fail("dt", dt->dump() + " is out of range (expected \"auto\" or a number > 0 [s])");
    }
  }
  s.dtPeriod = f.enumeration("dt_period", s.dtPeriod, &parsePeriodRule);
  // Without dt_fraction the rule's own default applies (0; integrator.h): "element" is the
  // paper's 0.1. The range is where symplectic Euler is stable with a margin (docs/scenes.md):
  // omega_max dt < 2, i.e. 1/pi = 0.318 of the operator's period; measured, the vertex rule holds
  // at 0.3 and diverges at 0.33, the element rule holds at 0.12 and diverges at 0.15.
  s.dtFraction = f.number("dt_fraction", s.dtFraction, Bound{0, maxDtFraction(s.dtPeriod), true, false}, "");
  s.damping = f.number("damping", s.damping, kNonNegative, "1/s");
  s.gravity = f.vec("gravity", s.gravity, "m/s^2");  // World projects it into a 2D body's plane
  scene.output.duration = f.number("duration", scene.output.duration, kPositive, "s");
  scene.output.frameInterval = f.number("frame_interval", scene.output.frameInterval, kPositive, "s");
  s.threads = f.optInteger("threads", 1, 1024).value_or(s.threads);
  s.implicitIterations = f.optInteger("implicit_iterations", 1, 1000).value_or(s.implicitIterations);
  s.largeStepPasses = f.optInteger("large_step_passes", 1, 1000).value_or(s.largeStepPasses);
  s.largeStepSubsteps = f.optInteger("large_step_substeps", 1, 64).value_or(s.largeStepSubsteps);
  s.largeStepCoarseNodes = f.optInteger("large_step_coarse_nodes", 0, 512).value_or(s.largeStepCoarseNodes);
  coreCheck(f, [&] { validate(s); });
  f.finish();
}

void readDomain(Fields f, Scene& scene) {
  DomainSettings& d = scene.domain;
  d.enabled = true;  // a "domain" object means walls
  d.min = f.vec("min", d.min, "m");
  d.max = f.vec("max", d.max, "m");  // 2D: z is unused (its range set by normalizeFor2D, plane.h)
  checkMaxAboveMin(f, d.min, d.max);
  d.restitution = f.number("restitution", d.restitution, kUnit, "");
  d.friction = f.number("friction", d.friction, kNonNegative, "");
  coreCheck(f, [&] { validate(d, scene.dim); });
  f.finish();
}

void readBodyContact(Fields f, Scene& scene) {
  BodyContactSettings& c = scene.bodyContact;
  c.restitution = f.number("restitution", c.restitution, kUnit, "");
  c.friction = f.number("friction", c.friction, kNonNegative, "");
  c.selfContact = f.optBool("self_contact", c.selfContact);
  if (scene.dim != 3) f.fail("self_contact", "contact between bodies needs 3D bodies");
  coreCheck(f, [&] { validate(c); });
  f.finish();
}

namespace {

Keyframe readKeyframe(Fields& f) {
  Keyframe k;
  k.time = f.requireNumber("t", kNonNegative, "s");
  k.position = f.requireVec("position", kAny, "m");
  k.velocity = f.optVec("velocity", kAny, "m/s");
  f.finish();
  return k;
}

// A path of keyframes with strictly increasing times.
Path readPath(Fields& f) {
  Path path;
  std::vector<Fields> keys = f.objectArray("path", false);
  for (size_t i = 0; i < keys.size(); ++i) {
    Keyframe k = readKeyframe(keys[i]);
    if (i > 0 && !(k.time > path.keys.back().time))
      keys[i].fail("t", numberText(k.time) + " is not after the previous key's t = " +
                            numberText(path.keys.back().time) + " (expected strictly increasing times [s])");
    path.keys.push_back(k);
  }
  return path;
}

}  // namespace

// A pinned box or voxel mask of one body (`body`, default 0); its path's positions are offsets
// from rest (pins.h). A mask lives on its body's lattice: mask voxel (i, j, k) is body voxel
// offset + (i, j, k).
PinSettings readPin(Fields& f, const Scene& scene) {
  const int dim = scene.dim;
  PinSettings p;
  p.body = uint32_t(f.optInteger("body", 0, int(scene.numBodies()) - 1).value_or(0));
  const BodySettings& body = scene.bodies[p.body];
  if (auto mf = f.optObject("mask")) {
    f.forbid("min", "a pin takes a box (\"min\", \"max\") or a \"mask\", not both");
    f.forbid("max", "a pin takes a box (\"min\", \"max\") or a \"mask\", not both");
    auto mask = std::make_shared<PinMask>();
    mask->voxelSize = body.shape.voxelSize;
    Vec3 offset = Vec3::Zero();
    if (mf->take("offset")) {
      const std::array<int, 3> o = mf->requireIntVec("offset", -kMaxGridEdge, kMaxGridEdge);
      offset = Vec3(o[0], o[1], dim == 3 ? o[2] : 0);
    }
    mask->origin = body.position + offset * mask->voxelSize;  // 2D: z = 0, as read
    for (Fields& bf : mf->objectArray("boxes", false)) {
      const std::array<int, 3> lo = bf.requireIntVec("min", 0, kMaxGridEdge),
                               hi = bf.requireIntVec("max", 0, kMaxGridEdge);
      for (int a = 0; a < dim; ++a)
        if (hi[a] < lo[a])
          bf.fail("max", "is below \"min\" on axis " + std::to_string(a) +
                             " (expected max >= min; both inclusive voxel indices)");
      bf.finish();
      mask->boxes.push_back({Int3(lo[0], lo[1], dim == 3 ? lo[2] : 0), Int3(hi[0], hi[1], dim == 3 ? hi[2] : 0)});
    }
    if (mf->take("file")) {
      mask->source = readSource(*mf, dim, mask->voxelSize);  // also finishes mf; read by buildScene
    } else {
      if (mask->boxes.empty()) mf->fail("file", "missing (expected a volume file, or \"boxes\": voxel index boxes)");
      mf->finish();
    }
    p.mask = mask;
  } else {
    p.min = f.requireVec("min", kAny, "m");
    p.max = f.requireVec("max", kAny, "m");  // 2D: z is unused (normalizeFor2D, plane.h)
    checkMaxAboveMin(f, p.min, p.max);
  }
  p.path = readPath(f);
  f.finish();
  return p;
}

namespace {

// A blade's "axes" (two perpendicular directions, each "x", "y", "z" or [x, y, z]) and
// "half_extents" (two lengths [m] > 0): its rectangle (contacts.h).
void readBlade(Fields& f, ManipulatorSettings& m) {
  const std::string axesText = "two perpendicular directions, each \"x\", \"y\", \"z\" or [x, y, z]";
  const json& axes = f.require("axes", axesText);
  if (!axes.is_array() || axes.size() != 2) f.failWrongType("axes", axes, axesText);
  Vec3 a[2];
  for (size_t i = 0; i < 2; ++i) {
    const json& v = axes[i];
    const std::string path = f.keyPath("axes") + "[" + std::to_string(i) + "]";
    const std::string expected = "\"x\", \"y\", \"z\" or 3 finite numbers, not all zero";
    if (v.is_string() && (v == "x" || v == "y" || v == "z")) {
      a[i] = Vec3::Unit(v == "x" ? 0 : v == "y" ? 1 : 2);
      continue;
    }
    bool ok = v.is_array() && v.size() == 3;
    for (size_t k = 0; ok && k < 3; ++k) ok = v[k].is_number() && std::isfinite(v[k].get<double>());
    if (ok) a[i] = Vec3(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
    if (!ok || !(a[i].norm() > 0)) failAt(f.context(), path, "got " + describeValue(v) + " (expected " + expected + ")");
  }
  if (std::abs(a[0].normalized().dot(a[1].normalized())) > 1e-6)
    f.fail("axes", "the two directions are not perpendicular (the blade is a rectangle)");
  const std::string extentsText = "two lengths > 0 [m]: the half extents along the two axes";
  const json& e = f.require("half_extents", extentsText);
  if (!e.is_array() || e.size() != 2) f.failWrongType("half_extents", e, extentsText);
  Real h[2];
  for (size_t i = 0; i < 2; ++i) {
    if (!e[i].is_number() || !(e[i].get<double>() > 0) || !std::isfinite(e[i].get<double>()))
      failAt(f.context(), f.keyPath("half_extents") + "[" + std::to_string(i) + "]",
             "got " + describeValue(e[i]) + " (expected a length > 0 [m])");
    h[i] = e[i].get<double>();
  }
  m.axis = a[0], m.widthAxis = a[1], m.halfLength = h[0], m.halfWidth = h[1];
  f.forbid("radius", "a blade is a rectangle (\"axes\", \"half_extents\"), it has no radius");
  f.forbid("half_length", "a blade's sizes are \"half_extents\"");
  f.forbid("axis", "a blade's directions are \"axes\"");
  if (const json* c = f.take("carve"))
    if (!(c->is_boolean() && c->get<bool>())) f.fail("carve", "a blade always cuts (leave \"carve\" out or set it true)");
  m.carve = true;
}

// "carve_labels": the regions a carving tool removes (ContactSettings::carveLabels), sorted.
void readCarveLabels(Fields& f, ManipulatorSettings& m) {
  const json* c = f.take("carve_labels");
  if (!c) return;
  const char* expected = "a list of region labels, integers 1 .. 65535";
  if (!c->is_array() || c->empty()) f.failWrongType("carve_labels", *c, expected);
  for (size_t i = 0; i < c->size(); ++i) {
    const json& v = (*c)[i];
    if (!v.is_number_integer() || v.get<long long>() < 1 || v.get<long long>() > 65535)
      failAt(f.context(), f.keyPath("carve_labels") + "[" + std::to_string(i) + "]",
             "got " + describeValue(v) + " (expected a region label, an integer 1 .. 65535)");
    m.carveLabels.push_back(uint16_t(v.get<long long>()));
  }
  std::sort(m.carveLabels.begin(), m.carveLabels.end());  // a label twice, or no "carve": validate's
}

}  // namespace

ManipulatorSettings readManipulator(Fields& f, int dim) {
  ManipulatorSettings m;
  f.require("type", dim == 3 ? "\"sphere\", \"cylinder\" or \"blade\"" : "\"circle\" or \"sphere\"");
  m.shape = f.enumeration("type", m.shape, &parseManipulatorShape);
  if (m.shape == ManipulatorShape::Blade) {
    if (dim == 2) f.fail("type", "\"blade\" is 3D only (a 2D blade, a segment, is not done)");
    readBlade(f, m);
    f.forbid("restitution", "a blade cuts and never touches the body (no contact)");
    f.forbid("friction", "a blade cuts and never touches the body (no contact)");
    readCarveLabels(f, m);
    m.path = readPath(f);
    coreCheck(f, [&] { validate(m); });
    f.finish();
    return m;
  }
  if (m.shape == ManipulatorShape::Cylinder && dim == 2)
    f.fail("type", "\"cylinder\" is 3D only (expected \"circle\" in a 2D scene)");
  if (m.shape == ManipulatorShape::Circle && dim == 3)
    f.fail("type", "\"circle\" is 2D only (expected \"sphere\" or \"cylinder\" in a 3D scene)");
  m.radius = f.number("radius", m.radius, kPositive, "m");
  if (m.shape == ManipulatorShape::Cylinder) {
    m.halfLength = f.number("half_length", m.halfLength, kPositive, "m");
    // "x", "y", "z" as a union primitive's axis, or a direction vector.
    const json* a = f.take("axis");
    if (a && a->is_string()) {
      const int k = f.choice("axis", {"x", "y", "z"}, 2);
      m.axis = Vec3::Unit(k);
    } else if (const auto axis = f.optVec("axis", kAny, "")) {
      if (!(axis->norm() > 0)) f.fail("axis", "is the zero vector (expected a non-zero direction)");
      m.axis = *axis;
    }
  } else {
    f.forbid("half_length", "only a cylinder manipulator takes \"half_length\"");
    f.forbid("axis", "only a cylinder manipulator takes \"axis\"");
  }
  f.forbid("axes", "only a blade takes \"axes\"");
  f.forbid("half_extents", "only a blade takes \"half_extents\"");
  m.restitution = f.number("restitution", m.restitution, kUnit, "");
  m.friction = f.number("friction", m.friction, kNonNegative, "");
  m.path = readPath(f);
  m.carve = f.optBool("carve", false);
  if (m.carve && m.shape == ManipulatorShape::Circle)
    f.fail("carve", "only a sphere or a cylinder manipulator carves (a 2D scene: \"sphere\")");
  readCarveLabels(f, m);
  coreCheck(f, [&] { validate(m); });
  f.finish();
  return m;
}

}  // namespace gradel::scene_json
