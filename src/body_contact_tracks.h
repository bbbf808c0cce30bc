// The body-contact stage's broad-phase types (BodyContacts::Grid and BodyContacts::Track,
// declared in body_contacts.h): private to the stage's files. The grid's queries are in
// body_contact_grid.h, its build in body_contact_grid.cpp, the tracks' upkeep in
// body_contact_tracks.cpp.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "gradel/body_contacts.h"

namespace gradel {

// Some faces of one body in a dense table of cubic cells over the box they fill (buildGrid),
// cell (i, j, k) at index (k dims[1] + j) dims[0] + i. Each listed face has a box that holds
// it: its box at the build, grown by how far its corners may move before the grid is rebuilt
// (a pair's track), or by nothing (a grid for one query pass).
struct BodyContacts::Grid {
  Box box;  ///< The listed faces' boxes within the region: a query box missing it finds none.
  Vec3 origin{0, 0, 0};
  Real cell = 1, inv = 1;  ///< [m] edge of a cell, its inverse.
  std::array<int64_t, 3> dims{0, 0, 0};
  size_t count = 0;             ///< Cells (0: no face listed).
  std::vector<uint32_t> tri;    ///< The listed faces' triangle ids, in listing order.
  std::vector<Box> triBox;      ///< Their boxes (see above).
  std::vector<Box> now;         ///< A track's: their boxes at the positions of the round (the queries' pruning).
  std::vector<uint32_t> start;  ///< Per cell: its faces at items[start[c] .. start[c + 1]).
  std::vector<uint32_t> items;  ///< Indices into tri.
  std::vector<Box> cellBox;     ///< Per cell: its faces' boxes clipped to it (see buildGrid).
  std::array<std::vector<Real>, 3> cellLo,
      cellHi;                  ///< Per axis and cell: its edges, grown by a rounding slack (outer cells: +-inf).
  std::vector<uint32_t> fill;  ///< Scratch of the build.
  std::vector<std::array<int32_t, 6>> range;  ///< Scratch of the build: each face's cell range.
  int64_t cellOf(Real v, int a) const;        ///< Clamped into the table.
  bool rangeOf(const Vec3& lo, const Vec3& hi, std::array<int64_t, 6>& c) const;
};
// A pair of bodies across steps (ordered: a's vertices against b's faces), valid until either
// body's surface moved farther than loose_ from where it was at the rebuild (sinceRebuild_) or a
// step's search radius exceeds rCap_ (then every track is rebuilt).
struct BodyContacts::Track {
  Grid grid;  ///< b's faces that can come within rCap_ of a vertex of a before then.
  std::vector<uint32_t>
      vertices;  ///< a's vertices that can come within rCap_ of one of them (indices into `vertices`).
  std::vector<Real>
      clearance;  ///< Per candidate: its distance to b's surface at its last check was at least this (< 0: look).
  std::vector<Vec3> checkedAt;         ///< Per candidate: where it was then.
  std::vector<Real> faceDrift;         ///< Per candidate: how far b's surface had moved from the rebuild then.
  std::vector<Real> faceCorrected;     ///< Per candidate: how far the stage's corrections had moved b's surface then.
  std::vector<uint32_t> checkedStage;  ///< Per candidate: the stage (resolve call) of its last check.
  std::vector<uint8_t> checkedRound;   ///< Per candidate: the round of that stage.
  // Per candidate, what a round's local bound found (preparePair, shiftCells): outside, at least
  // roundClearance from b's surface at roundAt, in round roundOf of stage roundStage.
  std::vector<Real> roundClearance;
  std::vector<Vec3> roundAt;
  std::vector<uint32_t> roundStage;
  std::vector<uint8_t> roundOf;
  std::vector<uint32_t> nearest;  ///< Per vertex of a (index into `vertices`): its nearest face of b and its nearest
                                  ///< facing face (detectVertex) when last found (kNone: none).
};

}  // namespace gradel
