// The page's view of gradel (issue 14), bound to JavaScript with embind: one Demo holds a built
// scene (scene.h), its body view (render/draw_list.h) and an orbit camera (render/camera.h), and
// does what gradel-view does per frame: steps the world as many times as real time needs within
// a wall-time budget, moves a dragged manipulator along the mouse with the drag's velocity, and
// builds the same draw list (smooth surface, stress colour and legend, level wireframe,
// manipulators, walls) as plain float arrays that app.js hands to WebGL2.
// bench() measures the paper's Table 1 setting exactly as gradel-bench does (bench/).
#include <emscripten/bind.h>
#include <emscripten/emscripten.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "gradel/divergence.h"
#include "gradel/render/camera.h"
#include "gradel/render/draw_list.h"
#include "gradel/render/manipulator_drag.h"
#include "gradel/scene.h"
#include "gradel/shared/scene_presets.h"
#include "gradel/shared/step_batch.h"

namespace {

using namespace gradel;
using namespace gradel::render;
using emscripten::val;

constexpr double kMaxFrameSeconds = 0.1;  // longer frames (tab in the background) are not caught up

double nowMs() { return emscripten_get_now(); }

val floats(const std::vector<DrawVertex>& v) {
  static_assert(sizeof(DrawVertex) == 10 * sizeof(float));
  return val(emscripten::typed_memory_view(v.size() * 10, reinterpret_cast<const float*>(v.data())));
}

class Demo {
 public:
  /// Loads a scene from JSON text; returns "" or the InputError's message (the scene is kept).
  std::string load(const std::string& json, const std::string& name) {
    try {
      Scene s = parseScene(json, name);
      BuiltScene b = buildScene(s);
      scene_ = s;
      original_ = std::move(s);
      install(std::move(b));
      const VoxelVolume& v = built_.bodies[0].volume;
      bodyExtent_ = v.voxelSize() * std::max(v.nx(), v.ny());
      return "";
    } catch (const std::exception& e) {
      return e.what();
    }
  }

  /// A preset shape of `size` voxels and the same physical size replaces the body (the viewer's
  /// "Body" controls); manipulators the user moved keep their place.
  std::string setBody(const std::string& shape, int size, const std::string& layout) {
    try {
      Scene s = scene_;
      s.bodies[0].shape = presetShape(shape, size, s.dim, bodyExtent_ / size);
      s.bodies[0].source = nullptr;
      s.bodies[0].layout = parseLayoutKind(layout);
      keepManipulatorPoses(*built_.world, s);
      install(buildScene(s));
      scene_ = std::move(s);
      return "";
    } catch (const std::exception& e) {
      return e.what();
    }
  }

  void reset() {
    scene_ = original_;
    install(buildScene(scene_));
  }

  /// Advances the world by `frameSeconds` of wall time (times `speed`) in whole steps, within
  /// `budgetMs` of wall time; returns the number of steps taken. behind() tells whether the
  /// budget cut the frame short.
  int advance(double frameSeconds, double budgetMs, double speed) {
    World& w = *built_.world;
    const double want = std::clamp(frameSeconds, 0.0, kMaxFrameSeconds) * speed;
    StepBatchOptions options;
    options.budgetSeconds = budgetMs / 1000;
    if (drag_) options.beforeStep = [&](double fraction) { feedDrag(w, *drag_, fraction, want); };
    const StepBatch b = stepBatch(w, stepsFor(want, w.dt()), options);
    behind_ = b.cut;
    if (b.cut && drag_) feedDrag(w, *drag_, 1.0, want);
    if (drag_) drag_->from = drag_->to;
    if (!b.finite) {
      diverged_ = true;
      install(buildScene(scene_));
    }
    return int(b.steps);
  }

  // ---- drawing ----
  void setView(int surface, bool stress, bool wireframe, double stressScale) {
    view_.surface = surface == 1 ? SurfaceMode::Voxel : surface == 2 ? SurfaceMode::None : SurfaceMode::Smooth;
    view_.stress = stress;
    view_.wireframe = wireframe;
    view_.stressScale = stressScale;
  }
  /// Builds this frame's draw list for a width x height (CSS pixels) canvas; with follow on, the
  /// camera first moves with the bodies (render/camera.h CameraFollow, as gradel-view's).
  void buildFrame(int width, int height) {
    if (follow_) {
      const std::vector<Vec3>& x = built_.world->state().positions;
      if (!x.empty()) {
        Vec3 lo = x.front(), hi = lo;
        for (const Vec3& p : x) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
        followState_.update(camera_, lo, hi, mode_ == Mode::Drag);
      }
    }
    list_ = buildDrawList(body_, *built_.world, view_, width, height);
  }
  /// The camera follows the bodies (on by default, as in gradel-view).
  void setFollow(bool on) {
    follow_ = on;
    followState_.reset();
  }
  val triangles() const { return floats(list_.triangles); }  ///< 10 floats a vertex: position, normal, RGBA.
  val lines() const { return floats(list_.lines); }
  val overlay() const { return floats(list_.overlay); }  ///< Pixels, y down.
  val background() const { return floatArray(list_.background.data(), 3); }
  /// Column-major projection * view for the canvas aspect, and the light direction (renderer.cpp's).
  val viewProjection(int width, int height) const {
    const Mat4f m = camera_.projection(Real(width) / std::max(height, 1)) * camera_.view();
    return floatArray(m.data(), 16);
  }
  val light() const {
    const Vec3 l = ((camera_.eye() - camera_.target).normalized() * 0.8 + camera_.up() * 0.45 + camera_.right() * 0.3)
                       .normalized();
    const float f[3] = {float(l.x()), float(l.y()), float(l.z())};
    return floatArray(f, 3);
  }

  // ---- mouse (CSS pixels, y down) ----
  /// Left button: grabs the manipulator under the cursor (true) or starts an orbit; other
  /// buttons pan.
  bool pointerDown(double x, double y, int button, int width, int height) {
    lastX_ = x, lastY_ = y;
    if (button != 0) return mode_ = Mode::Pan, false;
    if (const std::optional<size_t> m = pickManipulator(camera_, *built_.world, x, y, width, height)) {
      drag_ = grabManipulator(camera_, *built_.world, *m, x, y, width, height);
      mode_ = Mode::Drag;
      return true;
    }
    mode_ = Mode::Orbit;
    return false;
  }
  void pointerMove(double x, double y, bool depth, int width, int height) {
    const double dx = x - lastX_, dy = y - lastY_;
    lastX_ = x, lastY_ = y;
    if (mode_ == Mode::Orbit) camera_.orbit(dx, dy);
    if (mode_ == Mode::Pan) camera_.pan(dx, dy, height);
    if (mode_ != Mode::Drag || !drag_) return;
    if (depth && !camera_.flat) return dragInDepth(camera_, *drag_, -dy * pixelSize(camera_, height));
    dragInPlane(camera_, *drag_, x, y, width, height);
  }
  void pointerUp() {
    drag_.reset();
    mode_ = Mode::None;
  }
  /// Wheel: zooms, or moves a held manipulator towards / away from the camera.
  void wheel(double steps, int height) {
    if (mode_ == Mode::Drag && drag_ && !camera_.flat)
      return dragInDepth(camera_, *drag_, steps * 10 * pixelSize(camera_, height));
    camera_.zoom(steps);
  }
  /// Frames the scene, its centre moved `panX` CSS pixels right (beside the page's panel).
  void reframe(double panX, int height) {
    Vec3 lo, hi;
    sceneBounds(*built_.world, &lo, &hi);
    camera_ = frameBox(lo, hi, scene_.dim == 2);
    camera_.pan(panX, 0, std::max(height, 1));
    followState_.reset();
  }
  bool dragging() const { return drag_.has_value(); }
  int manipulators() const { return int(built_.world->manipulators().size()); }
  /// Centre of manipulator i [m], and where it is on a width x height canvas (CSS pixels, y down).
  val manipulatorPosition(int i) const {
    const Vec3 p = built_.world->manipulators().at(size_t(i)).position;
    const float f[3] = {float(p.x()), float(p.y()), float(p.z())};
    return floatArray(f, 3);
  }
  val manipulatorPixel(int i, int width, int height) const {
    const Vec3 q = camera_.project(built_.world->manipulators().at(size_t(i)).position, width, height);
    const float f[2] = {float(q.x()), float(q.y())};
    return floatArray(f, 2);
  }

  // ---- live figures ----
  double time() const { return built_.world->time(); }
  double dt() const { return built_.world->dt(); }
  int elements() const { return int(built_.world->model().numElements()); }
  int vertices() const { return int(built_.world->model().numVertices()); }
  int levels() const { return body_.levels; }
  bool behind() const { return behind_; }
  bool takeDiverged() { return std::exchange(diverged_, false); }
  /// [Pa] the largest von Mises stress of the elements (World::elementStress).
  double maxStress() const {
    const std::vector<Real> s = built_.world->elementStress();
    return s.empty() ? 0.0 : *std::max_element(s.begin(), s.end());
  }
  /// maxStress() as the legend writes it ("12.5 kPa").
  std::string maxStressText() const { return pascalText(maxStress()); }
  /// Mass-weighted centre of the body [m].
  val centreOfMass() const {
    const World& w = *built_.world;
    Vec3 c = Vec3::Zero();
    Real m = 0;
    for (size_t i = 0; i < w.state().positions.size(); ++i)
      c += w.model().mass[i] * w.state().positions[i], m += w.model().mass[i];
    c /= std::max(m, Real(1e-30));
    const float f[3] = {float(c.x()), float(c.y()), float(c.z())};
    return floatArray(f, 3);
  }
  bool finite() const { return finiteState(built_.world->state()); }

 private:
  enum class Mode { None, Orbit, Pan, Drag };
  static val floatArray(const float* f, int n) {
    val a = val::global("Float32Array").new_(n);
    for (int i = 0; i < n; ++i) a.set(i, f[i]);
    return a;
  }

  void install(BuiltScene b) {
    built_ = std::move(b);
    body_ = makeBodyView(built_);
    drag_.reset();
    if (mode_ == Mode::Drag) mode_ = Mode::None;
    followState_.reset();
  }

  Scene scene_, original_;
  BuiltScene built_;
  BodyView body_;
  DrawList list_;
  Camera camera_;
  CameraFollow followState_;
  bool follow_ = true;
  ViewOptions view_;
  std::optional<ManipulatorDrag> drag_;
  Mode mode_ = Mode::None;
  double lastX_ = 0, lastY_ = 0;
  bool behind_ = false, diverged_ = false;
  Real bodyExtent_ = 0.12;
};

/// One row of gradel-bench's CSV (same columns, same measurement: the paper's Table 1 setting,
/// 20 steps, then the median over `reps` repetitions of at least `minTime` seconds each).
std::string bench(const std::string& shape, int n, const std::string& layoutName, int reps, double minTime) {
  const LayoutKind layout = parseLayoutKind(layoutName);
  BuiltScene b = buildScene(paperBenchScene(shape, n, layout, 1));
  World& w = *b.world;
  preparePaperBench(w);
  for (int i = 0; i < 20; ++i) w.step();
  const uint64_t hash = w.stateHash();
  int steps = 1;
  for (;;) {
    const double t0 = nowMs();
    for (int i = 0; i < steps; ++i) w.step();
    const double s = (nowMs() - t0) / 1e3;
    if (s >= 0.25 * minTime || steps >= (1 << 20)) {
      steps = std::max(1, int(steps * minTime / std::max(s, 1e-9)));
      break;
    }
    steps *= 4;
  }
  std::vector<double> perStep;
  for (int k = 0; k < reps; ++k) {
    const double t0 = nowMs();
    for (int i = 0; i < steps; ++i) w.step();
    perStep.push_back((nowMs() - t0) / 1e3 / steps);
  }
  std::sort(perStep.begin(), perStep.end());
  const double t = perStep[perStep.size() / 2];
  const RestModel& m = w.model();
  char row[512];
  std::snprintf(row, sizeof row, "%s,%d,%s,1,%zu,%zu,%zu,%.3f,%.3f,%.1f,%.6g,%.4g,%.1f,%016llx", shape.c_str(), n,
                layoutKindName(layout), m.numElements(), m.numVertices(), m.numPairs(),
                t * 1e9 / double(m.numVertices()), t * 1e9 / double(m.numPairs()), 1 / t, w.dt(), w.dt() / t,
                double(w.memoryBytes()) / double(m.numVertices()), static_cast<unsigned long long>(hash));
  return row;
}

}  // namespace

EMSCRIPTEN_BINDINGS(gradel) {
  using emscripten::class_;
  using emscripten::function;
  class_<Demo>("Demo")
      .constructor<>()
      .function("load", &Demo::load)
      .function("setBody", &Demo::setBody)
      .function("reset", &Demo::reset)
      .function("advance", &Demo::advance)
      .function("setView", &Demo::setView)
      .function("buildFrame", &Demo::buildFrame)
      .function("triangles", &Demo::triangles)
      .function("lines", &Demo::lines)
      .function("overlay", &Demo::overlay)
      .function("background", &Demo::background)
      .function("viewProjection", &Demo::viewProjection)
      .function("light", &Demo::light)
      .function("pointerDown", &Demo::pointerDown)
      .function("pointerMove", &Demo::pointerMove)
      .function("pointerUp", &Demo::pointerUp)
      .function("wheel", &Demo::wheel)
      .function("reframe", &Demo::reframe)
      .function("dragging", &Demo::dragging)
      .function("manipulators", &Demo::manipulators)
      .function("manipulatorPosition", &Demo::manipulatorPosition)
      .function("manipulatorPixel", &Demo::manipulatorPixel)
      .function("time", &Demo::time)
      .function("dt", &Demo::dt)
      .function("elements", &Demo::elements)
      .function("vertices", &Demo::vertices)
      .function("levels", &Demo::levels)
      .function("behind", &Demo::behind)
      .function("takeDiverged", &Demo::takeDiverged)
      .function("maxStress", &Demo::maxStress)
      .function("maxStressText", &Demo::maxStressText)
      .function("setFollow", &Demo::setFollow)
      .function("centreOfMass", &Demo::centreOfMass)
      .function("finite", &Demo::finite);
  function("bench", &bench);
  // The CSV header of bench() rows (gradel-bench's).
  function("benchHeader", emscripten::optional_override([]() -> std::string {
             return "shape,n,layout,threads,elements,unique_vertices,pairs,ns_per_vertex_step,ns_per_pair_step,"
                    "steps_per_second,dt_s,real_time_factor,bytes_per_vertex,state_hash";
           }));
}
