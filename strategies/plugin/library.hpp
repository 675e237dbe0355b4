#pragma once
/// @file
/// A plugin (ccdbench_plugin.h) as ccdbench knows it: its description (what its table says, checked, and the digest
/// of its code as loaded), and, for in-process use, the library loaded into this process. The adapters
/// (plugin_narrow_phase.cpp, plugin_strategy.cpp) enter it into the registries beside the built-ins.
///
/// ccdbench describes a plugin from a child process (docs/DESIGN.md §10): this process loads a plugin's code only
/// to run it in-process (isolate=off), so that a plugin whose load crashes, or that changes the process as it is
/// loaded, is refused or contained before it can touch a run.

#include "strategies/narrowphase/spec.hpp"
#include "strategies/plugin/call_guard.hpp"
#include "strategies/plugin/ccdbench_plugin.h"
#include "strategies/plugin/digest.hpp"
#include "strategies/plugin/fp_environment.hpp"
#include "strategies/plugin/loaded_code.hpp"

#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

namespace ccd::plugin {

/// A key of a plugin's table, as plain data.
struct TableKey {
  std::string name;
  int kind = 0;
  std::string default_value;
  double minimum = 0, maximum = 0;
  std::string choices;
  std::string help;
};

/// What a plugin's table says of it, as plain data (copied out of the loaded library, or received from a child).
struct PluginTable {
  std::uint64_t size = 0;
  std::uint32_t abi_version = 0;
  std::string name, version, help;
  std::uint32_t capabilities = 0;
  std::vector<TableKey> keys;
  bool has_create = false, has_destroy = false, has_vertex_face = false, has_edge_edge = false, has_step = false;
};

/// A plugin described and checked: its table, its keys as the registries declare keys, and the code it brought into
/// the process that described it, with their digests (loaded_code.hpp).
struct PluginDescription {
  /// The absolute path it is loaded from.
  std::string path;
  PluginTable table;
  std::vector<narrowphase::KeySpec> keys;
  /// Its file and each library it brings in (loaded_code.hpp: found and digested by this process from the files,
  /// never taken from the plugin's own process); `digest` is theirs together (its version in cell keys).
  std::vector<LoadedObject> objects;
  std::string digest;
  /// How its load changed the floating-point environment ("" when it did not): its calls run so in-process.
  std::string environment_at_load;

  bool thread_safe() const { return (table.capabilities & CCDBENCH_THREAD_SAFE) != 0; }
  bool reports_toi() const { return (table.capabilities & CCDBENCH_REPORTS_TOI) != 0; }
  bool conservative() const { return (table.capabilities & CCDBENCH_CONSERVATIVE) != 0; }
  bool answers_queries() const { return table.has_vertex_face && table.has_edge_edge; }
  bool answers_steps() const { return table.has_step; }
  /// "NAME VERSION: HELP (reports TOIs; thread-safe)": what listings say of it.
  std::string description() const;
  /// "plugin NAME (PATH)": how messages name it.
  std::string label() const;
};

/// Checks a table (the entry point's ABI version, the table's size, query or step functions, create and destroy,
/// its keys) and makes the description. @throws std::invalid_argument "plugin PATH: REASON".
PluginDescription describe(const std::string& path, const PluginTable& table, std::vector<LoadedObject> objects, std::string environment_at_load);

/// A description sent between processes, and read back (checked as `describe` checks). A reply that is not one is
/// refused: @throws std::invalid_argument.
std::vector<char> encode(const PluginDescription& description);
PluginDescription decode_description(const std::string& path, std::string_view bytes);

class Library {
 public:
  /// Loads `path` (dlopen) into this process with chdir refused and exit caught (call_guard.hpp), keeps the
  /// floating-point environment its load left as its calls' and puts ccdbench's back, and describes it.
  /// @throws std::invalid_argument "plugin FILE: REASON".
  explicit Library(const std::filesystem::path& path);
  ~Library();
  Library(const Library&) = delete;
  Library& operator=(const Library&) = delete;

  const ccdbench_plugin& table() const { return *table_; }
  const PluginDescription& description() const { return description_; }
  /// The floating-point environment its load left, which its calls run in.
  const FpEnvironment& environment() const { return environment_; }

 private:
  void* handle_ = nullptr;
  const ccdbench_plugin* table_ = nullptr;
  PluginDescription description_;
  FpEnvironment environment_;
};

/// The library at `path` (absolute), loaded into this process once and kept, unchecked: what a build without the
/// describe-in-child guard describes in this process.
std::shared_ptr<const Library> library_loaded_at(const std::string& path);

/// The library described by `description`, loaded into this process once and kept (a loaded library is never
/// unloaded while an entry may point into it), after checking that the code loaded here is the code described.
/// @throws std::invalid_argument as Library's constructor, or when the code differs from the description's.
std::shared_ptr<const Library> load_library(const PluginDescription& description);

/// The keys ccdbench adds to every plugin, after the plugin's own:
/// - digest: the digest of the plugin's code; filled in by the resolved name, and checked when given, so that a cell
///   kept for one build of a plugin is never reused for another;
/// - errors=miss|hit: how an error or undecided answer counts for the verdicts and the gate (it is counted apart too);
/// - isolate=on|off: run the plugin in a child process (a crash or a hang becomes an error, not the end of the run);
///   on unless the spec says off (or --in-process makes off the default: set_default_isolation);
/// - timeout: the seconds a query or a step may take (isolated: that call's error; in-process: the end of the run);
/// - batch: isolated, how many queries go to the child at a time (1: one pipe round trip each).
std::vector<narrowphase::KeySpec> host_keys();

/// What a plugin's registry entry declares: its own keys, then ccdbench's (host_keys).
std::vector<narrowphase::KeySpec> entry_keys(const PluginDescription& description);

/// The host's settings of a plugin spec (the keys above).
struct HostSettings {
  std::string digest;
  bool errors_count_as_hits = false;
  bool isolate = true;
  double timeout_seconds = 10;
  long batch = 4096;
};

/// Whether a plugin spec that does not say isolate= runs isolated (on, unless a command's --in-process said off).
void set_default_isolation(bool isolate);
/// @throws std::invalid_argument when `keys` gives a digest other than the description's.
HostSettings read_host_settings(const narrowphase::SpecReader& keys, const PluginDescription& description);

/// The plugin's own key values, in its table's order, as the configure call takes them.
std::vector<std::string> plugin_values(const narrowphase::SpecReader& keys, const PluginDescription& description);

/// "plugin:PATH:key=value...:digest=HEX:errors=miss[:isolate=on:timeout=T]": the resolved name, every key filled in.
std::string resolved_name(const PluginDescription& description, const std::vector<std::string>& values, const HostSettings& host);

/// A context of an in-process plugin, created from `values` (inside a guarded call) and destroyed with the object;
/// a plugin that is not thread-safe is called under the mutex.
class Context {
 public:
  /// @throws std::invalid_argument "plugin NAME: REASON" when the plugin refuses the values.
  Context(std::shared_ptr<const Library> library, const std::vector<std::string>& values, double timeout_seconds);
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
  const Library& library() const { return *library_; }
  void* handle() const { return handle_; }
  std::mutex& mutex() const { return mutex_; }
  /// What every call of this context needs (call_guard.hpp).
  const CallSite& call_site() const { return site_; }

 private:
  std::shared_ptr<const Library> library_;
  CallSite site_;
  void* handle_ = nullptr;
  mutable std::mutex mutex_;
};

}  // namespace ccd::plugin
