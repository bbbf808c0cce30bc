// gradel-view: the interactive viewer (GLFW + OpenGL 3.3 core + Dear ImGui).
//   gradel-view [SCENE.json] [--size WxH] [--screenshot FILE] [--run-for S]
// Mouse: left-drag a manipulator to move it in the plane facing the camera (wheel or
// Shift+drag: towards / away from the camera); left-drag elsewhere orbits, right- or
// middle-drag pans, the wheel zooms. 2D scenes are shown flat.
// The simulation runs as many steps per frame as real time needs, within a time budget, and says
// so on screen when it cannot keep up.
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "gradel/render/body_table.h"
#include "gradel/render/draw_list.h"
#include "gradel/render/manipulator_drag.h"
#include "gradel/render/render_command.h"
#include "gradel/render/renderer.h"
#include "gradel/scene.h"

namespace {

using namespace gradel;
using namespace gradel::render;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// The default scene: the paper's 12^3 sphere on the floor and one free sphere manipulator
// beside it, ready to be grabbed.
constexpr const char* kPlayScene = R"({
  "name": "play",
  "dim": 3,
  "body": { "shape": "sphere", "size": 12, "voxel_size": 0.01, "layout": "gradational", "position": [0, 0, 0] },
  "material": { "scaling": "consistent", "youngs_modulus": 1e5, "density": 1000 },
  "simulation": { "integrator": "auto", "dt": "auto", "damping": 1.0, "gravity": [0, -9.81, 0] },
  "domain": { "min": [-0.3, 0.0, -0.3], "max": [0.4, 0.5, 0.4], "restitution": 0.3, "friction": 0.5 },
  "manipulators": [ { "type": "sphere", "radius": 0.03, "restitution": 0.5, "friction": 0.5,
                      "path": [ { "t": 0, "position": [-0.1, 0.06, 0.06] } ] } ]
})";

constexpr double kStepBudgetSeconds = 0.030;  // wall time per frame the simulation may use
constexpr double kMaxFrameSeconds = 0.1;      // longer frames (window moves, stalls) are not caught up
constexpr float kPanelWidth = 330;            // [pixels] the settings panel at the left

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
};

// Moving averages of the live figures over the last second.
struct Rates {
  std::deque<std::pair<double, long>> frames;  // (wall time, steps in that frame)
  double simPerWall = 0;
  void add(double now, long steps) {
    frames.push_back({now, steps});
    while (frames.size() > 2 && now - frames.front().first > 1.0) frames.pop_front();
  }
  double fps() const {
    if (frames.size() < 2) return 0;
    return double(frames.size() - 1) / (frames.back().first - frames.front().first);
  }
  double stepsPerSecond() const {
    if (frames.size() < 2) return 0;
    long n = 0;
    for (size_t i = 1; i < frames.size(); ++i) n += frames[i].second;
    return double(n) / (frames.back().first - frames.front().first);
  }
};

// A titled separator (ImGui 1.86 has no SeparatorText).
void section(const char* title) {
  ImGui::Separator();
  ImGui::TextDisabled("%s", title);
}

class Viewer {
 public:
  Viewer(GLFWwindow* window, Scene scene) : window_(window) { load(std::move(scene)); }

  void load(Scene scene) {
    scene_ = std::move(scene);
    original_ = scene_;
    rebuild(true);
    // A body from a mesh file shows that mesh (embedded) first; other bodies the smooth surface.
    view_.surface = built_.embedded ? SurfaceMode::Embedded : SurfaceMode::Smooth;
    view_.forces = true;  // the contact force arrows on the tools
    // Each body keeps its physical size when its resolution changes.
    edits_.clear();
    for (size_t i = 0; i < built_.numBodies(); ++i) {
      const VoxelVolume& v = built_.body(i).volume;
      BodyEdit e;
      e.extent = v.voxelSize() * std::max(v.nx(), v.ny());
      e.sizeVoxels = std::clamp(std::max(v.nx(), v.ny()), 4, 48);
      edits_.push_back(e);
    }
    editBody_ = 0;
  }

  // Rebuilds the world from scene_ (settings changed); reframes the camera on a new scene.
  void rebuild(bool reframe) {
    built_ = buildScene(scene_);
    body_ = makeBodyView(built_);
    drag_.reset();
    steps_ = 0;
    if (reframe) reframeCamera();
  }

  // Frames the scene in the part of the window right of the panel.
  void reframeCamera() {
    Vec3 lo, hi;
    sceneBounds(*built_.world, &lo, &hi);
    camera_ = frameBox(lo, hi, scene_.dim == 2);
    int width, height;
    glfwGetWindowSize(window_, &width, &height);
    camera_.pan(kPanelWidth / 2, 0, height);
  }

  void frame(double wallNow, double frameSeconds) {
    World& w = *built_.world;
    long steps = 0;
    behind_ = false;
    if (!paused_ || stepOnce_) {
      const double want = stepOnce_ ? w.dt() : std::min(frameSeconds, kMaxFrameSeconds) * speed_;
      const long n = std::max(1L, std::lround(want / w.dt()));
      const auto start = Clock::now();
      w.restartForceAverage();  // the force arrows: averaged over this frame's steps
      for (long k = 0; k < n; ++k) {
        if (drag_) feedDrag(*built_.world, *drag_, double(k + 1) / double(n), want);
        w.step();
        ++steps;
        if (std::chrono::duration<double>(Clock::now() - start).count() > kStepBudgetSeconds && k + 1 < n) {
          behind_ = true;  // drop the rest: the simulation runs slower than real time
          if (drag_) feedDrag(*built_.world, *drag_, 1.0, want);
          break;
        }
      }
      if (drag_) drag_->from = drag_->to;
      stepOnce_ = false;
      if (!finite(w)) {
        status_ = "simulation diverged; reset";
        rebuild(false);
      }
    }
    steps_ += steps;
    rates_.add(wallNow, steps);
    if (steps > 0) realTime_ = 0.9 * realTime_ + 0.1 * (double(steps) * w.dt() / std::max(frameSeconds, 1e-6));
  }

  void draw(int width, int height, Renderer& renderer) {
    renderer.draw(buildDrawList(body_, *built_.world, view_, width, height), camera_, width, height);
  }

  void panel() {
    World& w = *built_.world;
    ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(kPanelWidth, 0), ImGuiCond_FirstUseEver);
    ImGui::Begin("gradel");
    // ---- live figures ----
    ImGui::Text("%.0f fps   %.0f steps/s   real time x%.2f", rates_.fps(), rates_.stepsPerSecond(), realTime_);
    if (behind_) ImGui::TextColored(ImVec4(0.9f, 0.1f, 0.1f, 1), "cannot keep up: simulation slower than real time");
    ImGui::Text("t = %.3f s  dt = %.3g s  %s", w.time(), w.dt(), integratorKindName(w.settings().integrator));
    if (!w.integratorChoice().empty()) ImGui::TextWrapped("auto: %s", w.integratorChoice().c_str());
    ImGui::Text("%zu elements  %zu vertices  %zu pairs", w.model().numElements(), w.model().numVertices(),
                w.model().numPairs());
    const std::vector<Real> es = w.elementStress();
    ImGui::Text("max stress %.4f", es.empty() ? 0.0 : *std::max_element(es.begin(), es.end()));
    // Several bodies: a row of figures per body (render/body_table.h); the lines above are all of them.
    if (built_.numBodies() > 1 &&
        ImGui::BeginTable("bodies", 5,
                          ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingFixedFit)) {
      for (const char* h : {"body", "vertices", "kinetic [J]", "elastic [J]", "max stress"}) ImGui::TableSetupColumn(h);
      ImGui::TableHeadersRow();
      for (const BodyRow& r : bodyTable(built_)) {
        ImGui::TableNextRow();
        ImGui::TableNextColumn(), ImGui::TextUnformatted(r.name.c_str());
        ImGui::TableNextColumn(), ImGui::Text("%zu", r.vertices);
        ImGui::TableNextColumn(), ImGui::Text("%.3g", r.kineticEnergy);
        ImGui::TableNextColumn(), ImGui::Text("%.3g", r.elasticEnergy);
        ImGui::TableNextColumn(), ImGui::Text("%.4f", r.maxStress);
      }
      ImGui::EndTable();
    }
    if (!status_.empty()) ImGui::TextColored(ImVec4(0.8f, 0.3f, 0.0f, 1), "%s", status_.c_str());

    // ---- run ----
    if (ImGui::Button(paused_ ? "Run" : "Pause")) paused_ = !paused_;
    ImGui::SameLine();
    if (ImGui::Button("Step")) paused_ = true, stepOnce_ = true;
    ImGui::SameLine();
    if (ImGui::Button("Reset")) scene_ = original_, rebuild(false);
    ImGui::SliderFloat("speed", &speed_, 0.05f, 2.0f, "x%.2f");

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
    if (ImGui::Button("Play (free manipulator)")) load(parseScene(kPlayScene, "play"));
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
    ImGui::Checkbox("wireframe (levels)", &view_.wireframe);
    ImGui::SameLine();
    ImGui::Checkbox("vertices", &view_.vertices);
    ImGui::Checkbox("stress colour", &view_.stress);
    ImGui::Checkbox("tool forces", &view_.forces);
    float scale = float(view_.stressScale);
    if (view_.stress && ImGui::SliderFloat("stress scale", &scale, 0.005f, 0.3f, "%.3f", ImGuiSliderFlags_Logarithmic))
      view_.stressScale = scale;
    if (ImGui::Button("Reframe camera")) reframeCamera();

    // ---- body and settings: any change rebuilds the world ----
    section("Body (changes restart)");
    bool changed = false, reshaped = false;
    static const char* shapes[] = {"sphere", "box", "cylinder"};
    static const char* layouts[] = {"gradational", "uniform", "voxel"};
    // With several bodies the settings below are those of the body picked here.
    editBody_ = std::min(editBody_, int(scene_.numBodies()) - 1);
    if (scene_.numBodies() > 1 && ImGui::BeginCombo("edit body", scene_.bodyAt(size_t(editBody_)).name.c_str())) {
      for (size_t i = 0; i < scene_.numBodies(); ++i)
        if (ImGui::Selectable(scene_.bodyAt(i).name.c_str(), int(i) == editBody_)) editBody_ = int(i);
      ImGui::EndCombo();
    }
    BodySettings& body = scene_.bodyAt(size_t(editBody_));
    BodyEdit& edit = edits_.at(size_t(editBody_));
    if (ImGui::Combo("shape", &edit.shapeIndex, shapes, scene_.dim == 3 ? 3 : 2)) changed = reshaped = true;
    if (ImGui::SliderInt("size [voxels]", &edit.sizeVoxels, 4, 48)) changed = reshaped = true;
    int layout = int(body.layout);
    if (ImGui::Combo("layout", &layout, layouts, 3)) body.layout = LayoutKind(layout), changed = true;
    float E = float(body.material.youngsModulus), rho = float(body.material.density);
    if (ImGui::SliderFloat("E [Pa]", &E, 1e3f, 1e7f, "%.3g", ImGuiSliderFlags_Logarithmic))
      body.material.youngsModulus = E, changed = true;
    if (ImGui::SliderFloat("density", &rho, 100.f, 5000.f, "%.0f kg/m3")) body.material.density = rho, changed = true;
    if (!body.material.regions.empty())
      ImGui::TextWrapped("this body has %zu materials per region: E and density above are the default for other labels",
                         body.material.regions.size());
    float damping = float(scene_.simulation.damping);
    if (ImGui::SliderFloat("damping [1/s]", &damping, 0.f, 20.f, "%.2f"))
      scene_.simulation.damping = damping, changed = true;
    float friction = float(scene_.domain.friction);
    if (ImGui::SliderFloat("friction", &friction, 0.f, 2.f, "%.2f")) {
      scene_.domain.friction = friction;
      for (ManipulatorSettings& m : scene_.manipulators) m.friction = friction;
      changed = true;
    }
    int integrator = int(scene_.simulation.integrator);
    static const char* integrators[] = {"symplectic", "forward_euler", "implicit", "large_step",
                                        "auto"};  // IntegratorKind order
    if (ImGui::Combo("integrator", &integrator, integrators, 5))
      scene_.simulation.integrator = IntegratorKind(integrator), changed = true;
    bool autoDt = scene_.simulation.dt == 0;
    if (ImGui::Checkbox("dt auto", &autoDt)) scene_.simulation.dt = autoDt ? 0 : w.dt(), changed = true;
    if (!autoDt) {
      float dt = float(scene_.simulation.dt * 1e3);
      ImGui::SameLine();
      ImGui::SetNextItemWidth(140);
      if (ImGui::SliderFloat("dt [ms]", &dt, 0.005f, 2.0f, "%.3f", ImGuiSliderFlags_Logarithmic))
        scene_.simulation.dt = dt * 1e-3, changed = true;
    }
    float g = float(-scene_.simulation.gravity.y());
    if (ImGui::SliderFloat("gravity [m/s2]", &g, 0.f, 20.f, "%.2f"))
      scene_.simulation.gravity = Vec3(0, -g, 0), changed = true;

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
      if (reshaped) {  // a preset shape of the same physical size replaces the body's volume
        body.shape = presetShape(shapes[edit.shapeIndex], edit.sizeVoxels, scene_.dim, edit.extent / edit.sizeVoxels);
        body.source = nullptr;
      }
      keepManipulatorPoses(*built_.world, scene_);
      try {
        rebuild(false);
        status_.clear();
      } catch (const InputError& e) {
        status_ = e.what();
        scene_ = original_;
        rebuild(false);
      }
    }
    ImGui::End();
  }

  // ---- mouse ----
  void mouseButton(int button, int action, int mods) {
    if (ImGui::GetIO().WantCaptureMouse && action == GLFW_PRESS) return;
    double x, y;
    glfwGetCursorPos(window_, &x, &y);
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
      if (const std::optional<size_t> m = pickManipulator(camera_, *built_.world, x, y, width, height)) {
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

  void scroll(double dy) {
    if (ImGui::GetIO().WantCaptureMouse) return;
    if (mode_ == Mode::Drag && drag_ && !camera_.flat) {
      int width, height;
      glfwGetWindowSize(window_, &width, &height);
      dragInDepth(camera_, *drag_, dy * 10 * pixelSize(camera_, height));
      return;
    }
    camera_.zoom(dy);
  }

  const Camera& camera() const { return camera_; }
  World& world() { return *built_.world; }
  long totalSteps() const { return steps_; }
  const Rates& rates() const { return rates_; }
  double realTime() const { return realTime_; }
  bool behind() const { return behind_; }
  const ViewOptions& view() const { return view_; }
  void setView(const ViewOptions& v) { view_ = v; }

  void openScene(const std::string& path) {
    try {
      load(loadScene(path));
      status_.clear();
    } catch (const InputError& e) {
      status_ = e.what();
    }
  }

 private:
  enum class Mode { None, Orbit, Pan, Drag };
  static bool finite(const World& w) {
    for (const Vec3& p : w.state().positions)
      if (!p.allFinite()) return false;
    return true;
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
    // Beside the body being edited, on the side away from the other manipulators.
    const std::vector<Vec3>& x = built_.world->state().positions;
    const BodyRange& range = built_.range(size_t(editBody_));
    Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
    if (range.vertexEnd > range.vertexBegin) lo = hi = x[range.vertexBegin];
    for (uint32_t i = range.vertexBegin; i < range.vertexEnd; ++i) lo = lo.cwiseMin(x[i]), hi = hi.cwiseMax(x[i]);
    const Vec3 c = (lo + hi) / 2;
    const Real side = scene_.manipulators.size() % 2 == 0 ? -1 : 1;
    Vec3 p = c + Vec3(side * (0.5 * extent + m.radius + 0.05), 0, 0);
    if (scene_.dim == 2) p.z() = 0;
    m.path.keys = {Keyframe{0, p, std::nullopt}};
    keepManipulatorPoses(*built_.world, scene_);
    scene_.manipulators.push_back(m);
  }

  GLFWwindow* window_;
  Scene scene_, original_;
  BuiltScene built_;
  BodyView body_;
  Camera camera_;
  ViewOptions view_;
  Rates rates_;
  std::optional<ManipulatorDrag> drag_;
  Mode mode_ = Mode::None;
  double lastX_ = 0, lastY_ = 0;
  bool shift_ = false, paused_ = false, stepOnce_ = false, behind_ = false;
  float speed_ = 1.0f;
  double realTime_ = 0;
  long steps_ = 0;
  /// The panel's shape settings of one body (the scene holds the rest).
  struct BodyEdit {
    int shapeIndex = 0, sizeVoxels = 12;
    Real extent = 0.12;  ///< [m] kept when the resolution changes.
  };
  std::vector<BodyEdit> edits_;  ///< Per body.
  int editBody_ = 0;             ///< The body the "Body" settings edit.
  std::string status_;
};

Viewer* gViewer = nullptr;

void onMouseButton(GLFWwindow* w, int button, int action, int mods) {
  ImGui_ImplGlfw_MouseButtonCallback(w, button, action, mods);
  gViewer->mouseButton(button, action, mods);
}
void onCursor(GLFWwindow*, double x, double y) { gViewer->cursor(x, y); }
void onScroll(GLFWwindow* w, double dx, double dy) {
  ImGui_ImplGlfw_ScrollCallback(w, dx, dy);
  gViewer->scroll(dy);
}

int run(const Options& o) {
  int width = 0, height = 0;
  parseSize(o.size, &width, &height);
  Scene scene = o.scene.empty() ? parseScene(kPlayScene, "play") : loadScene(o.scene);
  if (!(o.runFor >= 0) || !std::isfinite(o.runFor)) throw InputError("--run-for: must be >= 0 seconds");

  glfwSetErrorCallback(
      [](int code, const char* text) { std::cerr << "gradel-view: GLFW error " << code << ": " << text << "\n"; });
  if (!glfwInit()) {
    std::cerr << "gradel-view: cannot open a window (no display? set DISPLAY, or use `gradel render` headless)\n";
    return 4;
  }
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_SAMPLES, 4);
  GLFWwindow* window = glfwCreateWindow(width, height, "gradel", nullptr, nullptr);
  if (!window) {
    glfwTerminate();
    std::cerr << "gradel-view: cannot create an OpenGL 3.3 core window\n";
    return 4;
  }
  glfwMakeContextCurrent(window);
  // Screenshots and timing runs measure the simulation, not the monitor's refresh.
  glfwSwapInterval(o.screenshot.empty() && o.runFor == 0 ? 1 : 0);

  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;
  ImGui::StyleColorsLight();
  ImGui_ImplGlfw_InitForOpenGL(window, false);
  ImGui_ImplOpenGL3_Init("#version 330 core");

  int code = 0;
  {
    Renderer renderer;
    Viewer viewer(window, std::move(scene));
    gViewer = &viewer;
    glfwSetMouseButtonCallback(window, onMouseButton);
    glfwSetCursorPosCallback(window, onCursor);
    glfwSetScrollCallback(window, onScroll);
    glfwSetKeyCallback(window, ImGui_ImplGlfw_KeyCallback);
    glfwSetCharCallback(window, ImGui_ImplGlfw_CharCallback);
    glfwSetWindowFocusCallback(window, ImGui_ImplGlfw_WindowFocusCallback);
    glfwSetCursorEnterCallback(window, ImGui_ImplGlfw_CursorEnterCallback);
    if (!o.screenshot.empty()) {
      ViewOptions v;
      v.surface = viewer.view().surface;  // the scene's own choice (embedded for a mesh file)
      v.stress = true;
      viewer.setView(v);
    }

    const auto start = Clock::now();
    double last = 0;
    long frames = 0;
    while (!glfwWindowShouldClose(window)) {
      glfwPollEvents();
      const double now = std::chrono::duration<double>(Clock::now() - start).count();
      // A screenshot advances fixed simulated time per frame so the picture does not depend on
      // the machine's speed.
      const double frameSeconds = o.screenshot.empty() ? now - last : 1.0 / 60;
      last = now;
      viewer.frame(now, frameSeconds);

      int fbw, fbh;
      glfwGetFramebufferSize(window, &fbw, &fbh);
      ImGui_ImplOpenGL3_NewFrame();
      ImGui_ImplGlfw_NewFrame();
      ImGui::NewFrame();
      viewer.panel();
      ImGui::Render();
      viewer.draw(fbw, fbh, renderer);
      ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
      ++frames;

      if (!o.screenshot.empty() && viewer.world().time() >= o.screenshotTime) {
        writePng(o.screenshot, readPixels(fbw, fbh));
        std::cout
            << nlohmann::json{{"screenshot", o.screenshot}, {"size", {fbw, fbh}}, {"t", viewer.world().time()}}.dump()
            << "\n";
        break;
      }
      glfwSwapBuffers(window);
      if (o.runFor > 0 && now >= o.runFor) {
        const World& w = viewer.world();
        nlohmann::json j;
        j["frames_per_second"] = double(frames) / now;
        j["steps_per_second"] = double(viewer.totalSteps()) / now;
        j["real_time_factor"] = w.time() / now;
        j["dt"] = w.dt();
        j["elements"] = w.model().numElements();
        j["vertices"] = w.model().numVertices();
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
