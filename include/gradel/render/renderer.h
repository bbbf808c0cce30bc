// Draws a DrawList with OpenGL 3.3 core into the current framebuffer. Needs a current GL 3.3
// context (a GLFW window in gradel-view, an EGL surfaceless context in `gradel render`).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "gradel/image.h"
#include "gradel/render/camera.h"
#include "gradel/render/draw_list.h"

namespace gradel::render {

class Renderer {
 public:
  /// Compiles the shaders; throws std::runtime_error with the GL log on failure.
  Renderer();
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// Clears the width x height viewport and draws the list as seen from `camera`.
  void draw(const DrawList& list, const Camera& camera, int width, int height);

  /// The GL_RENDERER string (e.g. "llvmpipe (LLVM 15.0.6, 256 bits)").
  static std::string glRenderer();

 private:
  unsigned program_ = 0, vao_ = 0, vbo_ = 0;
  // The indexed body surface: its own vertex array, vertex buffer and index buffer; the indices
  // are uploaded when another list of them comes in (held, so that its address is not reused).
  unsigned meshVao_ = 0, meshVbo_ = 0, meshEbo_ = 0;
  std::shared_ptr<const std::vector<uint32_t>> meshIndices_;
  int locMvp_ = -1, locLit_ = -1, locLight_ = -1, locPointSize_ = -1;
};

/// Reads the current read framebuffer's width x height pixels (rows top to bottom).
Image readPixels(int width, int height);

}  // namespace gradel::render
