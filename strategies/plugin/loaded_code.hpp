#pragma once
/// @file
/// What code a plugin brought into a process, and its digest as loaded (docs/DESIGN.md §10 "Identity"): the plugin's
/// own file and every shared library that came in with it (the user's CCD library beside a thin wrapper, the usual
/// case). A cell kept for one build of that code is never reused for another, and a child process started again
/// mid-run must have loaded the very same bytes.
///
/// Each object's digest is of its file's bytes, read through the path the dynamic loader reports, and checked
/// against the object in memory: every read-only segment the loader mapped (code, constants) must equal those bytes.
/// A file rebuilt or replaced after it was loaded therefore fails the check instead of naming code that did not run.
/// Only objects in the process's link map when the digest is taken count: a library the plugin opens itself later,
/// inside a call, is not covered (said in docs/audit.md).

#include <cstdint>
#include <string>
#include <vector>

namespace ccd::plugin {

/// A shared object in the process's link map: its path (as the loader names it) and its load address.
struct LinkMapEntry {
  std::string path;
  std::uintptr_t base = 0;
  bool operator==(const LinkMapEntry& other) const { return path == other.path && base == other.base; }
};

/// The objects the dynamic loader has loaded, in load order.
std::vector<LinkMapEntry> link_map();

struct LoadedObject {
  std::string path;
  std::string digest;  // 32 hex digits
};

/// The code a plugin file brings into this program, found and digested without running any of it: the file itself,
/// then every library the dynamic loader resolves for it (its `--list` mode, which maps and relocates nothing and
/// runs no constructor), less those this program had when it started. Each digest is of the file's bytes as read
/// now. This is the plugin's identity as the parent process knows it: no code of the plugin decides it.
/// @throws std::invalid_argument "plugin PATH: REASON" when the loader cannot resolve its libraries.
std::vector<LoadedObject> plugin_objects_on_disk(const std::string& path);

/// The objects of the link map that are not in `before`, each with its digest as loaded, in load order.
/// @throws std::runtime_error "FILE: REASON" when an object's file no longer holds what was loaded from it.
std::vector<LoadedObject> objects_loaded_since(const std::vector<LinkMapEntry>& before);

/// The object loaded from `path`, with its digest as loaded (a plugin already in the process under another name).
/// @throws std::runtime_error "PATH: REASON" when none is, or its file no longer holds what was loaded from it.
LoadedObject loaded_object(const std::string& path);

/// Why the code loaded in this process is not `expected` (plugin_objects_on_disk): an object of it that is not loaded
/// here as it was digested, or an object `loaded` (what the plugin's load brought in here) that it does not name.
/// "" when it is the same code.
std::string differs_from_loaded(const std::vector<LoadedObject>& expected, const std::vector<LoadedObject>& loaded);

/// Why the files of `expected` no longer hold the bytes digested, read now, before anything of them is loaded: ""
/// when they all do. A child process checks this before it loads a plugin, so that no code but the run's runs there.
std::string differs_on_disk(const std::vector<LoadedObject>& expected);

/// One digest of the objects (their digests in order): the plugin's identity in its resolved name and cell keys.
std::string combined_digest(const std::vector<LoadedObject>& objects);

}  // namespace ccd::plugin
