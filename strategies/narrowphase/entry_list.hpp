#pragma once
/// @file
/// What the two registries (strategies/registry.hpp, strategies/narrowphase/registry.hpp) do alike: gather the
/// entries of every file of the build's list, in order, and find one by name.

#include <initializer_list>
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

}  // namespace ccd::narrowphase
