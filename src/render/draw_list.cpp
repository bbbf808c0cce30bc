#include "gradel/render/draw_list.h"

#include "gradel/element_strain.h"
#include "gradel/isosurface.h"
#include "gradel/render/display_budget.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <set>
#include <unordered_map>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#include <stb_easy_font.h>
#pragma GCC diagnostic pop

namespace gradel::render {

SurfaceMode parseSurfaceMode(const std::string& name) {
  if (name == "smooth") return SurfaceMode::Smooth;
  if (name == "voxel") return SurfaceMode::Voxel;
  if (name == "embedded") return SurfaceMode::Embedded;
  if (name == "none") return SurfaceMode::None;
  throw InputError("unknown surface \"" + name + "\" (expected smooth, voxel, embedded or none)");
}

namespace {

using Color = std::array<float, 3>;

constexpr Color kBodyColor{0.86f, 0.72f, 0.50f};
constexpr Color kManipulatorColor{0.35f, 0.47f, 0.62f};
constexpr Color kWallColor{0.55f, 0.57f, 0.62f};
constexpr Color kFloorGridColor{0.78f, 0.80f, 0.84f};
constexpr Color kVertexColor{0.10f, 0.10f, 0.12f};
constexpr Color kTextColor{0.10f, 0.10f, 0.12f};
constexpr Real kFloorGridStep = 0.05;  // [m]

DrawVertex vertex(const Vec3& p, const Vec3& n, const Color& c, float alpha = 1) {
  return {{float(p.x()), float(p.y()), float(p.z())},
          {float(n.x()), float(n.y()), float(n.z())},
          {c[0], c[1], c[2], alpha}};
}

void addLine(std::vector<DrawVertex>& out, const Vec3& a, const Vec3& b, const Color& c) {
  out.push_back(vertex(a, Vec3::Zero(), c));
  out.push_back(vertex(b, Vec3::Zero(), c));
}

void addQuad2D(DrawList& list, float x0, float y0, float x1, float y1, const Color& top, const Color& bottom) {
  const Vec3 n = Vec3::Zero();
  const DrawVertex a = vertex({x0, y0, 0}, n, top), b = vertex({x1, y0, 0}, n, top), c = vertex({x1, y1, 0}, n, bottom),
                   d = vertex({x0, y1, 0}, n, bottom);
  list.overlay.insert(list.overlay.end(), {a, b, c, a, c, d});
}

// The vertices of a mesh drawn indexed (its triangles are the BodyView's index list).
void addIndexedMesh(DrawList& list, const TriangleMesh& m, const std::vector<Color>& colors,
                    const std::shared_ptr<const std::vector<uint32_t>>& indices) {
  list.meshVertices.resize(m.vertices.size());
  for (size_t v = 0; v < m.vertices.size(); ++v) list.meshVertices[v] = vertex(m.vertices[v], m.normals[v], colors[v]);
  list.meshIndices = indices;
}

std::shared_ptr<const std::vector<uint32_t>> indexList(const std::vector<std::array<uint32_t, 3>>& triangles) {
  auto out = std::make_shared<std::vector<uint32_t>>();
  out->reserve(3 * triangles.size());
  for (const auto& t : triangles) out->insert(out->end(), t.begin(), t.end());
  return out;
}

// Triangles of a mesh, flat shaded: one normal per face (the voxel staircase).
void addFlatMesh(DrawList& list, const TriangleMesh& m, const std::vector<Color>& colors) {
  for (const auto& t : m.triangles) {
    const Vec3 fn = (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]).normalized();
    for (uint32_t v : t) list.triangles.push_back(vertex(m.vertices[v], fn, colors[v]));
  }
}

void addSphere(DrawList& list, const Vec3& c, Real r, const Color& color) {
  constexpr int kRings = 14, kSegments = 24;
  auto point = [&](int i, int j) {
    const Real th = M_PI * i / kRings, ph = 2 * M_PI * j / kSegments;
    return Vec3(std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph));
  };
  for (int i = 0; i < kRings; ++i)
    for (int j = 0; j < kSegments; ++j) {
      const Vec3 a = point(i, j), b = point(i + 1, j), d = point(i + 1, j + 1), e = point(i, j + 1);
      for (const Vec3& n : {a, d, b, a, e, d}) list.triangles.push_back(vertex(c + r * n, n, color));
    }
}

void addCylinder(DrawList& list, const Manipulator& m, const Color& color) {
  constexpr int kSegments = 28;
  const Vec3 axis = m.settings.axis.normalized();
  const Vec3 u = axis.unitOrthogonal(), v = axis.cross(u);
  const Real r = m.settings.radius, hl = m.settings.halfLength;
  for (int j = 0; j < kSegments; ++j) {
    const Real a0 = 2 * M_PI * j / kSegments, a1 = 2 * M_PI * (j + 1) / kSegments;
    const Vec3 n0 = std::cos(a0) * u + std::sin(a0) * v, n1 = std::cos(a1) * u + std::sin(a1) * v;
    const Vec3 top = m.position + hl * axis, bot = m.position - hl * axis;
    for (const auto& [p, n] : {std::pair<Vec3, Vec3>{bot + r * n0, n0},
                               {bot + r * n1, n1},
                               {top + r * n1, n1},
                               {bot + r * n0, n0},
                               {top + r * n1, n1},
                               {top + r * n0, n0}})
      list.triangles.push_back(vertex(p, n, color));
    for (int s = -1; s <= 1; s += 2) {
      const Vec3 c = m.position + s * hl * axis;
      for (const Vec3& p : {c, Vec3(c + r * n0), Vec3(c + r * n1)})
        list.triangles.push_back(vertex(p, s * axis, color));
    }
  }
}

// A blade: its rectangle, both faces.
void addBlade(DrawList& list, const Manipulator& m, const Color& color) {
  const Vec3 u = m.settings.halfLength * m.settings.axis.normalized();
  const Vec3 w = m.settings.halfWidth * m.settings.widthAxis.normalized();
  const Vec3 n = u.cross(w).normalized(), c = m.position;
  const Vec3 p[4] = {c - u - w, c + u - w, c + u + w, c - u + w};
  for (int i : {0, 1, 2, 0, 2, 3}) list.triangles.push_back(vertex(p[i], n, color));
  for (int i : {0, 2, 1, 0, 3, 2}) list.triangles.push_back(vertex(p[i], -n, color));
}

void addDisk(DrawList& list, const Vec3& c, Real r, const Color& color) {
  constexpr int kSegments = 40;
  const Vec3 front = c + Vec3(0, 0, 1e-4);  // just in front of the z = 0 body
  for (int j = 0; j < kSegments; ++j) {
    const Real a0 = 2 * M_PI * j / kSegments, a1 = 2 * M_PI * (j + 1) / kSegments;
    for (const Vec3& p : {front, Vec3(front + r * Vec3(std::cos(a0), std::sin(a0), 0)),
                          Vec3(front + r * Vec3(std::cos(a1), std::sin(a1), 0))})
      list.triangles.push_back(vertex(p, Vec3(0, 0, 1), color));
  }
}

void addWalls(DrawList& list, const DomainSettings& d, int dim) {
  const Vec3 lo = d.min, hi = d.max;
  if (dim == 2) {
    const Vec3 c[4] = {{lo.x(), lo.y(), 0}, {hi.x(), lo.y(), 0}, {hi.x(), hi.y(), 0}, {lo.x(), hi.y(), 0}};
    for (int i = 0; i < 4; ++i) addLine(list.lines, c[i], c[(i + 1) % 4], kWallColor);
    return;
  }
  for (Real x = std::ceil(lo.x() / kFloorGridStep) * kFloorGridStep; x <= hi.x(); x += kFloorGridStep)
    addLine(list.lines, {x, lo.y(), lo.z()}, {x, lo.y(), hi.z()}, kFloorGridColor);
  for (Real z = std::ceil(lo.z() / kFloorGridStep) * kFloorGridStep; z <= hi.z(); z += kFloorGridStep)
    addLine(list.lines, {lo.x(), lo.y(), z}, {hi.x(), lo.y(), z}, kFloorGridColor);
  for (int a = 0; a < 3; ++a)
    for (int k = 0; k < 4; ++k) {
      Vec3 p = lo, q;
      const int b = (a + 1) % 3, c = (a + 2) % 3;
      p[b] = (k & 1) ? hi[b] : lo[b];
      p[c] = (k & 2) ? hi[c] : lo[c];
      q = p;
      q[a] = hi[a];
      addLine(list.lines, p, q, kWallColor);
    }
}

void addLegend(DrawList& list, Real scale, int width, int height) {
  const float x0 = float(width) - 46, x1 = float(width) - 26, y0 = 40, y1 = std::max(120.0f, float(height) * 0.45f);
  constexpr int kSteps = 24;
  const Color backdrop{0.97f, 0.97f, 0.98f};
  const std::string top = pascalText(scale), mid = pascalText(scale / 2), title = "von Mises";
  // Labels right-aligned to the left of the bar, the title above it ending at the bar's right
  // edge; the backdrop as wide as they need (9.6 pixels a character at this font scale).
  const auto textWidth = [](const std::string& t) { return 9.6f * float(t.size()); };
  const float left =
      std::min(x0 - 14 - std::max({textWidth(top), textWidth(mid), textWidth("0 Pa")}), x1 - textWidth(title) - 4);
  addQuad2D(list, left, y0 - 28, float(width) - 4, y1 + 10, backdrop, backdrop);
  for (int i = 0; i < kSteps; ++i) {
    // Top of the bar = high stress (dark).
    const float ya = y0 + (y1 - y0) * i / kSteps, yb = y0 + (y1 - y0) * (i + 1) / kSteps;
    addQuad2D(list, x0, ya, x1, yb, stressColor(scale * (1 - Real(i) / kSteps), scale),
              stressColor(scale * (1 - Real(i + 1) / kSteps), scale));
  }
  addText(list, title, x1 - textWidth(title), y0 - 22, 1.6f, kTextColor);
  addText(list, top, x0 - 10 - textWidth(top), y0 - 4, 1.6f, kTextColor);
  addText(list, mid, x0 - 10 - textWidth(mid), (y0 + y1) / 2 - 6, 1.6f, kTextColor);
  addText(list, "0 Pa", x0 - 10 - textWidth("0 Pa"), y1 - 8, 1.6f, kTextColor);
}

// Each manipulator's contact force as an arrow from its centre (length |F| scale, a head of a
// fifth of it) and, bottom left, its size in N with the scale of the arrows.
void addForceArrows(DrawList& list, const World& world, Real scale, int height) {
  const RestModel& m = world.model();
  if (!(scale > 0)) {
    Vec3 lo = m.restPositions.front(), hi = lo;
    for (const Vec3& p : m.restPositions) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    scale = 0.5 * (hi - lo).maxCoeff() / std::max(m.totalMass * 9.81, 1e-30);
  }
  const ContactForces f = world.forceAverageTime() > 0 ? world.averageContactForces() : world.stepContactForces();
  const Color arrow{0.85f, 0.15f, 0.10f};
  char line[96];
  float y = float(height) - 14.0f * float(f.manipulators.size()) - 24;
  std::snprintf(line, sizeof line, "force on the tools [N] (arrow: %.3g N per cm)", 0.01 / scale);
  addText(list, line, 12, y - 14, 1.6f, kTextColor);
  for (size_t k = 0; k < f.manipulators.size() && k < world.manipulators().size(); ++k, y += 14) {
    const Vec3 F = f.manipulators[k].force, c = world.manipulators()[k].position;
    std::snprintf(line, sizeof line, "tool %zu: %.3g  (%.3g, %.3g, %.3g)", k, F.norm(), F.x(), F.y(), F.z());
    addQuad2D(list, 12, y + 1, 24, y + 11, arrow, arrow);
    addText(list, line, 30, y, 1.6f, kTextColor);
    const Real len = F.norm() * scale;
    if (!(len > 0) || !std::isfinite(len)) continue;
    const Vec3 d = F.normalized(), tip = c + len * d;
    const Vec3 side = (m.dim == 2 ? Vec3(-d.y(), d.x(), 0) : Vec3(d.unitOrthogonal())) * (0.1 * len);
    addLine(list.lines, c, tip, arrow);
    addLine(list.lines, tip, tip - 0.2 * len * d + side, arrow);
    addLine(list.lines, tip, tip - 0.2 * len * d - side, arrow);
    if (m.dim == 3) {
      const Vec3 other = d.cross(side);
      addLine(list.lines, tip, tip - 0.2 * len * d + other, arrow);
      addLine(list.lines, tip, tip - 0.2 * len * d - other, arrow);
    }
  }
}

}  // namespace

Real autoStressScale(const RestModel& m) {
  Real e = 0;
  for (size_t k = 0; k < m.numElements(); ++k) e = std::max(e, elementYoungsModulus(m, k));
  return 0.05 * (e > 0 ? e : m.material.youngsModulus);
}

std::string pascalText(Real pa) {
  if (!std::isfinite(pa)) return "- Pa";
  const Real a = std::abs(pa);
  const char* unit = "Pa";
  Real v = pa;
  if (a >= 1e9)
    v = pa / 1e9, unit = "GPa";
  else if (a >= 1e6)
    v = pa / 1e6, unit = "MPa";
  else if (a >= 1e3)
    v = pa / 1e3, unit = "kPa";
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.3g %s", v, unit);
  return buf;
}

std::array<float, 3> stressColor(Real s, Real scale) {
  // Cream -> orange -> dark red-brown: luminance falls monotonically with stress.
  constexpr Color stops[3] = {{0.98f, 0.95f, 0.84f}, {0.93f, 0.55f, 0.20f}, {0.35f, 0.04f, 0.04f}};
  const Real t = std::clamp(scale > 0 ? s / scale : 0.0, 0.0, 1.0) * 2;
  const int i = std::min(int(t), 1);
  const float f = float(t - i);
  Color c;
  for (int k = 0; k < 3; ++k) c[size_t(k)] = stops[i][size_t(k)] * (1 - f) + stops[i + 1][size_t(k)] * f;
  return c;
}

std::array<float, 3> levelColor(int level) {
  constexpr Color palette[8] = {{0.15f, 0.35f, 0.85f}, {0.10f, 0.65f, 0.20f}, {0.95f, 0.55f, 0.05f},
                                {0.85f, 0.10f, 0.10f}, {0.55f, 0.20f, 0.75f}, {0.45f, 0.30f, 0.15f},
                                {0.05f, 0.65f, 0.65f}, {0.90f, 0.30f, 0.70f}};
  return palette[size_t(level) % 8];
}

namespace {

// One body's view, in the vertex ids of its own model.
// `budget` > 0: also the coarse display mesh of at most that many triangles (display_budget.h);
// `smooth`: the body's smooth surface, when the caller has built it already.
BodyView makeOneBodyView(const BuiltBody& scene, const TriangleMesh* restMesh, size_t budget,
                         std::optional<DisplaySurface> smooth = std::nullopt) {
  const Layout& layout = scene.layout;
  const RestModel& model = *scene.model;
  BodyView v;
  v.smooth = smooth ? std::move(*smooth) : buildDisplaySurface(layout, scene.volume, SurfaceKind::Smooth);
  v.fullTriangles = v.smooth.triangles.size();
  if (restMesh) {
    v.embedded = embedMesh(*restMesh, layout, model);
  } else if (scene.embedded) {
    v.embedded = scene.embedded;  // the body's own mesh file
  } else if (layout.dim == 3 && budget == 0) {
    v.embedded = embedMesh(isosurface(scene.volume, model.origin), layout, model);
  }
  if (budget > 0 && layout.dim == 3) {
    if (v.embedded) {
      v.coarse = v.embedded;  // a given mesh is drawn as it is
    } else {
      // Over the budget the full isosurface (3x the smooth surface's triangles: 462,456 at 128,
      // seconds to build and embed) is not built: the embedded mode draws the coarse one too.
      const CoarseSurface c =
          coarseIsosurface(scene.volume, model.origin, budget, displayStepEstimate(v.fullTriangles, budget));
      v.coarse = embedMesh(c.mesh, layout, model);
      v.coarseStep = c.step;
    }
  }
  v.voxel = buildDisplaySurface(layout, scene.volume, SurfaceKind::Voxel);
  v.levels = layout.numLevels();
  const int dim = layout.dim, corners = dim == 3 ? 8 : 4;
  for (size_t e = 0; e < layout.numElements(); ++e) {
    // Outline of a full element: its block; of an incomplete one: its filled cells (fig. 6).
    // Both only connect the element's own vertices.
    const bool full = layout.isFull(e);
    const int32_t c = layout.cellSize[e], span = full ? 2 * c : c;
    std::set<std::pair<uint32_t, uint32_t>> edges;
    for (int k = 0; k < (full ? 1 : corners); ++k) {
      if (!full && !(layout.cellMask[e] >> k & 1)) continue;
      const Int3 lo = layout.origin[e] + c * Int3(k & 1, k >> 1 & 1, k >> 2 & 1);
      for (int corner = 0; corner < corners; ++corner)
        for (int a = 0; a < dim; ++a) {
          if (corner >> a & 1) continue;
          const Int3 p = lo + span * Int3(corner & 1, corner >> 1 & 1, corner >> 2 & 1);
          Int3 q = p;
          q[a] += span;
          const uint32_t ip = layout.vertexAt(p), iq = layout.vertexAt(q);
          if (ip != Layout::kNoVertex && iq != Layout::kNoVertex) edges.insert(std::minmax(ip, iq));
        }
    }
    // The section plane runs through voxel centres (z = nz/2 + 1/2), so no element only touches it.
    const double mid = dim == 3 ? layout.dims[2] / 2 + 0.5 : 0.0;
    const bool cut = dim == 2 || (layout.origin[e].z() < mid && mid < layout.origin[e].z() + 2 * c);
    for (const auto& [a, b] : edges) {
      v.edges.push_back({a, b});
      v.edgeLevel.push_back(layout.level[e]);
      v.edgeInSection.push_back(cut ? 1 : 0);
    }
  }
  return v;
}

// Appends a body's embedded mesh (ids of its own model) to `all`'s, its ids moved by the body's range.
void appendEmbedded(std::optional<EmbeddedMesh>& all, std::optional<EmbeddedMesh> part, const BodyRange& range) {
  if (!part) return;
  shiftVertexIds(*part, range.vertexBegin, range.elementBegin);
  if (!all) {
    all = std::move(part);
    return;
  }
  EmbeddedMesh& to = *all;
  const EmbeddedMesh& from = *part;
  const uint32_t vertexBase = uint32_t(to.weightStart.size() - 1), weightBase = uint32_t(to.weight.size());
  for (auto t : from.triangles) to.triangles.push_back({t[0] + vertexBase, t[1] + vertexBase, t[2] + vertexBase});
  for (size_t v = 1; v < from.weightStart.size(); ++v) to.weightStart.push_back(weightBase + from.weightStart[v]);
  to.weightVertex.insert(to.weightVertex.end(), from.weightVertex.begin(), from.weightVertex.end());
  to.weight.insert(to.weight.end(), from.weight.begin(), from.weight.end());
  to.element.insert(to.element.end(), from.element.begin(), from.element.end());
  if (to.restFieldNormals.size() == vertexBase && !from.restFieldNormals.empty()) {
    to.restMeshNormals.insert(to.restMeshNormals.end(), from.restMeshNormals.begin(), from.restMeshNormals.end());
    to.restFieldNormals.insert(to.restFieldNormals.end(), from.restFieldNormals.begin(), from.restFieldNormals.end());
  } else {
    to.restMeshNormals.clear(), to.restFieldNormals.clear();
  }
}

// Appends `part` (vertex ids of a body's own model) to `all`, its ids moved to the world's model
// by the body's range there.
void appendBodyView(BodyView& all, BodyView part, const BodyRange& range) {
  const uint32_t offset = range.vertexBegin;
  auto appendSurface = [&](DisplaySurface& to, DisplaySurface from) {
    shiftVertexIds(from, offset);
    const uint32_t base = uint32_t(to.modelVertex.size());
    const bool normals = to.restFieldNormals.size() == base && !from.restFieldNormals.empty();
    to.dim = from.dim, to.kind = from.kind;
    if (normals) {  // every body's carried normals, or none
      to.restMeshNormals.insert(to.restMeshNormals.end(), from.restMeshNormals.begin(), from.restMeshNormals.end());
      to.restFieldNormals.insert(to.restFieldNormals.end(), from.restFieldNormals.begin(), from.restFieldNormals.end());
    } else {
      to.restMeshNormals.clear(), to.restFieldNormals.clear();
    }
    to.modelVertex.insert(to.modelVertex.end(), from.modelVertex.begin(), from.modelVertex.end());
    for (auto t : from.triangles) to.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  };
  appendSurface(all.smooth, std::move(part.smooth));
  appendSurface(all.voxel, std::move(part.voxel));
  for (auto& e : part.edges) all.edges.push_back({e[0] + offset, e[1] + offset});
  all.edgeLevel.insert(all.edgeLevel.end(), part.edgeLevel.begin(), part.edgeLevel.end());
  all.edgeInSection.insert(all.edgeInSection.end(), part.edgeInSection.begin(), part.edgeInSection.end());
  all.levels = std::max(all.levels, part.levels);
  appendEmbedded(all.embedded, std::move(part.embedded), range);
  appendEmbedded(all.coarse, std::move(part.coarse), range);
  all.coarseStep = std::max(all.coarseStep, part.coarseStep);
  all.fullTriangles += part.fullTriangles;
}

}  // namespace

BodyView makeBodyView(const BuiltScene& scene, const TriangleMesh* restMesh, size_t triangleBudget) {
  // The smooth surfaces first: their triangle counts share the budget out.
  std::vector<DisplaySurface> smooth;
  size_t total = 0;
  for (size_t i = 0; i < scene.numBodies(); ++i) {
    const BuiltBody& b = scene.bodies[i];
    smooth.push_back(buildDisplaySurface(b.layout, b.volume, SurfaceKind::Smooth));
    total += smooth.back().triangles.size();
  }
  const bool coarse = triangleBudget > 0 && total > triangleBudget;
  std::vector<size_t> share(smooth.size(), 0);
  if (coarse)
    for (size_t i = 0; i < smooth.size(); ++i)
      share[i] =
          std::max<size_t>(1, size_t(double(triangleBudget) * double(smooth[i].triangles.size()) / double(total)));
  BodyView all;
  if (scene.numBodies() == 1) {
    all = makeOneBodyView(scene.bodies[0], restMesh, share[0], std::move(smooth[0]));
  } else {
    for (size_t i = 0; i < scene.numBodies(); ++i)
      appendBodyView(all, makeOneBodyView(scene.bodies[i], i == 0 ? restMesh : nullptr, share[i], std::move(smooth[i])),
                     scene.range(i));
  }
  all.smoothIndices = indexList(all.smooth.triangles);
  if (all.embedded) all.embeddedIndices = indexList(all.embedded->triangles);
  if (all.coarse) all.coarseIndices = indexList(all.coarse->triangles);
  return all;
}

void addText(DrawList& list, const std::string& text, float x, float y, float scale, std::array<float, 3> color) {
  // stb_easy_font emits quads of 16-byte vertices (x, y, z floats + RGBA bytes) at 1 unit per pixel.
  std::vector<char> buffer(text.size() * 300 + 1024);
  std::string copy = text;
  const int quads = stb_easy_font_print(0, 0, copy.data(), nullptr, buffer.data(), int(buffer.size()));
  for (int q = 0; q < quads; ++q) {
    float v[4][2];
    for (int k = 0; k < 4; ++k) {
      const float* f = reinterpret_cast<const float*>(buffer.data() + 16 * (4 * q + k));
      v[k][0] = x + f[0] * scale;
      v[k][1] = y + f[1] * scale;
    }
    addQuad2D(list, v[0][0], v[0][1], v[2][0], v[2][1], color, color);
  }
}

void sceneBounds(const World& world, Vec3* lo, Vec3* hi) {
  Vec3 a = Vec3::Constant(std::numeric_limits<Real>::infinity()), b = -a;
  for (const Vec3& p : world.state().positions) a = a.cwiseMin(p), b = b.cwiseMax(p);
  for (const Manipulator& m : world.manipulators()) {
    std::vector<Vec3> centres{m.position};
    for (const Keyframe& k : m.settings.path.keys) centres.push_back(k.position);
    const Real r = m.settings.shape == ManipulatorShape::Blade
                       ? std::hypot(m.settings.halfLength, m.settings.halfWidth)
                       : m.settings.radius + (m.settings.shape == ManipulatorShape::Cylinder ? m.settings.halfLength : 0);
    for (const Vec3& c : centres) a = a.cwiseMin(c - Vec3::Constant(r)), b = b.cwiseMax(c + Vec3::Constant(r));
  }
  if (world.model().dim == 2) a.z() = b.z() = 0;
  *lo = a;
  *hi = b;
}

DrawList buildDrawList(const BodyView& body, const World& world, const ViewOptions& o, int width, int height,
                       const std::vector<Real>* vertexStress) {
  DrawList list;
  const std::vector<Vec3>& x = world.state().positions;
  const int dim = world.model().dim;
  std::vector<Real> own;
  if (o.stress && !(vertexStress && vertexStress->size() == x.size())) own = world.vertexStress();
  const std::vector<Real>& stress = own.empty() && vertexStress ? *vertexStress : own;
  const Real stressScale = o.stressScale > 0 ? o.stressScale : (o.stress ? autoStressScale(world.model()) : 0);

  // ---- the body's surface ----
  const bool coarse =
      body.coarse && !o.fullResolution && (o.surface == SurfaceMode::Smooth || o.surface == SurfaceMode::Embedded);
  const bool embedded = coarse || (o.surface == SurfaceMode::Embedded && body.embedded.has_value());
  if (embedded) {
    const EmbeddedMesh& em = coarse ? *body.coarse : *body.embedded;
    const auto& indices = coarse ? body.coarseIndices : body.embeddedIndices;
    const TriangleMesh m = embeddedMesh(em, x);
    std::vector<Color> colors(m.vertices.size(), kBodyColor);
    if (o.stress)
      for (size_t v = 0; v < colors.size(); ++v) {
        Real s = 0;
        for (uint32_t k = em.weightStart[v]; k < em.weightStart[v + 1]; ++k)
          s += em.weight[k] * stress[em.weightVertex[k]];
        colors[v] = stressColor(std::max(s, 0.0), stressScale);
      }
    addIndexedMesh(list, m, colors, indices ? indices : indexList(m.triangles));
  } else if (o.surface != SurfaceMode::None) {
    const DisplaySurface& s = o.surface == SurfaceMode::Voxel ? body.voxel : body.smooth;
    const TriangleMesh m = surfaceMesh(s, x);
    std::vector<Color> colors(m.vertices.size(), kBodyColor);
    if (o.stress)
      for (size_t v = 0; v < colors.size(); ++v) colors[v] = stressColor(stress[s.modelVertex[v]], stressScale);
    if (o.surface == SurfaceMode::Voxel)
      addFlatMesh(list, m, colors);  // a vertex per triangle corner
    else
      addIndexedMesh(list, m, colors, body.smoothIndices ? body.smoothIndices : indexList(m.triangles));
  }

  if (o.wireframe)
    for (size_t i = 0; i < body.edges.size(); ++i)
      if (!o.section || body.edgeInSection[i])
        addLine(list.lines, x[body.edges[i][0]], x[body.edges[i][1]], levelColor(body.edgeLevel[i]));
  if (o.vertices)
    for (const Vec3& p : x) list.points.push_back(vertex(p, Vec3::Zero(), kVertexColor));

  // ---- manipulators and walls ----
  if (o.manipulators)
    for (const Manipulator& m : world.manipulators()) {
      if (dim == 2)
        addDisk(list, m.position, m.settings.radius, kManipulatorColor);
      else if (m.settings.shape == ManipulatorShape::Cylinder)
        addCylinder(list, m, kManipulatorColor);
      else if (m.settings.shape == ManipulatorShape::Blade)
        addBlade(list, m, kManipulatorColor);
      else
        addSphere(list, m.position, m.settings.radius, kManipulatorColor);
    }
  if (o.walls && world.domain().enabled) addWalls(list, world.domain(), dim);
  if (o.forces && !world.manipulators().empty()) addForceArrows(list, world, o.forceScale, height);

  // ---- overlay ----
  if (o.stress) addLegend(list, stressScale, width, height);
  if (o.wireframe) {
    float y = float(height) - 14.0f * float(body.levels) - 10;
    for (int l = 0; l < body.levels; ++l, y += 14) {
      addQuad2D(list, 12, y + 1, 24, y + 11, levelColor(l), levelColor(l));
      addText(list, "level " + std::to_string(l), 30, y, 1.6f, kTextColor);
    }
  }
  if (!o.caption.empty()) addText(list, o.caption, 12, 12, 2.0f, kTextColor);
  return list;
}

}  // namespace gradel::render
