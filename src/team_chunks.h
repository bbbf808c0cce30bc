// The explicit step's element chunks for a team (private to the engine): which member computes
// which elements' frames.
#pragma once
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "gradel/model.h"

namespace gradel {

/// An element chunk: elements [first, second).
using ElementChunk = std::pair<uint32_t, uint32_t>;

/// The element chunks of a team, grouped by owner. Member t's vertex share is
/// [vertexBound[t], vertexBound[t + 1]) (members + 1 ascending bounds, the last the vertex count);
/// a batch of `batch` elements (the rotation fit's lanes: chunks start at multiples of it) belongs
/// to the member whose share holds its first element's first vertex, so that member's element pass
/// writes the frames its vertex pass reads and reads the positions its vertex pass wrote. Runs of
/// consecutive batches with one owner are cut into chunks of at most maxChunk elements (a multiple
/// of batch), listed member after member in element order; `split` receives where each member's
/// chunks start (members + 1 entries, as ChunkQueue::reset takes). Every element is in exactly
/// one chunk; which member computes an element never changes its frame.
std::vector<ElementChunk> ownerElementChunks(const RestModel& m, const std::vector<size_t>& vertexBound, size_t batch,
                                             size_t maxChunk, std::vector<size_t>& split);

}  // namespace gradel
