#include "datasets/atomic_file.hpp"

#include "core/error.hpp"

#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <sys/file.h>

#include <unistd.h>
#include <stdexcept>
#include <system_error>

namespace ccd::datasets {

AtomicFile::AtomicFile(std::filesystem::path path, std::ios::openmode mode) : path_(std::move(path)) {
  // Host and pid keep two processes writing the same target from sharing a temporary, also on a folder shared
  // by the nodes of a cluster (MPI ranks writing one truth cache).
  char host[256] = {};
  ::gethostname(host, sizeof host - 1);
  temporary_ = path_;
  temporary_ += ".tmp." + std::string(host) + "." + std::to_string(::getpid());
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

FileLock::FileLock(const std::filesystem::path& path) : fd_(::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644)) {
  if (fd_ < 0) throw InputError(path, {}, "cannot open the lock file");
  if (::flock(fd_, LOCK_EX) != 0) {
    ::close(fd_);
    throw InputError(path, {}, "cannot take the lock");
  }
}

FileLock::~FileLock() {
  ::flock(fd_, LOCK_UN);
  ::close(fd_);
}

SharedFileLock::SharedFileLock(const std::filesystem::path& path) : fd_(::open(path.c_str(), O_RDONLY | O_CLOEXEC)) {
  if (fd_ >= 0 && ::flock(fd_, LOCK_SH) != 0) {
    ::close(fd_);
    fd_ = -1;
  }
}

SharedFileLock::~SharedFileLock() {
  if (fd_ < 0) return;
  ::flock(fd_, LOCK_UN);
  ::close(fd_);
}

void require_writable_directory(const std::filesystem::path& directory) {
  std::error_code error;
  if (std::filesystem::exists(directory, error) && !std::filesystem::is_directory(directory, error)) {
    throw InputError(directory, {}, "cannot write output here: it is a file, a folder is expected");
  }
  std::filesystem::create_directories(directory, error);
  if (error) throw InputError(directory, {}, "cannot create the output folder: " + error.message());
  std::filesystem::path probe = directory / (".ccdbench-probe." + std::to_string(::getpid()));
  {
    std::ofstream out(probe);
    if (!out || !(out << "probe") || !out.flush()) {
      throw InputError(directory, {}, "cannot write output here (permission denied or read-only?)");
    }
  }
  std::filesystem::remove(probe, error);
}

void require_creatable_directory(const std::filesystem::path& directory) {
  std::error_code error;
  std::filesystem::path existing = std::filesystem::absolute(directory);
  while (!std::filesystem::exists(existing, error) && existing.has_parent_path() && existing != existing.parent_path())
    existing = existing.parent_path();
  if (!std::filesystem::is_directory(existing, error)) throw InputError(existing, {}, "cannot write output here: it is a file, a folder is expected");
  if (::access(existing.c_str(), W_OK) != 0) throw InputError(existing, {}, "cannot write output here (permission denied or read-only?)");
}

void require_writable_file(const std::filesystem::path& file) {
  std::error_code error;
  if (std::filesystem::is_directory(file, error)) {
    throw InputError(file, {}, "cannot write output here: it is a folder, a file is expected");
  }
  const std::filesystem::path folder = file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
  require_writable_directory(folder);
}

void write_json_file(const std::filesystem::path& path, const nlohmann::json& document) {
  AtomicFile file(path, std::ios::out);
  file.stream() << document.dump(2) << '\n';
  file.commit();
}

}  // namespace ccd::datasets
