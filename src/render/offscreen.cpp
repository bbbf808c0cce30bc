#include "gradel/render/offscreen.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include "gl.h"
#include "gradel/render/renderer.h"

namespace gradel::render {

namespace {
constexpr int kSamples = 4;  // multisampling for smooth edges in the pictures

std::string eglError(const char* what) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "%s failed (EGL error 0x%04x)", what, eglGetError());
  return buf;
}
}  // namespace

OffscreenContext::OffscreenContext(int width, int height) : width_(width), height_(height) {
  if (width < 16 || height < 16 || width > 8192 || height > 8192)
    throw GlUnavailable("picture size " + std::to_string(width) + "x" + std::to_string(height) + " outside 16..8192");
  auto getPlatformDisplay =
      reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (!getPlatformDisplay) throw GlUnavailable("EGL has no eglGetPlatformDisplayEXT (install libegl-mesa0)");
  EGLDisplay dpy = getPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (dpy == EGL_NO_DISPLAY)
    throw GlUnavailable("no EGL surfaceless display (install libegl-mesa0 and libgl1-mesa-dri)");
  EGLint major = 0, minor = 0;
  if (!eglInitialize(dpy, &major, &minor)) throw GlUnavailable(eglError("eglInitialize (surfaceless)"));
  display_ = dpy;
  if (!eglBindAPI(EGL_OPENGL_API)) throw GlUnavailable(eglError("eglBindAPI(OpenGL)"));
  // We draw into our own framebuffer object, so any config will do; surfaceless configs are
  // pbuffer configs (EGL's default surface type, window, matches none of them).
  const EGLint configAttribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig config = EGL_NO_CONFIG_KHR;
  EGLint count = 0;
  if (!eglChooseConfig(dpy, configAttribs, &config, 1, &count) || count < 1) config = EGL_NO_CONFIG_KHR;
  const EGLint contextAttribs[] = {
      EGL_CONTEXT_MAJOR_VERSION,           3,       EGL_CONTEXT_MINOR_VERSION, 3, EGL_CONTEXT_OPENGL_PROFILE_MASK,
      EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
  EGLContext ctx = eglCreateContext(dpy, config, EGL_NO_CONTEXT, contextAttribs);
  if (ctx == EGL_NO_CONTEXT) throw GlUnavailable(eglError("eglCreateContext (OpenGL 3.3 core)"));
  context_ = ctx;
  if (!eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) throw GlUnavailable(eglError("eglMakeCurrent"));

  glGenFramebuffers(1, &msFbo_);
  glGenRenderbuffers(1, &msColor_);
  glGenRenderbuffers(1, &msDepth_);
  glBindRenderbuffer(GL_RENDERBUFFER, msColor_);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, kSamples, GL_RGBA8, width, height);
  glBindRenderbuffer(GL_RENDERBUFFER, msDepth_);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, kSamples, GL_DEPTH_COMPONENT24, width, height);
  glBindFramebuffer(GL_FRAMEBUFFER, msFbo_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, msColor_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, msDepth_);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw GlUnavailable("multisampled framebuffer incomplete");

  glGenFramebuffers(1, &fbo_);
  glGenRenderbuffers(1, &color_);
  glBindRenderbuffer(GL_RENDERBUFFER, color_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color_);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw GlUnavailable("resolve framebuffer incomplete");
  glBindFramebuffer(GL_FRAMEBUFFER, msFbo_);
}

OffscreenContext::~OffscreenContext() {
  if (context_) {
    glDeleteFramebuffers(1, &msFbo_);
    glDeleteFramebuffers(1, &fbo_);
    glDeleteRenderbuffers(1, &msColor_);
    glDeleteRenderbuffers(1, &msDepth_);
    glDeleteRenderbuffers(1, &color_);
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display_, context_);
  }
  if (display_) eglTerminate(display_);
}

Image OffscreenContext::read() {
  glBindFramebuffer(GL_READ_FRAMEBUFFER, msFbo_);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, fbo_);
  glBlitFramebuffer(0, 0, width_, height_, 0, 0, width_, height_, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
  Image img = readPixels(width_, height_);
  glBindFramebuffer(GL_FRAMEBUFFER, msFbo_);
  return img;
}

}  // namespace gradel::render
