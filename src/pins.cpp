#include "gradel/pins.h"

#include <cmath>

namespace gradel {

namespace {

// A mask: is the closed cube of some filled voxel holding x?
class LoadedMask {
 public:
  LoadedMask(const PinMask& m, size_t index) : m_(m) {
    const std::string where = "pins[" + std::to_string(index) + "].mask";
    if (!(m.voxelSize > 0) || !std::isfinite(m.voxelSize))
      throw InputError("", where, "voxel_size must be a positive finite number");
    if (!m.origin.allFinite()) throw InputError("", where, "origin must be finite");
    for (size_t b = 0; b < m.boxes.size(); ++b)
      if ((m.boxes[b][1] - m.boxes[b][0]).minCoeff() < 0)
        throw InputError("", where, "boxes[" + std::to_string(b) + "]: max must be >= min on every axis");
    if (!m.source && !m.volume && m.boxes.empty()) throw InputError("", where, "has neither a file nor boxes");
    if (m.source && !m.volume) throw InputError("", where, m.source->describe() + ": not read (loadPinMasks)");
    if (m.volume && m.volume->countFilled() == 0)
      throw InputError("", where, (m.source ? m.source->describe() + ": " : std::string()) + "no filled voxel");
  }

  bool filled(const Int3& v) const {
    if (m_.volume) {
      if (m_.volume->at(v.x(), v.y(), v.z())) return true;
    }
    for (const auto& b : m_.boxes)
      if ((v.array() >= b[0].array()).all() && (v.array() <= b[1].array()).all()) return true;
    return false;
  }

  bool holds(const Vec3& x) const {
    const Vec3 u = (x - m_.origin) / m_.voxelSize;
    Int3 lo, hi;
    for (int a = 0; a < 3; ++a) {
      // Voxel v holds u on axis a when v <= u <= v + 1 (with a rounding tolerance).
      const Real t = 1e-6;
      if (!(std::abs(u[a]) < 1e9)) return false;
      lo[a] = int(std::ceil(u[a] - 1 - t));
      hi[a] = int(std::floor(u[a] + t));
    }
    for (int k = lo.z(); k <= hi.z(); ++k)
      for (int j = lo.y(); j <= hi.y(); ++j)
        for (int i = lo.x(); i <= hi.x(); ++i)
          if (filled(Int3(i, j, k))) return true;
    return false;
  }

 private:
  const PinMask& m_;
};

}  // namespace

void loadPinMasks(std::vector<PinSettings>& pins) {
  for (size_t p = 0; p < pins.size(); ++p) {
    if (!pins[p].mask || !pins[p].mask->source || pins[p].mask->volume) continue;
    auto mask = std::make_shared<PinMask>(*pins[p].mask);
    try {
      mask->volume = std::make_shared<const VoxelVolume>(mask->source->load());
    } catch (const InputError& e) {
      throw InputError("", "pins[" + std::to_string(p) + "].mask", e.what());
    }
    pins[p].mask = std::move(mask);
  }
}

PinSet selectPins(const std::vector<PinSettings>& pins, const std::vector<Vec3>& restPositions,
                  const std::vector<std::array<uint32_t, 2>>& bodyVertices) {
  std::vector<std::array<uint32_t, 2>> bodies = bodyVertices;
  if (bodies.empty()) bodies.push_back({0, uint32_t(restPositions.size())});
  for (size_t p = 0; p < pins.size(); ++p)
    if (pins[p].body >= bodies.size())
      throw InputError("", "pins[" + std::to_string(p) + "].body",
                       std::to_string(pins[p].body) + " is out of range (expected a body index below " +
                           std::to_string(bodies.size()) + ")");
  PinSet s;
  std::vector<size_t> held(pins.size(), 0);
  std::vector<std::unique_ptr<LoadedMask>> masks(pins.size());
  for (size_t p = 0; p < pins.size(); ++p) {
    if (pins[p].mask) {
      masks[p] = std::make_unique<LoadedMask>(*pins[p].mask, p);
      continue;
    }
    if (!pins[p].min.allFinite() || !pins[p].max.allFinite() || (pins[p].max - pins[p].min).minCoeff() < 0)
      throw InputError("", "pins[" + std::to_string(p) + "]", "max must be >= min on every axis");
  }
  for (size_t i = 0; i < restPositions.size(); ++i) {
    const Vec3& x = restPositions[i];
    for (size_t p = 0; p < pins.size(); ++p) {
      const std::array<uint32_t, 2>& range = bodies[pins[p].body];
      if (i < range[0] || i >= range[1]) continue;
      bool in = false;
      if (masks[p]) {
        in = masks[p]->holds(x);
      } else {
        // A relative tolerance: lattice positions are origin + integer * voxelSize, rounded.
        const Vec3 tol = 1e-9 * (pins[p].max - pins[p].min).cwiseAbs().cwiseMax(x.cwiseAbs()) + Vec3::Constant(1e-12);
        in = ((x - pins[p].min).array() >= -tol.array()).all() && ((pins[p].max - x).array() >= -tol.array()).all();
      }
      if (in) {
        s.vertices.push_back(uint32_t(i));
        s.pinOf.push_back(uint32_t(p));
        ++held[p];
        break;
      }
    }
  }
  for (size_t p = 0; p < pins.size(); ++p)
    if (held[p] == 0)
      throw InputError(
          "", "pins[" + std::to_string(p) + "]",
          std::string("the ") + (masks[p] ? "mask" : "box") + " holds no vertex of " +
              (bodyVertices.size() > 1 ? "body " + std::to_string(pins[p].body) : std::string("the body")));
  return s;
}

}  // namespace gradel
