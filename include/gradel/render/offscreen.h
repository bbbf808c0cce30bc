// An offscreen OpenGL 3.3 core context without any display: EGL on Mesa's surfaceless platform
// (software rasteriser llvmpipe when there is no GPU), drawing into a 4x multisampled
// framebuffer object that is resolved for reading.
#pragma once

#include <stdexcept>
#include <string>

#include "gradel/image.h"

namespace gradel::render {

/// No OpenGL could be had (no EGL, no surfaceless platform, no GL 3.3 core).
class GlUnavailable : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class OffscreenContext {
 public:
  /// Creates the context, makes it current on this thread and binds a width x height
  /// framebuffer. Throws GlUnavailable with the reason.
  OffscreenContext(int width, int height);
  ~OffscreenContext();
  OffscreenContext(const OffscreenContext&) = delete;
  OffscreenContext& operator=(const OffscreenContext&) = delete;

  int width() const { return width_; }
  int height() const { return height_; }
  /// Resolves the multisampled picture and reads it back.
  Image read();

 private:
  int width_, height_;
  void* display_ = nullptr;
  void* context_ = nullptr;
  unsigned msFbo_ = 0, msColor_ = 0, msDepth_ = 0, fbo_ = 0, color_ = 0;
};

}  // namespace gradel::render
