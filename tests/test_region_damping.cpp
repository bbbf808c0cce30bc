// Damping per region (issue 12): `material.regions[i].damping` [1/s] (docs/scenes.md), each
// vertex's rate the mass-weighted mean of its regions' (model.h RestModel::vertexDamping), used
// by every integrator; one rate for all is today's uniform path, bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "gradel/integration.h"
#include "gradel/scene.h"
#include "gradel/shapes.h"
#include "test_support.h"

using namespace gradel;
using namespace gradel::test;

namespace {

constexpr const char* kFile = "x.json";

// Two separate spheres without gravity, moving apart rigidly: body "damped" (its label 1 entry
// gives rate `c` unless empty) and body "free" (the simulation's damping `c0`).
std::string twoBodies(const std::string& integrator, const std::string& dt, const std::string& c, Real c0) {
  const std::string regions = c.empty() ? "" : R"(, "material": {"regions": [{"label": 1, "damping": )" + c + "}]}";
  return R"({ "bodies": [
      { "name": "damped", "shape": "sphere", "size": 8, "position": [-0.2, 0, 0], "velocity": [-1, 0.5, 0])" +
         regions + R"( },
      { "name": "free", "shape": "sphere", "size": 8, "position": [0.2, 0, 0], "velocity": [1, 0.5, 0] } ],
    "simulation": { "integrator": ")" +
         integrator + R"(", "dt": )" + dt + R"(, "gravity": [0, 0, 0], "damping": )" + std::to_string(c0) + " } }";
}

// Body i's momentum over its mass: the velocity of a rigidly moving body.
Vec3 meanVelocity(const BuiltScene& s, size_t i) {
  const RestModel& m = s.world->model();
  const BodyRange& b = s.range(i);
  Vec3 p = Vec3::Zero();
  Real mass = 0;
  for (uint32_t v = b.vertexBegin; v < b.vertexEnd; ++v)
    p += m.mass[v] * s.world->state().velocities[v], mass += m.mass[v];
  return p / mass;
}

}  // namespace

// The border rule (model.h): a vertex inside one region has that region's rate exactly (the
// simulation's for a region without one), a vertex on the border a mean strictly between, and
// sum_i m_i c_i = sum_r c_r M_r (the lumped mass-proportional damping keeps each region's share).
TEST(RegionDamping, BorderVerticesTakeTheMassWeightedMeanOfTheirRegions) {
  ShapeSpec s;
  s.dims = {12, 12, 12};
  Primitive lower, upper;
  lower.kind = upper.kind = PrimitiveKind::Box;
  lower.min = Vec3(0, 0, 0), lower.max = Vec3(12, 6, 12), lower.label = 1;
  upper.min = Vec3(0, 6, 0), upper.max = Vec3(12, 12, 12), upper.label = 2;
  s.primitives = {lower, upper};
  const VoxelVolume volume = rasterize(s);
  MaterialSettings material;
  material.density = 1000;
  RegionMaterial r;
  r.label = 2, r.density = 3000, r.damping = 40;
  material.regions = {r};
  const Layout layout = buildLayout(volume, LayoutKind::Gradational);
  const RestModel m = buildRestModel(layout, volume, material, Vec3::Zero());
  ASSERT_TRUE(m.hasRegionDamping());
  const Real c0 = 2;
  size_t inLower = 0, inUpper = 0, border = 0;
  Real weighted = 0;
  for (size_t i = 0; i < m.numVertices(); ++i) {
    const Real c = m.vertexDamping(i, c0), y = m.restPositions[i].y() / m.voxelSize;
    weighted += m.mass[i] * c;
    if (y < 5.5) {
      EXPECT_EQ(c, c0) << i;
      ++inLower;
    } else if (y > 6.5) {
      EXPECT_EQ(c, 40.0) << i;
      ++inUpper;
    } else {
      EXPECT_GT(c, c0) << i;
      EXPECT_LT(c, 40.0) << i;
      ++border;
    }
  }
  EXPECT_GT(inLower, 0u);
  EXPECT_GT(inUpper, 0u);
  EXPECT_GT(border, 0u);
  const Real h3 = std::pow(m.voxelSize, 3), halfVoxels = 12 * 6 * 12;
  const Real expected = c0 * 1000 * halfVoxels * h3 + 40 * 3000 * halfVoxels * h3;
  EXPECT_NEAR(weighted, expected, 1e-12 * expected);
  // With the rate of region 2 equal to the simulation's, every vertex has it (a mean of equal
  // rates, to rounding).
  for (size_t i = 0; i < m.numVertices(); ++i) EXPECT_NEAR(m.vertexDamping(i, 40), 40.0, 1e-12);
}

// A rigidly moving body is damped by exactly 1 / (1 + c dt) per step (integration.h) by every
// integrator: the body with its own rate at its rate, the other at the simulation's. The large
// step damps each of its substeps (dt / largeStepSubsteps).
TEST(RegionDamping, RigidBodiesDecayAtTheirOwnRatePerStep) {
  struct Case {
    const char* integrator;
    const char* dt;
    Real tolerance;
  };
  for (const Case& k : {Case{"symplectic", "\"auto\"", 1e-12}, Case{"forward_euler", "1e-4", 1e-12},
                        Case{"implicit", "0.004", 1e-9}, Case{"large_step", "0.004", 1e-9}}) {
    const Real c = 30, c0 = 0.5;
    BuiltScene s = buildScene(parseScene(twoBodies(k.integrator, k.dt, "30", c0), kFile));
    const int steps = 40;
    for (int n = 0; n < steps; ++n) s.world->step();
    const int sub = std::string(k.integrator) == "large_step" ? s.world->settings().largeStepSubsteps : 1;
    const Real dt = s.world->dt() / sub;
    const Vec3 damped = meanVelocity(s, 0), free = meanVelocity(s, 1);
    const Real fd = std::pow(dampingFactor(c, dt), steps * sub), ff = std::pow(dampingFactor(c0, dt), steps * sub);
    EXPECT_LT((damped - fd * Vec3(-1, 0.5, 0)).norm(), k.tolerance) << k.integrator << " " << damped.transpose();
    EXPECT_LT((free - ff * Vec3(1, 0.5, 0)).norm(), k.tolerance) << k.integrator << " " << free.transpose();
    EXPECT_LT(fd, 0.9 * ff) << k.integrator;  // the rates really differ over the run
  }
}

// A free vibration (random velocities, no gravity) dies out in the body with the heavy rate and
// not in the other. Damping takes c 2 K per second from kinetic energy K: a vibration's energy
// (on average half kinetic) decays as exp(-c t), rigid motion's (all kinetic) as exp(-2 c t);
// these random velocities decay at close to the latter (measured 0.00265 after 0.1 s at c = 30
// against exp(-6) = 0.00248).
TEST(RegionDamping, FreeVibrationDecaysInTheDampedBodyOnly) {
  BuiltScene s = buildScene(parseScene(twoBodies("symplectic", "\"auto\"", "30", 0), kFile));
  perturb(*s.world, 0, 0.05, 7);
  auto energy = [&](size_t i) {
    const Metrics m = s.world->bodyMetrics()[i];
    return m.kineticEnergy + m.elasticEnergy;
  };
  const Real d0 = energy(0), f0 = energy(1);
  s.world->advanceTo(0.1);
  const Real dRatio = energy(0) / d0, fRatio = energy(1) / f0;
  EXPECT_GT(dRatio, std::exp(-2 * 30 * 0.1) / 2) << dRatio;
  EXPECT_LT(dRatio, std::exp(-30 * 0.1)) << dRatio;
  EXPECT_GT(fRatio, 0.9) << fRatio;
}

// One rate for every vertex is today's path, bit for bit: a label 1 entry with rate c is the
// simulation's damping c, and an entry with the simulation's own rate changes nothing.
TEST(RegionDamping, OneRateForAllIsTheUniformPathBitForBit) {
  for (const char* integrator : {"symplectic", "implicit", "large_step"}) {
    const std::string dt = std::string(integrator) == "symplectic" ? "\"auto\"" : "0.004";
    auto hash = [&](const std::string& text) {
      BuiltScene s = buildScene(parseScene(text, kFile));
      perturb(*s.world, 0.0005, 0.05, 3);
      for (int n = 0; n < 30; ++n) s.world->step();
      return s.world->stateHash();
    };
    // Both bodies with a label 1 entry of rate 3 and the simulation's 0, or no entries and 3.
    auto scene = [&](bool own) {
      const std::string material = own ? R"(, "material": {"regions": [{"label": 1, "damping": 3}]})" : "";
      return R"({ "bodies": [ { "shape": "sphere", "size": 8, "velocity": [1, 0, 0])" + material +
             R"( }, { "shape": "sphere", "size": 8, "position": [0.3, 0, 0])" + material +
             R"( } ], "simulation": { "integrator": ")" + std::string(integrator) + R"(", "dt": )" + dt +
             R"(, "gravity": [0, -9.81, 0], "damping": )" + (own ? "0" : "3") + " } }";
    };
    EXPECT_EQ(hash(scene(true)), hash(scene(false))) << integrator;
  }
}

// The same two bodies of different rates at one and two threads: the same state bit for bit.
TEST(RegionDamping, StateHashIsTheSameAtOneAndTwoThreads) {
  Scene scene = parseScene(R"({
    "bodies": [ { "shape": "sphere", "size": 16, "position": [-0.2, 0.1, 0], "velocity": [1, 0, 0],
                  "material": {"regions": [{"label": 1, "damping": 25}]} },
                { "shape": "sphere", "size": 14, "voxel_size": 0.012, "position": [0.1, 0.1, 0],
                  "velocity": [-1, 0, 0] } ],
    "simulation": { "damping": 0.5 },
    "domain": { "min": [-1, 0, -1], "max": [1, 1, 1] }
  })",
                           kFile);
  uint64_t hash[2];
  for (int t : {1, 2}) {
    scene.simulation.threads = t;
    BuiltScene b = buildScene(scene);
    ASSERT_GE(b.world->model().numVertices(), 2048u);  // two members, not one
    ASSERT_TRUE(b.world->model().hasRegionDamping());
    for (int k = 0; k < 150; ++k) b.world->step();
    hash[t - 1] = b.world->stateHash();
  }
  EXPECT_EQ(hash[0], hash[1]);
}

TEST(RegionDamping, BadInputNamesTheKey) {
  const std::string body = R"("body": {"shape": "sphere", "size": 4}, )";
  EXPECT_EQ(
      sceneErrorOf("{" + body + R"("material": {"regions": [{"label": 2}, {"label": 3, "damping": -1}]}})", kFile),
      "x.json: material.regions[1].damping: -1 is out of range (expected a number >= 0 [1/s])");
  EXPECT_NE(sceneErrorOf("{" + body + R"("material": {"regions": [{"label": 2, "damping": "fast"}]}})", kFile)
                .find("material.regions[0].damping: got"),
            std::string::npos);
  EXPECT_NE(sceneErrorOf(R"({"bodies": [{"shape": "sphere", "size": 4},
      {"shape": "sphere", "size": 4, "material": {"regions": [{"label": 1, "damping": -2}]}}]})",
                         kFile)
                .find("bodies[1].material.regions[0].damping: -2 is out of range"),
            std::string::npos);
  // Outside a scene (a material made in C++), validate() names the entry.
  MaterialSettings m;
  RegionMaterial r;
  r.damping = -1;
  m.regions = {r};
  try {
    buildRestModel(buildLayout(rasterize(presetShape("box", 2, 3, 0.01)), LayoutKind::Voxel),
                   rasterize(presetShape("box", 2, 3, 0.01)), m, Vec3::Zero());
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("regions[0].damping"), std::string::npos) << e.what();
  }
}
