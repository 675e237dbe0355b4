#include "datasets/atomic_file.hpp"

#include <stdexcept>
#include <system_error>
#include <unistd.h>

namespace ccd::datasets {

AtomicFile::AtomicFile(std::filesystem::path path, std::ios::openmode mode) : path_(std::move(path)) {
  // The pid keeps two processes writing the same target from sharing a temporary.
  temporary_ = path_;
  temporary_ += ".tmp." + std::to_string(::getpid());
  if (path_.has_parent_path()) std::filesystem::create_directories(path_.parent_path());
  stream_.open(temporary_, mode | std::ios::out | std::ios::trunc);
  if (!stream_) throw std::runtime_error("cannot write " + temporary_.string());
}

AtomicFile::~AtomicFile() {
  if (committed_) return;
  stream_.close();
  std::error_code ignored;
  std::filesystem::remove(temporary_, ignored);
}

void AtomicFile::commit() {
  stream_.flush();
  const bool written = static_cast<bool>(stream_);
  stream_.close();
  if (!written || stream_.fail()) throw std::runtime_error("writing " + temporary_.string() + " failed");
  std::filesystem::rename(temporary_, path_);
  committed_ = true;
}

}  // namespace ccd::datasets
