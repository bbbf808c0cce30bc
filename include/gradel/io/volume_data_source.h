// A volume already in memory (a numpy array from Python, a volume a tool built) as a
// VolumeSource, so scene building (buildScene) treats it like a file or a shape.
#pragma once

#include <memory>
#include <string>

#include "gradel/volume.h"

namespace gradel::io {

class VolumeDataSource : public VolumeSource {
 public:
  /// `name` describes the data in error messages ("numpy array").
  VolumeDataSource(std::shared_ptr<const VoxelVolume> volume, std::string name)
      : volume_(std::move(volume)), name_(std::move(name)) {}
  VoxelVolume load() const override { return *volume_; }  // one copy: the world owns its volume
  std::string describe() const override { return name_; }

 private:
  std::shared_ptr<const VoxelVolume> volume_;
  std::string name_;
};

}  // namespace gradel::io
