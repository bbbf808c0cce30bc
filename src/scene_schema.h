// The scene file's schema (docs/scenes.md): one reader per section, each taking its keys from a
// `Fields` (scene_json.h) into the settings it fills. Bodies and their materials in
// scene_schema_bodies.cpp; simulation, walls, body contact, manipulators and pins in
// scene_schema_world.cpp; the top level (which section when) in scene_io.cpp.
#pragma once

#include <memory>

#include "gradel/scene.h"
#include "scene_json.h"

namespace gradel::scene_json {

// "body.source": a volume or mesh file (io/volume_file.h), also a pin mask's "file". Relative
// paths are relative to the scene file's folder; the file must exist when the scene is read, and
// is read by buildScene.
std::shared_ptr<const VolumeSource> readSource(Fields f, int dim, Real voxelSize);
// A body's keys (`body`, or an entry of `bodies`, whose material and name readBodies reads).
void readBody(Fields& f, int dim, BodySettings& body);
// `material` (the top level's with `body`, or a `bodies` entry's): material.h's settings.
void readMaterial(Fields f, MaterialSettings& m);
// `bodies`: several bodies, each with its own material and an output name (default "body<i>").
void readBodies(Fields& top, Scene& scene);

// `simulation`: integrator, dt, damping, gravity, output times, threads (integrator.h).
void readSimulation(Fields f, Scene& scene);
// `domain`: the walls (contacts.h).
void readDomain(Fields f, Scene& scene);
// `body_contact` (body_contacts.h).
void readBodyContact(Fields f, Scene& scene);
// A `pins` entry (pins.h); its `body` indexes scene.bodies, read before.
PinSettings readPin(Fields& f, const Scene& scene);
// A `manipulators` entry (contacts.h).
ManipulatorSettings readManipulator(Fields& f, int dim);

}  // namespace gradel::scene_json
