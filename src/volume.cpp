#include "gradel/volume.h"

#include <cmath>

namespace gradel {

VoxelVolume::VoxelVolume(int dim, int nx, int ny, int nz, Real voxelSize)
    : dim_(dim), n_{nx, ny, nz}, voxelSize_(voxelSize) {
  if (dim != 2 && dim != 3) throw InputError("volume: dim must be 2 or 3, got " + std::to_string(dim));
  if (nx <= 0 || ny <= 0 || nz <= 0)
    throw InputError("volume: dimensions must be positive, got " + std::to_string(nx) + "x" + std::to_string(ny) + "x" +
                     std::to_string(nz));
  if (dim == 2 && nz != 1) throw InputError("volume: a 2D volume must have nz == 1");
  if (!(voxelSize > 0) || !std::isfinite(voxelSize))
    throw InputError("volume: voxel_size must be a positive finite number of metres");
  const double cells = double(nx) * double(ny) * double(nz);
  if (cells > 4.0e9) throw InputError("volume: too many voxels (" + std::to_string(cells) + ")");
  data_.assign(size_t(nx) * size_t(ny) * size_t(nz), 0);
}

bool VoxelVolume::isSurface(int i, int j, int k) const {
  if (!at(i, j, k)) return false;
  if (!at(i - 1, j, k) || !at(i + 1, j, k) || !at(i, j - 1, k) || !at(i, j + 1, k)) return true;
  if (dim_ == 3 && (!at(i, j, k - 1) || !at(i, j, k + 1))) return true;
  return false;
}

void VoxelVolume::set(int i, int j, int k, bool v) {
  const size_t n = index(i, j, k);
  data_[n] = v ? 1 : 0;
  if (!labels_.empty()) labels_[n] = v ? (labels_[n] != 0 ? labels_[n] : uint16_t(1)) : uint16_t(0);
}

void VoxelVolume::setLabel(int i, int j, int k, uint16_t label) {
  const size_t n = index(i, j, k);
  data_[n] = label != 0 ? 1 : 0;
  if (labels_.empty() && label <= 1) return;  // still binary
  enableLabels()[n] = label;
}

std::vector<uint16_t>& VoxelVolume::enableLabels() {
  if (labels_.empty()) {
    labels_.resize(data_.size());
    for (size_t n = 0; n < data_.size(); ++n) labels_[n] = data_[n] != 0 ? 1 : 0;
  }
  return labels_;
}

std::vector<uint16_t> VoxelVolume::labelsPresent() const {
  if (labels_.empty()) return countFilled() > 0 ? std::vector<uint16_t>{1} : std::vector<uint16_t>{};
  std::vector<uint8_t> seen(65536, 0);
  for (uint16_t l : labels_) seen[l] = 1;
  std::vector<uint16_t> out;
  for (size_t l = 1; l < seen.size(); ++l)
    if (seen[l]) out.push_back(uint16_t(l));
  return out;
}

size_t VoxelVolume::countFilled() const {
  size_t c = 0;
  for (uint8_t v : data_) c += v != 0;
  return c;
}

}  // namespace gradel
