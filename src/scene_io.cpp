// Scene files (docs/scenes.md): strict JSON -> Scene. The top level: which sections a file has
// and in which order they are read; the reader and its one-line messages
// ("FILE: KEY.PATH: what is wrong (expected ...)") are scene_json.h, the sections scene_schema.h.
#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>

#include "gradel/scene.h"
#include "scene_schema.h"

namespace gradel {

using namespace scene_json;

namespace {

// A scene is a few kilobytes; this cap only stops `gradel run /dev/zero` from eating memory.
constexpr size_t kMaxSceneBytes = 16u << 20;

std::string defaultName(const std::string& sourceName) {
  std::string stem = std::filesystem::path(sourceName).stem().string();
  for (char& c : stem)
    if (!isNameChar(c)) c = '_';
  while (!stem.empty() && stem[0] == '.') stem.erase(0, 1);
  if (stem.size() > 100) stem.resize(100);
  return stem.empty() ? "scene" : stem;
}

}  // namespace

Scene parseScene(const std::string& jsonText, const std::string& sourceName) {
  Context ctx;
  ctx.file = sourceName;
  const json root = parseStrict(jsonText, ctx);
  if (!root.is_object()) failAt(ctx, "", "got " + describeValue(root) + " at the top level (expected an object)");

  Scene scene;
  Fields top(root, "", ctx);
  // dim first: every vector below has `dim` components.
  scene.dim = top.optInteger("dim", 2, 3).value_or(scene.dim);
  ctx.dim = scene.dim;

  scene.name = defaultName(sourceName);
  if (auto name = top.optString("name")) {
    if (!isSafeName(*name))
      top.fail("name",
               "\"" + shown(*name) +
                   "\" is not usable as a directory name (expected 1-100 of A-Z a-z 0-9 _ - ., not starting with .)");
    scene.name = *name;
  }
  top.optString("description");  // free text for people; ignored

  // `body` (+ top-level `material`) is the one-body shorthand of `bodies`.
  if (top.take("bodies")) {
    top.forbid("body", "give \"body\" (one body) or \"bodies\" (a list), not both");
    top.forbid("material", "with \"bodies\", each body's \"material\" goes inside its entry");
    readBodies(top, scene);
  } else {
    Fields body = top.requireObject("body");
    readBody(body, scene.dim, scene.bodies[0]);
    body.finish();
    if (auto m = top.optObject("material")) readMaterial(*m, scene.bodies[0].material);
  }
  if (auto s = top.optObject("simulation")) readSimulation(*s, scene);
  if (auto d = top.optObject("domain")) readDomain(*d, scene);
  if (auto c = top.optObject("body_contact")) readBodyContact(*c, scene);
  for (Fields& mf : top.objectArray("manipulators", false))
    scene.manipulators.push_back(readManipulator(mf, scene.dim));
  for (Fields& pf : top.objectArray("pins", false)) scene.pins.push_back(readPin(pf, scene));
  top.finish();

  // A union's labels need materials (a volume file's labels are checked when it is read).
  for (const BodySettings& body : scene.bodies) {
    if (body.source) continue;
    // The body's key path ("body" or "bodies[k]"), from the key that set its grid.
    const std::string key = body.sizeKey.substr(0, body.sizeKey.rfind('.'));
    const auto& prims = body.shape.primitives;
    for (size_t i = 0; i < prims.size(); ++i) {
      try {
        (void)regionMaterial(body.material, prims[i].label);
      } catch (const InputError&) {
        failAt(ctx, key + ".primitives[" + std::to_string(i) + "].label",
               std::to_string(prims[i].label) + " has no material (expected an entry with \"label\": " +
                   std::to_string(prims[i].label) + " in material.regions)");
      }
    }
  }
  return scene;
}

Scene loadScene(const std::string& path) {
  // C stdio rather than iostreams: errno then names the reason ("No such file or directory",
  // "Is a directory", "Permission denied").
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw InputError(path + ": cannot read: " + std::strerror(errno));
  std::string text;
  char buf[65536];
  size_t n = 0;
  errno = 0;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) {
    text.append(buf, n);
    if (text.size() > kMaxSceneBytes) {
      std::fclose(f);
      throw InputError(path + ": cannot read: larger than 16 MiB (not a scene file?)");
    }
  }
  const bool failed = std::ferror(f);
  const int err = errno;
  std::fclose(f);
  if (failed) throw InputError(path + ": cannot read: " + std::strerror(err ? err : EIO));
  return parseScene(text, path);
}

}  // namespace gradel
