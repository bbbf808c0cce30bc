#include "gradel/render/display_budget.h"

#include <algorithm>
#include <cmath>

#include "gradel/isosurface.h"
#include "gradel/types.h"

namespace gradel::render {

int displayStepEstimate(size_t triangles, size_t budget) {
  if (budget == 0 || triangles <= budget) return 1;
  int s = std::max(1, int(std::floor(std::sqrt(double(triangles) / double(budget)))));
  while (triangles > budget * size_t(s) * size_t(s)) ++s;  // the rounding of sqrt either way
  while (s > 1 && triangles <= budget * size_t(s - 1) * size_t(s - 1)) --s;
  return s;
}

CoarseSurface coarseIsosurface(const VoxelVolume& volume, const Vec3& origin, size_t budget, int firstStep) {
  if (budget == 0) throw InputError("coarseIsosurface: a budget of 0 triangles");
  const int largest = std::max({volume.nx(), volume.ny(), volume.nz()});
  CoarseSurface c;
  for (int step = std::max(1, firstStep);; ++step) {
    TriangleMesh mesh = isosurface(volume, origin, step);
    // A step so coarse that no sample block is more than half full leaves no surface: the last
    // one with triangles is kept.
    if (mesh.triangles.empty() && !c.mesh.triangles.empty()) return c;
    c.mesh = std::move(mesh), c.step = step;
    if (c.mesh.triangles.size() <= budget || step >= largest) return c;
  }
}

}  // namespace gradel::render
