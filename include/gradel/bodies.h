// Several bodies in one world: the World steps one RestModel whose arrays are the bodies' models
// one after another (vertex and element ids offset), so every stage, thread split, integrator,
// pin, contact and metric works on several bodies unchanged. RestModel::bodies says which
// vertices and elements belong to which body. Nothing couples the bodies but what acts on
// vertices (contacts); two bodies that never touch move exactly as each would alone (the same dt).
#pragma once

#include <memory>
#include <vector>

#include "gradel/model.h"

namespace gradel {

/// Concatenates the models (in the given order): per-vertex and per-element arrays appended,
/// element vertex ids offset by the vertices before, `bodies` the bodies of every model in turn
/// (offset likewise), the materials tables appended (elementMaterial offset). Totals are recomputed: totalMass summed
/// over every vertex in order, the smallest periods the minimum over the models. The top-level voxelSize, origin and
/// material are the first body's. One model gives a copy of it. Throws std::invalid_argument for no models, a null
/// model, models of different `dim`, or more than 2^32 - 1 vertices, elements or pairs.
RestModel combineRestModels(const std::vector<std::shared_ptr<const RestModel>>& models);

}  // namespace gradel
