// Several bodies in one world (bodies.h): the combined rest model is the bodies' models side by
// side, and bodies that do not touch move exactly as each would alone.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "gradel/bodies.h"
#include "gradel/output.h"
#include "struck_balls_scene.h"
#include "test_support.h"

using namespace gradel;
using namespace gradel::test;

namespace {

bool sameBits(const Vec3& a, const Vec3& b) { return std::memcmp(a.data(), b.data(), sizeof(Vec3)) == 0; }

MaterialSettings material(Real E, Real rho) {
  MaterialSettings m;
  m.youngsModulus = E, m.density = rho;
  return m;
}

}  // namespace

TEST(MultiBody, CombinedModelIsTheModelsSideBySide) {
  const Body a = makeBody("sphere", 8, 3, LayoutKind::Gradational, material(1e5, 1000), 0.01);
  const Body b = makeBody("box", 5, 3, LayoutKind::Voxel, material(3e5, 500), 0.02, Vec3(1, 0, 0));
  const RestModel c = combineRestModels({a.model, b.model});
  const RestModel &A = *a.model, &B = *b.model;
  const size_t VA = A.numVertices(), EA = A.numElements(), PA = A.numPairs();
  ASSERT_EQ(c.numVertices(), VA + B.numVertices());
  ASSERT_EQ(c.numElements(), EA + B.numElements());
  ASSERT_EQ(c.numPairs(), PA + B.numPairs());
  ASSERT_EQ(c.bodies.size(), 2u);
  EXPECT_EQ(c.bodies[0].vertexBegin, 0u);
  EXPECT_EQ(c.bodies[0].vertexEnd, VA);
  EXPECT_EQ(c.bodies[1].vertexBegin, VA);
  EXPECT_EQ(c.bodies[1].vertexEnd, c.numVertices());
  EXPECT_EQ(c.bodies[1].elementBegin, EA);
  EXPECT_EQ(c.bodies[1].elementEnd, c.numElements());
  EXPECT_EQ(c.bodies[1].voxelSize, 0.02);
  EXPECT_EQ(c.bodies[1].material.youngsModulus, 3e5);
  EXPECT_EQ(c.bodies[1].origin, Vec3(1, 0, 0));
  EXPECT_EQ(c.voxelSize, 0.01);  // body 0's
  for (size_t v = 0; v < c.numVertices(); ++v) {
    const RestModel& m = v < VA ? A : B;
    const size_t i = v < VA ? v : v - VA;
    ASSERT_EQ(c.restPositions[v], m.restPositions[i]);
    ASSERT_EQ(c.mass[v], m.mass[i]);
    ASSERT_EQ(c.invMass[v], m.invMass[i]);
    ASSERT_EQ(c.onSurface[v], m.onSurface[i]);
    ASSERT_EQ(c.bodyOfVertex(v), v < VA ? 0u : 1u);
  }
  for (size_t e = 0; e < c.numElements(); ++e) {
    const RestModel& m = e < EA ? A : B;
    const size_t k = e < EA ? e : e - EA;
    ASSERT_EQ(c.stiffness[e], m.stiffness[k]);
    ASSERT_EQ(c.size[e], m.size[k]);
    ASSERT_EQ(c.level[e], m.level[k]);
    ASSERT_EQ(c.restCentroids[e], m.restCentroids[k]);
    ASSERT_EQ(c.elemStart[e + 1] - c.elemStart[e], m.elemStart[k + 1] - m.elemStart[k]);
    for (uint32_t p = 0; p < m.elemStart[k + 1] - m.elemStart[k]; ++p) {
      const uint32_t cp = c.elemStart[e] + p, mp = m.elemStart[k] + p;
      ASSERT_EQ(c.elemVerts[cp], m.elemVerts[mp] + (e < EA ? 0 : VA));
      ASSERT_EQ(c.restOffset(e, cp), m.restOffset(k, mp));
    }
  }
  EXPECT_DOUBLE_EQ(c.totalMass, A.totalMass + B.totalMass);
  EXPECT_EQ(c.smallestPeriod, std::min(A.smallestPeriod, B.smallestPeriod));
  EXPECT_EQ(c.smallestVertexPeriod, std::min(A.smallestVertexPeriod, B.smallestVertexPeriod));
  // One model: a copy of it, totals and all.
  const RestModel one = combineRestModels({a.model});
  EXPECT_EQ(one.totalMass, A.totalMass);
  EXPECT_EQ(one.elemVerts, A.elemVerts);
  ASSERT_EQ(one.bodies.size(), 1u);
  EXPECT_EQ(one.bodies[0].vertexEnd, VA);
}

TEST(MultiBody, CombineRefusesMixedDimensionsAndNoModels) {
  const Body a = makeBody("sphere", 6, 3, LayoutKind::Gradational);
  const Body b = makeBody("sphere", 6, 2, LayoutKind::Gradational);
  EXPECT_THROW(combineRestModels({a.model, b.model}), std::invalid_argument);
  EXPECT_THROW(combineRestModels({}), std::invalid_argument);
}

// Two bodies that never touch, with different voxel sizes, materials and layouts, in one world
// with walls, gravity, damping and a manipulator striking the first: each evolves bit for bit as
// it does alone in a world of its own (same dt), at one thread and at two.
TEST(MultiBody, SeparatedBodiesEvolveBitIdenticallyToEachAlone) {
  const Body a = makeBody("sphere", 16, 3, LayoutKind::Gradational, material(1e5, 1000), 0.01, Vec3(0, 0.05, 0));
  const Body b = makeBody("box", 7, 3, LayoutKind::Voxel, material(4e5, 700), 0.013, Vec3(0.4, 0.02, 0));
  auto combined = std::make_shared<RestModel>(combineRestModels({a.model, b.model}));
  SimulationSettings sim;
  sim.dt = 2e-4;
  sim.damping = 0.5;
  DomainSettings domain;
  domain.enabled = true;
  domain.min = Vec3(-1, 0, -1), domain.max = Vec3(1, 1, 1);
  ManipulatorSettings strike;
  strike.radius = 0.03;
  strike.path.keys = {{0, Vec3(-0.15, 0.1, 0.06), {}}, {0.04, Vec3(0.1, 0.1, 0.06), {}}};
  for (int threads : {1, 2}) {
    sim.threads = threads;
    World wa(a.model, sim, domain, {strike}), wb(b.model, sim, domain, {strike});
    World both(combined, sim, domain, {strike});
    perturb(wa, 1e-4, 0.05, 1), perturb(wb, 1e-4, 0.05, 2);
    const size_t VA = a.model->numVertices();
    for (size_t i = 0; i < VA; ++i)
      both.state().positions[i] = wa.state().positions[i], both.state().velocities[i] = wa.state().velocities[i];
    for (size_t i = 0; i < b.model->numVertices(); ++i)
      both.state().positions[VA + i] = wb.state().positions[i],
                                  both.state().velocities[VA + i] = wb.state().velocities[i];
    for (int s = 0; s < 300; ++s) wa.step(), wb.step(), both.step();
    EXPECT_GT(both.metrics().maxContactDepth + wa.state().velocities[0].norm(), 0);  // it moved
    size_t differ = 0;
    for (size_t i = 0; i < VA; ++i)
      differ += !sameBits(both.state().positions[i], wa.state().positions[i]) ||
                !sameBits(both.state().velocities[i], wa.state().velocities[i]);
    for (size_t i = 0; i < b.model->numVertices(); ++i)
      differ += !sameBits(both.state().positions[VA + i], wb.state().positions[i]) ||
                !sameBits(both.state().velocities[VA + i], wb.state().velocities[i]);
    EXPECT_EQ(differ, 0u) << "threads " << threads;
    // Per-body metrics are each body's own; the world's are their sum.
    const std::vector<Metrics> each = both.bodyMetrics();
    ASSERT_EQ(each.size(), 2u);
    EXPECT_EQ(each[0].kineticEnergy, wa.metrics().kineticEnergy);
    EXPECT_EQ(each[1].elasticEnergy, wb.metrics().elasticEnergy);
    EXPECT_EQ(each[1].linearMomentum, wb.metrics().linearMomentum);
    EXPECT_EQ(both.metrics().kineticEnergy, each[0].kineticEnergy + each[1].kineticEnergy);
    // The strike moved the sphere, not the box: the comparison is not between two resting bodies.
    EXPECT_GT(each[0].linearMomentum.x(), 1e-3);
  }
}

// World(model, WorldSettings, contact surfaces) is the whole creation: pins, body contacts, the
// start overlaps' release and each body's velocity, in that order. Two balls placed half a voxel
// inside each other, one pinned at its far side, the other thrown at it: the same state, bit for
// bit, as a bare world set up call by call, and each setting took effect.
TEST(MultiBody, WorldSettingsCreateTheWholeWorldInOneCall) {
  const Body a = makeBody("sphere", 8, 3, LayoutKind::Gradational, {}, 0.01);
  const Body b = makeBody("sphere", 8, 3, LayoutKind::Voxel, {}, 0.01, Vec3(0.075, 0, 0));
  auto combined = std::make_shared<RestModel>(combineRestModels({a.model, b.model}));
  const std::vector<ContactBody> surfaces = buildContactBodies(*combined, {&a.layout, &b.layout}, {&a.volume, &b.volume});
  WorldSettings settings;
  settings.simulation = isolated();
  PinSettings pin;
  pin.min = Vec3(0.145, -1, -1), pin.max = Vec3(1, 1, 1), pin.body = 1;
  settings.pins = {pin};
  settings.bodyContact.friction = 0.3;
  settings.bodyVelocities = {Vec3(0.5, 0, 0), Vec3(0, 0, 0)};
  World one(combined, settings, surfaces);

  World byHand(combined, settings.simulation, settings.domain, settings.manipulators);
  byHand.setPins(settings.pins);
  byHand.setBodyContacts(surfaces, settings.bodyContact);
  byHand.releaseStartOverlaps();
  for (uint32_t u = combined->bodies[0].vertexBegin; u < combined->bodies[0].vertexEnd; ++u)
    byHand.state().velocities[u] = settings.bodyVelocities[0];

  ASSERT_NE(one.bodyContacts(), nullptr);
  EXPECT_FALSE(one.pinned().vertices.empty());
  EXPECT_FALSE(one.startOverlaps().empty());  // the balls start inside each other
  EXPECT_TRUE(one.separatingStartOverlaps());
  EXPECT_EQ(one.state().velocities[combined->bodies[0].vertexBegin], Vec3(0.5, 0, 0));
  EXPECT_EQ(one.state().velocities[combined->bodies[1].vertexBegin], Vec3(0, 0, 0));
  EXPECT_EQ(one.stateHash(), byHand.stateHash());
  for (int s = 0; s < 40; ++s) one.step(), byHand.step();
  EXPECT_EQ(one.stateHash(), byHand.stateHash());
  EXPECT_GT(one.metrics().kineticEnergy, 0);

  // Without the release, the overlap is left to the contacts' instant push, as a bare world's.
  settings.releaseStartOverlaps = false;
  EXPECT_FALSE(World(combined, settings, surfaces).separatingStartOverlaps());
  // One velocity per body, or none.
  settings.bodyVelocities.pop_back();
  EXPECT_THROW(World(combined, settings, surfaces), std::invalid_argument);
}

TEST(MultiBody, PinsSelectOnlyTheirBodysVertices) {
  const Body a = makeBody("box", 4, 3, LayoutKind::Voxel, {}, 0.01);
  const Body b = makeBody("box", 4, 3, LayoutKind::Voxel, {}, 0.01);  // the same place: boxes overlap
  auto combined = std::make_shared<RestModel>(combineRestModels({a.model, b.model}));
  World w(combined, isolated(), {}, {});
  PinSettings p;
  p.min = Vec3(-1, -1, -1), p.max = Vec3(1, 1, 1);  // every vertex of both
  p.body = 1;
  w.setPins({p});
  const size_t VA = a.model->numVertices();
  ASSERT_EQ(w.pinned().vertices.size(), b.model->numVertices());
  EXPECT_EQ(w.pinned().vertices.front(), VA);
  p.body = 2;
  try {
    w.setPins({p});
    FAIL() << "no body 2";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("pins[0].body"), std::string::npos) << e.what();
  }
}

// ---- scenes -------------------------------------------------------------------------------

namespace {

constexpr const char* kFile = "scenes/two.json";

std::string errorOf(const std::string& text) { return test::sceneErrorOf(text, kFile); }

// Two balls 12 cm apart flying at each other (no soft contact in this test: they do not reach).
const char* kTwoBalls = R"({
  "bodies": [
    { "name": "left", "shape": "sphere", "size": 6, "voxel_size": 0.01, "position": [-0.1, 0, 0],
      "velocity": [0.5, 0, 0], "material": { "youngs_modulus": 2e5, "density": 800 } },
    { "shape": "box", "size": 4, "voxel_size": 0.015, "layout": "voxel", "position": [0.06, 0, 0],
      "velocity": [-0.5, 0, 0] }
  ],
  "simulation": { "dt": 1e-4, "gravity": [0, 0, 0], "damping": 0, "duration": 0.01, "frame_interval": 0.005 },
  "pins": [ { "body": 1, "min": [0.059, 0, 0], "max": [0.061, 0.06, 0.06] } ]
})";

}  // namespace

TEST(MultiBodyScene, BodiesKeyGivesEachBodyItsOwnSettings) {
  const Scene s = parseScene(kTwoBalls, kFile);
  ASSERT_EQ(s.numBodies(), 2u);
  EXPECT_EQ(s.bodies[0].name, "left");
  EXPECT_EQ(s.bodies[1].name, "body1");
  EXPECT_EQ(s.bodies[0].material.youngsModulus, 2e5);
  EXPECT_EQ(s.bodies[1].material.youngsModulus, MaterialSettings{}.youngsModulus);
  EXPECT_EQ(s.bodies[1].shape.voxelSize, 0.015);
  EXPECT_EQ(s.bodies[1].layout, LayoutKind::Voxel);
  EXPECT_EQ(s.bodies[1].sizeKey, "bodies[1].size");
  ASSERT_EQ(s.pins.size(), 1u);
  EXPECT_EQ(s.pins[0].body, 1u);

  const BuiltScene b = buildScene(s);
  ASSERT_EQ(b.numBodies(), 2u);
  const RestModel& m = b.world->model();
  EXPECT_EQ(m.numVertices(), b.bodies[0].model->numVertices() + b.bodies[1].model->numVertices());
  EXPECT_EQ(b.range(1).voxelSize, 0.015);
  EXPECT_EQ(b.range(1).material.density, MaterialSettings{}.density);
  EXPECT_EQ(b.range(0).material.density, 800);
  // Velocities per body; the pins hold body 1's vertices only (the box lies on x = 0.06).
  EXPECT_EQ(b.world->state().velocities[0], Vec3(0.5, 0, 0));
  for (uint32_t v : b.world->pinned().vertices) {
    EXPECT_GE(v, b.range(1).vertexBegin);
    EXPECT_NEAR(m.restPositions[v].x(), 0.06, 1e-12);
  }
  EXPECT_EQ(b.world->pinned().vertices.size(), 5u * 5u);
}

TEST(MultiBodyScene, MistakesNameTheKey) {
  auto expect = [](const std::string& text, const std::string& key, const std::string& what) {
    const std::string msg = errorOf(text);
    SCOPED_TRACE(text);
    ASSERT_FALSE(msg.empty());
    EXPECT_EQ(msg.rfind(std::string(kFile) + ": " + key, 0), 0u) << msg;
    EXPECT_NE(msg.find(what), std::string::npos) << msg;
  };
  const std::string ball = R"({"shape": "sphere", "size": 4})";
  expect(R"({"bodies": []})", "bodies", "empty");
  expect(R"({"bodies": [)" + ball + R"(], "body": )" + ball + "}", "body", "not both");
  expect(R"({"bodies": [)" + ball + R"(], "material": {"density": 5}})", "material", "inside its entry");
  expect(R"({"bodies": [)" + ball + "," + ball + R"(], "pins": [{"body": 2, "min": [0,0,0], "max": [1,1,1]}]})",
         "pins[0].body", "");
  expect(R"({"bodies": [)" + ball + R"(, {"shape": "sphere", "size": 4, "densty": 3}]})", "bodies[1].densty",
         "unknown key");
  expect(R"({"bodies": [{"name": "a", "shape": "box", "size": 2}, {"name": "a", "shape": "box", "size": 2}]})",
         "bodies[1].name", "bodies[0]");
  expect(R"({"bodies": [{"name": "../x", "shape": "box", "size": 2}]})", "bodies[0].name", "file name");
  expect(R"({"bodies": [)" + ball + R"(, {"shape": "sphere", "size": 4, "material": {"density": -1}}]})",
         "bodies[1].material.density", "");
  expect(R"({"bodies": 3})", "bodies", "array");
}

TEST(MultiBodyScene, SizeLimitsCountEveryBody) {
  // Each body alone fits; both together do not.
  const std::string text = R"({"bodies": [{"shape": "box", "size": 24}, {"shape": "box", "size": 24}]})";
  const Scene s = parseScene(text, kFile);
  Scene single = s;
  single.bodies.resize(1);
  // The bytes one body takes, measured through the limit's own estimate: a limit just above it.
  const uint64_t bytes =
      estimateModelBytes(countLayout(rasterize(presetShape("box", 24, 3, 0.01)), LayoutKind::Gradational), 3);
  SizeLimits limits;
  limits.maxBytes = bytes + bytes / 2;
  EXPECT_NO_THROW(buildScene(single, limits));
  try {
    buildScene(s, limits);
    FAIL() << "two bodies over the limit";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("bodies[1].size", 0), 0u) << e.what();
    EXPECT_NE(std::string(e.what()).find("the bodies before it"), std::string::npos) << e.what();
  }
}

// The same two-body scene at one and two threads: the same state bit for bit. The tool (6 m/s)
// strikes the first ball into the second, which it reaches after about step 90 (body contacts in
// the last third). At 12 m/s the struck ball's surface tangles and the body-contact stage
// costs ~150 ms a step (43 s for this test, 24 min under ASan in CI): issue 26.
TEST(MultiBodyScene, StateHashIsTheSameAtOneAndTwoThreads) {
  Scene s = parseScene(struckBallsScene(0.1), kFile);
  uint64_t hash[2];
  for (int t : {1, 2}) {
    s.simulation.threads = t;
    BuiltScene b = buildScene(s);
    ASSERT_GE(b.world->model().numVertices(), 2048u);  // two members, not one
    const Real p0 = b.world->bodyMetrics()[1].linearMomentum.x();
    for (int k = 0; k < 150; ++k) b.world->step();
    // The second ball was struck by the first (its x momentum, -2.54 kg m/s, changed by over 0.5).
    EXPECT_GT(b.world->bodyMetrics()[1].linearMomentum.x() - p0, 0.5);
    hash[t - 1] = b.world->stateHash();
  }
  EXPECT_EQ(hash[0], hash[1]);
}

// `gradel run` of a two-body scene: one .vtu per body and frame, run.pvd listing both per
// timestep as parts, metrics.csv with a body column (a row per body and one "all" per frame).
TEST(MultiBodyScene, RunWritesPerBodyFramesPvdPartsAndMetricsRows) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("gradel-bodies-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "two.json") << kTwoBalls;
  const std::string cmd =
      "cd '" + dir.string() + "' && '" + std::string(GRADEL_CLI_PATH) + "' run two.json --out res > out.txt 2> err.txt";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  auto read = [](const fs::path& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  const fs::path res = dir / "res";
  // Frames at 0, 0.005 and 0.01 s for each body.
  for (const char* body : {"left", "body1"})
    for (int f = 0; f < 3; ++f) EXPECT_TRUE(fs::exists(res / frameFileName(size_t(f), body))) << body << " " << f;
  EXPECT_FALSE(fs::exists(res / frameFileName(0)));
  const std::string pvd = read(res / "run.pvd");
  EXPECT_NE(pvd.find(R"(timestep="0.005" group="" part="1" name="body1" file="body1_00001.vtu")"), std::string::npos)
      << pvd;
  EXPECT_NE(pvd.find(R"(timestep="0.005" group="" part="0" name="left" file="left_00001.vtu")"), std::string::npos)
      << pvd;
  // Each body's file holds its own vertices: the box's 5^3 lattice points.
  const std::string box = read(res / "body1_00000.vtu");
  EXPECT_NE(box.find(R"(NumberOfPoints="125" NumberOfCells="64")"), std::string::npos);
  // metrics.csv: header with "body", 3 frames x (2 bodies + all); the total is the sum.
  std::istringstream csv(read(res / "metrics.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, MetricsCsv::header(0, /*bodyColumn=*/true));  // no manipulator: the walls' force columns
  std::vector<std::vector<std::string>> rows;
  while (std::getline(csv, line)) {
    std::vector<std::string> cells;
    std::stringstream ls(line);
    for (std::string c; std::getline(ls, c, ',');) cells.push_back(c);
    rows.push_back(cells);
  }
  ASSERT_EQ(rows.size(), 9u);
  for (size_t f = 0; f < 3; ++f) {
    EXPECT_EQ(rows[3 * f][0], "left");
    EXPECT_EQ(rows[3 * f + 1][0], "body1");
    EXPECT_EQ(rows[3 * f + 2][0], "all");
    // The walls' force columns: filled on the "all" row only (forces are the world's).
    EXPECT_EQ(rows[3 * f + 2].size(), 21u + 36u + 1u);  // the walls together, each of the six, max_strain
    ASSERT_EQ(rows[3 * f].size(), rows[3 * f + 2].size());
    for (size_t c = 15; c + 1 < rows[3 * f].size(); ++c) EXPECT_EQ(rows[3 * f][c], "") << c;
    EXPECT_GE(std::stod(rows[3 * f].back()), 0);  // max_strain: every row has its own
    // px (column 5): the ball moves at +0.5 m/s, the box is pinned on one face and moves at -0.5
    // m/s elsewhere; the total is their sum.
    const double a = std::stod(rows[3 * f][5]), b = std::stod(rows[3 * f + 1][5]), all = std::stod(rows[3 * f + 2][5]);
    EXPECT_GT(a, 0);
    EXPECT_DOUBLE_EQ(all, a + b);
  }
  const std::string out = read(dir / "out.txt");
  EXPECT_NE(out.find("\"bodies\": 2"), std::string::npos) << out;
  EXPECT_NE(out.find("\"frames\": 3"), std::string::npos) << out;
  fs::remove_all(dir);
}
