// Pictures with real content (issue 3): drawn offscreen through EGL (Mesa llvmpipe when there is
// no GPU) and, for the viewer, in a window under Xvfb. No OpenGL = failure, never a skip.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <optional>
#include <set>

#include "gradel/image.h"
#include "gradel/render/body_table.h"
#include "gradel/render/display_budget.h"
#include "gradel/render/draw_list.h"
#include "gradel/render/layout_picture.h"
#include "gradel/render/manipulator_drag.h"
#include "gradel/render/offscreen.h"
#include "gradel/render/renderer.h"
#include "gradel/scene.h"
#include "gradel/shapes.h"

namespace gradel::render {
namespace {

namespace fs = std::filesystem;
constexpr int kW = 480, kH = 360;

OffscreenContext& gl() {
  static OffscreenContext context(kW, kH);  // throws GlUnavailable: the test fails with the reason
  return context;
}

Image draw(const BuiltScene& built, const ViewOptions& v, const Camera& cam) {
  gl();
  static Renderer renderer;
  renderer.draw(buildDrawList(makeBodyView(built), *built.world, v, kW, kH), cam, kW, kH);
  return gl().read();
}

double luminance(const uint8_t* p) { return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]; }

// Mean luminance of the body's pixels within `radius` pixels of `centre` (pixels that differ
// from the background and from the manipulator's blue).
double bodyLuminanceNear(const Image& img, const Vec3& centre, double radius, int* count) {
  double sum = 0;
  *count = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      if (std::hypot(x - centre.x(), y - centre.y()) > radius) continue;
      const uint8_t* p = img.pixel(x, y);
      const bool background = p[0] > 225 && p[1] > 225 && p[2] > 225 && std::abs(p[0] - p[2]) < 12;
      const bool blueish = p[2] > p[0] + 20;  // manipulator, floor grid, walls
      if (background || blueish) continue;
      sum += luminance(p);
      ++*count;
    }
  return *count ? sum / *count : 0;
}

TEST(RenderHeadless, ContextIsOpenGl33) {
  gl();
  EXPECT_FALSE(Renderer::glRenderer().empty());
  std::cout << "GL_RENDERER: " << Renderer::glRenderer() << "\n";
}

// The draw list (no OpenGL): the force arrow of a manipulator pressed into the ball starts at
// its centre and points along the force the body exerts on it, |F| x scale long.
TEST(DrawList, ForceArrowStartsAtTheToolAndPointsAlongItsForce) {
  Scene scene = loadScene(std::string(GRADEL_SOURCE_DIR) + "/scenes/strike.json");
  BuiltScene built = buildScene(scene);
  World& w = *built.world;
  while (w.time() < 0.3 && w.stepContactForces().manipulators.at(0).force.norm() == 0) w.step();
  const Vec3 F = w.stepContactForces().manipulators[0].force, c = w.manipulators()[0].position;
  ASSERT_GT(F.norm(), 0);
  ViewOptions v;
  v.surface = SurfaceMode::None, v.walls = false, v.manipulators = false;
  const size_t without = buildDrawList(makeBodyView(built), w, v, kW, kH).lines.size();
  v.forces = true;
  v.forceScale = 0.01;      // 1 cm per N
  w.restartForceAverage();  // nothing averaged: the last step's force is drawn
  const DrawList list = buildDrawList(makeBodyView(built), w, v, kW, kH);
  ASSERT_EQ(list.lines.size(), without + 2 * 5);  // shaft and four head lines
  const DrawVertex& a = list.lines[without];
  const DrawVertex& b = list.lines[without + 1];
  const Vec3 from(a.position[0], a.position[1], a.position[2]), to(b.position[0], b.position[1], b.position[2]);
  EXPECT_LT((from - c).norm(), 1e-6);
  EXPECT_LT((to - from - 0.01 * F).norm(), 1e-6 * std::max(1.0, 0.01 * F.norm()));
  EXPECT_GT(list.overlay.size(), 0u);  // the legend
}

TEST(RenderHeadless, StressColourIsDarkerAtTheContactThanFarFromIt) {
  // Strike scene at the moment the manipulator is pressed into the ball.
  Scene scene = loadScene(std::string(GRADEL_SOURCE_DIR) + "/scenes/strike.json");
  BuiltScene built = buildScene(scene);
  World& w = *built.world;
  const Vec3 centre0 = [&] {
    Vec3 c = Vec3::Zero();
    for (const Vec3& p : w.state().positions) c += p;
    return Vec3(c / Real(w.state().positions.size()));
  }();
  // Advance until the manipulator has entered the ball's bounding sphere (deepest contact).
  Real best = 1e9;
  for (int i = 0; i < 400 && w.time() < 0.2; ++i) {
    w.advanceTo(w.time() + 0.0005);
    best = std::min(best, (w.manipulators()[0].position - centre0).norm());
    if ((w.manipulators()[0].position - centre0).norm() > best + 1e-4) break;
  }
  ViewOptions v;
  v.stress = true;
  v.manipulators = false;
  v.walls = false;
  // Look from +z (the contact on the -x side and the far +x side both visible).
  Camera cam;
  cam.target = centre0;
  cam.yaw = 0;
  cam.pitch = 0.2;
  cam.distance = 0.35;
  const Image img = draw(built, v, cam);
  writePng("render_stress.png", img);

  const Manipulator& m = w.manipulators()[0];
  const Vec3 contact = m.position + m.settings.radius * (centre0 - m.position).normalized();
  const Vec3 far = centre0 + (centre0 - contact);
  int nNear = 0, nFar = 0;
  const double radius = 18;
  const double lumNear = bodyLuminanceNear(img, cam.project(contact, kW, kH), radius, &nNear);
  const double lumFar = bodyLuminanceNear(img, cam.project(far, kW, kH), radius, &nFar);
  ASSERT_GT(nNear, 50) << "no body pixels near the contact";
  ASSERT_GT(nFar, 50) << "no body pixels on the far side";
  EXPECT_LT(lumNear, lumFar - 25) << "stress colour must be darker near the contact (" << lumNear << " vs " << lumFar
                                  << ")";
}

// Number of layout levels whose colour appears on at least `minPixels` pixels.
int levelsSeen(const Image& img, int levels, int minPixels) {
  int seen = 0;
  for (int l = 0; l < levels + 2; ++l) {
    const auto c = levelColor(l);
    int n = 0;
    for (int y = 0; y < img.height; ++y)
      for (int x = 60; x < img.width; ++x) {  // skip the legend at the left
        const uint8_t* p = img.pixel(x, y);
        if (std::abs(p[0] - c[0] * 255) < 24 && std::abs(p[1] - c[1] * 255) < 24 && std::abs(p[2] - c[2] * 255) < 24)
          ++n;
      }
    if (n >= minPixels) ++seen;
  }
  return seen;
}

TEST(RenderHeadless, WireframeShowsMoreLevelsForALargerSphere) {
  auto wire = [&](int size) {
    Scene scene =
        parseScene(R"({"dim": 3, "body": {"shape": "sphere", "size": )" + std::to_string(size) + R"(, "voxel_size": )" +
                       std::to_string(0.12 / size) + R"(}, "simulation": {"gravity": [0, 0, 0]}})",
                   "wire");
    BuiltScene built = buildScene(scene);
    ViewOptions v;
    v.surface = SurfaceMode::None;
    v.wireframe = true;
    Vec3 lo, hi;
    sceneBounds(*built.world, &lo, &hi);
    const Image img = draw(built, v, frameBox(lo, hi, false));
    writePng("render_wire_" + std::to_string(size) + ".png", img);
    return std::pair{levelsSeen(img, built.bodies[0].layout.numLevels(), 30), built.bodies[0].layout.numLevels()};
  };
  const auto [small, smallLevels] = wire(8);
  const auto [large, largeLevels] = wire(32);
  EXPECT_EQ(small, smallLevels);
  EXPECT_EQ(large, largeLevels);
  EXPECT_GT(large, small);
}

// Several bodies: the body view holds every body's surfaces and outlines in the world's vertex
// ids (each body's moved by its first vertex), so both bodies are drawn where they are.
TEST(RenderHeadless, EveryBodyIsInTheBodyViewAtItsWorldVertices) {
  const Scene scene = parseScene(R"({"bodies": [{"shape": "sphere", "size": 6},
      {"shape": "box", "size": 3, "layout": "voxel", "voxel_size": 0.02, "position": [0.2, 0, 0]}]})",
                                 "two");
  const BuiltScene built = buildScene(scene);
  const BodyView all = makeBodyView(built);
  const RestModel& m = built.world->model();
  const uint32_t b1 = built.range(1).vertexBegin;
  // The box's voxel surface: 6 faces of 3 x 3 squares, all on the box's vertices at x >= 0.2.
  size_t boxVertices = 0;
  for (uint32_t v : all.voxel.modelVertex) {
    ASSERT_LT(v, m.numVertices());
    if (v < b1) continue;
    ++boxVertices;
    EXPECT_GE(m.restPositions[v].x(), 0.2 - 1e-12);
  }
  EXPECT_EQ(boxVertices, 6u * 16u - 12u * 4u + 8u);  // the 56 lattice points on the box's faces
  size_t boxEdges = 0;
  for (const auto& e : all.edges) boxEdges += e[0] >= b1 && e[1] >= b1;
  EXPECT_EQ(boxEdges, 27u * 12u);  // each of the 27 voxel elements outlined by its 12 edges
  ASSERT_TRUE(all.embedded);       // both isosurfaces, each bound to its own body's vertices
  EXPECT_GE(*std::max_element(all.embedded->weightVertex.begin(), all.embedded->weightVertex.end()), b1);
  EXPECT_LT(*std::min_element(all.embedded->weightVertex.begin(), all.embedded->weightVertex.end()), b1);
}

// The display budget's first step (render/display_budget.h): the smallest s with
// triangles / s^2 within the budget, 1 when it fits or there is no budget.
TEST(DisplayBudget, StepEstimateIsTheSmallestStepThatFitsTheBudget) {
  EXPECT_EQ(displayStepEstimate(36336, kDisplayTriangleBudget), 1);  // the size-64 sphere: whole
  EXPECT_EQ(displayStepEstimate(142704, 40000), 2);
  EXPECT_EQ(displayStepEstimate(160000, 40000), 2);
  EXPECT_EQ(displayStepEstimate(160001, 40000), 3);
  EXPECT_EQ(displayStepEstimate(1000000, 0), 1);
  for (size_t t = 1; t < 200000; t += 997) {
    const size_t s = size_t(displayStepEstimate(t, 1000));
    EXPECT_LE(t, 1000 * s * s) << t;
    if (s > 1) EXPECT_GT(t, 1000 * (s - 1) * (s - 1)) << t;
  }
}

// A body whose smooth surface is over the budget gets a coarse display mesh within it, drawn by
// default instead of the smooth surface (and of the embedded one), the full surface on request;
// the coarse mesh follows the body's vertices (a rigid shift moves it by that shift). Under the
// budget, or without one, nothing changes.
TEST(DisplayBudget, LargeBodyIsDrawnWithinTheBudgetAndFollowsTheBody) {
  BuiltScene built = buildScene(parseScene(R"({"body": {"shape": "sphere", "size": 40},
      "simulation": {"gravity": [0, 0, 0]}})",
                                           "large"));
  const size_t budget = 5000;
  const BodyView view = makeBodyView(built, nullptr, budget);
  ASSERT_TRUE(view.coarse);
  EXPECT_EQ(view.fullTriangles, view.smooth.triangles.size());
  EXPECT_GT(view.fullTriangles, budget);
  EXPECT_LE(view.coarse->triangles.size(), budget);
  EXPECT_GT(view.coarse->triangles.size(), budget / 4);  // no coarser than needed (steps go as 1/s^2)
  EXPECT_GT(view.coarseStep, 1);
  World& w = *built.world;
  ViewOptions o;
  for (SurfaceMode mode : {SurfaceMode::Smooth, SurfaceMode::Embedded}) {
    o.surface = mode;
    const DrawList coarse = buildDrawList(view, w, o, kW, kH);
    EXPECT_EQ(coarse.meshIndices, view.coarseIndices);
    EXPECT_LE(coarse.meshIndices->size() / 3, budget);
  }
  o.surface = SurfaceMode::Smooth;
  o.fullResolution = true;
  EXPECT_EQ(buildDrawList(view, w, o, kW, kH).meshIndices, view.smoothIndices);
  o.fullResolution = false;
  const DrawList before = buildDrawList(view, w, o, kW, kH);
  const Vec3 shift(0.3, -0.2, 0.1);
  for (Vec3& x : w.state().positions) x += shift;
  const DrawList after = buildDrawList(view, w, o, kW, kH);
  ASSERT_EQ(after.meshVertices.size(), before.meshVertices.size());
  for (size_t v = 0; v < after.meshVertices.size(); ++v)
    for (int k = 0; k < 3; ++k)
      ASSERT_NEAR(after.meshVertices[v].position[k] - before.meshVertices[v].position[k], shift[k], 1e-5) << v;
  EXPECT_FALSE(makeBodyView(built, nullptr, view.fullTriangles).coarse);  // within the budget
  EXPECT_FALSE(makeBodyView(built).coarse);                               // no budget
}

// The viewer's panel with several bodies (render/body_table.h): a row per body, its own
// vertices and figures; only the moving body has kinetic energy.
TEST(ViewerLogic, BodyTableHasARowPerBodyWithItsOwnFigures) {
  const BuiltScene built = buildScene(parseScene(R"({"bodies": [{"name": "still", "shape": "sphere", "size": 6},
      {"shape": "box", "size": 3, "position": [0.2, 0, 0], "velocity": [0, 2, 0]}],
      "simulation": {"gravity": [0, 0, 0]}})",
                                                 "two"));
  const std::vector<BodyRow> rows = bodyTable(built);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].name, "still");
  EXPECT_EQ(rows[1].name, "body1");
  EXPECT_EQ(rows[0].vertices, built.range(0).numVertices());
  EXPECT_EQ(rows[1].vertices, built.range(1).numVertices());
  EXPECT_NE(rows[0].vertices, rows[1].vertices);
  EXPECT_EQ(rows[1].elements, built.range(1).numElements());
  EXPECT_LT(rows[0].kineticEnergy, 1e-20);  // at rest (metrics take the half-step velocity: ~1e-30 J)
  EXPECT_NEAR(rows[1].kineticEnergy, 0.5 * rows[1].mass * 4, 1e-12);  // 1/2 m v^2 at 2 m/s
  EXPECT_NEAR(rows[1].velocity.y(), 2, 1e-12);
  EXPECT_GT(rows[1].centre.x(), 0.2);
  EXPECT_LT(rows[0].centre.x(), 0.1);
  // One body: one row, the whole model.
  const BuiltScene one = buildScene(parseScene(R"({"body": {"shape": "sphere", "size": 6}})", "one"));
  ASSERT_EQ(bodyTable(one).size(), 1u);
  EXPECT_EQ(bodyTable(one)[0].vertices, one.world->model().numVertices());
}

// The viewer's drag (render/manipulator_drag.h) with two bodies: a manipulator picked at its
// pixel and dragged, frame by frame as the viewer feeds it, into body 1 pushes body 1 (which
// was at rest) and leaves body 0 alone: the drag moves a manipulator, whose contacts see every
// body's vertices.
TEST(ViewerLogic, DraggedManipulatorPushesWhicheverBodyItMeets) {
  BuiltScene built = buildScene(parseScene(R"({"bodies": [
      {"shape": "sphere", "size": 8, "position": [-0.15, 0, 0]},
      {"shape": "sphere", "size": 8, "position": [0.15, 0, 0]}],
      "simulation": {"gravity": [0, 0, 0], "damping": 0},
      "manipulators": [{"type": "sphere", "radius": 0.02, "path": [{"t": 0, "position": [0.19, 0.2, 0.04]}]}]})",
                                           "drag"));
  World& w = *built.world;
  Camera cam;  // looking down -z at the scene
  cam.yaw = 0, cam.pitch = 0, cam.target = Vec3(0, 0.1, 0), cam.distance = 0.8;
  const Vec3 at = cam.project(w.manipulators()[0].position, kW, kH);
  ASSERT_EQ(pickManipulator(cam, w, at.x(), at.y(), kW, kH), std::optional<size_t>(0));
  ManipulatorDrag drag = grabManipulator(cam, w, 0, at.x(), at.y(), kW, kH);
  EXPECT_TRUE(w.manipulators()[0].settings.path.keys.empty());  // the user's now
  // Down through body 1 (centre (0.19, 0.04, 0.04) at rest), in frames of 1/60 s.
  const Vec3 target = cam.project(Vec3(0.19, -0.1, 0.04), kW, kH);
  const double frame = 1.0 / 60;
  auto momentum = [&](size_t b) {
    Vec3 p = Vec3::Zero();
    for (uint32_t v = built.range(b).vertexBegin; v < built.range(b).vertexEnd; ++v)
      p += w.model().mass[v] * w.state().velocities[v];
    return p;
  };
  for (int f = 1; f <= 20; ++f) {
    drag.from = drag.to;
    dragInPlane(cam, drag, at.x() + (target.x() - at.x()) * f / 20, at.y() + (target.y() - at.y()) * f / 20, kW, kH);
    const int steps = int(std::ceil(frame / w.dt()));
    for (int k = 0; k < steps; ++k) feedDrag(w, drag, double(k + 1) / steps, frame), w.step();
  }
  EXPECT_LT(momentum(1).y(), -1e-4) << momentum(1).transpose();     // body 1 pushed down
  EXPECT_LT(momentum(0).norm(), 1e-12) << momentum(0).transpose();  // body 0 untouched
  EXPECT_NEAR(w.manipulators()[0].position.y(), -0.1, 0.01);
}

TEST(RenderHeadless, CliWritesPngFramesThatShowTheBody) {
  const fs::path out = fs::temp_directory_path() / ("gradel-render-test-" + std::to_string(::getpid()));
  fs::remove_all(out);
  const std::string cmd = std::string(GRADEL_CLI_PATH) + " render " + GRADEL_SOURCE_DIR +
                          "/scenes/strike.json --frames 3 --size 200x150 --stress --export obj --no-video --out " +
                          out.string() + " > /dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  for (int f = 0; f < 3; ++f) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.png", f);
    const Image img = readPng((out / name).string());
    EXPECT_EQ(img.width, 200);
    EXPECT_EQ(img.height, 150);
    // The body (warm colours: red well above blue) covers a real part of the picture.
    int body = 0;
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x)
        if (img.pixel(x, y)[0] > img.pixel(x, y)[2] + 40) ++body;
    EXPECT_GT(body, 300) << name;
    std::snprintf(name, sizeof name, "surface_%05d.obj", f);
    EXPECT_GT(fs::file_size(out / name), 1000u);
  }
  EXPECT_TRUE(fs::exists(out / "render.json"));
  fs::remove_all(out);
}

TEST(ViewerWindow, ScreenshotShowsBodyAndPanel) {
  ASSERT_NE(std::getenv("DISPLAY"), nullptr) << "run under xvfb-run";
  const fs::path shot = fs::temp_directory_path() / ("gradel-view-test-" + std::to_string(::getpid()) + ".png");
  const std::string cmd = std::string(GRADEL_VIEW_PATH) + " " + GRADEL_SOURCE_DIR +
                          "/scenes/grasp-two.json --size 640x480 --screenshot " + shot.string() +
                          " --screenshot-time 0.3 > /dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const Image img = readPng(shot.string());
  EXPECT_EQ(img.width, 640);
  EXPECT_EQ(img.height, 480);
  int body = 0, panel = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const uint8_t* p = img.pixel(x, y);
      if (p[0] > p[2] + 40) ++body;
      if (x < 300 && y < 200 && p[0] < 60 && p[1] < 60 && p[2] < 60) ++panel;  // the panel's text
    }
  EXPECT_GT(body, 1000) << "the body is visible";
  EXPECT_GT(panel, 100) << "the ImGui panel is drawn";
  fs::remove(shot);
}

// The viewer's screenshot of `scene` at `time` [s] (its run JSON, the picture, counted body
// pixels: red over blue by > 40), the files removed after.
struct ViewerShot {
  std::string json;
  int bodyPixels = 0;
  double number(const std::string& key) const {
    const size_t at = json.find("\"" + key + "\":");
    EXPECT_NE(at, std::string::npos) << key << " in " << json;
    return at == std::string::npos ? -1.0 : std::stod(json.substr(at + key.size() + 3));
  }
};

ViewerShot viewerShot(const std::string& scene, const char* time) {
  const fs::path base = fs::temp_directory_path() / ("gradel-view-" + scene + "-" + std::to_string(::getpid()));
  const std::string cmd = std::string(GRADEL_VIEW_PATH) + " " + GRADEL_SOURCE_DIR + "/scenes/" + scene +
                          ".json --size 480x360 --screenshot " + base.string() + ".png --screenshot-time " + time +
                          " > " + base.string() + ".json";
  ViewerShot shot;
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::ifstream in(base.string() + ".json");
  std::stringstream text;
  text << in.rdbuf();
  shot.json = text.str();
  const Image img = readPng(base.string() + ".png");
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      if (img.pixel(x, y)[0] > img.pixel(x, y)[2] + 40) ++shot.bodyPixels;
  fs::remove(base.string() + ".png"), fs::remove(base.string() + ".json");
  return shot;
}

// The viewer carves (issue 30): scenes/drill.json's burr ("carve": true) drills into the block
// in the viewer as in `gradel run` (296 voxels by t = 0.6 s there, per chunk of steps; the
// viewer carves after each batch), the body is laid out again (its vertex count changes) and
// the carved body is drawn.
TEST(ViewerWindow, DrillSceneCarvesTheBlock) {
  ASSERT_NE(std::getenv("DISPLAY"), nullptr) << "run under xvfb-run";
  const ViewerShot shot = viewerShot("drill", "0.6");
  const double carved = shot.number("carved_voxels"), vertices = shot.number("vertices");
  EXPECT_GT(carved, 200) << shot.json;  // the burr's path into the block: ~300 voxels
  EXPECT_LT(carved, 450) << shot.json;
  EXPECT_GT(vertices, 703) << shot.json;  // the uncarved block has 703: small elements line the hole
  EXPECT_GT(shot.bodyPixels, 1000) << "the carved body is drawn";
}

// The viewer follows a body cut into pieces (issue 30): scenes/cut.json's blade cuts the held bar
// in two by t = 0.45 s; at 0.8 s the viewer has two bodies, the 36 voxels of the kerf carved, and
// draws the blade and both halves.
TEST(ViewerWindow, CutSceneShowsTwoBodies) {
  ASSERT_NE(std::getenv("DISPLAY"), nullptr) << "run under xvfb-run";
  const ViewerShot shot = viewerShot("cut", "0.8");
  EXPECT_EQ(shot.number("bodies"), 2) << shot.json;
  EXPECT_EQ(shot.number("carved_voxels"), 36) << shot.json;
  EXPECT_GT(shot.bodyPixels, 500) << "the halves are drawn";
}

// The picture of docs/layout.md (materials per region): a 2D block of tissue (label 1) with a
// round inclusion (label 2). Pure pixels, no OpenGL. With GRADEL_DOC_IMAGES=DIR set it also
// writes DIR/layout-regions.png (the committed docs/img/layout-regions.png).
TEST(LayoutPicture, TwoLabelsShowOneColourPerElementAndTheirBorder) {
  ShapeSpec s;
  s.dim = 2;
  s.dims = {48, 32, 1};
  Primitive tissue, inclusion;
  tissue.kind = PrimitiveKind::Box;
  tissue.max = Vec3(48, 32, 1);
  inclusion.kind = PrimitiveKind::Sphere;
  inclusion.center = Vec3(21, 15, 0);
  inclusion.radius = 9.5;
  inclusion.label = 2;
  s.primitives = {tissue, inclusion};
  const VoxelVolume v = rasterize(s);
  const Layout L = buildLayout(v, LayoutKind::Gradational);
  const int p = 12;
  const Image img = layoutPicture(L, 0, p);
  ASSERT_EQ(img.width, 50 * p);
  ASSERT_EQ(img.height, 34 * p);
  // The centre pixel of voxel (x, y): y up, one voxel of margin.
  auto centre = [&](int x, int y) { return img.pixel((x + 1) * p + p / 2, img.height - 1 - ((y + 1) * p + p / 2)); };
  EXPECT_GT(centre(21, 15)[2], centre(21, 15)[0]);  // label 2: blue
  EXPECT_GT(centre(40, 28)[0], centre(40, 28)[2]);  // label 1: red
  // Along the row y = 15, from the inclusion's centre outwards: a black line two pixels wide on
  // each side where the labels meet (before the first voxel of label 1).
  int first = 21;
  while (v.label(first, 15, 0) == 2) ++first;
  const int edge = (first + 1) * p, row = img.height - 1 - ((15 + 1) * p + p / 2);
  for (int dx : {-2, -1, 0, 1}) {
    const uint8_t* q = img.pixel(edge + dx, row);
    EXPECT_EQ(q[0] + q[1] + q[2], 0) << dx;
  }
  // Every voxel of an element has the element's colour at its centre.
  for (size_t e = 0; e < L.numElements(); ++e) {
    const int c = L.cellSize[e];
    const uint8_t* ref = nullptr;
    for (int bit = 0; bit < 4; ++bit) {
      if (!(L.cellMask[e] >> bit & 1)) continue;
      for (int y = L.origin[e].y() + (bit >> 1) * c; y < L.origin[e].y() + (bit >> 1) * c + c; ++y)
        for (int x = L.origin[e].x() + (bit & 1) * c; x < L.origin[e].x() + (bit & 1) * c + c; ++x) {
          if (!ref) ref = centre(x, y);
          EXPECT_TRUE(std::equal(ref, ref + 3, centre(x, y))) << "element " << e << " voxel " << x << "," << y;
        }
    }
  }
  if (const char* dir = std::getenv("GRADEL_DOC_IMAGES"))
    writePng((fs::path(dir) / "layout-regions.png").string(), img);
}

}  // namespace
}  // namespace gradel::render
