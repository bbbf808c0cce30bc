// stability_warm.h: the operator rule's estimate after carving, warm started.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "gradel/carve_scene.h"
#include "gradel/stability.h"
#include "gradel/stability_warm.h"
#include "test_support.h"

using namespace gradel;
using namespace gradel::test;

TEST(StabilityWarm, askingForTheRitzVectorLeavesTheEstimateBitForBit) {
  const Body b = makeBody("sphere", 12, 3, LayoutKind::Gradational);
  std::vector<Vec3> ritz;
  const FrequencyEstimate a = highestFrequency(*b.model), c = highestFrequency(*b.model, 48, &ritz);
  EXPECT_EQ(a.omega, c.omega);
  EXPECT_EQ(a.ritz, c.ritz);
  ASSERT_EQ(ritz.size(), b.model->numVertices());
  double n = 0;
  for (const Vec3& v : ritz) n += v.squaredNorm();
  EXPECT_NEAR(n, 1.0, 1e-4);  // unit length to single precision
  // Started from its own Ritz vector, a few products find the same fastest mode.
  const FrequencyEstimate w = highestFrequencyFrom(*b.model, ritz, 8);
  EXPECT_NEAR(w.ritz / a.ritz, 1.0, 1e-3);
  EXPECT_GE(w.omega, a.ritz);
}

// Burrs at the top face, an edge and a corner of a box (the new fastest mode at the cut, not
// where the old one was): every warm estimate is at or above the converged fastest mode (Lanczos
// run to 400 products) and within 10 % of the estimate from scratch; the same at 1 and 2 threads.
TEST(StabilityWarm, warmEstimateAfterCarvingIsAtOrAboveTheFastestMode) {
  const int n = 14;
  const Real h = 0.005;
  std::vector<double> omegas[2];
  for (int threads : {1, 2}) {
    Scene scene;
    scene.bodies[0].shape = presetShape("box", n, 3, h);
    scene.simulation.gravity = Vec3::Zero();
    scene.simulation.threads = threads;
    BuiltScene b = buildScene(scene);
    const Vec3 centres[] = {{h * n / 2, h * n, h * n / 2}, {h * n, h * n, h * n / 2}, {0, h * n, 0},
                            {h * n / 3, h * n, h * n / 2}, {h * n, 0, h * n},          {h * n / 2, h * n * 0.8, 0}};
    int events = 0;
    for (const Vec3& c : centres) {
      const std::vector<uint8_t> mask = voxelsInSphere(carveInput(b, 0), c, 2.5 * h);
      if (carveSceneBody(b, 0, mask).removedVoxels == 0) continue;
      ++events;
      b.world->step();
      const FrequencyEstimate warm = b.world->stabilityEstimate();
      omegas[threads - 1].push_back(warm.omega);
      if (threads == 2) continue;
      const FrequencyEstimate full = highestFrequency(b.world->model()), converged = highestFrequency(b.world->model(), 400);
      SCOPED_TRACE("event " + std::to_string(events));
      EXPECT_GE(warm.omega, converged.ritz * (1 - 1e-9));
      EXPECT_LE(warm.omega, 1.1 * full.omega);
    }
    EXPECT_GE(events, 5);
  }
  EXPECT_EQ(omegas[0], omegas[1]);
}
