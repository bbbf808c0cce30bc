#include "gradel/mesh.h"

#include <cstring>
#include <fstream>

namespace gradel {

namespace {
std::ofstream openOrThrow(const std::string& path, std::ios::openmode mode) {
  std::ofstream out(path, mode);
  if (!out) throw InputError(path + ": cannot open for writing: " + std::strerror(errno));
  return out;
}
void closeOrThrow(std::ofstream& out, const std::string& path) {
  out.close();
  if (!out) throw InputError(path + ": write failed");
}
}  // namespace

void writeObj(const std::string& path, const TriangleMesh& mesh) {
  std::ofstream out = openOrThrow(path, std::ios::out | std::ios::trunc);
  out.precision(9);
  out << "# gradel display surface\n";
  for (const Vec3& v : mesh.vertices) out << "v " << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
  const bool normals = mesh.normals.size() == mesh.vertices.size() && !mesh.normals.empty();
  if (normals)
    for (const Vec3& n : mesh.normals) out << "vn " << n.x() << ' ' << n.y() << ' ' << n.z() << '\n';
  for (const auto& t : mesh.triangles) {
    out << 'f';
    for (uint32_t i : t) {
      out << ' ' << i + 1;
      if (normals) out << "//" << i + 1;
    }
    out << '\n';
  }
  closeOrThrow(out, path);
}

void writePly(const std::string& path, const TriangleMesh& mesh) {
  std::ofstream out = openOrThrow(path, std::ios::out | std::ios::trunc | std::ios::binary);
  const bool normals = mesh.normals.size() == mesh.vertices.size() && !mesh.normals.empty();
  out << "ply\nformat binary_little_endian 1.0\ncomment gradel display surface\n"
      << "element vertex " << mesh.vertices.size() << "\nproperty float x\nproperty float y\nproperty float z\n";
  if (normals) out << "property float nx\nproperty float ny\nproperty float nz\n";
  out << "element face " << mesh.triangles.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
  auto put = [&](const void* p, size_t n) { out.write(static_cast<const char*>(p), std::streamsize(n)); };
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const float p[3] = {float(mesh.vertices[i].x()), float(mesh.vertices[i].y()), float(mesh.vertices[i].z())};
    put(p, sizeof p);
    if (normals) {
      const float n[3] = {float(mesh.normals[i].x()), float(mesh.normals[i].y()), float(mesh.normals[i].z())};
      put(n, sizeof n);
    }
  }
  for (const auto& t : mesh.triangles) {
    const unsigned char three = 3;
    const int32_t idx[3] = {int32_t(t[0]), int32_t(t[1]), int32_t(t[2])};
    put(&three, 1);
    put(idx, sizeof idx);
  }
  closeOrThrow(out, path);
}

}  // namespace gradel
