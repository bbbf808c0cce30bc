#include "gradel/io/volume_file.h"

#include <algorithm>
#include <cstring>

#include "gradel/io/binvox.h"
#include "gradel/io/mesh_file.h"
#include "gradel/io/nifti.h"
#include "gradel/io/nrrd.h"
#include "gradel/io/vox.h"
#include "gradel/io/voxelize.h"

namespace gradel::io {

namespace {
struct FormatInfo {
  VolumeFormat format;
  const char* name;
  const char* extension;
};
constexpr FormatInfo kFormats[] = {
    {VolumeFormat::Binvox, "binvox", ".binvox"}, {VolumeFormat::Vox, "vox", ".vox"},
    {VolumeFormat::Nrrd, "nrrd", ".nrrd"},       {VolumeFormat::Nifti, "nifti", ".nii"},
    {VolumeFormat::Raw, "raw", ".raw"},          {VolumeFormat::Obj, "obj", ".obj"},
    {VolumeFormat::Stl, "stl", ".stl"},          {VolumeFormat::Ply, "ply", ".ply"},
};

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}
bool endsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// Gzip magic (RFC 1952): 1f 8b.
bool startsGzip(const std::string& path) {
  auto in = openFileStream(path);
  uint8_t m[2] = {0, 0};
  return in->read(m, 2) == 2 && m[0] == 0x1f && m[1] == 0x8b;
}
}  // namespace

VolumeFormat parseVolumeFormat(const std::string& name) {
  for (const FormatInfo& f : kFormats)
    if (name == f.name) return f.format;
  throw InputError("unknown format '" + name + "' (expected binvox, vox, nrrd, nifti, raw, obj, stl or ply)");
}

const char* volumeFormatName(VolumeFormat f) {
  for (const FormatInfo& i : kFormats)
    if (i.format == f) return i.name;
  return "?";
}

VolumeFormat volumeFormatFromPath(const std::string& path) {
  std::string p = lower(path);
  if (endsWith(p, ".gz")) p.erase(p.size() - 3);
  for (const FormatInfo& f : kFormats)
    if (endsWith(p, f.extension)) return f.format;
  throw InputError(path +
                   ": cannot tell the format from the extension (expected .binvox, .vox, .nrrd, .nii, .raw, "
                   ".obj, .stl or .ply, or give \"format\")");
}

bool isMeshFormat(VolumeFormat f) { return f == VolumeFormat::Obj || f == VolumeFormat::Stl || f == VolumeFormat::Ply; }

VoxelVolume readVolumeStream(ByteStream& in, VolumeFormat format, const VolumeFileSpec& spec,
                             TriangleMesh* latticeMesh) {
  if (latticeMesh) *latticeMesh = TriangleMesh{};
  switch (format) {
    case VolumeFormat::Binvox: return readBinvox(in, spec.voxelSize, spec.limits);
    case VolumeFormat::Vox: return readVox(in, spec.voxelSize, spec.model, spec.limits);
    case VolumeFormat::Nrrd: return readNrrd(in, spec.grey, spec.voxelSize, spec.limits);
    case VolumeFormat::Nifti: return readNifti(in, spec.grey, spec.voxelSize, spec.limits);
    case VolumeFormat::Raw: return readRawVolume(in, spec.raw, spec.grey, spec.voxelSize, spec.limits);
    case VolumeFormat::Obj:
    case VolumeFormat::Stl:
    case VolumeFormat::Ply: {
      const TriangleMesh mesh = format == VolumeFormat::Obj   ? readObj(in, spec.limits)
                                : format == VolumeFormat::Stl ? readStl(in, spec.limits)
                                                              : readPly(in, spec.limits);
      return voxelize(mesh, {spec.resolution, spec.voxelSize, spec.limits.minRayCrossingCap}, in.name(), latticeMesh);
    }
  }
  in.fail("unknown format");
}

VoxelVolume readVolumeFile(const VolumeFileSpec& spec, TriangleMesh* latticeMesh) {
  const VolumeFormat format = spec.format ? *spec.format : volumeFormatFromPath(spec.path);
  std::unique_ptr<ByteStream> in = openFileStream(spec.path);
  if (startsGzip(spec.path)) in = gzipStream(std::move(in));
  VoxelVolume v = readVolumeStream(*in, format, spec, latticeMesh);
  if (v.countFilled() == 0) throw InputError(spec.path + ": the volume is empty (no filled voxel)");
  if (spec.dim == 2) {
    if (v.nz() != 1)
      throw InputError(spec.path +
                       ": a 2D scene needs a volume one voxel thick in z, this one has nz = " + std::to_string(v.nz()));
    VoxelVolume flat(2, v.nx(), v.ny(), 1, v.voxelSize());
    flat.data().swap(v.data());
    if (v.hasLabels()) flat.enableLabels().swap(v.enableLabels());  // a 2D label map keeps its labels
    return flat;
  }
  return v;
}

std::unique_ptr<VolumeSource> openVolume(const VolumeFileSpec& spec) {
  return std::make_unique<FileVolumeSource>(spec);
}

}  // namespace gradel::io
