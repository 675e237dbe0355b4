#pragma once
/// @file
/// A plugin run in a child process (the `isolate=on` key): a crash, an abort or a hang of the plugin becomes an
/// error of the one query or step that caused it, and the run goes on with a fresh child. The child is this
/// program started again as `PROGRAM plugin-host PATH VALUE...` (harness/main.cpp hands that to serve_plugin before
/// anything else); it loads the plugin, creates its context and answers requests on file descriptors 3 and 4, so
/// that whatever the plugin prints on its standard output never mixes with its answers.

#include "strategies/plugin/ccdbench_plugin.h"
#include "strategies/plugin/library.hpp"

#include <sys/types.h>

#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace ccd::plugin {

/// The child's side: argv = PROGRAM plugin-host PATH VALUE... Returns the process's exit status.
int serve_plugin(int argc, char** argv);

/// The first argument that makes ccdbench a plugin's child process.
inline constexpr const char* kPluginHostCommand = "plugin-host";

class IsolatedPlugin {
 public:
  /// The child is started at the first request (and again after a crash or a hang).
  IsolatedPlugin(const Library& library, std::vector<std::string> values, double timeout_seconds);
  ~IsolatedPlugin();
  IsolatedPlugin(const IsolatedPlugin&) = delete;
  IsolatedPlugin& operator=(const IsolatedPlugin&) = delete;

  /// A query's answer; a crash or a hang comes back as CCDBENCH_ERROR saying which. One request at a time.
  ccdbench_answer query(bool vertex_face, const double* rows, double thickness);

  /// A whole-step plugin's calls. `begin` keeps the scene, so that a child started again after a crash is given it
  /// before its next step (its state across steps starts over). A nonzero status comes with `message`.
  int begin(const ccdbench_scene& scene, std::string& message);
  int step(const ccdbench_step& step, std::size_t vertex_count, const ccdbench_contacts& contacts, std::string& message);
  void end();

 private:
  /// Starts the child and reads its greeting (whether the plugin accepted its configuration).
  /// @throws std::invalid_argument when the plugin refuses its configuration.
  void start();
  /// Kills and reaps the child; returns what happened to it ("crashed with signal 11 (Segmentation fault)").
  std::string stop(bool kill_it);
  /// Writes a request and reads `reply_size` bytes of its reply within the timeout; false (with `why`) when the
  /// child died or did not answer in time (it is then stopped).
  bool exchange(const std::vector<char>& request, std::vector<char>& reply, std::size_t reply_size, std::string& why);
  /// Reads more of a reply (after exchange), within the same deadline.
  bool read_more(std::vector<char>& reply, std::size_t size, std::string& why);
  bool send_scene(std::string& message);

  std::string path_;
  std::vector<std::string> values_;
  double timeout_seconds_;
  std::mutex mutex_;
  pid_t child_ = -1;
  int to_child_ = -1, from_child_ = -1;
  double deadline_ = 0;
  /// The scene of `begin`, as sent (empty: none yet).
  std::vector<char> scene_request_;
};

/// One plugin as a narrow phase or a strategy holds it: the library, its key values and ccdbench's settings, and
/// where it runs, in-process (`context`) or, with isolate=on, in a child process (`isolated`); the other is null.
struct PluginInstance {
  /// From a spec's keys (the library's, then host_keys).
  PluginInstance(std::shared_ptr<const Library> library_, const narrowphase::SpecReader& keys);
  /// The resolved name (resolved_name).
  std::string name() const;

  std::shared_ptr<const Library> library;
  std::vector<std::string> values;
  HostSettings host;
  std::unique_ptr<Context> context;
  std::unique_ptr<IsolatedPlugin> isolated;
};

}  // namespace ccd::plugin
