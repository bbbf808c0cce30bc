#include "gradel/pins.h"

namespace gradel {

PinSet selectPins(const std::vector<PinSettings>& pins, const std::vector<Vec3>& restPositions) {
  PinSet s;
  std::vector<size_t> held(pins.size(), 0);
  for (size_t p = 0; p < pins.size(); ++p) {
    if (!pins[p].min.allFinite() || !pins[p].max.allFinite() || (pins[p].max - pins[p].min).minCoeff() < 0)
      throw InputError("pins[" + std::to_string(p) + "]: max must be >= min on every axis");
  }
  for (size_t i = 0; i < restPositions.size(); ++i) {
    const Vec3& x = restPositions[i];
    for (size_t p = 0; p < pins.size(); ++p) {
      // A relative tolerance: lattice positions are origin + integer * voxelSize, rounded.
      const Vec3 tol = 1e-9 * (pins[p].max - pins[p].min).cwiseAbs().cwiseMax(x.cwiseAbs()) + Vec3::Constant(1e-12);
      if (((x - pins[p].min).array() >= -tol.array()).all() && ((pins[p].max - x).array() >= -tol.array()).all()) {
        s.vertices.push_back(uint32_t(i));
        s.pinOf.push_back(uint32_t(p));
        ++held[p];
        break;
      }
    }
  }
  for (size_t p = 0; p < pins.size(); ++p)
    if (held[p] == 0) throw InputError("pins[" + std::to_string(p) + "]: the box holds no vertex of the body");
  return s;
}

}  // namespace gradel
