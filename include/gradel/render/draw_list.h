// What one picture shows, as plain vertex arrays (no OpenGL): the body's surfaces, the element
// wireframe coloured by level (fig. 4), stress colour (fig. 1: darker where the stress is
// high) with its legend, vertices, manipulators and the domain's walls. The viewer and
// `gradel render` build the same draw list and hand it to Renderer.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "gradel/embedding.h"
#include "gradel/scene.h"
#include "gradel/surface.h"

namespace gradel::render {

/// Which surface covers the body.
enum class SurfaceMode {
  Smooth,    ///< The paper's display surface (sec. 3.3), smooth vertex normals.
  Voxel,     ///< The plain voxel staircase, flat shaded (for comparison).
  Embedded,  ///< The embedded render mesh (embedding.h); the smooth surface if there is none.
  None,
};
SurfaceMode parseSurfaceMode(
    const std::string& name);  ///< "smooth" | "voxel" | "embedded" | "none"; InputError otherwise.

/// What to draw (the viewer's toggles; `gradel render --show`).
struct ViewOptions {
  SurfaceMode surface = SurfaceMode::Smooth;
  bool wireframe = false;  ///< Element outlines coloured by level.
  bool section = false;    ///< Wireframe of only the elements cut by the body's middle z plane (fig. 4's section).
  bool stress = false;     ///< Colour the surface by stress, with a legend.
  bool vertices = false;   ///< Model vertices as points.
  bool manipulators = true;
  bool walls = true;
  /// The contact force the body exerts on each manipulator (World::averageContactForces, the
  /// last step's when no time was averaged) as an arrow from its centre, with a legend in N.
  bool forces = false;
  /// [m/N] arrow length per newton; 0 = auto: the body's weight under 9.81 m/s^2 is drawn half
  /// the body's largest extent long (the same scale in every frame of a run).
  Real forceScale = 0;
  /// [Pa] von Mises stress drawn darkest (World::vertexStress); 0 = auto (autoStressScale).
  Real stressScale = 0;
  std::string caption;  ///< Text drawn at the top left (empty = none).
  /// With a coarse display mesh in the BodyView (a body over the viewer's triangle budget,
  /// render/display_budget.h): false draws it for the smooth and embedded surfaces, true the
  /// full-resolution ones.
  bool fullResolution = false;
};

/// Everything about the bodies that drawing needs and that is built once per model (rest data).
struct BodyView {
  DisplaySurface smooth, voxel;
  std::vector<std::array<uint32_t, 2>> edges;  ///< Element outline edges (model vertex ids).
  std::vector<uint8_t> edgeLevel;              ///< Level of the element each edge comes from.
  std::vector<uint8_t> edgeInSection;          ///< 1 if that element is cut by the middle z plane (3D; always 1 in 2D).
  int levels = 1;
  std::optional<EmbeddedMesh> embedded;  ///< Drawn in SurfaceMode::Embedded (none in 2D without a mesh).
  /// The smooth surface's and the embedded mesh's triangles as one index list each (rest data,
  /// shared with every draw list: the renderer uploads them once).
  std::shared_ptr<const std::vector<uint32_t>> smoothIndices, embeddedIndices;
  /// Set when the bodies' smooth surfaces have more triangles than the budget makeBodyView was
  /// given: the coarse display mesh drawn instead (each body's isosurface sampled every
  /// coarseStep voxels, or its own mesh file's mesh, embedded), its index list, the largest step
  /// taken and the smooth surfaces' triangle count it stands for.
  std::optional<EmbeddedMesh> coarse;
  std::shared_ptr<const std::vector<uint32_t>> coarseIndices;
  int coarseStep = 1;
  size_t fullTriangles = 0;
};

/// Builds the surfaces and element outlines of a built scene, of every body (their vertex ids
/// those of the world's model: each body's moved by its RestModel::bodies[i].vertexBegin). The
/// embedded mesh is `restMesh` (rest coordinates [m], body 0) when given, else the body's own (a
/// body voxelised from a mesh file: BuiltBody::embedded), else (3D) the isosurface of its volume
/// (isosurface.h). `triangleBudget` > 0 (the viewer: display_budget.h): when the smooth
/// surfaces of the 3D bodies together have more triangles than that, a coarse display mesh is
/// built too, each body's share of the budget in proportion to its smooth surface; such a body
/// without a mesh of its own then has no full-resolution isosurface (`embedded` unset: the
/// embedded mode draws the coarse mesh, and with fullResolution the smooth surface).
BodyView makeBodyView(const BuiltScene& scene, const TriangleMesh* restMesh = nullptr, size_t triangleBudget = 0);

struct DrawVertex {
  float position[3];
  float normal[3];
  float color[4];
};

struct DrawList {
  /// The body's smooth or embedded surface: lit, world space, drawn indexed. The vertices are
  /// this frame's; the indices are the BodyView's (the same pointer frame after frame, so the
  /// renderer keeps them on the GPU and uploads only the vertices).
  std::vector<DrawVertex> meshVertices;
  std::shared_ptr<const std::vector<uint32_t>> meshIndices;
  std::vector<DrawVertex> triangles;  ///< Lit, world space (voxel surface, manipulators).
  std::vector<DrawVertex> lines;      ///< Unlit, world space.
  std::vector<DrawVertex> points;     ///< Unlit, world space.
  std::vector<DrawVertex> overlay;    ///< Unlit triangles in pixels (x right, y down): legend, caption.
  std::array<float, 3> background{0.93f, 0.94f, 0.96f};
};

/// The stress scale `auto` draws darkest [Pa]: the von Mises stress of a 5 % uniaxial strain in
/// the model's stiffest element (0.05 x its Young's modulus, element_strain.h).
Real autoStressScale(const RestModel& model);
/// A stress for a legend or panel: "0 Pa", "850 Pa", "12.5 kPa", "3.2 MPa", "1.1 GPa".
std::string pascalText(Real pa);

/// Colour of stress s for the legend and the surface: light cream at 0, dark red-brown at
/// `scale` and above (fig. 1: darker where the stress is high).
std::array<float, 3> stressColor(Real s, Real scale);
/// Distinct colour of layout level L (the wireframe of fig. 4).
std::array<float, 3> levelColor(int level);

/// The draw list of one picture of `world` (whose model `body` was made from). With the stress
/// colour on, `vertexStress` (World::vertexStress, [Pa]) when the caller has it at hand (the
/// viewer computes it off the drawing thread), else the world's now.
DrawList buildDrawList(const BodyView& body, const World& world, const ViewOptions& options, int width, int height,
                       const std::vector<Real>* vertexStress = nullptr);

/// Adds text in pixels at (x, y) (top left), `scale` pixels per font unit (stb_easy_font).
void addText(DrawList& list, const std::string& text, float x, float y, float scale, std::array<float, 3> color);

/// Axis-aligned bounds of everything in the scene worth framing: the body, the manipulators and,
/// when walls are shown, the part of the domain near the body.
void sceneBounds(const World& world, Vec3* lo, Vec3* hi);

}  // namespace gradel::render
