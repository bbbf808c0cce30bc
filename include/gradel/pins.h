// Boundary conditions: pinned regions (a clamped beam, a held organ). A pin selects model
// vertices by their rest positions, either every vertex in an axis-aligned box or every corner of
// a filled voxel of a voxel mask (a label volume from a segmentation, or voxel index boxes), and
// prescribes their positions: the rest position plus the pin's path offset at time t (no path:
// fixed at rest). Explicit integrators
// overwrite pinned vertices' position and velocity after each step; the implicit integrator
// eliminates them from its linear system (projective.h).
#pragma once

#include <array>
#include <memory>
#include <vector>

#include "gradel/contacts.h"
#include "gradel/volume.h"

namespace gradel {

/// A voxel mask: the union of the filled voxels of `volume` (if any) and of `boxes`, on a lattice
/// of edge `voxelSize` whose voxel (0, 0, 0) has its lower corner at `origin` (world, at rest).
/// A vertex is selected when it lies on the closed cube of a filled mask voxel; on the body's own
/// lattice (origin = body.position + offset * h, voxelSize = h, what scenes use) these are exactly
/// the corners of the filled voxels. In 2D the mask is one voxel thick (z index 0).
struct PinMask {
  std::shared_ptr<const VolumeSource> source;  ///< A volume file (e.g. io::openVolume), read by loadPinMasks.
  std::shared_ptr<const VoxelVolume> volume;   ///< The voxels read from `source` (loadPinMasks); null: boxes only.
  std::vector<std::array<Int3, 2>> boxes;      ///< Inclusive voxel index ranges {lo, hi} on the mask lattice.
  Vec3 origin{0, 0, 0};                        ///< [m] lower corner of mask voxel (0, 0, 0).
  Real voxelSize = 0;                          ///< [m] mask voxel edge (> 0).
};

struct PinSettings {
  Vec3 min{0, 0, 0};  ///< [m] lower corner of the box, world coordinates at rest (ignored with a mask).
  Vec3 max{0, 0, 0};  ///< [m] upper corner (closed box: vertices on its faces are pinned).
  std::shared_ptr<const PinMask> mask;  ///< When set, selects the vertices instead of the box.
  Path path;          ///< Keyframe `position` = offset [m] of the pinned vertices from rest; empty = fixed.
  uint32_t body = 0;  ///< The body whose vertices it selects (RestModel::bodies; bodies.h).
};

/// The pinned vertices of a model: ids (ascending) and, per id, the index of the pin that holds it
/// (the first pin whose box contains it).
struct PinSet {
  std::vector<uint32_t> vertices;  ///< Pinned vertex ids, ascending.
  std::vector<uint32_t> pinOf;     ///< Per entry of `vertices`: index into the settings list.
  bool empty() const { return vertices.empty(); }
};

/// Selects the pinned vertices from rest positions (a vertex held by several pins goes to the
/// first). Reads no file (a mask whose source was not read by loadPinMasks is an error). Throws
/// InputError when a pin holds no vertex, its box is inverted, or its mask is malformed or empty
/// (messages "pins[i]: ..." and "pins[i].mask: ...", the latter naming the mask's file).
/// `bodyVertices` lists each body's vertex range [begin, end) (RestModel::bodies); a pin selects
/// only among its body's vertices ("pins[i].body: ..." when there is no such body). Empty: one
/// body of every vertex.
PinSet selectPins(const std::vector<PinSettings>& pins, const std::vector<Vec3>& restPositions,
                  const std::vector<std::array<uint32_t, 2>>& bodyVertices = {});

/// Reads every mask's file (PinMask::source) into PinMask::volume, once, before the pins reach a
/// World (buildScene does this; World::setPins reads no file). Throws InputError
/// "pins[i].mask: <file>: ..." when a file cannot be read.
void loadPinMasks(std::vector<PinSettings>& pins);

}  // namespace gradel
