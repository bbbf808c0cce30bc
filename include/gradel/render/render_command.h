// `gradel render SCENE.json --out DIR [--frames N] [--size WxH] ...`: simulates a scene and draws
// the viewer's pictures offscreen (EGL surfaceless) into DIR/frame_NNNNN.png, then DIR/render.mp4
// when ffmpeg is on the PATH; optionally exports the display surface of every frame as OBJ or
// PLY (DIR/surface_NNNNN.obj) for Blender. DIR/render.json summarises the run. The command-line
// options that fill RenderCommandOptions are the CLI's (apps/render_cli.h).
#pragma once

#include <optional>
#include <string>

namespace gradel::render {

struct RenderCommandOptions {
  std::string scene;
  std::string out;
  std::optional<int> frames;     ///< Frames at the scene's frame interval; default: the whole duration.
  std::string size = "640x480";  ///< WxH [pixels].
  std::string surface =
      "auto";  ///< auto | smooth | voxel | embedded | none (auto: embedded for a body from a mesh file, else smooth)
  bool stress = false;
  bool wireframe = false;
  bool forces = false;  ///< Arrows of the contact forces on the manipulators (ViewOptions::forces).
  bool vertices = false;
  bool section = false;               ///< Wireframe of the middle z section only.
  double start = 0;                   ///< [s] simulated time of the first frame.
  std::optional<double> yaw, pitch;   ///< [rad] camera angles (default: framing's 0.6, 0.35).
  double zoom = 1;                    ///< > 1 moves the camera closer.
  double stressScale = 0;             ///< [Pa] von Mises stress drawn darkest; 0 = auto (draw_list.h).
  std::string exportFormat = "none";  ///< none | obj | ply
  bool noPictures = false;            ///< Export only (no OpenGL needed).
  bool noVideo = false;
};

/// Runs it. Returns the exit code: 0 ok, 4 no OpenGL (message on stderr); throws InputError for
/// bad input (exit code 2 in the CLI).
int runRenderCommand(const RenderCommandOptions& o);

/// Parses "WxH" (each 16..8192). Throws InputError.
void parseSize(const std::string& text, int* width, int* height);

}  // namespace gradel::render
