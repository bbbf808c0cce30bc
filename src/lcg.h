// A fixed pseudo-random sequence (a 64-bit LCG, Knuth's MMIX constants) for the starts of the
// operator rule's Lanczos estimates (stability.cpp, stability_warm.cpp): the same start on every
// run, platform and thread count, so dt = auto is reproducible bit for bit.
#pragma once

#include <cstdint>

namespace gradel {

struct Lcg {
  uint64_t state;
  /// Uniform in [-0.5, 0.5), 53 bits.
  double centred() {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return double(state >> 11) * 0x1.0p-53 - 0.5;
  }
};

}  // namespace gradel
