// A scene: everything needed to build a World, as read from a JSON file (docs/scenes.md).
// Scene builders live here and serve the CLI, tests, benchmarks, the viewer and Python.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

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
};

struct OutputSettings {
  Real duration = 1.0;              ///< [s] simulated time of `gradel run`.
  Real frameInterval = 1.0 / 30.0;  ///< [s] between written frames.
};

struct Scene {
  std::string name;  ///< From the file name or "name".
  int dim = 3;
  BodySettings body;
  SimulationSettings simulation;
  DomainSettings domain;
  std::vector<ManipulatorSettings> manipulators;
  std::vector<PinSettings> pins;  ///< Boundary conditions (pins.h).
  OutputSettings output;
};

/// Reads and validates a scene file (strict: unknown keys, wrong types, NaN, out-of-range values
/// are InputError naming the file and the key path, e.g. "scenes/x.json: body.radius: ...").
Scene loadScene(const std::string& path);
/// Same, from JSON text; `sourceName` is used in messages.
Scene parseScene(const std::string& jsonText, const std::string& sourceName);

/// The built body: volume, layout and world together.
struct BuiltScene {
  VoxelVolume volume;
  Layout layout;
  std::shared_ptr<const RestModel> model;
  std::unique_ptr<World> world;
  /// A body voxelised from a mesh file (body.source obj / stl / ply): that mesh in rest
  /// coordinates [m] (where it was voxelised, at body.position), and the same mesh embedded in
  /// the model (embedding.h), the body's render mesh. Empty for volumes and shapes.
  std::optional<TriangleMesh> sourceMesh;
  std::optional<EmbeddedMesh> embedded;
};

/// Rasterises the shape (or reads body.source), builds the layout, rest model and world, and
/// embeds a source mesh. Before the volume and before the layout, the sizes are checked against
/// `limits` (size_limits.h). Throws InputError.
BuiltScene buildScene(const Scene& scene, const SizeLimits& limits = {});

}  // namespace gradel
