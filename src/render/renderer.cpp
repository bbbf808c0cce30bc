#include "gradel/render/renderer.h"

#include <stdexcept>

#include "gl.h"

namespace gradel::render {

namespace {

// One program for everything: lit (two-sided Lambert + ambient) or unlit vertex colours.
constexpr const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 aPos;
layout(location = 1) in vec3 aNormal;
layout(location = 2) in vec4 aColor;
uniform mat4 uMvp;
uniform float uPointSize;
out vec3 vNormal;
out vec4 vColor;
void main() {
  gl_Position = uMvp * vec4(aPos, 1.0);
  gl_PointSize = uPointSize;
  vNormal = aNormal;
  vColor = aColor;
})";

constexpr const char* kFragmentShader = R"(#version 330 core
in vec3 vNormal;
in vec4 vColor;
uniform int uLit;
uniform vec3 uLight;
out vec4 fragColor;
void main() {
  if (uLit == 0) { fragColor = vColor; return; }
  vec3 n = normalize(vNormal);
  float d = abs(dot(n, uLight));
  fragColor = vec4(vColor.rgb * (0.35 + 0.65 * d), vColor.a);
})";

// Throws with the GL log when a shader did not compile or the program did not link.
template <class GetIv, class GetLog>
void check(GLuint object, GLenum status, GetIv getIv, GetLog getLog, const char* what) {
  GLint ok = 0;
  getIv(object, status, &ok);
  if (ok) return;
  char log[2048];
  getLog(object, sizeof log, nullptr, log);
  throw std::runtime_error(std::string(what) + " failed: " + log);
}

unsigned compile(GLenum type, const char* src) {
  const GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  check(s, GL_COMPILE_STATUS, glGetShaderiv, glGetShaderInfoLog, "shader compile");
  return s;
}

}  // namespace

Renderer::Renderer() {
  const GLuint vs = compile(GL_VERTEX_SHADER, kVertexShader), fs = compile(GL_FRAGMENT_SHADER, kFragmentShader);
  program_ = glCreateProgram();
  glAttachShader(program_, vs);
  glAttachShader(program_, fs);
  glLinkProgram(program_);
  glDeleteShader(vs);
  glDeleteShader(fs);
  check(program_, GL_LINK_STATUS, glGetProgramiv, glGetProgramInfoLog, "shader link");
  locMvp_ = glGetUniformLocation(program_, "uMvp");
  locLit_ = glGetUniformLocation(program_, "uLit");
  locLight_ = glGetUniformLocation(program_, "uLight");
  locPointSize_ = glGetUniformLocation(program_, "uPointSize");
  auto vertexArray = [](unsigned* vao, unsigned* vbo) {
    glGenVertexArrays(1, vao);
    glGenBuffers(1, vbo);
    glBindVertexArray(*vao);
    glBindBuffer(GL_ARRAY_BUFFER, *vbo);
    glEnableVertexAttribArray(0);
    glEnableVertexAttribArray(1);
    glEnableVertexAttribArray(2);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(DrawVertex),
                          reinterpret_cast<void*>(offsetof(DrawVertex, position)));
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(DrawVertex),
                          reinterpret_cast<void*>(offsetof(DrawVertex, normal)));
    glVertexAttribPointer(2, 4, GL_FLOAT, GL_FALSE, sizeof(DrawVertex),
                          reinterpret_cast<void*>(offsetof(DrawVertex, color)));
  };
  vertexArray(&vao_, &vbo_);
  vertexArray(&meshVao_, &meshVbo_);
  glGenBuffers(1, &meshEbo_);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, meshEbo_);  // part of meshVao_'s state
  glBindVertexArray(0);
}

Renderer::~Renderer() {
  glDeleteBuffers(1, &vbo_);
  glDeleteVertexArrays(1, &vao_);
  glDeleteBuffers(1, &meshVbo_);
  glDeleteBuffers(1, &meshEbo_);
  glDeleteVertexArrays(1, &meshVao_);
  glDeleteProgram(program_);
}

std::string Renderer::glRenderer() {
  const GLubyte* s = glGetString(GL_RENDERER);
  return s ? reinterpret_cast<const char*>(s) : "unknown";
}

void Renderer::draw(const DrawList& list, const Camera& camera, int width, int height) {
  glViewport(0, 0, width, height);
  glClearColor(list.background[0], list.background[1], list.background[2], 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glUseProgram(program_);
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glEnable(GL_PROGRAM_POINT_SIZE);

  auto drawArray = [&](const std::vector<DrawVertex>& v, GLenum mode) {
    if (v.empty()) return;
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(v.size() * sizeof(DrawVertex)), v.data(), GL_STREAM_DRAW);
    glDrawArrays(mode, 0, GLsizei(v.size()));
  };

  // ---- world: depth-tested ----
  const Mat4f mvp = camera.projection(Real(width) / height) * camera.view();
  // Light from over the viewer's right shoulder.
  const Vec3 light = (camera.eye() - camera.target).normalized() * 0.8 + camera.up() * 0.45 + camera.right() * 0.3;
  const Eigen::Vector3f l = light.normalized().cast<float>();
  glUniformMatrix4fv(locMvp_, 1, GL_FALSE, mvp.data());
  glUniform3f(locLight_, l.x(), l.y(), l.z());
  glUniform1f(locPointSize_, 4.0f);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);
  glDisable(GL_BLEND);
  glUniform1i(locLit_, 1);
  // Push filled triangles back a little so that lines on the surface stay visible.
  glEnable(GL_POLYGON_OFFSET_FILL);
  glPolygonOffset(1.0f, 1.0f);
  if (list.meshIndices && !list.meshIndices->empty() && !list.meshVertices.empty()) {
    glBindVertexArray(meshVao_);
    glBindBuffer(GL_ARRAY_BUFFER, meshVbo_);
    if (list.meshIndices != meshIndices_) {  // another body (or surface): its triangles, once
      meshIndices_ = list.meshIndices;
      glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(meshIndices_->size() * sizeof(uint32_t)), meshIndices_->data(),
                   GL_STATIC_DRAW);
    }
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(list.meshVertices.size() * sizeof(DrawVertex)), list.meshVertices.data(),
                 GL_STREAM_DRAW);
    glDrawElements(GL_TRIANGLES, GLsizei(meshIndices_->size()), GL_UNSIGNED_INT, nullptr);
    glBindVertexArray(vao_);
    glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  }
  drawArray(list.triangles, GL_TRIANGLES);
  glDisable(GL_POLYGON_OFFSET_FILL);
  glUniform1i(locLit_, 0);
  drawArray(list.lines, GL_LINES);
  drawArray(list.points, GL_POINTS);

  // ---- overlay: pixels, y down ----
  Mat4f ortho = Mat4f::Identity();
  ortho(0, 0) = 2.0f / float(width);
  ortho(0, 3) = -1;
  ortho(1, 1) = -2.0f / float(height);
  ortho(1, 3) = 1;
  glUniformMatrix4fv(locMvp_, 1, GL_FALSE, ortho.data());
  glDisable(GL_DEPTH_TEST);
  drawArray(list.overlay, GL_TRIANGLES);
  glBindVertexArray(0);
  glUseProgram(0);
}

Image readPixels(int width, int height) {
  Image img;
  img.width = width;
  img.height = height;
  img.rgb.resize(size_t(width) * size_t(height) * 3);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, img.rgb.data());
  flipRows(img);
  return img;
}

}  // namespace gradel::render
