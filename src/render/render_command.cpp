#include "gradel/render/render_command.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>

#include <nlohmann/json.hpp>

#include "gradel/divergence.h"
#include "gradel/output.h"
#include "gradel/render/draw_list.h"
#include "gradel/render/offscreen.h"
#include "gradel/render/renderer.h"
#include "gradel/scene.h"
#include "gradel/shared/frame_loop.h"

namespace gradel::render {

namespace fs = std::filesystem;

void parseSize(const std::string& text, int* width, int* height) {
  int w = 0, h = 0;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%dx%d%c", &w, &h, &tail) != 2 || w < 16 || h < 16 || w > 8192 || h > 8192)
    throw InputError("--size: \"" + text + "\" (expected WxH, each 16..8192, e.g. 640x480)");
  *width = w;
  *height = h;
}

namespace {

bool haveFfmpeg() { return std::system("command -v ffmpeg >/dev/null 2>&1") == 0; }

std::string shellQuote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

}  // namespace

int runRenderCommand(const RenderCommandOptions& o) {
  // All input is checked before anything is written.
  Scene scene = loadScene(o.scene);
  int width = 0, height = 0;
  parseSize(o.size, &width, &height);
  ViewOptions view;
  // "auto" is decided once the scene is built (does the body come from a mesh file?).
  if (o.surface != "auto") view.surface = parseSurfaceMode(o.surface);
  view.stress = o.stress;
  view.wireframe = o.wireframe;
  view.forces = o.forces;
  view.vertices = o.vertices;
  view.section = o.section;
  if (!(o.start >= 0) || !std::isfinite(o.start)) throw InputError("--start: must be >= 0 seconds");
  if (!(o.zoom > 0) || !std::isfinite(o.zoom)) throw InputError("--zoom: must be a positive number");
  for (const auto& [name, angle] : {std::pair{"--yaw", o.yaw}, {"--pitch", o.pitch}})
    if (angle && (!std::isfinite(*angle) || std::abs(*angle) > 10))
      throw InputError(std::string(name) + ": must be an angle in radians");
  if (!(o.stressScale >= 0) || !std::isfinite(o.stressScale))
    throw InputError("--stress-scale: must be a stress in Pa >= 0 (0: auto)");
  view.stressScale = o.stressScale;
  if (o.exportFormat != "none" && o.exportFormat != "obj" && o.exportFormat != "ply")
    throw InputError("--export: \"" + o.exportFormat + "\" (expected none, obj or ply)");
  if (o.noPictures && o.exportFormat == "none") throw InputError("--no-pictures without --export: nothing to write");
  if (o.frames && (*o.frames < 1 || *o.frames > 100000)) throw InputError("--frames: must be in [1, 100000]");

  BuiltScene built;
  try {
    built = buildScene(scene);
  } catch (const InputError& e) {
    throw e.at(o.scene);
  }
  World& world = *built.world;
  // The frames (frame_loop.h, as `gradel run`): from --start every frame_interval to the end of
  // the duration (the last one exactly at its end), or --frames of them.
  FrameSchedule schedule;
  try {
    schedule = frameSchedule(o.start, scene.output.duration, scene.output.frameInterval, world.dt(),
                             o.frames ? std::optional<long>(*o.frames) : std::nullopt);
  } catch (const InputError& e) {
    throw e.at(o.scene, "simulation.");
  }
  const Real interval = schedule.interval;
  // auto: none under a section (the section is what is looked at), else the body's own mesh or smooth.
  if (o.surface == "auto")
    view.surface = o.section ? SurfaceMode::None : built.bodies[0].embedded ? SurfaceMode::Embedded : SurfaceMode::Smooth;
  const BodyView body = makeBodyView(built);
  Vec3 lo, hi;
  sceneBounds(world, &lo, &hi);
  // Sized to hold the body and the manipulators' paths, centred on the body.
  Camera camera = frameBox(lo, hi, scene.dim == 2);
  camera.target = Vec3::Zero();
  for (const Vec3& p : world.state().positions) camera.target += p;
  camera.target /= Real(world.state().positions.size());
  if (o.yaw && !camera.flat) camera.yaw = *o.yaw;
  if (o.pitch && !camera.flat) camera.pitch = std::clamp(*o.pitch, -1.5, 1.5);
  camera.distance /= o.zoom;

  std::optional<OffscreenContext> gl;
  std::optional<Renderer> renderer;
  if (!o.noPictures) {
    try {
      gl.emplace(width, height);
      renderer.emplace();
    } catch (const std::exception& e) {
      std::cerr << "gradel render: no OpenGL: " << e.what() << "\n";
      return 4;
    }
  }

  OutputDirectory dir(o.out.empty() ? fs::path("out") / (scene.name + "-render") : fs::path(o.out), "render.json");
  const SurfaceKind exportKind = view.surface == SurfaceMode::Voxel ? SurfaceKind::Voxel : SurfaceKind::Smooth;
  const DisplaySurface& exportSurface = exportKind == SurfaceKind::Voxel ? body.voxel : body.smooth;
  const auto wallStart = std::chrono::steady_clock::now();
  double drawSeconds = 0;
  const auto onFrame = [&](size_t f) {
    char name[48];
    if (!o.noPictures) {
      const auto t0 = std::chrono::steady_clock::now();
      char caption[96];
      std::snprintf(caption, sizeof caption, "%s  t = %.2f s", scene.name.c_str(), world.time());
      view.caption = caption;
      renderer->draw(buildDrawList(body, world, view, width, height), camera, width, height);
      const Image img = gl->read();
      drawSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::snprintf(name, sizeof name, "frame_%05zu.png", f);
      writePng(dir.file(name).string(), img);
    }
    if (o.exportFormat != "none") {
      std::snprintf(name, sizeof name, "surface_%05zu.%s", f, o.exportFormat.c_str());
      const TriangleMesh m = view.surface == SurfaceMode::Embedded && body.embedded
                                 ? embeddedMesh(*body.embedded, world.state().positions)
                                 : surfaceMesh(exportSurface, world.state().positions);
      if (o.exportFormat == "obj")
        writeObj(dir.file(name).string(), m);
      else
        writePly(dir.file(name).string(), m);
    }
  };
  // A non-finite state stops the run with exit 3, as `gradel run` (gradel_main.cpp's exit codes).
  struct NonFinite {};
  FrameLoopChecks checks;
  checks.afterChunk = [&] {
    if (!finiteState(world.state())) throw NonFinite{};
  };
  size_t frames = 0;
  try {
    frames = runFrames(world, schedule, onFrame, checks);
  } catch (const NonFinite&) {
    std::cerr << "gradel render: simulation diverged at t=" << world.time() << " s (dt = " << world.dt()
              << " s): non-finite numbers\n";
    return 3;
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wallStart).count();

  bool video = false;
  if (!o.noPictures && !o.noVideo && frames > 1 && haveFfmpeg()) {
    // Even sizes for yuv420p; played back in real time (one frame per frame interval).
    const std::string cmd = "ffmpeg -loglevel error -y -framerate " + std::to_string(1.0 / interval) + " -i " +
                            shellQuote((dir.path() / "frame_%05d.png").string()) +
                            " -vf 'scale=trunc(iw/2)*2:trunc(ih/2)*2' -pix_fmt yuv420p " +
                            shellQuote((dir.path() / "render.mp4").string()) + " </dev/null";
    video = std::system(cmd.c_str()) == 0;
    if (!video) std::cerr << "gradel render: ffmpeg failed; PNG frames only\n";
  }

  nlohmann::json j;
  j["scene"] = scene.name;
  j["frames"] = frames;
  j["size"] = {width, height};
  j["simulated_seconds"] = world.time();
  j["wall_seconds"] = wall;
  j["draw_seconds"] = drawSeconds;
  j["gl_renderer"] = o.noPictures ? std::string("none") : Renderer::glRenderer();
  j["video"] = video ? "render.mp4" : "";
  j["export"] = o.exportFormat;
  static const char* kSurfaceNames[] = {"smooth", "voxel", "embedded", "none"};  // SurfaceMode order
  j["surface"] = kSurfaceNames[int(view.surface)];
  j["out"] = dir.target().string();
  {
    std::FILE* f = std::fopen(dir.file("render.json").c_str(), "w");
    if (!f) throw InputError(dir.file("render.json").string() + ": cannot write");
    std::fputs((j.dump(2) + "\n").c_str(), f);
    std::fclose(f);
  }
  dir.commit();
  std::cout << j.dump(2) << "\n";
  return 0;
}

}  // namespace gradel::render
