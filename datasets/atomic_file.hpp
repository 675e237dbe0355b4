#pragma once
/// @file
/// Writing a file so that readers never see half of it: write a temporary beside it, rename when complete.

#include <nlohmann/json_fwd.hpp>

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

/// An exclusive advisory lock (flock) on `path`, created if needed, held until destruction: serialises processes
/// that write the same files (two runs into one --out, two runs generating one scene).
class FileLock {
 public:
  /// Blocks until the lock is held. @throws InputError (path) when the lock file cannot be opened or locked.
  explicit FileLock(const std::filesystem::path& path);
  ~FileLock();
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  int fd_;
};

/// A shared advisory lock (flock) on `path` where that file exists and can be opened, held until destruction; nothing
/// otherwise (a folder the reader may not write, a run that never took FileLock there): what a reader takes of a file
/// that FileLock's holders append to in place (results.jsonl), so that it never reads half of an append.
class SharedFileLock {
 public:
  explicit SharedFileLock(const std::filesystem::path& path);
  ~SharedFileLock();
  SharedFileLock(const SharedFileLock&) = delete;
  SharedFileLock& operator=(const SharedFileLock&) = delete;

 private:
  int fd_;
};

/// Writes `document` (pretty-printed) to `path` atomically: the one writer of JSON result files (reports, --json,
/// scene.json of generated scenes).
void write_json_file(const std::filesystem::path& path, const nlohmann::json& document);

/// Checks before any work that `directory` can be written: creates it and writes and removes a probe file there.
/// @throws InputError (directory) naming why not.
void require_writable_directory(const std::filesystem::path& directory);

/// That `directory` can be made or written later, without making it now: it is a writable folder, or its nearest
/// existing ancestor is one. @throws InputError naming it otherwise.
void require_creatable_directory(const std::filesystem::path& directory);

/// Checks before any work that `file` can be written later (atomically, beside itself): it is not a folder and its
/// folder can be written. @throws InputError (file) naming why not.
void require_writable_file(const std::filesystem::path& file);

}  // namespace ccd::datasets
