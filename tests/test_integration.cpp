// integration.h: the per-vertex time step (eqs. 2-3) as pure functions, on scalars and Vec3.
#include <gtest/gtest.h>

#include <cmath>

#include "gradel/integration.h"

using namespace gradel;

namespace {
// One scalar "vector" for the oscillator tests.
using S = Real;
}  // namespace

// Free fall from rest under a constant acceleration g (dt and g powers of two: every product and
// sum below is exact in binary). Symplectic Euler moves with the new velocity:
// v_n = n g dt, x_n = g dt^2 n (n + 1) / 2. Forward Euler with the old one: x_n = g dt^2 n (n - 1) / 2.
TEST(Integration, FreeFallIsExact) {
  const Real dt = 1.0 / 64;
  const Vec3 g(0, -8, 0.5);
  Vec3 xs(1, 2, 3), vs = Vec3::Zero(), xf = xs, vf = vs;
  const Vec3 x0 = xs;
  for (int n = 1; n <= 200; ++n) {
    symplecticEulerStep(xs, vs, g, dt, 1.0);
    forwardEulerStep(xf, vf, g, dt, 1.0);
    EXPECT_EQ(vs, Vec3(n * dt * g));
    EXPECT_EQ(vf, Vec3(n * dt * g));
    EXPECT_EQ(xs, Vec3(x0 + dt * dt * Real(n * (n + 1) / 2) * g)) << n;
    EXPECT_EQ(xf, Vec3(x0 + dt * dt * Real(n * (n - 1) / 2) * g)) << n;
  }
}

// Harmonic oscillator a = -w^2 x. Symplectic Euler keeps the quadratic form
// v^2 + w^2 x^2 - dt w^2 x v exactly (its modified energy): no drift over 1e5 steps, and the true
// energy stays within O(w dt) of its start. Forward Euler multiplies v^2 + w^2 x^2 by
// (1 + (w dt)^2) every step.
TEST(Integration, OscillatorEnergy) {
  const Real w = 2.0, dt = 0.05;  // w dt = 0.1
  auto energy = [&](S x, S v) { return v * v + w * w * x * x; };
  auto modified = [&](S x, S v) { return v * v + w * w * x * x - dt * w * w * x * v; };
  S x = 1, v = 0;
  const Real q0 = modified(x, v), e0 = energy(x, v);
  Real maxSwing = 0;
  for (int n = 0; n < 100000; ++n) {
    const S a = -w * w * x;
    symplecticEulerStep(x, v, a, dt, 1.0);
    maxSwing = std::max(maxSwing, std::abs(energy(x, v) / e0 - 1));
  }
  EXPECT_NEAR(modified(x, v) / q0, 1.0, 1e-10);
  EXPECT_LT(maxSwing, w * dt);
  EXPECT_GT(maxSwing, 0.01);  // it does swing: the stored velocity is half a step off

  x = 1, v = 0;
  for (int n = 1; n <= 100; ++n) {
    const Real before = energy(x, v);
    const S a = -w * w * x;
    forwardEulerStep(x, v, a, dt, 1.0);
    EXPECT_NEAR(energy(x, v) / before, 1 + w * w * dt * dt, 1e-13);
  }
  EXPECT_GT(energy(x, v) / e0, 2.7);  // (1.01)^100
}

// Damping scales the velocity by 1 / (1 + c dt) after the kick: never adds energy, and without
// forces a velocity decays geometrically in both schemes.
TEST(Integration, DampingOnlyRemovesEnergy) {
  EXPECT_EQ(dampingFactor(0, 0.1), 1.0);
  EXPECT_DOUBLE_EQ(dampingFactor(4, 0.25), 0.5);
  const Real dt = 0.01, damp = dampingFactor(3, dt);
  EXPECT_LT(damp, 1.0);
  S x = 0, v = 1, xf = 0, vf = 1;
  for (int n = 1; n <= 50; ++n) {
    symplecticEulerStep(x, v, S(0), dt, damp);
    forwardEulerStep(xf, vf, S(0), dt, damp);
    EXPECT_DOUBLE_EQ(v, std::pow(damp, n));
    EXPECT_DOUBLE_EQ(vf, v);
  }
  // Damped oscillator: c = 3 /s over 20 s takes the energy from 25 to ~e^-60 of it.
  const Real w = 5;
  x = 1, v = 0;
  for (int n = 0; n < 2000; ++n) symplecticEulerStep(x, v, S(-w * w * x), dt, damp);
  EXPECT_LT(v * v + w * w * x * x, 1e-20);
}
