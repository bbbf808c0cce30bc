#include "gradel/contacts.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace gradel {

ManipulatorShape parseManipulatorShape(const std::string& name) {
  if (name == "sphere") return ManipulatorShape::Sphere;
  if (name == "cylinder") return ManipulatorShape::Cylinder;
  if (name == "circle") return ManipulatorShape::Circle;
  if (name == "blade") return ManipulatorShape::Blade;
  throw InputError("unknown manipulator type '" + name + "' (expected sphere, cylinder, circle or blade)");
}

const char* manipulatorShapeName(ManipulatorShape s) {
  switch (s) {
    case ManipulatorShape::Sphere: return "sphere";
    case ManipulatorShape::Cylinder: return "cylinder";
    case ManipulatorShape::Circle: return "circle";
    case ManipulatorShape::Blade: return "blade";
  }
  return "?";
}

// ---- paths ------------------------------------------------------------------

namespace {
// Index of the segment [keys[i], keys[i+1]] holding t, or -1 before the first key, or
// keys.size()-1 after the last.
long segmentOf(const std::vector<Keyframe>& keys, Real t) {
  if (t < keys.front().time) return -1;
  auto it = std::upper_bound(keys.begin(), keys.end(), t, [](Real tt, const Keyframe& k) { return tt < k.time; });
  return long(it - keys.begin()) - 1;
}
}  // namespace

Vec3 Path::position(Real t) const {
  if (keys.empty()) return Vec3::Zero();
  const long s = segmentOf(keys, t);
  if (s < 0) return keys.front().position;
  if (size_t(s) + 1 >= keys.size()) {
    const Keyframe& last = keys.back();
    return last.velocity ? Vec3(last.position + (t - last.time) * *last.velocity) : last.position;
  }
  const Keyframe& a = keys[size_t(s)];
  const Keyframe& b = keys[size_t(s) + 1];
  const Real h = b.time - a.time;
  const Real u = (t - a.time) / h;
  if (a.velocity && b.velocity) {
    // Cubic Hermite: matches positions and velocities at both keys.
    const Real u2 = u * u, u3 = u2 * u;
    return (2 * u3 - 3 * u2 + 1) * a.position + (u3 - 2 * u2 + u) * h * *a.velocity + (-2 * u3 + 3 * u2) * b.position +
           (u3 - u2) * h * *b.velocity;
  }
  return (1 - u) * a.position + u * b.position;
}

Vec3 Path::velocity(Real t) const {
  if (keys.empty()) return Vec3::Zero();
  const long s = segmentOf(keys, t);
  if (s < 0) return Vec3::Zero();
  if (size_t(s) + 1 >= keys.size()) {
    const Keyframe& last = keys.back();
    return last.velocity ? *last.velocity : Vec3::Zero();
  }
  const Keyframe& a = keys[size_t(s)];
  const Keyframe& b = keys[size_t(s) + 1];
  const Real h = b.time - a.time;
  const Real u = (t - a.time) / h;
  if (a.velocity && b.velocity) {
    const Real u2 = u * u;
    return ((6 * u2 - 6 * u) * a.position + (3 * u2 - 4 * u + 1) * h * *a.velocity + (-6 * u2 + 6 * u) * b.position +
            (3 * u2 - 2 * u) * h * *b.velocity) /
           h;
  }
  return (b.position - a.position) / h;
}

// ---- manipulator geometry -----------------------------------------------------

namespace {

// Signed distance of the shape centred at the origin, evaluated at d (frame coordinates).
Real shapeDistance(const ManipulatorSettings& settings, const Vec3& d, Vec3* normal) {
  if (settings.shape == ManipulatorShape::Blade) {  // it cuts, it never holds a vertex out
    if (normal) *normal = settings.axis.cross(settings.widthAxis).normalized();
    return std::numeric_limits<Real>::infinity();
  }
  if (settings.shape != ManipulatorShape::Cylinder) {
    const Real r = d.norm();
    if (normal) *normal = r > 0 ? Vec3(d / r) : Vec3::UnitY();
    return r - settings.radius;
  }
  // Capped cylinder: the intersection of an infinite cylinder (radial distance) and a slab
  // (axial distance); exact signed distance of that convex set.
  const Vec3 a = settings.axis.normalized();
  const Real h = a.dot(d);
  const Vec3 radial = d - h * a;
  const Real rr = radial.norm();
  const Vec3 radialDir = rr > 0 ? Vec3(radial / rr) : a.unitOrthogonal();
  const Real dr = rr - settings.radius;               // > 0 outside the side
  const Real dh = std::abs(h) - settings.halfLength;  // > 0 beyond a cap
  const Vec3 capDir = h >= 0 ? a : Vec3(-a);
  if (dr <= 0 && dh <= 0) {  // inside: nearest of side and cap
    if (normal) *normal = dr > dh ? radialDir : capDir;
    return std::max(dr, dh);
  }
  if (dr > 0 && dh > 0) {  // outside, nearest the rim
    const Vec3 g = dr * radialDir + dh * capDir;
    const Real len = g.norm();
    if (normal) *normal = g / len;
    return len;
  }
  if (dr > 0) {
    if (normal) *normal = radialDir;
    return dr;
  }
  if (normal) *normal = capDir;
  return dh;
}

}  // namespace

Real Manipulator::signedDistance(const Vec3& p, Vec3* normal) const {
  return shapeDistance(settings, p - position, normal);
}

namespace {

// Relative signed distance at a point given in the manipulator's frame (centre at origin).
Real frameDistance(const Manipulator& m, const Vec3& pFrame, Vec3* n) { return shapeDistance(m.settings, pFrame, n); }

// The signed distance of a convex set is a convex function, so along a segment it has one
// minimum (golden-section search) and the first entry point lies between the start and that
// minimum (bisection).
// Finds where the segment p0 -> p1 (frame coordinates, d0 = sd(p0) >= 0, d1 = sd(p1)) first
// enters the shape (tEntry) and, if it ends outside, where it leaves it again (tExit = 1 when it
// ends inside). Returns false if it never enters.
bool segmentCrossing(const Manipulator& m, const Vec3& p0, const Vec3& p1, Real d0, Real d1, Real* tEntry,
                     Real* tExit) {
  // The distance is 1-Lipschitz: along a segment of length L it stays >= (d0 + d1 - L) / 2.
  if (d0 + d1 - (p1 - p0).norm() > 0) return false;
  auto f = [&](Real t) { return frameDistance(m, p0 + t * (p1 - p0), nullptr); };
  Real tMin;
  if (d1 < 0) {
    tMin = 1;
  } else {
    Real a = 0, b = 1;
    const Real g = 0.5 * (std::sqrt(5.0) - 1);
    Real c = b - g * (b - a), d = a + g * (b - a);
    Real fc = f(c), fd = f(d);
    for (int i = 0; i < 60 && fc >= 0 && fd >= 0; ++i) {
      if (fc < fd) {
        b = d, d = c, fd = fc, c = b - g * (b - a), fc = f(c);
      } else {
        a = c, c = d, fc = fd, d = a + g * (b - a), fd = f(d);
      }
    }
    if (fc < 0)
      tMin = c;
    else if (fd < 0)
      tMin = d;
    else
      return false;
  }
  Real lo = 0, hi = tMin;  // f(lo) >= 0 > f(hi)
  for (int i = 0; i < 60; ++i) {
    const Real mid = 0.5 * (lo + hi);
    (f(mid) >= 0 ? lo : hi) = mid;
  }
  *tEntry = lo;
  *tExit = 1;
  if (d1 >= 0) {
    Real in = tMin, out = 1;  // f(in) < 0 <= f(out)
    for (int i = 0; i < 60; ++i) {
      const Real mid = 0.5 * (in + out);
      (f(mid) >= 0 ? out : in) = mid;
    }
    *tExit = out;
  }
  return true;
}

// Position-level Coulomb friction. Projecting a vertex back along the normal leaves the
// tangential part of its step relative to the surface, so a vertex whose velocity friction has
// stopped would still creep by dt^2 a_t every step (fast enough to let a grasped body slide out).
// The tangential displacement is undone up to friction * penetration depth (static friction
// cancels it; kinetic friction shortens it). Returns the correction to subtract.
Vec3 frictionSlipCorrection(const Vec3& relativeStep, const Vec3& n, Real depth, Real friction) {
  if (friction <= 0) return Vec3::Zero();
  const Vec3 tangential = relativeStep - relativeStep.dot(n) * n;
  const Real len = tangential.norm();
  const Real allowed = friction * depth;
  return len <= allowed ? tangential : Vec3(tangential * (allowed / len));
}

// The normal speed [m/s] at which a vertex approached the surface, for the bounce (contacts.h,
// rule 1). u1 < 0: its normal velocity at the end of the step; s0: its distance outside at the
// start. Under the constant acceleration a = (u1 - u0) / dt it crossed at sqrt(u0^2 - 2 a s0),
// never faster than it approached (|u0|) or ends (|u1|).
Real crossingSpeed(Real u1, Real s0, const Vec3& surfaceVelocity, const Vec3& n, const StepStart* start) {
  if (!start) return -u1;
  if (!(s0 >= 0)) return 0;  // it started inside: no crossing, nothing to bounce
  const Real u0 = (start->velocity - surfaceVelocity).dot(n);
  const Real a = (u1 - u0) / start->dt;
  const Real c2 = u0 * u0 - 2 * a * s0;
  // A vertex that was moving away at the start of the step and was turned back within it made a
  // flight shorter than a step, which the step cannot resolve: a resting contact, no bounce.
  if (u0 >= 0) return 0;
  return std::min({-u1, -u0, c2 > 0 ? std::sqrt(c2) : Real(0)});
}

// v relative to the surface: the normal part, if approaching, replaced by e times the crossing
// speed (outwards); the tangential part reduced by Coulomb friction. Then the elastic energy the
// position projection stored (per unit mass: the push `lift` [m] along n against the normal
// acceleration that pressed the vertex in) is taken out of what is left of the kinetic energy,
// first from the bounce, then from the sliding.
void reflectVelocity(Vec3& v, const Vec3& surfaceVelocity, const Vec3& n, Real restitution, Real friction, Real s0,
                     const StepStart* start, Real lift) {
  Vec3 rel = v - surfaceVelocity;
  const Real vn = rel.dot(n);
  if (vn < 0) {
    // Symplectic Euler's velocity is half a step behind its positions (the leapfrog v_{n+1/2});
    // the normal velocity at the time of the positions is wn = vn + a dt / 2 (metrics() measures
    // the kinetic energy with it). The bounce acts on wn, so that it never grows: reflecting vn
    // instead, a vertex oscillating near the stable limit (omega dt ~ 0.8) and pulled away from
    // the surface by its element (a > 0) gained (1 + e) m |vn| a dt / 2 per bounce (issue 15: a
    // 7^3 box on a floor, 1.2 J -> 290 J). A vertex already receding at that time (wn >= 0) keeps
    // its velocity: its next step takes it out.
    const Real half =
        start && start->leapfrog ? Real(0.5) * (vn - (start->velocity - surfaceVelocity).dot(n)) : Real(0);  // a dt / 2
    const Real wn = vn + half;
    if (wn >= 0) {
      v = surfaceVelocity + rel;
      return;
    }
    Real out =
        restitution > 0 ? restitution * std::min(crossingSpeed(vn, s0, surfaceVelocity, n, start), -wn) : Real(0);
    Vec3 vt = rel - vn * n;
    const Real vtLen = vt.norm();
    // Coulomb: the tangential impulse is at most friction times the normal impulse |wn| + out.
    const Real drop = friction * (out - wn);
    vt = vtLen > drop ? Vec3(vt * (1 - drop / vtLen)) : Vec3::Zero();
    if (start && lift > 0) {
      const Real an = (vn - (start->velocity - surfaceVelocity).dot(n)) / start->dt;  // < 0: pressed in
      Real stored = std::max(Real(0), -an) * lift;                                    // [J/kg]
      const Real fromBounce = std::min(stored, Real(0.5) * out * out);
      out = std::sqrt(std::max(Real(0), out * out - 2 * fromBounce));
      stored -= fromBounce;
      const Real vt2 = vt.squaredNorm();
      if (stored > 0 && vt2 > 0) vt *= std::sqrt(std::max(Real(0), vt2 - 2 * stored) / vt2);
    }
    rel = vt + (out - half) * n;
  }
  v = surfaceVelocity + rel;
}

}  // namespace

ContactResult resolveManipulator(const Manipulator& m, const Vec3& xPrev, Vec3& x, Vec3& v, bool bounce,
                                 const StepStart* start) {
  ContactResult res;
  const Vec3 p0 = xPrev - m.previousPosition;  // start of the step, in the moving frame
  const Vec3 p1 = x - m.position;              // end of the step, in the moving frame (2D: in the plane)
  Vec3 n1;
  const Real d1 = frameDistance(m, p1, &n1);
  Real tEntry = 0, tExit = 1;
  Vec3 target;  // frame position to put the vertex at
  Vec3 n;
  const Real skin = 1e-9 * m.settings.radius;  // stay just outside so that sd >= 0 holds exactly
  const Real d0 = frameDistance(m, p0, nullptr);
  if (d0 >= 0 && segmentCrossing(m, p0, p1, d0, d1, &tEntry, &tExit)) {
    const Vec3 pe = p0 + tEntry * (p1 - p0);
    Vec3 ne;
    frameDistance(m, pe, &ne);
    if (d1 < 0 && n1.dot(ne) > -1e-9) {  // ordinary contact: nearest surface point
      target = p1 - (d1 - skin) * n1;
      n = n1;
      res.depth = -d1;
      target -= frictionSlipCorrection(p1 - p0, n, res.depth, m.settings.friction);
    } else {
      if (d1 >= 0) {
        // Ends outside. It went right through the manipulator only if it left on the far side
        // (entry and exit normals opposed, more than 120 degrees apart: the chord crossed the
        // middle); a short chord near the surface (a vertex sliding along a curved side) or a
        // clipped corner (a vertex leaving a cylinder's rim: cap and side normals about 90
        // degrees apart) is no contact. Issue 15: the rim case, taken for a pass-through, put the
        // vertex back every step while its velocity grew (0.04 J -> 4 J).
        Vec3 nx;
        frameDistance(m, p0 + tExit * (p1 - p0), &nx);
        if (ne.dot(nx) > -0.5) return res;
      }
      // Passed through, or crossed the middle: back to where it entered.
      target = pe + skin * ne;
      n = ne;
      res.depth = (p1 - pe).norm();
    }
  } else if (d1 < 0) {  // started inside (initial overlap): nearest surface point
    target = p1 - (d1 - skin) * n1;
    n = n1;
    res.depth = -d1;
    target -= frictionSlipCorrection(p1 - p0, n, res.depth, m.settings.friction);
  } else {
    return res;
  }
  x = m.position + target;
  reflectVelocity(v, m.velocity, n, bounce ? m.settings.restitution : 0.0, m.settings.friction, d0, start,
                  (target - p1).dot(n));
  return res;
}

const char* wallName(int wall) {
  static const char* const names[kWalls] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};
  return wall >= 0 && wall < kWalls ? names[wall] : "none";
}

ContactResult resolveDomain(const DomainSettings& d, const Vec3& xPrev, Vec3& x, Vec3& v, int dim, bool bounce,
                            const StepStart* start, Vec3* wallDv) {
  ContactResult res;
  if (!d.enabled) return res;
  for (int a = 0; a < dim; ++a) {
    Real side = 0, depth = 0;
    if (x[a] < d.min[a])
      side = 1, depth = d.min[a] - x[a], x[a] = d.min[a];
    else if (x[a] > d.max[a])
      side = -1, depth = x[a] - d.max[a], x[a] = d.max[a];
    if (side != 0) {
      Vec3 n = Vec3::Zero();
      n[a] = side;
      res.depth = std::max(res.depth, depth);
      const Vec3 slip = frictionSlipCorrection(x - xPrev, n, depth, d.friction);
      for (int b = 0; b < dim; ++b)
        if (b != a) x[b] -= slip[b];
      const Real s0 = side > 0 ? xPrev[a] - d.min[a] : d.max[a] - xPrev[a];  // distance inside at the start
      const Vec3 before = v;
      reflectVelocity(v, Vec3::Zero(), n, bounce ? d.restitution : 0.0, d.friction, s0, start, depth);
      res.wall = 2 * a + (side < 0 ? 1 : 0);
      if (wallDv) wallDv[res.wall] += v - before;
    }
  }
  return res;
}

}  // namespace gradel
