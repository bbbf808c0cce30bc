// element: forces of the local shape-preserving element (eq. 1) and their invariants.
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <numeric>
#include <random>

#include "gradel/element.h"
#include "gradel/rotation_fit.h"

using namespace gradel;

namespace {
struct Element {
  std::vector<Vec3> rest;  // rest positions
  std::vector<Vec3> R0;    // offsets from rest centroid
  std::vector<uint32_t> ids;
};
Element makeElement(const std::vector<Vec3>& rest) {
  Element e;
  e.rest = rest;
  Vec3 c = Vec3::Zero();
  for (const Vec3& p : rest) c += p;
  c /= double(rest.size());
  for (size_t i = 0; i < rest.size(); ++i) e.R0.push_back(rest[i] - c), e.ids.push_back(uint32_t(i));
  return e;
}
// A cube element's corners plus `extra` hanging points on its faces (fig. 5).
std::vector<Vec3> cubeWithHanging(double s, int extra, std::mt19937& rng) {
  std::vector<Vec3> p;
  for (int k = 0; k < 8; ++k) p.emplace_back(s * (k & 1), s * ((k >> 1) & 1), s * ((k >> 2) & 1));
  std::uniform_int_distribution<int> face(0, 5), coord(0, 2);
  for (int i = 0; i < extra; ++i) {
    Vec3 q(coord(rng) * s / 2, coord(rng) * s / 2, coord(rng) * s / 2);
    const int f = face(rng);
    q[f / 2] = (f % 2) * s;
    p.push_back(q);
  }
  return p;
}
Quat randomRotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  Quat q(n(rng), n(rng), n(rng), n(rng));
  return q.normalized();
}
}  // namespace

RC_GTEST_PROP(Element, ZeroForceUnderRigidMotion, ()) {
  std::mt19937 rng(*rc::gen::inRange(0, 1 << 30));
  const double s = 0.01 * (1 << *rc::gen::inRange(0, 4));
  Element e = makeElement(cubeWithHanging(s, *rc::gen::inRange(0, 10), rng));
  const Quat q = randomRotation(rng);
  const Vec3 t = Vec3::Random();
  std::vector<Vec3> x;
  for (const Vec3& p : e.rest) x.push_back(q * p + t);
  std::vector<Vec3> f(x.size());
  Quat rot = q * Quat(Eigen::AngleAxisd(0.2, Vec3::UnitX()));  // warm start 0.2 rad off
  const double k = 1e4;
  const ElementResult r = elementForces(3, x.data(), e.ids.data(), e.R0.data(), int(x.size()), k, rot, f.data(), 20);
  for (const Vec3& fi : f) RC_ASSERT(fi.norm() < 1e-9 * k * s);
  RC_ASSERT(r.energy < 1e-18 * k * s * s + 1e-30);
}

RC_GTEST_PROP(Element, ForcesHaveNoNetForceOrTorque, ()) {
  std::mt19937 rng(*rc::gen::inRange(0, 1 << 30));
  Element e = makeElement(cubeWithHanging(0.02, *rc::gen::inRange(0, 8), rng));
  std::normal_distribution<double> n(0, 0.006);  // large deformation, possibly inverting
  std::vector<Vec3> x;
  const Quat q = randomRotation(rng);
  for (const Vec3& p : e.rest) x.push_back(q * p + Vec3(n(rng), n(rng), n(rng)));
  std::vector<Vec3> f(x.size());
  Quat rot = q;
  elementForces(3, x.data(), e.ids.data(), e.R0.data(), int(x.size()), 1e4, rot, f.data(), 50);
  Vec3 F = Vec3::Zero(), T = Vec3::Zero();
  double scale = 0;
  for (size_t i = 0; i < x.size(); ++i) F += f[i], T += x[i].cross(f[i]), scale += f[i].norm();
  RC_ASSERT(F.norm() <= 1e-10 * scale + 1e-15);
  RC_ASSERT(T.norm() <= 1e-8 * scale * 0.02 + 1e-15);
  RC_ASSERT(std::abs(rot.norm() - 1) < 1e-12);
}

TEST(Element, ForceIsMinusEnergyGradient) {
  std::mt19937 rng(7);
  Element e = makeElement(cubeWithHanging(1.0, 3, rng));
  std::normal_distribution<double> n(0, 0.15);
  std::vector<Vec3> x;
  for (const Vec3& p : e.rest) x.push_back(p + Vec3(n(rng), n(rng), n(rng)));
  const double k = 3.0;
  std::vector<Vec3> f(x.size()), tmp(x.size());
  Quat rot = Quat::Identity();
  elementForces(3, x.data(), e.ids.data(), e.R0.data(), int(x.size()), k, rot, f.data(), 50);
  const double h = 1e-6;
  for (size_t i = 0; i < x.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      auto energyAt = [&](double d) {
        std::vector<Vec3> y = x;
        y[i][a] += d;
        Quat r = rot;
        return elementForces(3, y.data(), e.ids.data(), e.R0.data(), int(y.size()), k, r, tmp.data(), 50).energy;
      };
      const double grad = (energyAt(h) - energyAt(-h)) / (2 * h);
      EXPECT_NEAR(-grad, f[i][a], 1e-6) << "vertex " << i << " axis " << a;
    }
}

TEST(Element, StretchGivesRestoringForce) {
  // A unit square (2D) stretched along x by 10%: the right side is pulled back, the left pushed.
  Element e = makeElement({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)});
  std::vector<Vec3> x = e.rest;
  for (Vec3& p : x) p.x() *= 1.1;
  std::vector<Vec3> f(4);
  Quat rot = Quat::Identity();
  const ElementResult r = elementForces(2, x.data(), e.ids.data(), e.R0.data(), 4, 10.0, rot, f.data());
  EXPECT_NEAR(f[1].x(), -10.0 * 0.05, 1e-12);
  EXPECT_NEAR(f[0].x(), 10.0 * 0.05, 1e-12);
  EXPECT_NEAR(r.energy, 0.5 * 10.0 * 4 * 0.05 * 0.05, 1e-12);
  for (const Vec3& fi : f) EXPECT_EQ(fi.z(), 0.0);
}

TEST(Element, TwoDimensionalRigidRotationIsForceFree) {
  Element e = makeElement({Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), Vec3(2, 2, 0), Vec3(1, 0, 0)});
  for (double th : {0.3, 1.7, 3.1, -2.5}) {
    const Mat3 R = Eigen::AngleAxisd(th, Vec3::UnitZ()).toRotationMatrix();
    std::vector<Vec3> x;
    for (const Vec3& p : e.rest) x.push_back(R * p + Vec3(5, -3, 0));
    std::vector<Vec3> f(x.size());
    Quat rot = Quat::Identity();
    elementForces(2, x.data(), e.ids.data(), e.R0.data(), int(x.size()), 100.0, rot, f.data());
    for (const Vec3& fi : f) EXPECT_LT(fi.norm(), 1e-11);
  }
}

TEST(Element, DeterminantSignsInversion) {
  std::mt19937 rng(1);
  Element e = makeElement(cubeWithHanging(1.0, 0, rng));
  std::vector<Vec3> x = e.rest;
  EXPECT_NEAR(elementDeterminant(3, x.data(), e.ids.data(), e.R0.data(), 8), 1.0, 1e-12);
  for (Vec3& p : x) p.z() = -p.z();  // mirror: inverted
  EXPECT_NEAR(elementDeterminant(3, x.data(), e.ids.data(), e.R0.data(), 8), -1.0, 1e-12);
  for (Vec3& p : x) p *= 2;
  EXPECT_NEAR(elementDeterminant(3, x.data(), e.ids.data(), e.R0.data(), 8), -8.0, 1e-12);
}
