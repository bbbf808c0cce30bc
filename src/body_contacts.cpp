// The body-contact stage (body_contacts.h): its construction and resolve(), the loop of rounds
// over the named phases (broad: body_contact_bounds/tracks.cpp, narrow:
// body_contact_narrow_phase.cpp, response: body_contact_response.cpp, warm start, last resort).
#include "gradel/body_contacts.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include "body_contact_tracks.h"
#include "body_contact_tuning.h"

namespace gradel {

void validate(const BodyContactSettings& s) {
  if (!(s.restitution >= 0 && s.restitution <= 1))
    throw InputError("", "body_contact.restitution",
                     "expected a number in [0, 1], got " + std::to_string(s.restitution));
  if (!(s.friction >= 0 && std::isfinite(s.friction)))
    throw InputError("", "body_contact.friction", "expected a finite number >= 0, got " + std::to_string(s.friction));
}

// Out of line: Grid and Track are complete only here (body_contact_tracks.h).
BodyContacts::BodyContacts() : grid_(std::make_unique<Grid>()) {}
BodyContacts::BodyContacts(BodyContacts&&) noexcept = default;
BodyContacts& BodyContacts::operator=(BodyContacts&&) noexcept = default;
BodyContacts::~BodyContacts() = default;

BodyContacts::BodyContacts(std::vector<ContactBody> bodies, const BodyContactSettings& settings)
    : bodies_(std::move(bodies)), settings_(settings), grid_(std::make_unique<Grid>()) {
  validate(settings_);
  Real thinnest = std::numeric_limits<Real>::infinity(), thickest = 0;
  for (const ContactBody& b : bodies_)
    thinnest = std::min(thinnest, b.thickness), thickest = std::max(thickest, b.thickness);
  skin_ = kSkin * thinnest;
  loose_ = kLoose * thickest;
  const size_t B = bodies_.size();
  bounds_.resize(B);
  active_.assign(B * B, 0);
  tracks_.resize(B * B);
  moved_.assign(B, 0), movedStart_.assign(B, 0), sinceRebuild_.assign(B, 0), sinceRebuildStart_.assign(B, 0);
  sinceAxis_.assign(B, 0), sinceAxisStart_.assign(B, 0);
  uint32_t vertexEnd = 0;
  blockStart_.assign(1, 0), chunkStart_.assign(1, 0);
  for (size_t b = 0; b < B; ++b) {
    vertexEnd = std::max(vertexEnd, bodies_[b].vertexEnd);
    blockStart_.push_back(blockStart_.back() +
                          uint32_t((bodies_[b].vertices.size() + kBoundsBlock - 1) / kBoundsBlock));
    chunkStart_.push_back(
        chunkStart_.back() +
        uint32_t((bodies_[b].vertexEnd - bodies_[b].vertexBegin + kMeasureChunk - 1) / kMeasureChunk));
  }
  chunkMotion_.resize(chunkStart_.back());  // (every chunk writes its own)
  blockBox_.resize(blockStart_.back());
  isTouched_.assign(vertexEnd, 0);
  startAskedStage_.assign(vertexEnd, 0), startAskedBody_.assign(vertexEnd, 0), startInside_.assign(vertexEnd, 0);
  roundShift_.assign(vertexEnd, 0);
  roundShiftMax_.assign(B, 0);
  ref_.assign(vertexEnd, RefPoint{0, 0, 0, 0});
  refRounding_.assign(B, Vec3::Zero());
  bodyOf_.assign(vertexEnd, uint32_t(B));
  for (size_t b = 0; b < B; ++b)
    for (uint32_t u : bodies_[b].vertices) bodyOf_[u] = uint32_t(b);
}

BodyContactStats BodyContacts::resolve(const BodyContactState& s) {
  const auto t0 = std::chrono::steady_clock::now();
  BodyContactStats stats;
  contacts_.clear(), keep_.clear();
  if (empty()) return stats;
  for (uint32_t u : touched_) isTouched_[u] = 0, roundShift_[u] = 0;
  touched_.clear(), touchedStart_.clear(), touchedLast_.clear(), touchedStartV_.clear();
  ++stage_;
  startWindings_ = 0;
  bool fellBack = false;
  const size_t B = bodies_.size();
  int firstDetect = 0;  // the first detection round: 1 after a warm start (round 0 applied the last stage's contacts)
  for (int round = 0; round < kRounds + firstDetect; ++round) {
    // Broad phase: the bodies' motion bounds, the tracks rebuilt when they no longer hold.
    measureRound(s, round);
    if (B >= 2 && (!keepTracks_ || !tracksHold())) {
      rebuildTracks(s.positions), ++stats.rebuilds;  // (sinceRebuild_ 0: a later round adds the corrections to come)
    }
    round_.clear();
    round_index_ = round;
    if (round == 0 && applyWarm(s, stats)) {
      firstDetect = 1;  // the warm contacts are this round's: pushed out below, then every pair is detected
    } else {
      // Narrow phase over the pairs that can have a new contact, its findings no step can reach dropped.
      pickPairs(round > firstDetect);
      detectPairs(s, stats, pick_);
      dropUnreachable(s, stats);
      stats.rounds = round + 1 - firstDetect;
      if (round_.empty()) break;
      if (round + 1 == kRounds + firstDetect) {
        fellBack = true;
        returnToStart(s);
        break;
      }
    }
    projectPositions(s);  // response: the positions
  }
  if (fellBack) takeBack(s, stats);  // last resort
  keepWarm(s.positions);
  applyImpulses(s);  // response: the velocities
  stats.contacts = contacts_.size();
  stats.windingNumbers += startWindings_;
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return stats;
}

}  // namespace gradel
