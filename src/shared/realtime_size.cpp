#include "gradel/shared/realtime_size.h"

#include <cmath>
#include <stdexcept>

namespace gradel {

double vertexExponent(LayoutKind layout) { return layout == LayoutKind::Gradational ? 2.2 : 3.0; }

SizeEstimate estimateSize(int fromSize, double fromCapacity, int toSize, double p, int minSize, int maxSize) {
  if (fromSize <= 0 || toSize <= 0 || !(fromCapacity > 0) || !(p > 0) || minSize <= 0 || maxSize < minSize)
    throw std::invalid_argument("estimateSize: sizes and capacity must be > 0");
  auto at = [&](int n) { return fromCapacity * std::pow(double(fromSize) / double(n), p + 1); };
  SizeEstimate e;
  e.realTimeFactor = at(toSize);
  e.largestRealTime = minSize;
  for (int n = maxSize; n >= minSize; --n)
    if (at(n) >= 1) {
      e.largestRealTime = n;
      break;
    }
  return e;
}

}  // namespace gradel
