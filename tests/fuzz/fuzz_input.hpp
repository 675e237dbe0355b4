#pragma once
/// @file
/// What the fuzz targets share: the readers take paths, so each input becomes an in-memory file (memfd, never on
/// disk), and only InputError is an acceptable way to refuse an input. Any other exception escapes the target and
/// aborts: libFuzzer reports it as a crash, and the corpus replay in ctest fails.

#include "core/error.hpp"

#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace ccd::fuzz {

/// An in-memory file holding the input, named /proc/self/fd/N while it lives.
class MemoryFile {
 public:
  MemoryFile(const std::uint8_t* data, std::size_t size) : fd_(::memfd_create("ccdbench-fuzz", MFD_CLOEXEC)) {
    if (fd_ < 0) throw std::runtime_error("memfd_create failed");
    for (std::size_t written = 0; written < size;) {
      const ssize_t n = ::write(fd_, data + written, size - written);
      if (n <= 0) throw std::runtime_error("writing the memfd failed");
      written += static_cast<std::size_t>(n);
    }
  }
  ~MemoryFile() { ::close(fd_); }
  MemoryFile(const MemoryFile&) = delete;
  MemoryFile& operator=(const MemoryFile&) = delete;
  std::filesystem::path path() const { return "/proc/self/fd/" + std::to_string(fd_); }

 private:
  int fd_;
};

/// Runs `read` on the input as a file; an InputError is a refusal, which is fine.
template <class Read>
int refuse_or_accept(const std::uint8_t* data, std::size_t size, Read read) {
  const MemoryFile file(data, size);
  try {
    read(file.path());
  } catch (const InputError&) {
  }
  return 0;
}

}  // namespace ccd::fuzz
