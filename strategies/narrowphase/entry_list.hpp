#pragma once
/// @file
/// What the two registries (strategies/registry.hpp, strategies/narrowphase_registry.hpp) do alike: gather the
/// entries of every file of the build's list, in order, and find one by name.

#include <initializer_list>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

namespace ccd::narrowphase {

/// The entries of each file's entries function, in the list's order.
template <class Entry>
std::vector<Entry> gather_entries(std::initializer_list<std::vector<Entry> (*)()> files) {
  std::vector<Entry> all;
  for (const auto entries_of : files) {
    for (Entry& entry : entries_of()) all.push_back(std::move(entry));
  }
  return all;
}

/// The names of `entries`, comma-separated, for messages.
template <class Entry>
std::string entry_names(const std::vector<Entry>& entries) {
  std::string names;
  for (const Entry& entry : entries) names += (names.empty() ? "" : ", ") + entry.name;
  return names;
}

/// The entry named `name`, or nullptr.
template <class Entry>
const Entry* find_entry(const std::vector<Entry>& entries, const std::string& name) {
  for (const Entry& entry : entries) {
    if (entry.name == name) return &entry;
  }
  return nullptr;
}

/// The entry named `name`. @throws std::invalid_argument "unknown WHAT 'NAME' (known: ...)".
template <class Entry>
const Entry& entry_named(const std::vector<Entry>& entries, const std::string& name, const std::string& what) {
  if (const Entry* entry = find_entry(entries, name)) return *entry;
  throw std::invalid_argument("unknown " + what + " '" + name + "' (known: " + entry_names(entries) + ")");
}

/// An entry made on demand for a name that names a file (plugin:PATH, answers:DIR), made once per name and kept for
/// the process, so that it is referred to like the build's own entries. A name whose entry cannot be made (`make`
/// throws) is not kept: the next lookup tries again and throws again.
template <class Entry>
const Entry& entry_made_once(const std::string& name, Entry (*make)(const std::string&)) {
  static std::mutex mutex;
  static std::map<std::string, std::unique_ptr<const Entry>> made;
  std::lock_guard lock(mutex);
  auto it = made.find(name);
  if (it == made.end()) it = made.emplace(name, std::make_unique<const Entry>(make(name))).first;
  return *it->second;
}

}  // namespace ccd::narrowphase
