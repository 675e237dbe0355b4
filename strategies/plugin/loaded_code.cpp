#include "strategies/plugin/loaded_code.hpp"

#include "strategies/plugin/library.hpp"

#include <elf.h>
#include <link.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <stdexcept>

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

/// The file's bytes, if its read-only segments are what is mapped in memory: the file the object was loaded from,
/// unchanged since. @throws std::runtime_error otherwise.
std::string bytes_as_loaded(const MappedObject& object) {
  std::ifstream in(object.entry.path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) throw std::runtime_error(object.entry.path + ": cannot be read again to take its digest");
  for (std::size_t h = 0; h < object.header_count; ++h) {
    const ElfW(Phdr)& segment = object.headers[h];
    if (segment.p_type != PT_LOAD || (segment.p_flags & PF_W) != 0) continue;
    const void* in_memory = reinterpret_cast<const void*>(object.entry.base + segment.p_vaddr);
    if (segment.p_offset + segment.p_filesz > bytes.size() || std::memcmp(in_memory, bytes.data() + segment.p_offset, segment.p_filesz) != 0) {
      throw std::runtime_error(object.entry.path +
                               ": the file no longer holds the code that was loaded from it (rebuilt or replaced after it was loaded): "
                               "its digest would name code that did not run");
    }
  }
  return bytes;
}

}  // namespace

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
    const auto it = std::find_if(mapped.begin(), mapped.end(), [&](const MappedObject& m) { return m.entry.path == object.path; });
    if (it == mapped.end()) return object.path + " is not loaded here";
    try {
      if (bytes_digest(bytes_as_loaded(*it)) != object.digest) return object.path + " is another file here (its digest differs)";
    } catch (const std::runtime_error& changed) {
      return changed.what();
    }
  }
  for (const LoadedObject& object : loaded) {
    const bool named = std::any_of(expected.begin(), expected.end(), [&](const LoadedObject& e) { return e.path == object.path; });
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
