// Grey-level volumes (CT, MRI, label maps) become binary: a voxel is filled when its value
// passes a threshold or lies in a range; or, with `labels`, keep their integer values as region
// labels (volume.h: 0 empty, 1..65535 a region). Shared by the NRRD, NIfTI and raw readers, which
// convert their samples slice by slice straight into the VoxelVolume (no full-size copy of the
// grey levels is ever held).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "gradel/io/byte_stream.h"
#include "gradel/volume.h"

namespace gradel::io {

/// Sample types of grey-level files.
enum class ScalarType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Int64, UInt64, Float32, Float64 };

/// "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64", "float32",
/// "float64"; InputError otherwise.
ScalarType parseScalarType(const std::string& name);
const char* scalarTypeName(ScalarType t);
size_t scalarTypeBytes(ScalarType t);

/// Which values are filled. Neither set: every non-zero value (masks, label maps).
struct GreyRule {
  std::optional<double> threshold;         ///< value >= threshold is filled [the file's units].
  std::optional<double> rangeLo, rangeHi;  ///< rangeLo <= value <= rangeHi is filled (both or neither).
  /// Keep the values as labels: every value (after scaling) must be an integer in [0, 65535]
  /// (0 = empty, NaN = empty); anything else is an InputError naming the sample. Not with
  /// threshold or range.
  bool labels = false;

  bool filled(double v) const {
    if (threshold) return v >= *threshold;
    if (rangeLo) return v >= *rangeLo && v <= *rangeHi;
    return v != 0;  // NaN != 0 is true, so NaN is checked by the caller
  }
  /// "threshold 300", "range [200, 3000]" or "non-zero" for messages.
  std::string describe() const;
};

/// How samples are stored in the file.
struct SampleLayout {
  ScalarType type = ScalarType::UInt8;
  bool bigEndian = false;
  double scale = 1.0;  ///< value = scale * stored + offset (NIfTI scl_slope / scl_inter).
  double offset = 0.0;
};

/// Smallest and largest value read (after scaling), for messages about the threshold.
struct SampleStats {
  double min = 0, max = 0;
  bool any = false;
};

/// Reads volume.size() samples (x fastest) from `in` and sets volume voxels by `rule` (with
/// `rule.labels`, their labels: VoxelVolume::enableLabels). NaN is empty. Reads in 1 MiB slices. Throws InputError when the data ends early.
SampleStats readGreyLevels(ByteStream& in, const SampleLayout& layout, const GreyRule& rule, VoxelVolume& volume);

/// Same, for whitespace-separated text samples (NRRD "ascii" encoding).
SampleStats readGreyLevelsText(ByteStream& in, const GreyRule& rule, VoxelVolume& volume);

/// The InputError for a volume where nothing passed the rule, naming the value range found.
[[noreturn]] void failNothingFilled(const std::string& name, const GreyRule& rule, const SampleStats& stats);

}  // namespace gradel::io
