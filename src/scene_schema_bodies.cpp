// The scene file's bodies (scene_schema.h): shape primitives, volume and mesh sources, a body's
// placement and velocity, its material (and regions), the `bodies` list.
#include <algorithm>
#include <string>
#include <vector>

#include "gradel/io/volume_file.h"
#include "gradel/settings_check.h"
#include "scene_schema.h"

namespace gradel::scene_json {

namespace {

Primitive readPrimitive(Fields& f) {
  const int dim = f.context().dim;
  Primitive p;
  const int type = f.choice("type", {"box", "sphere", "cylinder"});
  if (type == 0) {
    p.kind = PrimitiveKind::Box;
    f.forbid("center", "a box takes \"min\" and \"max\"");
    f.forbid("radius", "a box takes \"min\" and \"max\"");
    p.min = f.requireVec("min", kAny, "voxels");
    p.max = f.requireVec("max", kAny, "voxels");
    checkMaxAboveMin(f, p.min, p.max);
    // The 2D rasteriser ignores z; keep the box's z extent non-empty all the same.
    if (dim == 2) p.min.z() = -1, p.max.z() = 1;
  } else {
    f.forbid("min", "only a box takes \"min\"");
    f.forbid("max", "only a box takes \"max\"");
    p.center = f.requireVec("center", kAny, "voxels");
    p.radius = f.requireNumber("radius", kPositive, "voxels");
    if (type == 1) {
      p.kind = PrimitiveKind::Sphere;
      f.forbid("half_length", "only a cylinder takes \"half_length\"");
      f.forbid("axis", "only a cylinder takes \"axis\"");
    } else {
      if (dim == 2) f.fail("type", "\"cylinder\" is 3D only (expected \"box\" or \"sphere\" in a 2D scene)");
      p.kind = PrimitiveKind::Cylinder;
      p.halfLength = f.requireNumber("half_length", kPositive, "voxels");
      p.axis = f.choice("axis", {"x", "y", "z"}, 2);
    }
  }
  p.label = uint16_t(f.optInteger("label", 1, 65535).value_or(p.label));
  f.finish();
  return p;
}

}  // namespace

std::shared_ptr<const VolumeSource> readSource(Fields f, int dim, Real voxelSize) {
  io::VolumeFileSpec spec;
  spec.dim = dim;
  spec.voxelSize = voxelSize;
  const json& file = f.require("file", "a file path");
  if (!file.is_string() || file.get<std::string>().empty()) f.failWrongType("file", file, "a file path");
  std::filesystem::path path = file.get<std::string>();
  if (path.is_relative()) path = std::filesystem::path(f.context().file).parent_path() / path;
  spec.path = path.lexically_normal().string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(spec.path, ec))
    f.fail("file",
           "\"" + shown(file.get<std::string>()) + "\" is not a readable file (looked for " +
               shown(std::filesystem::absolute(spec.path, ec).lexically_normal().string(), 300) + ")");
  if (f.take("format")) {
    spec.format = f.enumeration("format", io::VolumeFormat::Binvox, &io::parseVolumeFormat);
  } else {
    try {
      spec.format = io::volumeFormatFromPath(spec.path);
    } catch (const InputError& e) {
      f.fail("file", e.what());
    }
  }
  const io::VolumeFormat format = *spec.format;
  const std::string name = io::volumeFormatName(format);
  const bool grey =
      format == io::VolumeFormat::Nrrd || format == io::VolumeFormat::Nifti || format == io::VolumeFormat::Raw;
  const bool mesh = io::isMeshFormat(format);
  const std::string greyOnly =
      "only grey-level formats (nrrd, nifti, raw) take it; " + name + " files are binary already";
  if (!grey) {
    f.forbid("threshold", greyOnly);
    f.forbid("range", greyOnly);
    f.forbid("labels", "only grey-level formats (nrrd, nifti, raw) hold labels; " + name + " files are binary");
  }
  if (const json* l = f.take("labels")) {
    if (!l->is_boolean()) f.failWrongType("labels", *l, "true or false");
    spec.grey.labels = l->get<bool>();
    if (spec.grey.labels)
      for (const char* key : {"threshold", "range"})
        f.forbid(key, "\"labels\": true keeps every value as a label (0 empty); no threshold or range");
  }
  spec.grey.threshold = f.optNumber("threshold", kAny, "");
  if (const json* r = f.take("range")) {
    const std::string expected = "2 numbers [lo, hi] with lo <= hi";
    if (!r->is_array() || r->size() != 2 || !(*r)[0].is_number() || !(*r)[1].is_number())
      f.failWrongType("range", *r, expected);
    const Real lo = (*r)[0].get<Real>(), hi = (*r)[1].get<Real>();
    if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi)
      f.fail("range", r->dump() + " is out of range (expected " + expected + ")");
    if (spec.grey.threshold) f.fail("range", "not allowed here: give \"threshold\" or \"range\", not both");
    spec.grey.rangeLo = lo;
    spec.grey.rangeHi = hi;
  }
  if (mesh) {
    if (dim == 2) f.fail("file", "a mesh is voxelised in 3D only (expected a voxel format in a 2D scene)");
    spec.resolution = f.optInteger("resolution", 1, 1024).value_or(spec.resolution);
  } else {
    f.forbid("resolution", "only meshes (obj, stl, ply) are voxelised at a resolution");
  }
  if (format == io::VolumeFormat::Vox)
    spec.model = f.optInteger("model", 0, 1 << 20).value_or(spec.model);
  else
    f.forbid("model", "only .vox files hold several models");
  if (format == io::VolumeFormat::Raw) {
    const std::array<int, 3> dims = f.requireIntVec("dims", 1, kMaxGridEdge);
    spec.raw.dims = {dims[0], dims[1], dims[2]};
    f.require("type", "a sample type");
    spec.raw.samples.type = f.enumeration("type", io::ScalarType::UInt8, &io::parseScalarType);
    spec.raw.samples.bigEndian = f.choice("endian", {"little", "big"}, 0) == 1;
    spec.raw.headerBytes = uint64_t(f.optInteger("header_bytes", 0, std::numeric_limits<int>::max()).value_or(0));
  } else {
    for (const char* key : {"dims", "type", "endian", "header_bytes"})
      f.forbid(key, "only raw files need their layout described (the " + name + " header has it)");
  }
  f.finish();
  return io::openVolume(spec);
}

// A body's keys (`body`, or an entry of `bodies`, whose material and name readBodies reads).
void readBody(Fields& f, int dim, BodySettings& body) {
  if (auto source = f.optObject("source")) {
    for (const char* key : {"shape", "size", "grid", "primitives"})
      f.forbid(key, "a body with \"source\" takes its volume from the file");
    body.shape.voxelSize = f.number("voxel_size", body.shape.voxelSize, kVoxelSize, "m");
    body.source = readSource(*source, dim, body.shape.voxelSize);
    body.sizeKey = f.keyPath("source");
  } else {
    const int shape = f.choice("shape", {"box", "sphere", "cylinder", "union"});
    const Real voxelSize = f.number("voxel_size", body.shape.voxelSize, kVoxelSize, "m");
    if (shape == 3) {
      f.forbid("size", "\"size\" is for the presets box, sphere and cylinder; a union takes \"grid\"");
      ShapeSpec spec;
      spec.dim = dim;
      spec.voxelSize = voxelSize;
      spec.dims = f.requireIntVec("grid", 1, kMaxGridEdge);
      body.sizeKey = f.keyPath("grid");
      std::vector<Fields> prims = f.objectArray("primitives", true);
      if (prims.empty()) f.fail("primitives", "empty (expected at least one primitive)");
      for (Fields& pf : prims) spec.primitives.push_back(readPrimitive(pf));
      body.shape = spec;
    } else {
      f.forbid("grid", "\"grid\" is only for shape \"union\"");
      f.forbid("primitives", "\"primitives\" is only for shape \"union\"");
      const int size = f.requireInteger("size", 1, kMaxGridEdge);
      body.sizeKey = f.keyPath("size");
      if (shape == 2 && dim == 2)
        f.fail("shape", "\"cylinder\" is 3D only (expected \"box\", \"sphere\" or \"union\" in a 2D scene)");
      static const char* kNames[] = {"box", "sphere", "cylinder"};
      try {
        body.shape = presetShape(kNames[shape], size, dim, voxelSize);
      } catch (const InputError& e) {
        f.fail("shape", e.what());
      }
    }
  }
  body.layout = f.enumeration("layout", body.layout, &parseLayoutKind);
  {
    const Real reach = kMaxPositionVoxels * body.shape.voxelSize;
    body.position = f.optVec("position", Bound{-reach, reach, false, false}, "m").value_or(body.position);
  }
  body.velocity = f.vec("velocity", body.velocity, "m/s");  // 2D: z = 0 (a vector of 2 numbers)
}

void readMaterial(Fields f, MaterialSettings& m) {
  m.scaling = f.enumeration("scaling", m.scaling, &parseScaling);
  m.youngsModulus = f.number("youngs_modulus", m.youngsModulus, kPositive, "Pa");
  m.density = f.number("density", m.density, kPositive, "kg/m^3");
  m.paperK = f.number("k", m.paperK, kPositive, "N");
  m.poissonRatio = f.number("poisson_ratio", m.poissonRatio, kPoissonRatio, "");
  // Per-label materials; a field an entry leaves out is the body's (read above).
  std::vector<Fields> regions = f.objectArray("regions", false);
  for (size_t i = 0; i < regions.size(); ++i) {
    Fields& rf = regions[i];
    RegionMaterial r;
    r.label = uint16_t(rf.requireInteger("label", 1, 65535));
    for (size_t j = 0; j < i; ++j)
      if (m.regions[j].label == r.label)
        rf.fail("label", std::to_string(r.label) + " appears twice (also in regions[" + std::to_string(j) +
                             "]; expected one entry per label)");
    r.youngsModulus = rf.number("youngs_modulus", m.youngsModulus, kPositive, "Pa");
    r.density = rf.number("density", m.density, kPositive, "kg/m^3");
    r.paperK = rf.number("k", m.paperK, kPositive, "N");
    r.poissonRatio = rf.number("poisson_ratio", m.poissonRatio, kPoissonRatio, "");
    r.damping = rf.optNumber("damping", kNonNegative, "1/s");
    rf.finish();
    m.regions.push_back(r);
  }
  coreCheck(f, [&] { validate(m); });
  f.finish();
}

// `bodies`: several bodies, each with its own material and an output name (default "body<i>").
void readBodies(Fields& top, Scene& scene) {
  std::vector<Fields> entries = top.objectArray("bodies", true);
  if (entries.empty()) top.fail("bodies", "empty (expected at least one body)");
  std::vector<BodySettings> bodies(entries.size());
  for (size_t i = 0; i < entries.size(); ++i) {
    Fields& f = entries[i];
    BodySettings& b = bodies[i];
    b.name = "body" + std::to_string(i);
    if (auto name = f.optString("name")) {
      if (!isSafeName(*name))
        f.fail("name",
               "\"" + shown(*name) +
                   "\" is not usable in a file name (expected 1-100 of A-Z a-z 0-9 _ - ., not starting with .)");
      for (size_t j = 0; j < i; ++j)
        if (bodies[j].name == *name)
          f.fail("name", "\"" + shown(*name) + "\" is the name of bodies[" + std::to_string(j) +
                             "] too (expected a name of its own)");
      b.name = *name;
    }
    readBody(f, scene.dim, b);
    if (auto m = f.optObject("material")) readMaterial(*m, b.material);
    f.finish();
  }
  scene.bodies = std::move(bodies);
}

}  // namespace gradel::scene_json
