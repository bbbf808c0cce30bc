#include "gradel/io/byte_stream.h"

#ifndef GRADEL_NO_ZLIB  // the WebAssembly build (web/) has no zlib: gzip input is an InputError there
#include <zlib.h>
#endif

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <cstring>
#include <vector>

namespace gradel::io {

void ByteStream::readExact(void* dst, size_t n, const std::string& what) {
  const size_t got = read(dst, n);
  if (got != n) fail("truncated: expected " + std::to_string(n) + " bytes of " + what + ", got " + std::to_string(got));
}

void ByteStream::skip(uint64_t n, const std::string& what) {
  if (const auto left = remaining(); left && *left < n)
    fail("truncated: " + what + " needs " + std::to_string(n) + " bytes, only " + std::to_string(*left) + " left");
  char buf[65536];
  while (n > 0) {
    const size_t want = size_t(std::min<uint64_t>(n, sizeof buf));
    const size_t got = read(buf, want);
    if (got != want) fail("truncated while skipping " + what);
    n -= got;
  }
}

std::optional<std::string> ByteStream::readLine(size_t maxBytes, const std::string& what) {
  std::string line;
  char c = 0;
  bool any = false;
  while (read(&c, 1) == 1) {
    any = true;
    if (c == '\n') break;
    if (line.size() >= maxBytes)
      fail(what + ": line longer than " + std::to_string(maxBytes) + " bytes (not a text header?)");
    line.push_back(c);
  }
  if (!any) return std::nullopt;
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return line;
}

namespace {

class FileStream final : public ByteStream {
 public:
  FileStream(std::string path, std::FILE* f, uint64_t size) : ByteStream(std::move(path)), f_(f), size_(size) {}
  ~FileStream() override { std::fclose(f_); }
  size_t read(void* dst, size_t n) override {
    const size_t got = std::fread(dst, 1, n, f_);
    if (got < n && std::ferror(f_)) fail(std::string("read error: ") + std::strerror(errno ? errno : EIO));
    offset_ += got;
    return got;
  }
  std::optional<uint64_t> remaining() const override { return offset_ <= size_ ? size_ - offset_ : 0; }

 private:
  std::FILE* f_;
  uint64_t size_;
};

class MemoryStream final : public ByteStream {
 public:
  MemoryStream(const void* data, size_t size, std::string name)
      : ByteStream(std::move(name)), data_(static_cast<const uint8_t*>(data)), size_(size) {}
  size_t read(void* dst, size_t n) override {
    const size_t got = std::min<size_t>(n, size_ - size_t(offset_));
    if (got > 0) std::memcpy(dst, data_ + offset_, got);
    offset_ += got;
    return got;
  }
  std::optional<uint64_t> remaining() const override { return size_ - offset_; }

 private:
  const uint8_t* data_;
  size_t size_;
};

#ifndef GRADEL_NO_ZLIB
class GzipStream final : public ByteStream {
 public:
  GzipStream(std::unique_ptr<ByteStream> owned, ByteStream& inner)
      : ByteStream(inner.name()), owned_(std::move(owned)), inner_(&inner), in_(1u << 16) {
    std::memset(&z_, 0, sizeof z_);
    // 15 + 32: the largest window, and detect a gzip or zlib header automatically.
    if (inflateInit2(&z_, 15 + 32) != Z_OK) fail("gzip: cannot initialise zlib");
  }
  ~GzipStream() override { inflateEnd(&z_); }

  size_t read(void* dst, size_t n) override {
    size_t done = 0;
    while (done < n && !ended_) {
      if (z_.avail_in == 0 && !innerEnded_) {
        const size_t got = inner_->read(in_.data(), in_.size());
        innerEnded_ = got == 0;
        z_.next_in = in_.data();
        z_.avail_in = uInt(got);
      }
      // zlib counts in uInt; ask for at most 1 GiB per call.
      const size_t chunk = std::min<size_t>(n - done, size_t(1) << 30);
      z_.next_out = static_cast<Bytef*>(dst) + done;
      z_.avail_out = uInt(chunk);
      const int rc = inflate(&z_, Z_NO_FLUSH);
      const size_t produced = chunk - z_.avail_out;
      done += produced;
      if (rc == Z_STREAM_END) {
        ended_ = true;
        checkNothingAfterEnd();
      } else if (rc == Z_BUF_ERROR) {
        // No progress possible: either more input is needed (read it on the next turn) or the
        // input is over while zlib still expects data. zlib may hold output back when the
        // caller's buffer was full, so an exhausted input alone is not yet an error.
        if (produced == 0 && innerEnded_) fail("gzip: compressed data ends early (truncated file?)");
        if (produced == 0 && z_.avail_in != 0) fail("gzip: corrupt compressed data (no progress)");
      } else if (rc != Z_OK) {
        fail(std::string("gzip: corrupt compressed data (") + (z_.msg ? z_.msg : "zlib error " + std::to_string(rc)) +
             ")");
      }
    }
    offset_ += done;
    return done;
  }
  std::optional<uint64_t> remaining() const override { return std::nullopt; }

 private:
  // Trailing bytes after the compressed stream would be silently ignored data: a concatenated
  // gzip member or a broken writer. Neither is what the header described.
  void checkNothingAfterEnd() {
    if (z_.avail_in > 0) fail("gzip: " + std::to_string(z_.avail_in) + " unexpected bytes after the compressed data");
    char c;
    if (inner_->read(&c, 1) != 0) fail("gzip: unexpected bytes after the compressed data");
  }

  std::unique_ptr<ByteStream> owned_;
  ByteStream* inner_;
  std::vector<Bytef> in_;
  z_stream z_;
  bool ended_ = false;       // the compressed stream is complete
  bool innerEnded_ = false;  // the compressed input is exhausted
};
#endif

}  // namespace

std::unique_ptr<ByteStream> openFileStream(const std::string& path) {
  errno = 0;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) {
    const int err = errno ? errno : ENOENT;
    // A relative path is shown resolved: where the file was looked for.
    std::string where;
    std::error_code ec;
    if (std::filesystem::path(path).is_relative()) {
      const std::filesystem::path abs = std::filesystem::absolute(path, ec);
      if (!ec) where = " (looked for " + abs.lexically_normal().string() + ")";
    }
    throw InputError(path + ": cannot read: " + std::strerror(err) + where);
  }
  // The size bounds every count read from a header; a directory or pipe has none we can trust.
  if (std::fseek(f, 0, SEEK_END) != 0) {
    std::fclose(f);
    throw InputError(path + ": cannot read: not a regular file");
  }
  const long size = std::ftell(f);
  if (size < 0 || std::fseek(f, 0, SEEK_SET) != 0) {
    std::fclose(f);
    throw InputError(path + ": cannot read: not a regular file");
  }
  return std::make_unique<FileStream>(path, f, uint64_t(size));
}

std::unique_ptr<ByteStream> memoryStream(const void* data, size_t size, std::string name) {
  return std::make_unique<MemoryStream>(data, size, std::move(name));
}

#ifndef GRADEL_NO_ZLIB
std::unique_ptr<ByteStream> gzipStream(std::unique_ptr<ByteStream> inner) {
  ByteStream& ref = *inner;
  return std::make_unique<GzipStream>(std::move(inner), ref);
}

std::unique_ptr<ByteStream> gzipStream(ByteStream& inner) { return std::make_unique<GzipStream>(nullptr, inner); }
#else
std::unique_ptr<ByteStream> gzipStream(std::unique_ptr<ByteStream> inner) { return gzipStream(*inner); }
std::unique_ptr<ByteStream> gzipStream(ByteStream& inner) {
  throw InputError(inner.name() + ": gzip-compressed input is not supported in this build (no zlib)");
}
#endif

}  // namespace gradel::io
