#include "gradel/shapes.h"

#include <algorithm>
#include <cmath>

namespace gradel {

bool Primitive::contains(const Vec3& p) const {
  switch (kind) {
    case PrimitiveKind::Box: return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
    case PrimitiveKind::Sphere: return (p - center).squaredNorm() <= radius * radius;
    case PrimitiveKind::Cylinder: {
      Vec3 d = p - center;
      if (std::abs(d[axis]) > halfLength) return false;
      d[axis] = 0;
      return d.squaredNorm() <= radius * radius;
    }
  }
  return false;
}

VoxelVolume rasterize(const ShapeSpec& spec) {
  if (spec.primitives.empty()) throw InputError("shape: at least one primitive is needed");
  VoxelVolume vol(spec.dim, spec.dims[0], spec.dims[1], spec.dims[2], spec.voxelSize);
  for (const Primitive& p : spec.primitives) {
    if (p.kind != PrimitiveKind::Box && !(p.radius > 0)) throw InputError("shape: radius must be positive");
    if (p.kind == PrimitiveKind::Cylinder && !(p.halfLength > 0))
      throw InputError("shape: cylinder half_length must be positive");
    if (p.kind == PrimitiveKind::Cylinder && spec.dim == 2)
      throw InputError("shape: cylinder is a 3D shape; use box or sphere (disk) in 2D");
    if (p.axis < 0 || p.axis > 2) throw InputError("shape: cylinder axis must be x, y or z");
    if (p.label == 0) throw InputError("shape: a primitive's label must be in [1, 65535] (0 is empty space)");
  }
  const bool labelled =
      std::any_of(spec.primitives.begin(), spec.primitives.end(), [](const Primitive& p) { return p.label != 1; });
  for (int k = 0; k < vol.nz(); ++k)
    for (int j = 0; j < vol.ny(); ++j)
      for (int i = 0; i < vol.nx(); ++i) {
        const Vec3 c(i + 0.5, j + 0.5, spec.dim == 3 ? k + 0.5 : 0.0);
        uint16_t label = 0;
        for (const Primitive& p : spec.primitives) {
          Primitive q = p;
          if (spec.dim == 2) q.center.z() = 0, q.min.z() = -1, q.max.z() = 1;
          if (q.contains(c)) {
            label = p.label;
            if (!labelled) break;  // binary: the first hit decides; labelled: the last one does
          }
        }
        if (label != 0) vol.setLabel(i, j, k, label);
      }
  if (vol.countFilled() == 0) throw InputError("shape: the volume is empty (no voxel inside any primitive)");
  return vol;
}

ShapeSpec scaleShape(const ShapeSpec& spec, int size) {
  if (size < 1) throw InputError("size: must be >= 1 voxel (got " + std::to_string(size) + ")");
  const int longest = *std::max_element(spec.dims.begin(), spec.dims.begin() + spec.dim);
  const Real f = Real(size) / Real(longest);
  ShapeSpec out = spec;
  for (int i = 0; i < spec.dim; ++i) out.dims[size_t(i)] = std::max(1, int(std::lround(spec.dims[size_t(i)] * f)));
  out.voxelSize = spec.voxelSize / f;
  for (Primitive& p : out.primitives) {
    for (int i = 0; i < spec.dim; ++i) p.min[i] *= f, p.max[i] *= f, p.center[i] *= f;
    p.radius *= f, p.halfLength *= f;
  }
  return out;
}

ShapeSpec presetShape(const std::string& name, int size, int dim, Real voxelSize) {
  if (dim != 2 && dim != 3) throw InputError("dim: must be 2 or 3 (got " + std::to_string(dim) + ")");
  if (size < 1 || size > 4096)
    throw InputError("size: must be between 1 and 4096 voxels (got " + std::to_string(size) + ")");
  ShapeSpec s;
  s.dim = dim;
  s.dims = {size, size, dim == 3 ? size : 1};
  s.voxelSize = voxelSize;
  const Real h = 0.5 * size;
  Primitive p;
  if (name == "box") {
    p.kind = PrimitiveKind::Box;
    p.min = Vec3(0, 0, 0);
    p.max = Vec3(size, size, dim == 3 ? size : 1);
  } else if (name == "sphere") {
    p.kind = PrimitiveKind::Sphere;
    p.center = Vec3(h, h, dim == 3 ? h : 0);
    p.radius = h;
  } else if (name == "cylinder") {
    if (dim == 2) throw InputError("shape: cylinder is 3D only (expected box or sphere in 2D)");
    p.kind = PrimitiveKind::Cylinder;
    p.center = Vec3(h, h, h);
    p.radius = h;
    p.halfLength = h;
    p.axis = 2;
  } else {
    throw InputError("unknown shape '" + name + "' (expected box, sphere or cylinder)");
  }
  s.primitives.push_back(p);
  return s;
}

}  // namespace gradel
