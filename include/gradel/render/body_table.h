// The viewer's per-body table (gradel-view's panel, docs/viewer.md): one row of live figures per
// body of a scene of several `bodies`. GL-free: only the built scene and its world.
#pragma once

#include <string>
#include <vector>

#include "gradel/scene.h"

namespace gradel::render {

/// One body's row: its name, size and the figures of World::bodyMetrics.
struct BodyRow {
  std::string name;  ///< BodySettings::name ("body0", "body1", ... unless named).
  size_t vertices = 0, elements = 0;
  Real mass = 0;           ///< [kg]
  Real kineticEnergy = 0;  ///< [J]
  Real elasticEnergy = 0;  ///< [J]
  Real maxStress = 0;      ///< [Pa] largest von Mises stress of the body's elements.
  Vec3 centre{0, 0, 0};    ///< [m] centre of mass.
  Vec3 velocity{0, 0, 0};  ///< [m/s] of the centre of mass (momentum / mass).
};

/// A row per body of `scene`, in body order (one row for a one-body scene).
std::vector<BodyRow> bodyTable(const BuiltScene& scene);

}  // namespace gradel::render
