#pragma once
/// @file
/// Writing a file so that readers never see half of it: write a temporary beside it, rename when complete.

#include <filesystem>
#include <fstream>

namespace ccd::datasets {

/// An output stream to `path` that becomes visible only on commit(). Destroyed without commit() (an exception,
/// an interrupted run), it removes its temporary file and leaves any previous `path` untouched.
class AtomicFile {
 public:
  explicit AtomicFile(std::filesystem::path path, std::ios::openmode mode = std::ios::binary);
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  ~AtomicFile();

  std::ofstream& stream() { return stream_; }
  /// Flushes, checks that every write succeeded, and renames into place. @throws std::runtime_error on failure.
  void commit();

 private:
  std::filesystem::path path_;
  std::filesystem::path temporary_;
  std::ofstream stream_;
  bool committed_ = false;
};

}  // namespace ccd::datasets
