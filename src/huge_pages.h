// Asks the kernel to back a large array with 2 MiB pages (Linux transparent huge pages): the
// explicit step walks several arrays of a large body at once, and with 4 KiB pages nearly every
// access past the caches also misses the TLB (costly under virtualisation). Advice only: a
// no-op for small arrays, on other systems, or when the kernel says no.
#pragma once

#include <cstddef>
#include <vector>

namespace gradel {

/// Advises huge pages for the 2 MiB-aligned part of [data, data + bytes) and collapses the pages
/// already there into huge pages (Linux >= 6.1; older kernels only take the advice).
void adviseHugePages(const void* data, size_t bytes);

template <class T>
void adviseHugePages(const std::vector<T>& v) {
  adviseHugePages(v.data(), v.capacity() * sizeof(T));
}

}  // namespace gradel
