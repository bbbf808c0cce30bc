// The body-contact stage's constants: units and the measurements behind them (docs/speed.md).
#pragma once

#include <cstdint>

#include "gradel/types.h"

namespace gradel {
namespace {

constexpr Real kSkin = 1e-6;  // [thickness] a corrected vertex ends this far outside
// [thickness] a step in which two surfaces together moved at most this far (before the
// corrections) is small (detectVertex).
constexpr Real kSmallStep = 0.25;

// The tracks (header, "across steps"): a surface may move this far (times the larger voxel size
// of the bodies) from where it was at the rebuild, and a step's search radius may grow this much
// (same unit) over the radius at the rebuild, before every track is rebuilt. Measured on two 64^3
// spheres in contact (gradel-bench --sets contact): see docs/speed.md.
constexpr Real kLoose = 0.5, kRadiusSlack = 0.25;
// A track's grid: cells of twice this (same unit); the queries start from their last answer, so
// their boxes are small and fine cells hold few faces.
constexpr Real kTrackCell = 0.5;
// measure(): surface vertices per chunk (a unit of the team's work).
constexpr uint32_t kMeasureChunk = 4096;
// detectPairs(): faces per chunk of the boxes now (a unit of the team's work).
constexpr uint32_t kBoxChunk = 512;
// [thickness] a vertex behind a contact's face plane at a step's start but outside that body
// (a misread fold) is pushed out at most this much past its start depth in an explicit step
// (BodyContacts::addContacts; measured: 0.05 left a stiff-into-soft ball pair at 1.029x, 0.01 at 1.021x).
constexpr Real kDepenetration = 0.01;
// shiftCells(): a vertex a round's local bound skips keeps at most this clearance (same unit).
constexpr Real kShiftMargin = 0.125;

}  // namespace
}  // namespace gradel
