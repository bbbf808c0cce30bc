// gradel-view: the interactive viewer (GLFW + OpenGL 3.3 core + Dear ImGui).
//   gradel-view [SCENE.json] [--size WxH] [--screenshot FILE] [--run-for S]
// Mouse: left-drag a manipulator to move it in the plane facing the camera (wheel or
// Shift+drag: towards / away from the camera); left-drag elsewhere orbits, right- or
// middle-drag pans, the wheel zooms. 2D scenes are shown flat.
// The simulation steps on its own thread, paced to real time (shared/step_pacer.h) in short
// batches, so drawing and the panel never wait for it; it says so on screen when it cannot keep
// up. A rebuild (a new size, shape, material ...) runs on a background thread with its progress
// shown; a size estimated below 0.1x real time is flagged before it is built (shared/realtime_size.h).
// A body whose smooth surface is over the display budget (render/display_budget.h) is drawn with
// a coarser embedded isosurface, so a frame's drawing stays bounded at any size.
// Frames are capped at 60 per second; no multisampling on a software OpenGL (llvmpipe).
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <deque>
#include <filesystem>
#include <iostream>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "gradel/carve_scene.h"
#include "gradel/divergence.h"
#include "gradel/render/body_table.h"
#include "gradel/render/display_budget.h"
#include "gradel/render/draw_list.h"
#include "gradel/render/manipulator_drag.h"
#include "gradel/render/render_command.h"
#include "gradel/render/renderer.h"
#include "gradel/scene.h"
#include "gradel/shared/rate_window.h"
#include "gradel/shared/realtime_size.h"
#include "gradel/shared/step_batch.h"
#include "gradel/shared/step_pacer.h"

namespace {

using namespace gradel;
using namespace gradel::render;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// [s] CPU time of the calling thread, and of the whole process (all threads: drawing, stepping
// and the OpenGL driver's).
double threadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}
double loadAverage() {
  double l[1] = {0};
  return getloadavg(l, 1) == 1 ? l[0] : -1.0;
}
double processCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

// The default scene: the paper's 12^3 sphere on the floor and one free sphere manipulator
// beside it, ready to be grabbed. Symplectic Euler, not "auto": the viewer does not let a cost
// estimate switch its sphere to the large step (at sizes 32 and up "auto" took the large step
// at 0.002-0.07x real time where the explicit step runs several times faster; issue 25). The
// integrator box offers "auto" and the others.
constexpr const char* kPlayScene = R"({
  "name": "play",
  "dim": 3,
  "body": { "shape": "sphere", "size": 12, "voxel_size": 0.01, "layout": "gradational", "position": [0, 0, 0] },
  "material": { "scaling": "consistent", "youngs_modulus": 1e5, "density": 1000 },
  "simulation": { "integrator": "symplectic", "dt": "auto", "dt_period": "operator", "damping": 1.0,
                  "gravity": [0, -9.81, 0] },
  "domain": { "min": [-0.3, 0.0, -0.3], "max": [0.4, 0.5, 0.4], "restitution": 0.3, "friction": 0.5 },
  "manipulators": [ { "type": "sphere", "radius": 0.03, "restitution": 0.5, "friction": 0.5,
                      "path": [ { "t": 0, "position": [-0.1, 0.06, 0.06] } ] } ]
})";

constexpr double kFrameSeconds = 1.0 / 60;  // [s] the frame cap
constexpr double kMaxFramePeriod = 0.1;     // [s] the longest wait the CPU budget makes a frame
constexpr double kDrawCores = 1.0;          // cores the drawing may use on average (the stepping has the rest)
constexpr double kSlowFactor = 0.1;         // sizes estimated below this real-time factor are flagged
constexpr int kMinBodySize = 4, kMaxBodySize = 256;
constexpr float kPanelWidth = 330;  // [pixels] the settings panel at the left

fs::path scenesDir() {
  for (const fs::path& p : {fs::path("scenes"), fs::path(GRADEL_SOURCE_DIR) / "scenes"})
    if (fs::is_directory(p)) return p;
  return fs::path("scenes");
}

struct Options {
  std::string scene;
  std::string size = "1280x800";
  std::string screenshot;
  double runFor = 0;             // [s] wall; 0 = until the window closes
  double screenshotTime = 0.15;  // [s] simulated before the screenshot
  int bodySize = 0;              // the first body's size [voxels] as the panel sets it (0 = the scene's)
  int rebuildSize = 0;           // with --run-for: ask for this size as the panel would ...
  double rebuildAt = 1.0;        // ... at this wall time [s]
  bool fullSurface = false;      // the panel's "full-resolution surface" on from the start
  bool framePieces = false;      // no window: time the frame loop's CPU pieces and exit
};

// Frame times [s] of a timing run (--run-for): their median and maximum, and the longest frame
// while a rebuild ran.
struct FrameTimes {
  // frame to frame; a frame's own work (events, panel, drawing), cap excluded; the world held
  std::vector<double> all, work, worldHeld;
  double longestDuringRebuild = 0;
  static double median(std::vector<double> v) {
    if (v.empty()) return 0;
    std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
    return v[v.size() / 2];
  }
  double longest() const { return all.empty() ? 0 : *std::max_element(all.begin(), all.end()); }
};

// A titled separator (ImGui 1.86 has no SeparatorText).
void section(const char* title) {
  ImGui::Separator();
  ImGui::TextDisabled("%s", title);
}

// The figures the panel shows, copied from the world once a frame (the stepping thread owns it
// between frames).
struct Figures {
  double time = 0, dt = 0;
  double maxStress = 0;    // [Pa] von Mises (World::elementStress)
  double stressAt = -1e9;  // [s] wall time maxStress was taken (the stress costs a pass over the elements)
  std::string integrator, choice, dtRule;
  size_t elements = 0, vertices = 0, pairs = 0;
  size_t bodyCount = 1;  // changes when carving cuts a body into pieces (carve_scene.h)
  std::vector<BodyRow> bodies;
  std::vector<std::pair<Vec3, Vec3>> bounds;  // per body: lowest and highest vertex
  // Carving (issue 30): voxels removed and events since the world was installed, the last event's wall time.
  size_t carvedVoxels = 0, carveEvents = 0;
  double carveLastSeconds = 0;
};

// A world being built on a background thread, and what the panel asked for.
struct Rebuild {
  Scene scene;
  bool load = false;          // a new scene: camera, surface mode and body edits start afresh
  bool reframe = false;       // frame the camera on it
  std::string what;           // shown while it builds, e.g. "size 128"
  double start = 0;           // [s] wall
  std::atomic<int> phase{0};  // 0 volume + layout + model + world, 1 display surfaces, 2 done
  std::optional<BuiltScene> built;
  std::optional<BodyView> view;
  std::string error;
  std::thread thread;
};

class Viewer {
 public:
  /// `threaded`: the simulation steps on its own thread paced to real time; otherwise each
  /// frame advances a fixed 1/60 s (screenshots: the picture does not depend on the machine).
  /// `bodySize` > 0: body 0 at that size, as the panel's slider sets it.
  Viewer(GLFWwindow* window, Scene scene, bool threaded, Clock::time_point start, int bodySize)
      : window_(window), start_(start) {
    BuiltScene built = buildScene(scene);
    BodyView view = makeBodyView(built, nullptr, kDisplayTriangleBudget);
    install(std::move(scene), std::move(built), std::move(view), true, true);
    if (bodySize > 0) {
      resizeBody(0, bodySize);
      built = buildScene(scene_);
      view = makeBodyView(built, nullptr, kDisplayTriangleBudget);
      install(scene_, std::move(built), std::move(view), false, true);
    }
    if (threaded) stepper_ = std::thread([this] { stepLoop(); });
  }

  ~Viewer() {
    quit_ = true;
    if (stepper_.joinable()) stepper_.join();
    if (rebuild_ && rebuild_->thread.joinable()) rebuild_->thread.join();
  }

  double wallNow() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

  // The viewer's state (everything but the world): held briefly by the stepping thread.
  std::unique_lock<std::mutex> lockState() { return std::unique_lock<std::mutex>(stateMutex_); }

  // The world, for the drawing thread (with the state lock held): the stepping thread lets it in
  // at its next batch (within its 4 ms budget, or one step when a step takes longer); when that
  // is more than 40 ms away (one long step: the large step, a large body) this gives up and the
  // frame shows the last picture instead of waiting.
  std::unique_lock<std::timed_mutex> tryWorld() {
    const double wait = std::clamp(1.5 * pacer_.secondsPerStep(), 0.008, 0.040);
    ++drawWaiting_;
    std::unique_lock<std::timed_mutex> lock(worldMutex_, std::defer_lock);
    (void)lock.try_lock_for(std::chrono::duration<double>(wait));
    --drawWaiting_;
    return lock;
  }

  // One frame's work, under the state lock: a finished rebuild is swapped in; when the world is
  // free the figures and the draw list are taken from it (else the last ones are shown); the
  // panel runs. Drawing happens after, without the locks.
  void frame(int width, int height) {
    const double now = wallNow();
    std::unique_lock<std::mutex> state = lockState();
    finishRebuild(now);
    if (diverged_) {
      diverged_ = false;
      status_ = "simulation diverged; reset";
      requestRebuild(builtScene_, false, false, "reset");
    }
    if (loopDue_ && !rebuild_) {
      loopDue_ = false;
      requestRebuild(builtScene_, false, false, "loop");
    }
    std::unique_lock<std::timed_mutex> world = tryWorld();
    if (world.owns_lock()) {
      advanceByFrame();
      refresh(now, width, height);
      world.unlock();
      worldHeldSeconds_ = wallNow() - now;
    } else {
      worldHeldSeconds_ = 0;
    }
    rates_.add(now, simTime_, steps_);  // every frame, also when the world was busy
    panel(now);
  }

  // Without the stepping thread (screenshots) a fixed 1/60 s of simulated time a frame; the
  // Step button's single step (both locks held).
  void advanceByFrame() {
    World& w = *built_.world;
    if (!stepper_.joinable() && !paused_ && !rebuild_) {  // fixed 1/60 s of simulated time a frame
      const long n = stepsFor(kFrameSeconds * speed_, w.dt());
      for (long k = 0; k < n && finiteState(w.state()); ++k) w.step();
      steps_ += n;
      if (finiteState(w.state()))
        noteCarving(carveAfterBatch(n, carveMode_ && drag_ ? std::optional<size_t>(drag_->index) : std::nullopt));
    }
    if (stepOnce_ && !rebuild_) {
      w.step();
      ++steps_;
      stepOnce_ = false;
    }
  }

  // The figures and the draw list from the world (both locks held).
  void refresh(double now, int width, int height) {
    World& w = *built_.world;
    if (carvedView_) body_ = std::move(*carvedView_), carvedView_.reset();  // before anything draws the carved model
    figures_.time = w.time(), figures_.dt = w.dt();
    figures_.integrator = integratorKindName(w.settings().integrator);
    figures_.choice = w.integratorChoice();
    figures_.dtRule = w.dtRule();
    figures_.elements = w.model().numElements(), figures_.vertices = w.model().numVertices();
    figures_.bodyCount = built_.numBodies();
    figures_.pairs = w.model().numPairs();
    // The stress: per vertex for the colour (every frame it is shown). Its maximum and the body
    // table's figures (each a pass over the elements: 6-7 ms of CPU at size 128) are taken four
    // times a second by the stepping thread after a batch (stressFigures); here only when that
    // thread has not for a second (paused, a new world, screenshots without it).
    std::vector<Real> vertexStress;
    if (view_.stress) {
      const std::vector<Real> es = w.elementStress();
      figures_.maxStress = es.empty() ? 0.0 : *std::max_element(es.begin(), es.end());
      vertexStress = w.vertexStress(es);
    }
    const double due = stepper_.joinable() && !paused_ ? 1.0 : 0.25;
    if (now - figures_.stressAt >= due || now < figures_.stressAt) {
      StressFigures sf = stressFigures(w, now);
      figures_.maxStress = sf.maxStress, figures_.stressAt = sf.at, figures_.bodies = std::move(sf.bodies);
      stressAt_ = sf.at;
    }
    figures_.bounds.clear();
    for (size_t b = 0; b < built_.numBodies(); ++b) {
      const BodyRange& range = built_.range(b);
      const std::vector<Vec3>& x = w.state().positions;
      Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
      if (range.vertexEnd > range.vertexBegin) lo = hi = x[range.vertexBegin];
      for (uint32_t i = range.vertexBegin; i < range.vertexEnd; ++i) lo = lo.cwiseMin(x[i]), hi = hi.cwiseMax(x[i]);
      figures_.bounds.push_back({lo, hi});
    }
    simTime_ = w.time();
    if (follow_ && !figures_.bounds.empty()) {  // the camera keeps the bodies where they were on screen
      Vec3 lo = figures_.bounds[0].first, hi = figures_.bounds[0].second;
      for (const auto& [a, b] : figures_.bounds) lo = lo.cwiseMin(a), hi = hi.cwiseMax(b);
      followState_.update(camera_, lo, hi, mode_ == Mode::Drag);
    }
    ViewOptions v = view_;
    v.stressScale = stressFactor_ * autoStressScale_;
    list_ = buildDrawList(body_, w, v, width, height, view_.stress ? &vertexStress : nullptr);
    w.restartForceAverage();  // the force arrows: averaged over the steps between two frames
  }

  // Draws the last draw list (no lock: only the drawing thread touches it and the camera).
  void draw(int width, int height, Renderer& renderer) { renderer.draw(list_, camera_, width, height); }

  // ---- mouse (GLFW callbacks on the drawing thread) ----
  void mouseButton(int button, int action, int mods) {
    if (ImGui::GetIO().WantCaptureMouse && action == GLFW_PRESS) return;
    double x, y;
    glfwGetCursorPos(window_, &x, &y);
    std::unique_lock<std::mutex> state = lockState();
    if (action == GLFW_RELEASE) {
      drag_.reset();
      mode_ = Mode::None;
      return;
    }
    lastX_ = x, lastY_ = y;
    shift_ = (mods & GLFW_MOD_SHIFT) != 0;
    if (button == GLFW_MOUSE_BUTTON_LEFT) {
      int width, height;
      glfwGetWindowSize(window_, &width, &height);
      // Picking needs the world; during one long step the press orbits instead.
      std::unique_lock<std::timed_mutex> world = tryWorld();
      const std::optional<size_t> m =
          world.owns_lock() && !rebuild_ ? pickManipulator(camera_, *built_.world, x, y, width, height) : std::nullopt;
      if (m) {
        drag_ = grabManipulator(camera_, *built_.world, *m, x, y, width, height);
        mode_ = Mode::Drag;
      } else {
        mode_ = Mode::Orbit;
      }
    } else {
      mode_ = Mode::Pan;
    }
  }

  void cursor(double x, double y) {
    std::unique_lock<std::mutex> state = lockState();
    const double dx = x - lastX_, dy = y - lastY_;
    lastX_ = x, lastY_ = y;
    int width, height;
    glfwGetWindowSize(window_, &width, &height);
    if (mode_ == Mode::Orbit) camera_.orbit(dx, dy);
    if (mode_ == Mode::Pan) camera_.pan(dx, dy, height);
    if (mode_ == Mode::Drag && drag_) {
      if (shift_ && !camera_.flat) return dragInDepth(camera_, *drag_, -dy * pixelSize(camera_, height));
      dragInPlane(camera_, *drag_, x, y, width, height);
    }
  }

  /// F: frame the camera on the scene again.
  void key(int key, int action) {
    if (ImGui::GetIO().WantCaptureKeyboard || action != GLFW_PRESS) return;
    std::unique_lock<std::mutex> state = lockState();
    if (key == GLFW_KEY_F) reframeCamera();
  }

  void scroll(double dy) {
    if (ImGui::GetIO().WantCaptureMouse) return;
    std::unique_lock<std::mutex> state = lockState();
    if (mode_ == Mode::Drag && drag_ && !camera_.flat) {
      int width, height;
      glfwGetWindowSize(window_, &width, &height);
      dragInDepth(camera_, *drag_, dy * 10 * pixelSize(camera_, height));
      return;
    }
    camera_.zoom(dy);
  }

  // ---- for main()'s timing runs and screenshots (call with lockState()) ----
  const Figures& figures() const { return figures_; }
  long totalSteps() const { return steps_; }
  double stepCpuSeconds() const { return stepCpuSeconds_; }
  double stepWallSeconds() const { return stepWallSeconds_; }
  double vertexSteps() const { return vertexSteps_; }
  /// [s] how long the last frame held the world (figures + draw list); 0 when it was busy.
  double worldHeldSeconds() const { return worldHeldSeconds_; }
  size_t drawTriangles() const {
    return list_.triangles.size() / 3 + (list_.meshIndices ? list_.meshIndices->size() / 3 : 0);
  }
  const RateWindow& rates() const { return rates_; }
  bool rebuilding() const { return rebuild_ != nullptr; }
  double lastRebuildSeconds() const { return lastRebuildSeconds_; }
  const ViewOptions& view() const { return view_; }
  const BodyView& bodyView() const { return body_; }
  void setView(const ViewOptions& v) { view_ = v; }
  /// Body 0's size as the panel's slider sets it, rebuilt in the background.
  void setBodySize(int size) {
    resizeBody(0, size);
    requestRebuild(scene_, false, false, "size " + std::to_string(edits_.at(0).sizeVoxels));
  }

 private:
  enum class Mode { None, Orbit, Pan, Drag };
  static constexpr const char* kShapes[] = {"sphere", "box", "cylinder", "as loaded"};
  static constexpr int kAsLoaded = 3;

  // Body b of scene_ at `size` voxels and the same physical extent: its panel shape (a preset),
  // or as loaded (a scene's union of primitives scaled; a volume from a file keeps the file's size).
  void resizeBody(size_t b, int size) {
    BodyEdit& edit = edits_.at(b);
    edit.sizeVoxels = std::clamp(size, kMinBodySize, kMaxBodySize);
    if (int(b) == editBody_) sizeDraft_ = edit.sizeVoxels;
    applyShape(b);
  }

  void applyShape(size_t b) {
    BodySettings& body = scene_.bodies[b];
    const BodyEdit& edit = edits_.at(b);
    if (edit.shapeIndex == kAsLoaded) {
      body.source = edit.loadedSource;
      body.shape = edit.loadedSource ? edit.loadedShape : scaleShape(edit.loadedShape, edit.sizeVoxels);
      return;
    }
    body.shape = presetShape(kShapes[edit.shapeIndex], edit.sizeVoxels, scene_.dim, edit.extent / edit.sizeVoxels);
    body.source = nullptr;
  }

  // The panel's shape index of a loaded body: a preset when it is one primitive filling its grid
  // as presetShape makes it, else kAsLoaded.
  int presetIndex(const BodySettings& b) const {
    if (b.source || b.shape.primitives.size() != 1) return kAsLoaded;
    const ShapeSpec& s = b.shape;
    const int n = s.dims[0];
    if (s.dims[1] != n || (s.dim == 3 && s.dims[2] != n)) return kAsLoaded;
    for (int i : {0, 1, 2})
      if (i < (s.dim == 3 ? 3 : 2)) {
        const ShapeSpec preset = presetShape(kShapes[i], n, s.dim, s.voxelSize);
        const Primitive &a = preset.primitives.front(), &c = s.primitives.front();
        if (a.kind == c.kind && a.min == c.min && a.max == c.max && a.center == c.center && a.radius == c.radius &&
            a.halfLength == c.halfLength && a.axis == c.axis && a.label == c.label)
          return i;
      }
    return kAsLoaded;
  }

  // The panel's max von Mises stress and body table (a pass over the elements), taken at wall
  // time `at` (call with the world held).
  struct StressFigures {
    Real maxStress = 0;
    std::vector<BodyRow> bodies;
    double at = 0;
  };
  StressFigures stressFigures(const World& w, double at) const {
    StressFigures sf;
    const std::vector<Real> es = w.elementStress();
    sf.maxStress = es.empty() ? 0.0 : *std::max_element(es.begin(), es.end());
    sf.bodies = built_.numBodies() > 1 ? bodyTable(built_) : std::vector<BodyRow>{};
    sf.at = at;
    return sf;
  }

  // ---- carving (issue 30, carve_scene.h) ----
  // After each batch, with the world held: the tools whose scene sets "carve", and in carve mode
  // the tool being dragged ("hold to drill"), remove the voxels they swept since the last batch
  // (carveWithManipulators, as `gradel run` after each chunk). A carved body is laid out again
  // and the world made anew over it; its view is built here too (both with the world held, so
  // that no frame draws the new model with the old view) and swapped in by the next refresh.
  struct CarveResult {
    size_t voxels = 0, events = 0;
    double seconds = 0;
    double dt = 0;  // [s] the world's dt after the events, when they changed it (else 0)
  };
  CarveResult carveAfterBatch(long steps, std::optional<size_t> carver) {
    World& w = *built_.world;
    if (w.model().dim != 3) return {};  // circles do not carve
    // At most every kCarveSteps steps, as `gradel run` after each chunk: an event remakes the
    // world (~12 ms on a 16^3 block), and carving after every 4 ms batch ran the drill scene at
    // 0.5x real time where every 32 steps keeps it real time; the sweep covers the whole path.
    stepsSinceCarve_ += steps;
    if (stepsSinceCarve_ < kCarveSteps && !carvePrevious_.empty()) return {};
    stepsSinceCarve_ = 0;
    std::vector<Manipulator>& tools = w.manipulators();
    for (size_t i = 0; i < tools.size(); ++i)
      tools[i].settings.carve = tools[i].settings.shape != ManipulatorShape::Circle &&
                                ((i < sceneCarve_.size() && sceneCarve_[i]) || carver == i);
    const auto t0 = Clock::now();
    const Real dt = w.dt();
    CarveResult r;
    // At every check, carving or not: the tools' centres move on (carvePrevious_), so that a drill
    // begins where the tool is, not where it was when carving last stopped.
    for (const CarveEvent& e : carveWithManipulators(built_, carvePrevious_)) r.voxels += e.removedVoxels, ++r.events;
    if (r.events == 0) return r;
    carvedView_ = makeBodyView(built_, nullptr, kDisplayTriangleBudget);
    r.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    if (built_.world->dt() != dt) r.dt = built_.world->dt();
    return r;
  }
  // The result into the panel's figures (state lock held); dt = auto follows a carved body
  // (World::replaceModel), and the pacer with it.
  void noteCarving(const CarveResult& r) {
    if (r.events == 0) return;
    figures_.carvedVoxels += r.voxels, figures_.carveEvents += r.events, figures_.carveLastSeconds = r.seconds;
    if (r.dt > 0) {  // (taken with the world held: here only the state lock is)
      pacer_ = StepPacer(r.dt, speed_);
      pacer_.restart(wallNow());
    }
  }

  // ---- stepping (its own thread) ----
  // Each batch: what to do, from the state (brief); the steps, holding only the world; the
  // result, into the state (brief). Never both locks at once.
  void stepLoop() {
    using namespace std::chrono_literals;
    while (!quit_) {
      if (drawWaiting_ > 0) {  // the drawing thread wants the world: let it in
        std::this_thread::sleep_for(50us);
        continue;
      }
      long n = 0, generation = 0;
      double wait = 2e-3;
      std::optional<ManipulatorDrag> drag;
      std::optional<size_t> carver;  // carve mode: the tool being dragged drills
      {
        std::unique_lock<std::mutex> state = lockState();
        const double now = wallNow();
        if (paused_ || rebuild_ || diverged_) {
          pacer_.restart(now);  // a pause is not owed
        } else {
          if (pacer_.speed() != double(speed_)) pacer_.setSpeed(speed_, now);
          n = pacer_.due(now);
          wait = pacer_.waitSeconds(now);
          behind_ = pacer_.behind(now);
        }
        drag = drag_, generation = generation_;
        if (carveMode_ && drag_) carver = drag_->index;
      }
      if (n == 0) {
        std::this_thread::sleep_for(std::chrono::duration<double>(std::clamp(wait, 50e-6, 2e-3)));
        continue;
      }
      std::unique_lock<std::timed_mutex> world(worldMutex_);
      if (generation != generation_) continue;  // a rebuilt world came in meanwhile
      World& w = *built_.world;
      const auto t0 = Clock::now();
      const double cpu0 = threadCpuSeconds();
      const double batchSim = double(n) * w.dt();
      StepBatchOptions options;
      if (drag) options.beforeStep = [&](double fraction) { feedDrag(w, *drag, fraction, batchSim); };
      const bool ok = stepBatch(w, n, options).finite;
      const CarveResult carved = ok ? carveAfterBatch(n, carver) : CarveResult{};
      const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
      const double cpu = threadCpuSeconds() - cpu0;
      const size_t vertices = w.model().numVertices();
      const double simTime = w.time();
      std::optional<StressFigures> stress;  // four times a second, here rather than in a frame
      if (const double at = wallNow(); ok && at - stressAt_.load() >= 0.25) stress = stressFigures(w, at);
      world.unlock();
      std::unique_lock<std::mutex> state = lockState();
      if (generation != generation_) continue;
      if (stress) {
        figures_.maxStress = stress->maxStress, figures_.stressAt = stress->at;
        figures_.bodies = std::move(stress->bodies);
        stressAt_ = stress->at;
      }
      if (drag && drag_ && drag_->index == drag->index) drag_->from = drag->to;  // reached
      pacer_.stepped(n, seconds);
      noteCarving(carved);
      steps_ += n;
      stepCpuSeconds_ += cpu, stepWallSeconds_ += seconds, vertexSteps_ += double(n) * double(vertices);
      const double end = builtScene_.output.duration, before = simTime_;
      simTime_ = simTime;
      if (!ok) diverged_ = true;
      if (before < end && simTime >= end) {  // crossed the scene's end in this batch
        if (atEnd_ == int(AtEnd::Stop)) paused_ = true, status_ = "stopped at the scene's end (Run goes on)";
        if (atEnd_ == int(AtEnd::Loop)) loopDue_ = true;
      }
    }
  }

  // ---- rebuilding (a background thread) ----
  // Builds `scene` in the background; stepping stops until it is swapped in. A request while one
  // builds replaces any waiting one (the latest settings win).
  void requestRebuild(const Scene& scene, bool load, bool reframe, const std::string& what) {
    auto r = std::make_unique<Rebuild>();
    r->scene = scene, r->load = load, r->reframe = reframe, r->what = what;
    if (rebuild_) {
      waiting_ = std::move(r);
      return;
    }
    startRebuild(std::move(r));
  }

  void startRebuild(std::unique_ptr<Rebuild> r) {
    r->start = wallNow();
    Rebuild* p = r.get();
    rebuild_ = std::move(r);
    World* running = built_.world.get();  // not replaced while a rebuild is pending
    rebuild_->thread = std::thread([this, p, running] {
      try {
        if (!p->load) {  // new settings: manipulators the user moved keep their place (waits for the batch)
          std::unique_lock<std::timed_mutex> world(worldMutex_);
          keepManipulatorPoses(*running, p->scene);
        }
        p->built = buildScene(p->scene);
        p->phase = 1;
        p->view = makeBodyView(*p->built, nullptr, kDisplayTriangleBudget);
      } catch (const InputError& e) {
        p->error = e.what();
      } catch (const std::exception& e) {
        p->error = std::string("internal error: ") + e.what();
      }
      p->phase = 2;
    });
  }

  void finishRebuild(double now) {
    if (!rebuild_ || rebuild_->phase != 2) return;
    std::unique_lock<std::timed_mutex> world = tryWorld();  // free: no batch starts during a rebuild
    if (!world.owns_lock()) return;
    rebuild_->thread.join();
    std::unique_ptr<Rebuild> r = std::move(rebuild_);
    lastRebuildSeconds_ = now - r->start;
    if (r->error.empty()) {
      install(std::move(r->scene), std::move(*r->built), std::move(*r->view), r->load, r->reframe);
      if (status_ != "simulation diverged; reset") status_.clear();
    } else {
      status_ = r->error;
      scene_ = builtScene_;  // the panel shows what runs
      syncEdits();
    }
    if (waiting_) startRebuild(std::move(waiting_));
  }

  // A built world replaces the one running (called with both locks, or before stepping starts).
  void install(Scene scene, BuiltScene built, BodyView view, bool load, bool reframe) {
    ++generation_;
    scene_ = std::move(scene);
    builtScene_ = scene_;
    built_ = std::move(built);
    // One core is left to drawing (software GL draws on the CPU): with both cores stepping, on
    // 2 loaded cores the frames took longer and the real-time factor did not rise beyond the
    // noise (docs/viewer.md).
    built_.world->setThreads(std::max(1, int(std::thread::hardware_concurrency()) - 1));
    body_ = std::move(view);
    sceneCarve_.clear(), carvePrevious_.clear(), carvedView_.reset(), stepsSinceCarve_ = 0;
    for (const Manipulator& m : built_.world->manipulators()) sceneCarve_.push_back(m.settings.carve);
    figures_.carvedVoxels = figures_.carveEvents = 0, figures_.carveLastSeconds = 0;
    autoStressScale_ = autoStressScale(built_.world->model());
    figures_.stressAt = -1e9;  // the new world's figures at the next frame
    stressAt_ = -1e9;
    drag_.reset();
    steps_ = 0;
    rates_.reset();
    pacer_ = StepPacer(built_.world->dt(), speed_);
    pacer_.restart(wallNow());
    behind_ = false;
    followState_.reset();
    if (load) {
      original_ = scene_;
      atEnd_ = int(scene_.name == "play" ? AtEnd::RunOn : AtEnd::Stop);
      // A body from a mesh file shows that mesh (embedded) first; other bodies the smooth surface.
      view_.surface = built_.bodies[0].embedded ? SurfaceMode::Embedded : SurfaceMode::Smooth;
      view_.forces = true;  // the contact force arrows on the tools
      // Each body keeps its physical size when its resolution changes.
      edits_.clear();
      for (size_t i = 0; i < built_.numBodies(); ++i) {
        const VoxelVolume& v = built_.bodies[i].volume;
        const BodySettings& settings = scene_.bodies[i];
        BodyEdit e;
        e.extent = v.voxelSize() * std::max(v.nx(), v.ny());
        e.sizeVoxels = std::clamp(std::max({v.nx(), v.ny(), v.nz()}), kMinBodySize, kMaxBodySize);
        e.loadedShape = settings.shape, e.loadedSource = settings.source;
        e.shapeIndex = presetIndex(settings);
        if (settings.source) {
          e.origin = "from " + settings.source->describe();
        } else if (e.shapeIndex == kAsLoaded) {
          e.origin = "a union of " + std::to_string(settings.shape.primitives.size()) + " primitives";
        } else {
          e.origin = "a preset shape";
        }
        char dims[64];
        std::snprintf(dims, sizeof dims, ", %dx%dx%d voxels", v.nx(), v.ny(), v.nz());
        e.origin += dims;
        edits_.push_back(e);
      }
      editBody_ = 0;
    }
    syncEdits();
    if (reframe) reframeCamera();
    int width, height;
    glfwGetFramebufferSize(window_, &width, &height);
    refresh(wallNow(), width, height);
  }

  void syncEdits() {
    if (editBody_ < int(edits_.size())) sizeDraft_ = edits_[size_t(editBody_)].sizeVoxels;
    confirmSize_ = 0;
  }

  // Frames the scene in the part of the window right of the panel.
  void reframeCamera() {
    followState_.reset();
    Vec3 lo, hi;
    sceneBounds(*built_.world, &lo, &hi);
    camera_ = frameBox(lo, hi, scene_.dim == 2);
    int width, height;
    glfwGetWindowSize(window_, &width, &height);
    camera_.pan(kPanelWidth / 2, 0, height);
  }

  void openScene(const std::string& path) {
    try {
      Scene s = loadScene(path);
      const std::string name = fs::path(path).filename().string();
      requestRebuild(s, true, true, name);
    } catch (const InputError& e) {
      status_ = e.what();
    }
  }

  // One line of text whether or not there is anything to say: the widgets below never move.
  static void reservedLine(bool show, const ImVec4& colour, const std::string& text) {
    if (show && !text.empty())
      ImGui::TextColored(colour, "%s", text.c_str());
    else
      ImGui::TextUnformatted(" ");
  }

  // The size slider's estimate: real-time factor at `size` from what this body measures now.
  std::optional<SizeEstimate> sizeEstimate(int size) const {
    const BodyEdit& edit = edits_.at(size_t(editBody_));
    if (pacer_.capacity() <= 0 || steps_ < 20) return std::nullopt;
    const LayoutKind layout = scene_.bodies.at(size_t(editBody_)).layout;
    return estimateSize(edit.sizeVoxels, pacer_.capacity(), size, vertexExponent(layout), kMinBodySize, kMaxBodySize);
  }

  void panel(double now) {
    const Figures& f = figures_;
    const ImVec4 red(0.85f, 0.1f, 0.1f, 1), orange(0.8f, 0.3f, 0.0f, 1);
    ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(kPanelWidth, 0), ImGuiCond_FirstUseEver);
    ImGui::Begin("gradel");
    // ---- live figures: a fixed number of lines, so that the buttons below never move ----
    ImGui::Text("%.0f fps   %.0f steps/s   real time x%.3g", rates_.samplesPerSecond(), rates_.stepsPerSecond(),
                rates_.realTimeFactor());
    if (rebuild_) {
      const double t = now - rebuild_->start;
      char text[160];
      std::snprintf(text, sizeof text, "building %s: %s  %.1f s", rebuild_->what.c_str(),
                    rebuild_->phase == 0 ? "volume, layout, model" : "display surfaces", t);
      ImGui::TextColored(orange, "%s", text);
      ImGui::ProgressBar(rebuild_->phase == 0 ? 0.33f : 0.8f, ImVec2(-1, 0), rebuild_->phase == 0 ? "1/2" : "2/2");
    } else {
      reservedLine(behind_, red, "cannot keep up: simulation slower than real time");
      char cap[120];
      std::snprintf(cap, sizeof cap, "this machine: up to x%.3g real time at this size", pacer_.capacity());
      reservedLine(pacer_.capacity() > 0 && steps_ >= 20, ImGui::GetStyleColorVec4(ImGuiCol_TextDisabled), cap);
    }
    ImGui::Text("t = %.3f s  dt = %.3g s  %s", f.time, f.dt, f.integrator.c_str());
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("dt: %s", f.dtRule.c_str());
    // The auto choice's reason: one line (the full text as a tooltip).
    reservedLine(!f.choice.empty(), ImGui::GetStyleColorVec4(ImGuiCol_Text),
                 "auto: " + f.choice.substr(0, 44) + (f.choice.size() > 44 ? "..." : ""));
    if (!f.choice.empty() && ImGui::IsItemHovered()) ImGui::SetTooltip("auto: %s", f.choice.c_str());
    ImGui::Text("%zu elements  %zu vertices  %zu pairs", f.elements, f.vertices, f.pairs);
    ImGui::Text("max von Mises stress %s", pascalText(f.maxStress).c_str());
    // Several bodies: a row of figures per body (render/body_table.h); the lines above are all of them.
    if (f.bodies.size() > 1 &&
        ImGui::BeginTable("bodies", 5,
                          ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingFixedFit)) {
      for (const char* h : {"body", "vertices", "kinetic [J]", "elastic [J]", "max stress"}) ImGui::TableSetupColumn(h);
      ImGui::TableHeadersRow();
      for (const BodyRow& r : f.bodies) {
        ImGui::TableNextRow();
        ImGui::TableNextColumn(), ImGui::TextUnformatted(r.name.c_str());
        ImGui::TableNextColumn(), ImGui::Text("%zu", r.vertices);
        ImGui::TableNextColumn(), ImGui::Text("%.3g", r.kineticEnergy);
        ImGui::TableNextColumn(), ImGui::Text("%.3g", r.elasticEnergy);
        ImGui::TableNextColumn(), ImGui::TextUnformatted(pascalText(r.maxStress).c_str());
      }
      ImGui::EndTable();
    }
    reservedLine(!status_.empty(), orange, status_.substr(0, 48) + (status_.size() > 48 ? "..." : ""));
    if (!status_.empty() && ImGui::IsItemHovered()) ImGui::SetTooltip("%s", status_.c_str());

    // ---- run ----
    if (ImGui::Button(paused_ ? "Run" : "Pause")) paused_ = !paused_, rates_.reset();
    ImGui::SameLine();
    if (ImGui::Button("Step")) paused_ = true, stepOnce_ = true;
    ImGui::SameLine();
    if (ImGui::Button("Reset")) requestRebuild(original_, true, false, "reset");
    float speed = speed_;
    if (ImGui::SliderFloat("speed", &speed, 0.05f, 2.0f, "x%.2f")) speed_ = speed;
    {
      char label[48];
      std::snprintf(label, sizeof label, "end (%.3g s)", builtScene_.output.duration);
      static const char* atEnd[] = {"run on", "stop", "loop"};  // AtEnd order
      ImGui::Combo(label, &atEnd_, atEnd, 3);
    }
    if (ImGui::Checkbox("camera follows the bodies", &follow_)) followState_.reset();
    ImGui::BeginDisabled(scene_.dim != 3);
    ImGui::Checkbox("carve: a dragged tool drills", &carveMode_);
    ImGui::EndDisabled();
    if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
      ImGui::SetTooltip("Hold the mouse on a sphere or cylinder and move it into a body: it removes every voxel\n"
                        "whose centre it sweeps (within one voxel), and the body is laid out again (3D only).");
    {
      char carved[96];
      std::snprintf(carved, sizeof carved, "carved %zu voxels in %zu events, last %.0f ms", f.carvedVoxels,
                    f.carveEvents, 1e3 * f.carveLastSeconds);
      reservedLine(f.carveEvents > 0, ImGui::GetStyleColorVec4(ImGuiCol_Text), carved);
    }

    // ---- the paper's interactions, one click each ----
    section("Scenes");
    auto sceneButton = [&](const char* label, const char* file) {
      if (ImGui::Button(label)) openScene((scenesDir() / file).string());
    };
    sceneButton("Strike", "strike.json");
    ImGui::SameLine();
    sceneButton("Grasp vs wall", "grasp-wall.json");
    ImGui::SameLine();
    sceneButton("Grasp two", "grasp-two.json");
    if (ImGui::Button("Play (free manipulator)")) requestRebuild(parseScene(kPlayScene, "play"), true, true, "play");
    ImGui::SameLine();
    sceneButton("2D strike", "strike-2d.json");
    // Several bodies and materials (issue 12).
    sceneButton("Two balls", "two-balls.json");
    ImGui::SameLine();
    sceneButton("Stack", "stack.json");
    ImGui::SameLine();
    sceneButton("Grasp body", "grasp-body.json");
    ImGui::SameLine();
    sceneButton("Phantom", "phantom.json");
    sceneButton("Drill (carving)", "drill.json");
    ImGui::SameLine();
    sceneButton("Cut (blade)", "cut.json");

    // ---- view ----
    section("View");
    int surface = int(view_.surface);
    ImGui::RadioButton("smooth", &surface, int(SurfaceMode::Smooth));
    ImGui::SameLine();
    ImGui::RadioButton("voxel", &surface, int(SurfaceMode::Voxel));
    ImGui::SameLine();
    ImGui::RadioButton("embedded", &surface, int(SurfaceMode::Embedded));
    ImGui::SameLine();
    ImGui::RadioButton("none", &surface, int(SurfaceMode::None));
    view_.surface = SurfaceMode(surface);
    // A body over the display budget (render/display_budget.h) is drawn with a coarser mesh that
    // follows the same elements; the full one on request (its frames then cost what they cost).
    ImGui::BeginDisabled(!body_.coarse);  // always there: the widgets below do not move
    ImGui::Checkbox("full-resolution surface", &view_.fullResolution);
    ImGui::EndDisabled();
    {
      char text[160] = "";
      if (body_.coarse && !view_.fullResolution)
        std::snprintf(text, sizeof text, "coarse surface%s: %zu of %zu triangles",
                      body_.coarseStep > 1 ? (" (every " + std::to_string(body_.coarseStep) + " voxels)").c_str() : "",
                      body_.coarse->triangles.size(), body_.fullTriangles);
      reservedLine(text[0] != 0, ImGui::GetStyleColorVec4(ImGuiCol_TextDisabled), text);
      if (text[0] != 0 && ImGui::IsItemHovered())
        ImGui::SetTooltip(
            "The smooth surface has more triangles than a frame's budget (%zu): the isosurface sampled "
            "every %d voxels is drawn, carried by the same elements. The physics is the full body's.",
            kDisplayTriangleBudget, body_.coarseStep);
    }
    ImGui::Checkbox("wireframe (levels)", &view_.wireframe);
    ImGui::SameLine();
    ImGui::Checkbox("vertices", &view_.vertices);
    ImGui::Checkbox("stress colour", &view_.stress);
    ImGui::SameLine();
    ImGui::Checkbox("tool forces", &view_.forces);
    ImGui::BeginDisabled(!view_.stress);  // always there: the widgets below do not move
    {
      // The darkest colour: a factor of the auto scale (5 % strain of the stiffest material), shown in Pa.
      const std::string darkest = pascalText(stressFactor_ * autoStressScale_);
      ImGui::SliderFloat("stress scale", &stressFactor_, 0.01f, 10.0f, darkest.c_str(), ImGuiSliderFlags_Logarithmic);
    }
    ImGui::EndDisabled();
    if (ImGui::Button("Reframe camera (F)")) reframeCamera();

    // ---- body and settings: any change rebuilds the world (in the background) ----
    section("Body (changes restart)");
    bool changed = false, reshaped = false;
    static const char* layouts[] = {"gradational", "uniform", "voxel"};
    // With several bodies the settings below are those of the body picked here.
    editBody_ = std::min(editBody_, int(scene_.numBodies()) - 1);
    if (scene_.numBodies() > 1 && ImGui::BeginCombo("edit body", scene_.bodies.at(size_t(editBody_)).name.c_str())) {
      for (size_t i = 0; i < scene_.numBodies(); ++i)
        if (ImGui::Selectable(scene_.bodies[i].name.c_str(), int(i) == editBody_)) editBody_ = int(i), syncEdits();
      ImGui::EndCombo();
    }
    BodySettings& body = scene_.bodies.at(size_t(editBody_));
    BodyEdit& edit = edits_.at(size_t(editBody_));
    // The presets, and the body as loaded (a file's volume, a scene's union of primitives).
    const char* shapeItems[] = {kShapes[0], kShapes[1], kShapes[2], kShapes[kAsLoaded]};
    if (scene_.dim == 2) shapeItems[2] = kShapes[kAsLoaded];  // no cylinder in 2D
    int shapeItem = scene_.dim == 2 && edit.shapeIndex == kAsLoaded ? 2 : edit.shapeIndex;
    if (ImGui::Combo("shape", &shapeItem, shapeItems, scene_.dim == 3 ? 4 : 3)) {
      edit.shapeIndex = scene_.dim == 2 && shapeItem == 2 ? kAsLoaded : shapeItem;
      changed = reshaped = true;
    }
    ImGui::TextDisabled("%s", edit.origin.substr(0, 52).c_str());
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("loaded: %s", edit.origin.c_str());
    // The size applies when the slider is released or a typed size is entered (Ctrl+click types).
    // A volume from a file keeps the file's size.
    const bool fixedSize = edit.shapeIndex == kAsLoaded && edit.loadedSource;
    ImGui::BeginDisabled(fixedSize);
    ImGui::SliderInt("size [voxels]", &sizeDraft_, kMinBodySize, kMaxBodySize);
    ImGui::EndDisabled();
    sizeDraft_ = std::clamp(sizeDraft_, kMinBodySize, kMaxBodySize);
    const bool sizeEntered = ImGui::IsItemDeactivatedAfterEdit();
    const std::optional<SizeEstimate> est = sizeEstimate(sizeDraft_);
    const bool slow = est && est->realTimeFactor < kSlowFactor;
    if (sizeEntered && sizeDraft_ != edit.sizeVoxels) {
      if (slow)
        confirmSize_ = sizeDraft_;  // flagged: built only when confirmed below
      else
        edit.sizeVoxels = sizeDraft_, confirmSize_ = 0, changed = reshaped = true;
    }
    {  // the estimate line and the confirmation row, reserved
      char text[160] = "";
      if (est && sizeDraft_ != edit.sizeVoxels)
        std::snprintf(text, sizeof text, "size %d: about x%.2g real time%s; real time up to %d", sizeDraft_,
                      est->realTimeFactor, slow ? " (below x0.1)" : "", est->largestRealTime);
      else if (est)
        std::snprintf(text, sizeof text, "real time up to size %d (estimate)", est->largestRealTime);
      reservedLine(true, slow ? red : ImGui::GetStyleColorVec4(ImGuiCol_TextDisabled), text);
      if (confirmSize_ > 0 && est) {
        char label[64];
        std::snprintf(label, sizeof label, "Build %d anyway", confirmSize_);
        if (ImGui::SmallButton(label)) edit.sizeVoxels = confirmSize_, confirmSize_ = 0, changed = reshaped = true;
        ImGui::SameLine();
        std::snprintf(label, sizeof label, "Build %d (real time)", est->largestRealTime);
        if (ImGui::SmallButton(label))
          edit.sizeVoxels = sizeDraft_ = est->largestRealTime, confirmSize_ = 0, changed = reshaped = true;
        ImGui::SameLine();
        if (ImGui::SmallButton("Cancel")) sizeDraft_ = edit.sizeVoxels, confirmSize_ = 0;
      } else {
        ImGui::Dummy(ImVec2(1, ImGui::GetTextLineHeight()));  // a SmallButton row's height
      }
    }
    int layout = int(body.layout);
    if (ImGui::Combo("layout", &layout, layouts, 3)) body.layout = LayoutKind(layout), changed = true;
    float E = float(body.material.youngsModulus), rho = float(body.material.density);
    if (ImGui::SliderFloat("E [Pa]", &E, 1e3f, 1e7f, "%.3g", ImGuiSliderFlags_Logarithmic))
      body.material.youngsModulus = E;
    if (ImGui::IsItemDeactivatedAfterEdit()) changed = true;
    if (ImGui::SliderFloat("density", &rho, 100.f, 5000.f, "%.0f kg/m3")) body.material.density = rho;
    if (ImGui::IsItemDeactivatedAfterEdit()) changed = true;
    // Poisson's ratio (material.h): [0, 0.5); 0.49 is rubber / tissue (dt = auto shrinks with it).
    float nu = float(body.material.poissonRatio);
    if (ImGui::SliderFloat("Poisson's ratio", &nu, 0.f, 0.49f, "%.2f (-)")) body.material.poissonRatio = nu;
    if (ImGui::IsItemDeactivatedAfterEdit()) changed = true;
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("nu, dimensionless, 0 ... 0.49 (0.5 is refused)\n0: the paper's element, no bulge\n"
                        "0.45 ... 0.49: tissue, rubber (volume kept)\ndt = auto shrinks: about 0.6x at 0.45, 0.3x "
                        "at 0.49");
    if (!body.material.regions.empty()) {
      // Label 1 without an entry of its own takes the fields above: one more material.
      bool label1Listed = false;
      for (const RegionMaterial& r : body.material.regions) label1Listed |= r.label == 1;
      const size_t materials = body.material.regions.size() + (label1Listed ? 0 : 1);
      ImGui::TextWrapped("%zu materials (one per region label)%s", materials,
                         label1Listed ? "" : "; E and density above are label 1's");
      for (const RegionMaterial& r : body.material.regions)
        ImGui::TextDisabled("  label %u: E %.3g Pa, density %.0f kg/m3", unsigned(r.label), r.youngsModulus, r.density);
    }
    float damping = float(scene_.simulation.damping);
    if (ImGui::SliderFloat("damping [1/s]", &damping, 0.f, 20.f, "%.2f")) scene_.simulation.damping = damping;
    if (ImGui::IsItemDeactivatedAfterEdit()) changed = true;
    float friction = float(scene_.domain.friction);
    if (ImGui::SliderFloat("friction", &friction, 0.f, 2.f, "%.2f")) {
      scene_.domain.friction = friction;
      for (ManipulatorSettings& m : scene_.manipulators) m.friction = friction;
    }
    if (ImGui::IsItemDeactivatedAfterEdit()) changed = true;
    int integrator = int(scene_.simulation.integrator);
    static const char* integrators[] = {"symplectic", "forward_euler", "implicit", "large_step",
                                        "auto"};  // IntegratorKind order
    if (ImGui::Combo("integrator", &integrator, integrators, 5))
      scene_.simulation.integrator = IntegratorKind(integrator), changed = true;
    bool autoDt = scene_.simulation.dt == 0;
    if (ImGui::Checkbox("dt auto", &autoDt)) scene_.simulation.dt = autoDt ? 0 : f.dt, changed = true;
    if (!autoDt) {
      float dt = float(scene_.simulation.dt * 1e3);
      ImGui::SameLine();
      ImGui::SetNextItemWidth(140);
      if (ImGui::SliderFloat("dt [ms]", &dt, 0.005f, 2.0f, "%.3f", ImGuiSliderFlags_Logarithmic))
        scene_.simulation.dt = dt * 1e-3;
      if (ImGui::IsItemDeactivatedAfterEdit()) changed = true;
    }
    float g = float(-scene_.simulation.gravity.y());
    if (ImGui::SliderFloat("gravity [m/s2]", &g, 0.f, 20.f, "%.2f")) scene_.simulation.gravity = Vec3(0, -g, 0);
    if (ImGui::IsItemDeactivatedAfterEdit()) changed = true;

    // ---- manipulators ----
    section("Manipulators");
    if (ImGui::Button(scene_.dim == 3 ? "+ sphere" : "+ circle"))
      addManipulator(ManipulatorShape::Sphere), changed = true;
    if (scene_.dim == 3) {
      ImGui::SameLine();
      if (ImGui::Button("+ cylinder")) addManipulator(ManipulatorShape::Cylinder), changed = true;
    }
    ImGui::SameLine();
    if (!scene_.manipulators.empty() && ImGui::Button("remove last")) scene_.manipulators.pop_back(), changed = true;
    ImGui::TextWrapped("Drag a manipulator with the left button; wheel or Shift+drag moves it in depth.");

    if (changed) {
      std::string what = "settings";
      if (reshaped) {  // the chosen shape at the chosen size, the same physical extent
        applyShape(size_t(editBody_));
        what = std::string(kShapes[edit.shapeIndex]) + " " + std::to_string(edit.sizeVoxels);
      }
      requestRebuild(scene_, false, false, what);
    }
    ImGui::End();
  }

  void addManipulator(ManipulatorShape shape) {
    ManipulatorSettings m;
    m.shape = scene_.dim == 2 ? ManipulatorShape::Circle : shape;
    const Real extent = edits_.at(size_t(editBody_)).extent;  // sized to the body being edited
    m.radius = 0.25 * extent;
    m.halfLength = 0.6 * extent;
    m.axis = Vec3(0, 1, 0);
    m.restitution = 0.3;
    m.friction = scene_.domain.friction;
    // Beside the body being edited (where the last figures saw it), on the side away from the
    // other manipulators.
    const auto& [lo, hi] = figures_.bounds.at(size_t(editBody_));
    const Vec3 c = (lo + hi) / 2;
    const Real side = scene_.manipulators.size() % 2 == 0 ? -1 : 1;
    const Vec3 p = c + Vec3(side * (0.5 * extent + m.radius + 0.05), 0, 0);  // 2D: buildScene puts it in the plane
    m.path.keys = {Keyframe{0, p, std::nullopt}};
    scene_.manipulators.push_back(m);
  }

  GLFWwindow* window_;
  Clock::time_point start_;
  // The world (built_.world) is guarded by worldMutex_, held by the stepping thread for each batch;
  // everything else below by stateMutex_. built_ is replaced only with both held.
  std::mutex stateMutex_;
  std::timed_mutex worldMutex_;
  std::atomic<int> drawWaiting_{0};
  std::atomic<long> generation_{0};  // counts installed worlds
  DrawList list_;                    // the last picture's draw list
  std::atomic<bool> quit_{false};
  std::thread stepper_;
  Scene scene_, original_, builtScene_;  // as edited / as loaded / as running
  BuiltScene built_;
  BodyView body_;
  // Carving: the panel's carve mode; per manipulator whether its scene sets "carve" (install);
  // with the world held: the tools' centres after the last batch and a carved model's view
  // waiting for the next refresh.
  bool carveMode_ = false;
  std::vector<uint8_t> sceneCarve_;
  std::vector<Vec3> carvePrevious_;
  std::optional<BodyView> carvedView_;
  static constexpr long kCarveSteps = 32;  // steps between two carving checks (gradel run's chunk)
  long stepsSinceCarve_ = 0;
  std::unique_ptr<Rebuild> rebuild_, waiting_;
  double lastRebuildSeconds_ = 0;
  StepPacer pacer_{1.0};
  RateWindow rates_;
  Figures figures_;
  Camera camera_;
  ViewOptions view_;
  float stressFactor_ = 1;      // the stress colour's darkest, in units of autoStressScale_
  double autoStressScale_ = 1;  // [Pa] draw_list.h autoStressScale of the running model
  std::optional<ManipulatorDrag> drag_;
  Mode mode_ = Mode::None;
  double lastX_ = 0, lastY_ = 0;
  bool shift_ = false, paused_ = false, stepOnce_ = false, behind_ = false, diverged_ = false;
  float speed_ = 1.0f;
  // The scene's end (its simulation.duration): run on, stop (pause there) or loop (start again
  // with the settings as running). The play scene has no end of its own: run on.
  enum class AtEnd { RunOn, Stop, Loop };
  int atEnd_ = int(AtEnd::Stop);
  bool loopDue_ = false;  ///< The stepping thread passed the end with AtEnd::Loop: the next frame restarts.
  // The camera follows the bodies: its target moves with the centre of their bounds.
  bool follow_ = true;
  CameraFollow followState_;  ///< Where the bodies were when the camera last moved with them.
  long steps_ = 0;
  // What the stepping thread spent (for --run-for): its CPU time, the wall time of its batches,
  // and the vertex-steps they made.
  double stepCpuSeconds_ = 0, stepWallSeconds_ = 0, vertexSteps_ = 0;
  double simTime_ = 0;  ///< [s] the world's time after the last batch
  double worldHeldSeconds_ = 0;
  /// [s] wall time of the last max-stress / body-table pass (set by either thread).
  std::atomic<double> stressAt_{-1e9};
  /// The panel's shape settings of one body (the scene holds the rest).
  struct BodyEdit {
    int shapeIndex = 0, sizeVoxels = 12;               ///< kShapes index (kAsLoaded: the loaded volume)
    Real extent = 0.12;                                ///< [m] kept when the resolution changes.
    ShapeSpec loadedShape;                             ///< As loaded: scaled for other sizes.
    std::shared_ptr<const VolumeSource> loadedSource;  ///< As loaded from a file (null: a shape).
    std::string origin;                                ///< "from <file>", "a preset shape", ... and the grid.
  };
  std::vector<BodyEdit> edits_;  ///< Per body.
  int editBody_ = 0;             ///< The body the "Body" settings edit.
  int sizeDraft_ = 12;           ///< The size slider's value, applied on release / Enter.
  int confirmSize_ = 0;          ///< A size flagged as slow, waiting for the user's choice (0 = none).
  std::string status_;
};

Viewer* gViewer = nullptr;

void onMouseButton(GLFWwindow* w, int button, int action, int mods) {
  ImGui_ImplGlfw_MouseButtonCallback(w, button, action, mods);
  gViewer->mouseButton(button, action, mods);
}
void onCursor(GLFWwindow*, double x, double y) { gViewer->cursor(x, y); }
void onKey(GLFWwindow* w, int key, int scancode, int action, int mods) {
  ImGui_ImplGlfw_KeyCallback(w, key, scancode, action, mods);
  gViewer->key(key, action);
}
void onScroll(GLFWwindow* w, double dx, double dy) {
  ImGui_ImplGlfw_ScrollCallback(w, dx, dy);
  gViewer->scroll(dy);
}

// True for a software OpenGL (Mesa's llvmpipe / softpipe, e.g. under xvfb): multisampling there
// costs every frame on the CPU the simulation needs.
bool softwareGl() {
  const std::string r = Renderer::glRenderer();
  for (const char* name : {"llvmpipe", "softpipe", "Software", "swrast"})
    if (r.find(name) != std::string::npos) return true;
  return false;
}

GLFWwindow* openWindow(int width, int height, int samples) {
  glfwDefaultWindowHints();
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_SAMPLES, samples);
  GLFWwindow* window = glfwCreateWindow(width, height, "gradel", nullptr, nullptr);
  if (window) glfwMakeContextCurrent(window);
  return window;
}

// --frame-pieces: the frame loop's CPU pieces without a window (no display, no OpenGL), on the
// calling thread's CPU clock so that a loaded machine stretches them less than wall time: the
// build, one step on one thread (what the stepping thread pays; dt / that = the real-time factor
// one free core would give), and what a frame does holding the world: the draw list as the
// viewer builds it (the coarse mesh over the budget) and at full resolution, the stress pass (4 a
// second, or every frame while the stress colour shows) and the bodies' bounds. JSON on stdout.
int framePieces(const Options& o, Scene scene) {
  auto cpuOf = [](auto&& f, int reps) {
    const double t0 = threadCpuSeconds();
    for (int r = 0; r < reps; ++r) f();
    return (threadCpuSeconds() - t0) / reps;
  };
  if (o.bodySize > 0) {
    BodySettings& b = scene.bodies[0];
    const Real extent = b.shape.voxelSize * b.shape.dims[0];
    b.shape = presetShape("sphere", o.bodySize, scene.dim, extent / o.bodySize);
    b.source = nullptr;
  }
  int width = 0, height = 0;
  parseSize(o.size, &width, &height);
  double t0 = threadCpuSeconds();
  BuiltScene built = buildScene(scene);
  const double buildCpu = threadCpuSeconds() - t0;
  t0 = threadCpuSeconds();
  const BodyView view = makeBodyView(built, nullptr, kDisplayTriangleBudget);
  const double viewCpu = threadCpuSeconds() - t0;
  World& w = *built.world;
  w.setThreads(1);
  for (int k = 0; k < 5; ++k) w.step();  // warm
  const int steps = std::max(5, int(2e6 / double(w.model().numVertices())));
  const double step = cpuOf([&] { w.step(); }, steps);
  ViewOptions v;
  const double drawList = cpuOf([&] { (void)buildDrawList(view, w, v, width, height); }, 10);
  v.fullResolution = true;
  const double drawListFull = cpuOf([&] { (void)buildDrawList(view, w, v, width, height); }, 10);
  const double stress = cpuOf([&] { (void)w.elementStress(); }, 5);
  const double bounds = cpuOf(
      [&] {
        Vec3 lo = w.state().positions[0], hi = lo;
        for (const Vec3& x : w.state().positions) lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
        volatile double sink = lo.x() + hi.x();
        (void)sink;
      },
      10);
  nlohmann::json j;
  j["body_size"] = o.bodySize > 0 ? o.bodySize : scene.bodies[0].shape.dims[0];
  j["vertices"] = w.model().numVertices();
  j["dt"] = w.dt();
  j["build_cpu_s"] = buildCpu;
  j["body_view_cpu_s"] = viewCpu;
  j["step_cpu_ms_1_thread"] = 1e3 * step;
  j["step_cpu_ns_per_vertex_step"] = 1e9 * step / double(w.model().numVertices());
  j["real_time_factor_one_free_core"] = w.dt() / step;
  j["draw_triangles"] = (view.coarse ? view.coarse->triangles.size() : view.smooth.triangles.size());
  j["full_surface_triangles"] = view.fullTriangles;
  j["coarse_step"] = view.coarseStep;
  j["draw_list_cpu_ms"] = 1e3 * drawList;
  j["draw_list_full_cpu_ms"] = 1e3 * drawListFull;
  j["stress_pass_cpu_ms"] = 1e3 * stress;
  j["bounds_cpu_ms"] = 1e3 * bounds;
  j["load_average_1min"] = loadAverage();
  std::cout << j.dump(2) << "\n";
  return 0;
}

int run(const Options& o) {
  int width = 0, height = 0;
  parseSize(o.size, &width, &height);
  Scene scene = o.scene.empty() ? parseScene(kPlayScene, "play") : loadScene(o.scene);
  if (o.framePieces) return framePieces(o, std::move(scene));
  if (!(o.runFor >= 0) || !std::isfinite(o.runFor)) throw InputError("--run-for: must be >= 0 seconds");
  if (o.bodySize != 0 && (o.bodySize < kMinBodySize || o.bodySize > kMaxBodySize))
    throw InputError("--body-size: must be " + std::to_string(kMinBodySize) + " ... " + std::to_string(kMaxBodySize));
  if (o.rebuildSize != 0 && (o.rebuildSize < kMinBodySize || o.rebuildSize > kMaxBodySize))
    throw InputError("--rebuild-size: must be " + std::to_string(kMinBodySize) + " ... " +
                     std::to_string(kMaxBodySize));

  glfwSetErrorCallback(
      [](int code, const char* text) { std::cerr << "gradel-view: GLFW error " << code << ": " << text << "\n"; });
  if (!glfwInit()) {
    std::cerr << "gradel-view: cannot open a window (no display? set DISPLAY, or use `gradel render` headless)\n";
    return 4;
  }
  GLFWwindow* window = openWindow(width, height, 4);
  if (window && softwareGl()) {  // no multisampling on a software renderer: reopen without
    glfwDestroyWindow(window);
    window = openWindow(width, height, 0);
  }
  if (!window) {
    glfwTerminate();
    std::cerr << "gradel-view: cannot create an OpenGL 3.3 core window\n";
    return 4;
  }
  // The frame cap is ours (60 per second, below); no waiting for the monitor on top of it.
  glfwSwapInterval(0);

  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;
  ImGui::StyleColorsLight();
  ImGui_ImplGlfw_InitForOpenGL(window, false);
  ImGui_ImplOpenGL3_Init("#version 330 core");

  int code = 0;
  {
    Renderer renderer;
    const auto start = Clock::now();
    const bool fixedSteps = !o.screenshot.empty();  // a screenshot: fixed simulated time per frame
    Viewer viewer(window, std::move(scene), !fixedSteps, start, o.bodySize);
    gViewer = &viewer;
    glfwSetMouseButtonCallback(window, onMouseButton);
    glfwSetCursorPosCallback(window, onCursor);
    glfwSetScrollCallback(window, onScroll);
    glfwSetKeyCallback(window, onKey);
    glfwSetCharCallback(window, ImGui_ImplGlfw_CharCallback);
    glfwSetWindowFocusCallback(window, ImGui_ImplGlfw_WindowFocusCallback);
    glfwSetCursorEnterCallback(window, ImGui_ImplGlfw_CursorEnterCallback);
    if (!o.screenshot.empty()) {
      ViewOptions v;
      v.surface = viewer.view().surface;  // the scene's own choice (embedded for a mesh file)
      v.stress = true;
      viewer.setView(v);
    }
    if (o.fullSurface) {
      ViewOptions v = viewer.view();
      v.fullResolution = true;
      viewer.setView(v);
    }

    FrameTimes times;
    double last = viewer.wallNow(), runStart = last;
    double cpuStart = processCpuSeconds(), stepCpuStart = 0, vertexStepsStart = 0;
    double lastCpu = cpuStart, lastStepCpu = 0, drawCpuAverage = -1;  // the frame cap's CPU budget
    {
      std::unique_lock<std::mutex> lock = viewer.lockState();
      stepCpuStart = lastStepCpu = viewer.stepCpuSeconds(), vertexStepsStart = viewer.vertexSteps();
    }
    bool rebuildAsked = false, rebuildSeen = false;
    double rebuildSeconds = 0;
    long frames = 0;
    while (!glfwWindowShouldClose(window)) {
      const double frameStart = viewer.wallNow();
      glfwPollEvents();
      int fbw, fbh;
      glfwGetFramebufferSize(window, &fbw, &fbh);
      ImGui_ImplOpenGL3_NewFrame();
      ImGui_ImplGlfw_NewFrame();
      ImGui::NewFrame();
      viewer.frame(fbw, fbh);
      ImGui::Render();
      viewer.draw(fbw, fbh, renderer);
      ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
      ++frames;

      if (!o.screenshot.empty()) {
        std::unique_lock<std::mutex> lock = viewer.lockState();
        if (viewer.figures().time >= o.screenshotTime) {
          writePng(o.screenshot, readPixels(fbw, fbh));
          std::cout
              << nlohmann::json{{"screenshot", o.screenshot},
                                {"size", {fbw, fbh}},
                                {"t", viewer.figures().time},
                                {"carved_voxels", viewer.figures().carvedVoxels},
                                {"bodies", viewer.figures().bodyCount},
                                {"vertices", viewer.figures().vertices}}
                     .dump()
              << "\n";
          break;
        }
      }
      glfwSwapBuffers(window);
      // The frame cap: at most 60 frames a second, and the drawing's CPU (this thread and the
      // OpenGL driver's: software GL rasterises on the CPU) held to the one core the stepping
      // leaves it, on average: a frame that cost c seconds of CPU is at least c long (up to
      // kMaxFramePeriod, so that the window still answers within 100 ms). The rest goes to the
      // stepping thread. Without it a large body's frames (40-50 ms of CPU each at size 64)
      // drawn 60 times a second would take both cores from the stepping.
      const double work = viewer.wallNow() - frameStart;
      if (o.screenshot.empty()) {
        const double cpuNow = processCpuSeconds();
        double stepCpuNow;
        {
          std::unique_lock<std::mutex> lock = viewer.lockState();
          stepCpuNow = viewer.stepCpuSeconds();
        }
        const double drawCpu = std::max(0.0, (cpuNow - lastCpu) - (stepCpuNow - lastStepCpu));
        lastCpu = cpuNow, lastStepCpu = stepCpuNow;
        drawCpuAverage = drawCpuAverage < 0 ? drawCpu : 0.7 * drawCpuAverage + 0.3 * drawCpu;
        const double period = std::clamp(drawCpuAverage / kDrawCores, kFrameSeconds, kMaxFramePeriod);
        const double rest = period - work;
        if (rest > 0) std::this_thread::sleep_for(std::chrono::duration<double>(rest));
      }
      const double now = viewer.wallNow();
      if (o.runFor > 0) {  // a timing run: frame times, a rebuild asked for as the panel would
        std::unique_lock<std::mutex> lock = viewer.lockState();
        times.all.push_back(now - last);
        times.work.push_back(work);
        times.worldHeld.push_back(viewer.worldHeldSeconds());
        if (viewer.rebuilding()) times.longestDuringRebuild = std::max(times.longestDuringRebuild, now - last);
        if (rebuildAsked && !viewer.rebuilding() && !rebuildSeen)
          rebuildSeen = true, rebuildSeconds = viewer.lastRebuildSeconds();
        if (o.rebuildSize > 0 && !rebuildAsked && now - runStart >= o.rebuildAt) {
          viewer.setBodySize(o.rebuildSize);
          rebuildAsked = true;
        }
      }
      last = now;
      if (o.runFor > 0 && now - runStart >= o.runFor) {
        std::unique_lock<std::mutex> lock = viewer.lockState();
        const Figures& f = viewer.figures();
        const double wall = now - runStart;
        nlohmann::json j;
        j["frames_per_second"] = double(frames) / wall;
        // CPU: the stepping thread's per vertex-step and share of a core; the rest of the process
        // (drawing thread and the OpenGL driver's threads) per frame. Comparable on a loaded machine.
        const double stepCpu = viewer.stepCpuSeconds() - stepCpuStart;
        const double vertexSteps = viewer.vertexSteps() - vertexStepsStart;
        j["step_cpu_ns_per_vertex_step"] = vertexSteps > 0 ? 1e9 * stepCpu / vertexSteps : 0.0;
        j["step_thread_core_share"] = stepCpu / wall;
        j["draw_cpu_ms_per_frame"] =
            frames > 0 ? 1e3 * (processCpuSeconds() - cpuStart - stepCpu) / double(frames) : 0.0;
        j["load_average_1min"] = loadAverage();
        j["frame_ms_median"] = 1e3 * FrameTimes::median(times.all);
        j["frame_work_ms_median"] = 1e3 * FrameTimes::median(times.work);
        j["world_held_ms_median"] = 1e3 * FrameTimes::median(times.worldHeld);
        j["frame_ms_max"] = 1e3 * times.longest();
        j["steps_per_second_last_s"] = viewer.rates().stepsPerSecond();
        j["real_time_factor_last_s"] = viewer.rates().realTimeFactor();
        j["steps"] = viewer.totalSteps();
        j["sim_time"] = f.time;
        j["integrator"] = f.integrator;
        j["integrator_choice"] = f.choice;
        j["dt"] = f.dt;
        j["dt_rule"] = f.dtRule;
        j["elements"] = f.elements;
        j["vertices"] = f.vertices;
        j["bodies"] = f.bodyCount;
        j["carved_voxels"] = f.carvedVoxels;
        j["carve_events"] = f.carveEvents;
        if (o.rebuildSize > 0) {
          j["rebuild_size"] = o.rebuildSize;
          j["rebuild_seconds"] = rebuildSeen ? rebuildSeconds : -1.0;  // -1: still building at the end
          j["frame_ms_max_during_rebuild"] = 1e3 * times.longestDuringRebuild;
        }
        j["draw_triangles"] = viewer.drawTriangles();
        j["full_surface_triangles"] = viewer.bodyView().fullTriangles;
        j["coarse_surface"] = viewer.bodyView().coarse.has_value() && !viewer.view().fullResolution;
        j["coarse_step"] = viewer.bodyView().coarseStep;
        j["gl_renderer"] = Renderer::glRenderer();
        std::cout << j.dump(2) << "\n";
        break;
      }
    }
    gViewer = nullptr;
  }
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  glfwDestroyWindow(window);
  glfwTerminate();
  return code;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"gradel-view: interactive viewer for gradel scenes", "gradel-view"};
  Options o;
  app.add_option("scene", o.scene, "Scene file (default: a sphere and a free manipulator)");
  app.add_option("--size", o.size, "Window size WxH [pixels]")->capture_default_str();
  app.add_option("--screenshot", o.screenshot, "Simulate briefly, save one picture of the window (PNG) and exit");
  app.add_option("--screenshot-time", o.screenshotTime, "Simulated time [s] before the screenshot")
      ->capture_default_str();
  app.add_option("--run-for", o.runFor, "Run for S wall seconds, print frame and simulation rates (JSON), exit");
  app.add_option("--body-size", o.bodySize, "Start with the first body at this size [voxels], as the panel sets it");
  app.add_option("--rebuild-size", o.rebuildSize,
                 "With --run-for: ask for this body size (as the panel would) at --rebuild-at; the JSON gives "
                 "the rebuild's time and the longest frame during it");
  app.add_option("--rebuild-at", o.rebuildAt, "[s] wall time of --rebuild-size")->capture_default_str();
  app.add_flag("--frame-pieces", o.framePieces,
               "No window: time the frame loop's CPU pieces (step, draw list, stress pass) at --body-size, print "
               "JSON and exit");
  app.add_flag("--full-surface", o.fullSurface,
               "Draw the full-resolution surface of a body over the display budget (the panel's checkbox)");
  try {
    app.parse(argc, argv);
    return run(o);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const InputError& e) {
    std::cerr << "gradel-view: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "gradel-view: internal error: " << e.what() << "\n";
    return 1;
  }
}
