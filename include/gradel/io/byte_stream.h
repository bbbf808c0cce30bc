// Byte streams that every file reader pulls from: a file (read in place, never loaded whole), a
// memory buffer (fuzz targets, tests) and a gzip / zlib decoder over either. Readers stream
// large volumes slice by slice, so a 512^3 volume never sits in memory twice.
//
// Every failure is an InputError whose message starts with the stream's name (the file path):
// "samples/ct.nrrd: truncated: expected 8388608 bytes of voxel data, got 120".
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "gradel/types.h"

namespace gradel::io {

class ByteStream {
 public:
  explicit ByteStream(std::string name) : name_(std::move(name)) {}
  virtual ~ByteStream() = default;
  ByteStream(const ByteStream&) = delete;
  ByteStream& operator=(const ByteStream&) = delete;

  /// Reads up to n bytes; fewer only at the end of the data. Throws InputError on a read error.
  virtual size_t read(void* dst, size_t n) = 0;
  /// Bytes left when known (files, memory); nullopt for decoders. Used to reject counts that the
  /// data cannot hold before anything is allocated.
  virtual std::optional<uint64_t> remaining() const = 0;

  const std::string& name() const { return name_; }

  /// Exactly n bytes, else InputError "NAME: truncated: expected N bytes of WHAT, got M".
  void readExact(void* dst, size_t n, const std::string& what);
  /// Skips n bytes (same error when the data ends first).
  void skip(uint64_t n, const std::string& what);
  /// One line without its "\n" (a trailing "\r" is dropped too). nullopt at the end of the data.
  /// A line longer than maxBytes is an InputError (a binary file read as text).
  std::optional<std::string> readLine(size_t maxBytes, const std::string& what);
  /// Bytes consumed so far.
  uint64_t offset() const { return offset_; }

  [[noreturn]] void fail(const std::string& what) const { throw InputError(name_ + ": " + what); }

 protected:
  uint64_t offset_ = 0;  ///< Advanced by the implementations' read().

 private:
  std::string name_;
};

/// A file read through C stdio (errno names the reason a file cannot be opened).
std::unique_ptr<ByteStream> openFileStream(const std::string& path);
/// A view of `size` bytes at `data` (not copied: the buffer must outlive the stream).
std::unique_ptr<ByteStream> memoryStream(const void* data, size_t size, std::string name);
/// Inflates a gzip or zlib stream (header detected) read from `inner`. Data after the end of the
/// compressed stream is an error; so is a stream that ends early.
std::unique_ptr<ByteStream> gzipStream(std::unique_ptr<ByteStream> inner);
/// Same, over a stream owned elsewhere (it must outlive the decoder).
std::unique_ptr<ByteStream> gzipStream(ByteStream& inner);

}  // namespace gradel::io
