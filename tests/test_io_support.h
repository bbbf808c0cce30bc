// Builders of small in-memory files for the reader tests (tests/test_io_*.cpp).
#pragma once

#include <zlib.h>

#include <cstring>
#include <string>
#include <vector>

#include "gradel/io/byte_stream.h"
#include "gradel/types.h"

namespace gradel::test {

using Bytes = std::string;

inline void putLE(Bytes& b, uint64_t v, int n) {
  for (int i = 0; i < n; ++i) b.push_back(char((v >> (8 * i)) & 0xff));
}
inline void putBE(Bytes& b, uint64_t v, int n) {
  for (int i = n - 1; i >= 0; --i) b.push_back(char((v >> (8 * i)) & 0xff));
}
inline void putFloatLE(Bytes& b, float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  putLE(b, u, 4);
}

/// gzip-compresses `data` (zlib's gzip wrapper).
inline Bytes gzipped(const Bytes& data) {
  z_stream z{};
  deflateInit2(&z, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY);
  Bytes out(deflateBound(&z, uLong(data.size())) + 32, '\0');
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
  z.avail_in = uInt(data.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = uInt(out.size());
  deflate(&z, Z_FINISH);
  out.resize(z.total_out);
  deflateEnd(&z);
  return out;
}

/// A memory stream that owns a copy of its bytes (so a temporary can be passed).
class OwningStream final : public io::ByteStream {
 public:
  OwningStream(Bytes bytes, const std::string& name)
      : io::ByteStream(name), bytes_(std::move(bytes)), view_(io::memoryStream(bytes_.data(), bytes_.size(), name)) {}
  size_t read(void* dst, size_t n) override {
    const size_t k = view_->read(dst, n);
    offset_ += k;
    return k;
  }
  std::optional<uint64_t> remaining() const override { return view_->remaining(); }

 private:
  Bytes bytes_;
  std::unique_ptr<io::ByteStream> view_;
};

inline std::unique_ptr<io::ByteStream> stream(Bytes b, const std::string& name = "mem") {
  return std::make_unique<OwningStream>(std::move(b), name);
}

/// Runs `f` and returns the InputError message ("" when nothing was thrown).
template <class F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace gradel::test
