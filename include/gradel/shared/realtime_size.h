// Which body sizes the viewer can run in real time, estimated before building one: from the
// current body's measured capacity (simulated seconds per wall second the machine manages at its
// size, StepPacer::capacity) and how a body's cost grows with its size n (voxels along its largest
// side, at a fixed physical extent): vertices ~ n^p (p = 3 for the uniform and voxel layouts; the
// gradational layout's vertices are mostly near the surface: p = 2.2, measured on the sphere from
// n = 12 to 96) and the stable dt ~ 1/n (the voxel size). So capacity(n) = capacity(n0) (n0/n)^(p+1).
// Valid for the same integrator, material and scene; an estimate, not a promise.
#pragma once

#include "gradel/layout.h"

namespace gradel {

/// The exponent p of vertices ~ n^p for a layout.
double vertexExponent(LayoutKind layout);

struct SizeEstimate {
  double realTimeFactor = 0;  ///< estimated capacity at the asked size (simulated s per wall s)
  int largestRealTime = 0;    ///< the largest size in [minSize, maxSize] estimated at >= 1 (minSize when none)
};

/// The estimate for size `toSize` from a body of size `fromSize` measured at `fromCapacity`
/// (> 0), with exponent p; largestRealTime is searched in [minSize, maxSize].
SizeEstimate estimateSize(int fromSize, double fromCapacity, int toSize, double p, int minSize, int maxSize);

}  // namespace gradel
