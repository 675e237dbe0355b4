#include "strategies/plugin/loaded_code.hpp"

#include "strategies/plugin/digest.hpp"

#include <elf.h>
#include <fcntl.h>
#include <link.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>

extern char** environ;

namespace ccd::plugin {
namespace {

/// What dl_iterate_phdr tells of one object: enough to find its read-only segments in memory.
struct MappedObject {
  LinkMapEntry entry;
  const ElfW(Phdr) * headers = nullptr;
  std::size_t header_count = 0;
};

std::vector<MappedObject> mapped_objects() {
  std::vector<MappedObject> objects;
  ::dl_iterate_phdr(
      [](dl_phdr_info* info, std::size_t, void* data) {
        // The program itself has no name here, and the vDSO no file: neither is a plugin's.
        if (info->dlpi_name == nullptr || info->dlpi_name[0] != '/') return 0;
        static_cast<std::vector<MappedObject>*>(data)->push_back(
            {{info->dlpi_name, static_cast<std::uintptr_t>(info->dlpi_addr)}, info->dlpi_phdr, info->dlpi_phnum});
        return 0;
      },
      &objects);
  return objects;
}

/// What /proc/self/maps says of the file mapped from `path` (the maps name files by their real path, without
/// symbolic links, and mark one removed or renamed over since it was mapped "(deleted)").
struct MappedFile {
  std::string device;
  unsigned long inode = 0;
  bool deleted = false;
};
std::optional<MappedFile> mapped_file(const std::string& path) {
  std::error_code error;
  const std::string real = std::filesystem::canonical(path, error).string();
  if (error) return std::nullopt;
  std::ifstream maps("/proc/self/maps");
  for (std::string line; std::getline(maps, line);) {
    std::istringstream fields(line);
    std::string range, permissions, offset, name;
    MappedFile file;
    fields >> range >> permissions >> offset >> file.device >> file.inode;
    std::getline(fields >> std::ws, name);
    file.deleted = name == real + " (deleted)";
    if (name == real || file.deleted) return file;
  }
  return std::nullopt;
}

/// Whether `n` bytes of a loaded object's read-only segment equal the file's. Not memcmp: an instrumented (ASan)
/// library's read-only data holds its globals' red zones, whose reads the sanitizer reports though they are mapped
/// bytes of the file; this reads them uninstrumented, a word at a time.
__attribute__((no_sanitize("address"))) bool same_bytes(const unsigned char* memory, const unsigned char* file, std::size_t n) {
  std::size_t k = 0;
  for (; k + sizeof(std::uint64_t) <= n; k += sizeof(std::uint64_t)) {
    std::uint64_t a, b;
    __builtin_memcpy(&a, memory + k, sizeof a);
    __builtin_memcpy(&b, file + k, sizeof b);
    if (a != b) return false;
  }
  for (; k < n; ++k) {
    if (memory[k] != file[k]) return false;
  }
  return true;
}

/// The file's bytes, if they are those the object was loaded from: the file is the very one mapped (its inode: a file
/// rebuilt and renamed over it is another, even where only its initialized data changed), and its read-only segments
/// equal the memory mapped from them (a file rewritten in place). Where the maps name another device than the file's
/// (overlay file systems report the layer's), the inodes cannot be compared and the segments alone decide.
/// @throws std::runtime_error otherwise.
std::string bytes_as_loaded(const MappedObject& object) {
  const int fd = ::open(object.entry.path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error(object.entry.path + ": cannot be read again to take its digest");
  struct stat status {};
  std::string bytes;
  bool read_whole = ::fstat(fd, &status) == 0;
  if (read_whole) {
    bytes.resize(static_cast<std::size_t>(status.st_size));
    std::size_t got = 0;
    while (got < bytes.size()) {
      const ssize_t n = ::read(fd, bytes.data() + got, bytes.size() - got);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      got += static_cast<std::size_t>(n);
    }
    read_whole = got == bytes.size();
  }
  ::close(fd);
  if (!read_whole) throw std::runtime_error(object.entry.path + ": cannot be read again to take its digest");
  char device[32];
  std::snprintf(device, sizeof device, "%02x:%02x", major(status.st_dev), minor(status.st_dev));
  const std::optional<MappedFile> mapped = mapped_file(object.entry.path);
  if (mapped && (mapped->deleted || (mapped->device == device && mapped->inode != static_cast<unsigned long>(status.st_ino)))) {
    throw std::runtime_error(object.entry.path +
                             ": the file at this path is not the one that was loaded (rebuilt or replaced after it was loaded): its "
                             "digest would name code that did not run");
  }
  for (std::size_t h = 0; h < object.header_count; ++h) {
    const ElfW(Phdr)& segment = object.headers[h];
    if (segment.p_type != PT_LOAD || (segment.p_flags & PF_W) != 0) continue;
    const void* in_memory = reinterpret_cast<const void*>(object.entry.base + segment.p_vaddr);
    if (segment.p_offset + segment.p_filesz > bytes.size() ||
        !same_bytes(static_cast<const unsigned char*>(in_memory), reinterpret_cast<const unsigned char*>(bytes.data()) + segment.p_offset,
                    segment.p_filesz)) {
      throw std::runtime_error(object.entry.path +
                               ": the file no longer holds the code that was loaded from it (rebuilt or replaced after it was loaded): "
                               "its digest would name code that did not run");
    }
  }
  return bytes;
}

/// A path without symbolic links, for comparing the loader's names of one file (a soname is usually a link).
std::string real_path(const std::string& path) {
  std::error_code error;
  const std::filesystem::path real = std::filesystem::canonical(path, error);
  return error ? path : real.string();
}

/// The objects this program had when it started (its own libraries), by real path: never a plugin's.
const std::vector<std::string>& program_objects() {
  static const std::vector<std::string> objects = [] {
    std::vector<std::string> paths;
    for (const MappedObject& object : mapped_objects()) paths.push_back(real_path(object.entry.path));
    return paths;
  }();
  return objects;
}
[[maybe_unused]] const std::vector<std::string>& program_objects_at_start = program_objects();

/// This program's dynamic loader (its PT_INTERP).
std::string dynamic_loader() {
  std::string loader;
  ::dl_iterate_phdr(
      [](dl_phdr_info* info, std::size_t, void* data) {
        for (int h = 0; h < info->dlpi_phnum; ++h) {
          if (info->dlpi_phdr[h].p_type == PT_INTERP) {
            *static_cast<std::string*>(data) = reinterpret_cast<const char*>(info->dlpi_addr + info->dlpi_phdr[h].p_vaddr);
            return 1;
          }
        }
        return 0;
      },
      &loader);
  return loader;
}

/// A file's bytes, read whole, or nullopt.
std::optional<std::string> file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) return std::nullopt;
  return bytes;
}

/// What `LOADER --list PATH` prints (the libraries it resolves for PATH), within a minute.
std::string loader_listing(const std::string& path, int& status) {
  int output[2];
  if (::pipe2(output, O_CLOEXEC) != 0) throw std::invalid_argument("plugin " + path + ": cannot make a pipe to list its libraries");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, output[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, output[1], STDERR_FILENO);
  std::string loader = dynamic_loader(), list = "--list", file = path;
  char* argv[] = {loader.data(), list.data(), file.data(), nullptr};
  pid_t pid = -1;
  const int spawned = loader.empty() ? ENOENT : ::posix_spawn(&pid, loader.c_str(), &actions, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(output[1]);
  std::string text;
  if (spawned == 0) {
    constexpr int kListSeconds = 60;  // resolving a few dozen libraries takes milliseconds
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(kListSeconds);
    char buffer[4096];
    while (std::chrono::steady_clock::now() < deadline && text.size() < (1u << 20)) {
      pollfd ready{output[0], POLLIN, 0};
      if (::poll(&ready, 1, 1000) <= 0) continue;
      const ssize_t n = ::read(output[0], buffer, sizeof buffer);
      if (n <= 0) break;
      text.append(buffer, static_cast<std::size_t>(n));
    }
    ::kill(pid, SIGKILL);  // it is done by now; a loader that is not is ended
    int wait_status = 0;
    while (::waitpid(pid, &wait_status, 0) < 0 && errno == EINTR) {
    }
    status = WIFEXITED(wait_status) ? WEXITSTATUS(wait_status) : 128 + WTERMSIG(wait_status);
  } else {
    status = -1;
  }
  ::close(output[0]);
  if (spawned != 0) throw std::invalid_argument("plugin " + path + ": cannot run the dynamic loader " + loader + " to list its libraries");
  return text;
}

}  // namespace

std::vector<LoadedObject> plugin_objects_on_disk(const std::string& path) {
  int status = 0;
  const std::string listing = loader_listing(path, status);
  if (status != 0) {
    throw std::invalid_argument("plugin " + path + ": the dynamic loader cannot resolve its libraries: " + listing.substr(0, 2000));
  }
  std::vector<std::string> paths{path};
  std::istringstream lines(listing);
  for (std::string line; std::getline(lines, line);) {
    // "\tNAME => /PATH (0xADDRESS)", "\t/PATH (0xADDRESS)" or "\tlinux-vdso.so.1 (0xADDRESS)".
    const std::size_t arrow = line.find("=> ");
    std::size_t start = arrow != std::string::npos ? arrow + 3 : line.find_first_not_of(" \t");
    if (start == std::string::npos || line[start] != '/') continue;
    const std::size_t end = line.find(" (0x", start);
    paths.push_back(line.substr(start, end == std::string::npos ? std::string::npos : end - start));
  }
  std::vector<LoadedObject> objects;
  for (const std::string& object : paths) {
    const std::string real = real_path(object);
    const auto& program = program_objects();
    if (object != path && std::find(program.begin(), program.end(), real) != program.end()) continue;
    const bool again = std::any_of(objects.begin(), objects.end(), [&](const LoadedObject& o) { return real_path(o.path) == real; });
    if (again) continue;
    const std::optional<std::string> bytes = file_bytes(object);
    if (!bytes) throw std::invalid_argument("plugin " + path + ": " + object + " cannot be read to take its digest");
    objects.push_back({object, bytes_digest(*bytes)});
  }
  return objects;
}

std::string differs_on_disk(const std::vector<LoadedObject>& expected) {
  for (const LoadedObject& object : expected) {
    const std::optional<std::string> bytes = file_bytes(object.path);
    if (!bytes) return object.path + " cannot be read";
    if (bytes_digest(*bytes) != object.digest) return object.path + " holds other bytes than the run's";
  }
  return {};
}

std::vector<LinkMapEntry> link_map() {
  std::vector<LinkMapEntry> entries;
  for (const MappedObject& object : mapped_objects()) entries.push_back(object.entry);
  return entries;
}

std::vector<LoadedObject> objects_loaded_since(const std::vector<LinkMapEntry>& before) {
  std::vector<LoadedObject> loaded;
  for (const MappedObject& object : mapped_objects()) {
    bool known = false;
    for (const LinkMapEntry& entry : before) known = known || entry == object.entry;
    if (!known) loaded.push_back({object.entry.path, bytes_digest(bytes_as_loaded(object))});
  }
  return loaded;
}

LoadedObject loaded_object(const std::string& path) {
  for (const MappedObject& object : mapped_objects()) {
    if (object.entry.path == path) return {path, bytes_digest(bytes_as_loaded(object))};
  }
  throw std::runtime_error(path + ": not loaded in this process");
}

std::string differs_from_loaded(const std::vector<LoadedObject>& expected, const std::vector<LoadedObject>& loaded) {
  const std::vector<MappedObject> mapped = mapped_objects();
  for (const LoadedObject& object : expected) {
    const std::string real = real_path(object.path);
    const auto it = std::find_if(mapped.begin(), mapped.end(), [&](const MappedObject& m) { return real_path(m.entry.path) == real; });
    if (it == mapped.end()) return object.path + " is not loaded here";
    try {
      if (bytes_digest(bytes_as_loaded(*it)) != object.digest) return object.path + " is another file here (its digest differs)";
    } catch (const std::runtime_error& changed) {
      return changed.what();
    }
  }
  for (const LoadedObject& object : loaded) {
    const bool named =
        std::any_of(expected.begin(), expected.end(), [&](const LoadedObject& e) { return real_path(e.path) == real_path(object.path); });
    if (!named) return object.path + " came in with it here, not where it was described";
  }
  return {};
}

std::string combined_digest(const std::vector<LoadedObject>& objects) {
  std::string digests;
  for (const LoadedObject& object : objects) digests += object.digest;
  return bytes_digest(digests);
}

}  // namespace ccd::plugin
