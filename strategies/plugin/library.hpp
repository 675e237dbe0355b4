#pragma once
/// @file
/// A plugin library (ccdbench_plugin.h) loaded and checked: its table, its keys as the registries declare keys, and
/// what a result must record of it (its file's digest). The adapters (plugin_narrow_phase.cpp, plugin_strategy.cpp)
/// enter it into the registries beside the built-ins.

#include "strategies/narrowphase/spec.hpp"
#include "strategies/plugin/ccdbench_plugin.h"

#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace ccd::plugin {

class Library {
 public:
  /// Loads `path` (dlopen) and checks its table: the entry point, the ABI version (a plugin built for another is
  /// refused naming both), the table's size, at least query or step functions, create and destroy, and its keys.
  /// @throws std::invalid_argument "plugin FILE: REASON".
  explicit Library(const std::filesystem::path& path);
  ~Library();
  Library(const Library&) = delete;
  Library& operator=(const Library&) = delete;

  const ccdbench_plugin& table() const { return *table_; }
  /// The absolute path it was loaded from, and the digest of that file's bytes (its version in cell keys).
  const std::string& path() const { return path_; }
  const std::string& digest() const { return digest_; }
  /// The plugin's own keys, as the registries declare keys.
  const std::vector<narrowphase::KeySpec>& keys() const { return keys_; }

  bool thread_safe() const { return (table_->capabilities & CCDBENCH_THREAD_SAFE) != 0; }
  bool reports_toi() const { return (table_->capabilities & CCDBENCH_REPORTS_TOI) != 0; }
  bool conservative() const { return (table_->capabilities & CCDBENCH_CONSERVATIVE) != 0; }
  bool answers_queries() const { return table_->vertex_face != nullptr && table_->edge_edge != nullptr; }
  bool answers_steps() const { return table_->step != nullptr; }
  /// "NAME VERSION: HELP (reports TOIs; thread-safe)": what listings say of it.
  std::string description() const;

 private:
  std::string path_;
  std::string digest_;
  void* handle_ = nullptr;
  const ccdbench_plugin* table_ = nullptr;
  std::vector<narrowphase::KeySpec> keys_;
};

/// XXH3-128 of a file's bytes, or of every file under a folder (their relative paths and bytes, in path order), as
/// 32 hex digits: what a result records of code or answers made outside ccdbench, so a changed one is never reused.
std::string content_digest(const std::filesystem::path& path);

/// The library at `path`, loaded once per process and kept (a loaded library is never unloaded while an entry may
/// point into it). @throws std::invalid_argument as Library's constructor.
std::shared_ptr<const Library> load_library(const std::string& path);

/// The keys ccdbench adds to every plugin, after the plugin's own:
/// - digest: the plugin file's digest; filled in by the resolved name, and checked when given, so that a cell kept
///   for one build of a plugin is never reused for another;
/// - errors=miss|hit: how an error or undecided answer counts for the verdicts and the gate (it is counted apart too);
/// - isolate=on|off: run the plugin in a child process (a crash or a hang becomes an error, not the end of the run);
/// - timeout: with isolate=on, the seconds a query or a step may take.
std::vector<narrowphase::KeySpec> host_keys();

/// What a plugin's registry entry declares: its own keys, then ccdbench's (host_keys).
std::vector<narrowphase::KeySpec> entry_keys(const Library& library);

/// The host's settings of a plugin spec (the keys above).
struct HostSettings {
  std::string digest;
  bool errors_count_as_hits = false;
  bool isolate = false;
  double timeout_seconds = 10;
};
/// @throws std::invalid_argument when `keys` gives a digest other than the library's.
HostSettings read_host_settings(const narrowphase::SpecReader& keys, const Library& library);

/// The plugin's own key values, in its table's order, as the configure call takes them.
std::vector<std::string> plugin_values(const narrowphase::SpecReader& keys, const Library& library);

/// "plugin:PATH:key=value...:digest=HEX:errors=miss[:isolate=on:timeout=T]": the resolved name, every key filled in.
std::string resolved_name(const Library& library, const std::vector<std::string>& values, const HostSettings& host);

/// A context of the plugin, created from `values` and destroyed with the object; a plugin that is not thread-safe
/// is called under the mutex.
class Context {
 public:
  /// @throws std::invalid_argument "plugin NAME: REASON" when the plugin refuses the values.
  Context(std::shared_ptr<const Library> library, const std::vector<std::string>& values);
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
  const Library& library() const { return *library_; }
  void* handle() const { return handle_; }
  std::mutex& mutex() const { return mutex_; }

 private:
  std::shared_ptr<const Library> library_;
  void* handle_ = nullptr;
  mutable std::mutex mutex_;
};

}  // namespace ccd::plugin
