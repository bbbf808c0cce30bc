#include "team_chunks.h"

#include <algorithm>
#include <stdexcept>

namespace gradel {

std::vector<ElementChunk> ownerElementChunks(const RestModel& m, const std::vector<size_t>& vertexBound, size_t batch,
                                             size_t maxChunk, std::vector<size_t>& split) {
  if (vertexBound.size() < 2 || batch == 0 || maxChunk < batch || maxChunk % batch != 0)
    throw std::logic_error("ownerElementChunks: no members, or a chunk that is not whole batches");
  const size_t E = m.numElements(), members = vertexBound.size() - 1;
  auto owner = [&](size_t e) {  // the last member whose share starts at or before the first vertex
    const size_t v = m.elemVerts[m.elemStart[e]];
    size_t t = 0;
    while (t + 1 < members && v >= vertexBound[t + 1]) ++t;
    return t;
  };
  std::vector<std::vector<ElementChunk>> own(members);
  for (size_t b = 0; b < E;) {  // b: the first element of a run (a multiple of batch)
    const size_t t = owner(b);
    size_t end = std::min(E, b + batch);
    while (end < E && end - b < maxChunk && owner(end) == t) end = std::min(E, end + batch);
    own[t].push_back({uint32_t(b), uint32_t(end)});
    b = end;
  }
  std::vector<ElementChunk> chunks;
  split.assign(1, 0);
  for (const std::vector<ElementChunk>& list : own) {
    chunks.insert(chunks.end(), list.begin(), list.end());
    split.push_back(chunks.size());
  }
  return chunks;
}

}  // namespace gradel
