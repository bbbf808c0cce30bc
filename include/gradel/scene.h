// A scene: everything needed to build a World, as read from a JSON file (docs/scenes.md).
// Scene builders live here and serve the CLI, tests, benchmarks, the viewer and Python.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "gradel/body_contacts.h"
#include "gradel/contacts.h"
#include "gradel/embedding.h"
#include "gradel/integrator.h"
#include "gradel/layout.h"
#include "gradel/material.h"
#include "gradel/pins.h"
#include "gradel/shapes.h"
#include "gradel/size_limits.h"
#include "gradel/world.h"

namespace gradel {

struct BodySettings {
  ShapeSpec shape;                             ///< Procedural volume, used when `source` is null.
  std::shared_ptr<const VolumeSource> source;  ///< File or array volume (io/volume_file.h); overrides `shape`.
  LayoutKind layout = LayoutKind::Gradational;
  MaterialSettings material;
  Vec3 position{0, 0, 0};  ///< [m] world position of the volume's lattice origin (voxel (0,0,0)'s lower corner).
  Vec3 velocity{0, 0, 0};  ///< [m/s] initial velocity of every vertex.
  std::string sizeKey = "body.size";  ///< The scene key that sets the grid (size-limit messages).
  /// Output name (frames/<name>_NNNNN.vtu with several bodies): `bodies[i].name`, default "body<i>".
  std::string name = "body0";
};

struct OutputSettings {
  Real duration = 1.0;              ///< [s] simulated time of `gradel run`.
  Real frameInterval = 1.0 / 30.0;  ///< [s] between written frames.
};

struct Scene {
  std::string name;  ///< From the file name or "name".
  int dim = 3;
  /// The bodies, at least one, in the world's body order (RestModel::bodies): the file's `body`
  /// (one body, its material at the top level) or `bodies`. A default scene holds one default body.
  std::vector<BodySettings> bodies = std::vector<BodySettings>(1);
  SimulationSettings simulation;
  DomainSettings domain;
  std::vector<ManipulatorSettings> manipulators;
  std::vector<PinSettings> pins;  ///< Boundary conditions (pins.h).
  OutputSettings output;
  /// Contact between the bodies (and of a body with itself): `body_contact` (body_contacts.h).
  /// On in 3D when there are several bodies or self_contact is set.
  BodyContactSettings bodyContact;

  size_t numBodies() const { return bodies.size(); }
};

/// Reads and validates a scene file (strict: unknown keys, wrong types, NaN, out-of-range values
/// are InputError naming the file and the key path, e.g. "scenes/x.json: body.radius: ...").
Scene loadScene(const std::string& path);
/// Same, from JSON text; `sourceName` is used in messages.
Scene parseScene(const std::string& jsonText, const std::string& sourceName);

/// One built body: volume, layout and its own rest model (vertex ids from 0; in the world its
/// vertices are RestModel::bodies[i] of the world's model, bodies.h).
struct BuiltBody {
  std::string name = "body0";  ///< BodySettings::name.
  VoxelVolume volume;
  Layout layout;
  std::shared_ptr<const RestModel> model;
  /// A body voxelised from a mesh file (body.source obj / stl / ply): that mesh in rest
  /// coordinates [m] (where it was voxelised, at body.position), and the same mesh embedded in
  /// the body's model (embedding.h, vertex ids of `model`), the body's render mesh. Empty for
  /// volumes and shapes.
  std::optional<TriangleMesh> sourceMesh;
  std::optional<EmbeddedMesh> embedded;
};

/// The built scene: each body's volume, layout and rest model, and the world that steps them all
/// (with one body the world's model is the body's; with several, their combination,
/// combineRestModels).
struct BuiltScene {
  std::vector<BuiltBody> bodies;  ///< In the scene's order.
  std::unique_ptr<World> world;

  size_t numBodies() const { return bodies.size(); }
  /// Where body i's vertices and elements are in the world's model.
  const BodyRange& range(size_t i) const { return world->model().bodies.at(i); }
};

/// A 2D scene is first put into its plane z = 0 (positions, velocities, gravity, paths; the
/// domain's and pin boxes' z range [-1, 1]), on a copy, once (src/plane.h normalizeFor2D). Then per
/// body: rasterises the shape (or reads its source), builds the layout and rest model, and
/// embeds a source mesh; then the world of all bodies in one call (World(model, WorldSettings,
/// contact surfaces): each body with its velocity, pins on their bodies, start overlaps released).
/// Before each volume and each layout, the sizes are checked against `limits` (size_limits.h),
/// the memory limit counting the bodies before. Throws InputError.
BuiltScene buildScene(const Scene& scene, const SizeLimits& limits = {});

}  // namespace gradel
