#include "render_cli.h"

namespace gradel::render {

CLI::App* addRenderCommand(CLI::App& app, RenderCommandOptions& o) {
  CLI::App* r = app.add_subcommand("render", "Simulate a scene and draw it offscreen into PNGs (+ MP4 with ffmpeg)");
  r->add_option("scene", o.scene, "Scene file (JSON, see docs/scenes.md)")->required();
  r->add_option("--out", o.out, "Result directory (default: out/<scene name>-render)");
  r->add_option("--frames", o.frames, "Number of frames at the scene's frame interval (default: the whole duration)");
  r->add_option("--size", o.size, "Picture size WxH [pixels]")->capture_default_str();
  r->add_option(
       "--surface", o.surface,
       "auto | smooth | voxel | embedded | none (auto: none with --section; the body's own mesh, embedded, when it "
       "comes from a mesh file; else smooth)")
      ->capture_default_str();
  r->add_flag("--stress", o.stress,
              "Colour the surface by von Mises stress (darker = higher), with a legend in Pa");
  r->add_flag("--wireframe", o.wireframe, "Draw the element outlines coloured by level");
  r->add_flag("--forces", o.forces,
              "Draw the contact force on each manipulator (averaged over the frame) as an arrow, with a legend in N");
  r->add_flag("--vertices", o.vertices, "Draw the model vertices");
  r->add_flag("--section", o.section, "With --wireframe: only the elements cut by the middle z plane (fig. 4)");
  r->add_option("--start", o.start, "Simulated time of the first frame [s]")->capture_default_str();
  r->add_option("--yaw", o.yaw, "Camera yaw about +y [rad] (0 = looking along -z)");
  r->add_option("--pitch", o.pitch, "Camera pitch above the horizon [rad]");
  r->add_option("--zoom", o.zoom, "Camera zoom factor (> 1 = closer)")->capture_default_str();
  r->add_option("--stress-scale", o.stressScale,
                "Von Mises stress drawn darkest [Pa]; 0 = auto (5 % strain of the stiffest material)")
      ->capture_default_str();
  r->add_option(
       "--export", o.exportFormat,
       "Also write the drawn surface per frame (the embedded mesh when it is drawn, else the display surface): "
       "none | obj | ply")
      ->capture_default_str();
  r->add_flag("--no-pictures", o.noPictures, "Write no PNGs (export only; needs no OpenGL)");
  r->add_flag("--no-video", o.noVideo, "Do not make render.mp4 even if ffmpeg is present");
  return r;
}

}  // namespace gradel::render
