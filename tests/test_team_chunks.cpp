// The explicit step's element chunks (team_chunks.h): every element once, whole batches, and the
// owner rule that keeps a member's element and vertex passes on the same data.
#include <gtest/gtest.h>

#include "team_chunks.h"
#include "test_support.h"

namespace gradel {
namespace {
using test::Body;
using test::makeBody;

// Pairs (element, vertex) whose element is computed by another member than the vertex's.
double crossShare(const RestModel& m, const std::vector<ElementChunk>& chunks, const std::vector<size_t>& split,
                  const std::vector<size_t>& bound) {
  std::vector<size_t> owner(m.numElements(), SIZE_MAX);
  for (size_t t = 0; t + 1 < split.size(); ++t)
    for (size_t c = split[t]; c < split[t + 1]; ++c)
      for (uint32_t e = chunks[c].first; e < chunks[c].second; ++e) owner[e] = t;
  size_t cross = 0;
  for (size_t e = 0; e < m.numElements(); ++e)
    for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1]; ++p) {
      size_t t = 0;
      while (t + 2 < bound.size() && m.elemVerts[p] >= bound[t + 1]) ++t;
      cross += t != owner[e];
    }
  return double(cross) / double(m.numPairs());
}

TEST(TeamChunks, EveryElementOnceInWholeBatchesOfItsOwner) {
  const Body b = makeBody("sphere", 40, 3, LayoutKind::Gradational);
  const RestModel& m = *b.model;
  const size_t V = m.numVertices(), E = m.numElements();
  for (size_t members : {1, 2, 3}) {
    std::vector<size_t> bound(members + 1);
    for (size_t t = 0; t <= members; ++t) bound[t] = V * t / members;
    std::vector<size_t> split;
    const std::vector<ElementChunk> chunks = ownerElementChunks(m, bound, 4, 64, split);
    ASSERT_EQ(split.size(), members + 1);
    EXPECT_EQ(split.front(), 0u);
    EXPECT_EQ(split.back(), chunks.size());
    std::vector<int> seen(E, 0);
    for (size_t t = 0; t < members; ++t)
      for (size_t c = split[t]; c < split[t + 1]; ++c) {
        const ElementChunk k = chunks[c];
        EXPECT_EQ(k.first % 4, 0u);
        EXPECT_LT(k.first, k.second);
        EXPECT_LE(k.second - k.first, 64u);
        EXPECT_TRUE(k.second % 4 == 0 || k.second == E);
        for (uint32_t e = k.first; e < k.second; ++e) ++seen[e];
        for (uint32_t e = k.first; e < k.second; e += 4) {  // the batch's first vertex is in t's share
          const uint32_t v = m.elemVerts[m.elemStart[e]];
          EXPECT_GE(v, bound[t]);
          EXPECT_LT(v, bound[t + 1]);
        }
      }
    for (size_t e = 0; e < E; ++e) ASSERT_EQ(seen[e], 1) << "element " << e << ", " << members << " members";
  }
}

TEST(TeamChunks, FewPairsCrossMembersWhereTheIndexSplitHadManyCross) {
  // Elements are numbered by level first (layout.h): halving them by index gives one member most
  // of the finest shell and the other the rest, so about a third of the pairs read or write data
  // of the other member's vertex share. By owner, only elements at the shares' border do.
  const Body b = makeBody("sphere", 40, 3, LayoutKind::Gradational);
  const RestModel& m = *b.model;
  const std::vector<size_t> bound = {0, m.numVertices() / 2, m.numVertices()};
  std::vector<size_t> split;
  const std::vector<ElementChunk> chunks = ownerElementChunks(m, bound, 4, 256, split);
  std::vector<ElementChunk> byIndex;
  const size_t half = m.numElements() / 8 * 4;
  byIndex.push_back({0, uint32_t(half)}), byIndex.push_back({uint32_t(half), uint32_t(m.numElements())});
  const double owned = crossShare(m, chunks, split, bound), indexed = crossShare(m, byIndex, {0, 1, 2}, bound);
  EXPECT_GT(indexed, 0.15);
  EXPECT_LT(owned, 0.1);
  EXPECT_LT(owned, 0.25 * indexed);
}

}  // namespace
}  // namespace gradel
