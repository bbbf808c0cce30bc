// The narrow phase's inside test (body contacts): the angle-weighted pseudo-normal of the
// feature of a closed surface nearest to a point (Baerentzen & Aanaes 2005, "Signed distance
// computation using the angle weighted pseudonormal"), and which side of the faces around that
// feature a point lies on. Kernels over a ContactBody's faces at positions x.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

#include "gradel/contact_surface.h"

namespace gradel {
namespace {

[[maybe_unused]] Vec3 faceNormal(const std::array<uint32_t, 3>& t, const Vec3* x) {
  return (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]);
}

[[maybe_unused]] Vec3 unit(const Vec3& v) {
  const Real n = v.norm();
  return n > 0 ? Vec3(v / n) : Vec3::Zero();
}

// The angle-weighted pseudo-normal (not normalised) at surface vertex s of the body.
[[maybe_unused]] Vec3 vertexPseudoNormal(const ContactBody& body, uint32_t s, const Vec3* x) {
  const uint32_t a = body.vertices[s];
  Vec3 n = Vec3::Zero();
  for (uint32_t k = body.vertexTriStart[s]; k < body.vertexTriStart[s + 1]; ++k) {
    const auto& u = body.triangles[body.vertexTris[k]];
    const int i = u[0] == a ? 0 : (u[1] == a ? 1 : (u[2] == a ? 2 : -1));
    if (i < 0) {  // a vertex inside the face (buildContactBody)
      n += unit(faceNormal(u, x));
      continue;
    }
    const Vec3 e1 = x[u[size_t((i + 1) % 3)]] - x[a], e2 = x[u[size_t((i + 2) % 3)]] - x[a];
    const Real angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
    n += angle * unit(faceNormal(u, x));
  }
  return n;
}

// Which way a surface vertex's body lies, asked of several directions f: whether f . n >= 0 for
// its angle-weighted pseudo-normal n. The weights are positive, so where f is on one side of every
// face around the vertex the answer needs no angle (atan2 per face); only mixed sides (or a flat
// face) compute n, once.
class OwnSide {
 public:
  OwnSide(const ContactBody& body, uint32_t s, const Vec3* x) : body_(body), s_(s), x_(x) {
    const uint32_t k0 = body.vertexTriStart[s], k1 = body.vertexTriStart[s + 1];
    count_ = k1 - k0 <= kMax ? int(k1 - k0) : -1;  // (more faces than kept: always n)
    for (int k = 0; k < count_; ++k)
      normals_[size_t(k)] = faceNormal(body.triangles[body.vertexTris[k0 + uint32_t(k)]], x);
  }
  bool along(const Vec3& f) {
    int along = 0, against = 0;
    for (int k = 0; k < count_; ++k) {
      const Real d = normals_[size_t(k)].dot(f);
      along += d > 0, against += d < 0;
    }
    if (count_ > 0 && against == count_) return false;
    if (count_ > 0 && along == count_) return true;
    if (!haveN_) n_ = vertexPseudoNormal(body_, s_, x_), haveN_ = true;
    return f.dot(n_) >= 0;
  }

 private:
  static constexpr uint32_t kMax = 24;
  const ContactBody& body_;
  uint32_t s_;
  const Vec3* x_;
  std::array<Vec3, kMax> normals_;
  int count_ = 0;
  bool haveN_ = false;
  Vec3 n_;
};

// The angle-weighted pseudo-normal (not normalised) of the feature of triangle t that the closest
// point lies on (closestPointOnTriangle's feature), from the body's faces around it.
// f(u) for each face around the feature of triangle t that a closest point lies on
// (closestPointOnTriangle's): the face itself; an edge's faces, those holding both of its ends; a
// corner's faces (with those that hold it inside, buildContactBody), in the body's order.
template <class F>
[[maybe_unused]] void forFeatureFaces(const ContactBody& body, uint32_t t, int feature, F&& f) {
  const auto& tri = body.triangles[t];
  if (feature == 0) return f(tri);
  const uint32_t a = tri[size_t(feature <= 3 ? feature - 1 : feature - 4)];
  const uint32_t s = body.surfaceIndex(a);
  for (uint32_t k = body.vertexTriStart[s]; k < body.vertexTriStart[s + 1]; ++k) {
    const auto& u = body.triangles[body.vertexTris[k]];
    if (feature <= 3) {  // an edge
      const uint32_t b = tri[size_t(feature % 3)];
      if (u[0] != b && u[1] != b && u[2] != b) continue;
    }
    f(u);
  }
}

[[maybe_unused]] Vec3 pseudoNormal(const ContactBody& body, uint32_t t, int feature, const Vec3* x) {
  if (feature == 0) return unit(faceNormal(body.triangles[t], x));
  if (feature <= 3) {  // an edge: the unit normals of its faces
    Vec3 n = Vec3::Zero();
    forFeatureFaces(body, t, feature, [&](const std::array<uint32_t, 3>& u) { n += unit(faceNormal(u, x)); });
    return n;
  }
  return vertexPseudoNormal(body, body.surfaceIndex(body.triangles[t][size_t(feature - 4)]), x);
}

// Which side of the faces around a closest point's feature the offset d = p - c lies on: 1 in
// front of every one (strictly), -1 behind every one, 0 mixed or on one.
[[maybe_unused]] int sideOfFaces(const ContactBody& body, uint32_t t, int feature, const Vec3& d, const Vec3* x) {
  int front = 0, behind = 0, faces = 0;
  forFeatureFaces(body, t, feature, [&](const std::array<uint32_t, 3>& u) {
    const Real s = faceNormal(u, x).dot(d);
    ++faces, front += s > 0, behind += s < 0;
  });
  return faces > 0 && front == faces ? 1 : (faces > 0 && behind == faces ? -1 : 0);
}

}  // namespace
}  // namespace gradel
