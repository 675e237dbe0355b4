#pragma once
/// @file
/// A plugin run in a child process (the `isolate=on` key): a crash, an exit, an abort or a hang of the plugin
/// becomes an error of the one query or step that caused it, and the run goes on with a fresh child. The child is
/// this program started again as `PROGRAM plugin-host PATH DIGEST VALUE...` (harness/main.cpp hands that to serve_plugin
/// before anything else); it loads the plugin, creates its context and answers requests on file descriptors 3 and
/// 4, so that whatever the plugin prints on its standard output never mixes with its answers.
///
/// What the parent holds the child to (docs/DESIGN.md §10 "Isolated"):
/// - `PROGRAM plugin-host --describe PATH` describes a plugin (its table and the digest of its code as loaded), so
///   that this process never loads a plugin it runs isolated, nor one whose load crashes;
/// - every child is told the digest of the code the run was planned with, and one that loaded other code (the file
///   was replaced or rebuilt during the run) calls none of it and says so: from then on each request is an error;
/// - a child dies with its parent: it watches a pipe that only the parent holds open (fd 5), and ends its process
///   group when the parent is gone, even while the plugin hangs in a call;
/// - every request is numbered and every reply carries its request's number, and every batch answer its batch's:
///   a second reply (a process the plugin forked, still answering) is never taken for another request's;
/// - ending a child ends its process group (child_process.hpp).

#include "strategies/plugin/ccdbench_plugin.h"
#include "strategies/plugin/child_process.hpp"
#include "strategies/plugin/library.hpp"

#include <sys/types.h>

#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace ccd::plugin {

/// The child's side: argv = PROGRAM plugin-host PATH DIGEST VALUE... (DIGEST: the code it may run, "-" for any), or
/// PROGRAM plugin-host --describe PATH. Returns the process's exit status.
int serve_plugin(int argc, char** argv);

/// The description of the plugin at `path`, made once per process (by a child process: plugin-host --describe).
/// @throws std::invalid_argument "plugin PATH: REASON" when it cannot be loaded, its table is refused, or its child
///         crashed or hung while loading it.
const PluginDescription& plugin_description(const std::string& path);

/// The plugin at `path` described by a child process (plugin-host --describe).
/// @throws std::invalid_argument "plugin PATH: REASON": its table is refused, or the child crashed, exited or hung
///         while loading it.
PluginDescription describe_in_child(const std::string& path);

class IsolatedPlugin {
 public:
  /// The child is started here, outside any timed call (and again at the request after a crash or a hang). Queries
  /// go to it `batch` at a time (query_batch.hpp); 1 sends each on its own over the pipe. @throws
  /// std::invalid_argument when the plugin refuses its configuration or its create call fails (as in-process).
  IsolatedPlugin(const PluginDescription& description, std::vector<std::string> values, double timeout_seconds, std::size_t batch);
  ~IsolatedPlugin();
  IsolatedPlugin(const IsolatedPlugin&) = delete;
  IsolatedPlugin& operator=(const IsolatedPlugin&) = delete;

  /// A query's answer; a crash or a hang comes back as CCDBENCH_ERROR saying which. One request at a time.
  ccdbench_answer query(bool vertex_face, const double* rows, double thickness);

  /// One query of a batch: 24 doubles in the ABI's order.
  struct Query {
    const double* rows;
    double thickness;
    bool vertex_face;
  };
  /// The answers of many queries, in order, in batches through shared memory: a crash or a hang is the error of the
  /// query it happened on alone, and a fresh child answers the ones after it.
  std::vector<ccdbench_answer> queries(const std::vector<Query>& asked);

  /// A whole-step plugin's calls. `begin` keeps the scene, so that a child started again after a crash is given it
  /// before its next step (its state across steps starts over). A nonzero status comes with `message`.
  int begin(const ccdbench_scene& scene, std::string& message);
  int step(const ccdbench_step& step, std::size_t vertex_count, const ccdbench_contacts& contacts, std::string& message);
  void end();

 private:
  /// Starts the child and reads its greeting; false (with `why`) when it died while starting, or loaded other code
  /// than the run's (every later request is then an error too). @throws std::invalid_argument when the plugin
  /// refuses its configuration.
  bool start(std::string& why);
  /// Ends the child and its process group (killed first with `kill_it`) and reaps it; returns what happened to it
  /// ("it crashed with signal 11 (Segmentation fault)").
  std::string stop(bool kill_it);
  /// Numbers a request ({kind, payload...}) and writes it, starting its timeout; false (with `why`) when the child
  /// is gone (it is then stopped).
  bool send(std::vector<char> request, std::string& why);
  /// Reads the number the reply starts with: false (with `why`, the child killed) when it is another request's.
  bool reply_is_this_requests(std::string& why);
  /// Writes a request and reads `reply_size` bytes of its reply within the timeout; false (with `why`) when the
  /// child died, did not answer in time or answered another request (it is then stopped).
  bool exchange(const std::vector<char>& request, std::vector<char>& reply, std::size_t reply_size, std::string& why);
  /// Reads more of a reply (after exchange), within the same deadline.
  bool read_more(std::vector<char>& reply, std::size_t size, std::string& why);
  bool send_scene(std::string& message);
  /// Queries [first, first + count) of `asked` in one batch; returns how many got an answer before the child died or
  /// hung (then `why` says which), or `count`.
  std::size_t batch(const std::vector<Query>& asked, std::size_t first, std::size_t count, std::vector<ccdbench_answer>& answers, std::string& why);

  std::string path_;
  std::string digest_;
  std::vector<LoadedObject> objects_;
  std::vector<std::string> values_;
  double timeout_seconds_;
  std::size_t batch_;
  /// The memory shared with every child for batches (none when batch_ is 1).
  std::unique_ptr<class BatchRegion> region_;
  std::mutex mutex_;
  ChildProcess child_;
  /// The number of the last request sent (every reply must carry it).
  std::uint64_t sequence_ = 0;
  double deadline_ = 0;
  /// The scene of `begin`, as sent (empty: none yet), and the most contacts of each kind its mesh can have.
  std::vector<char> scene_request_;
  std::uint64_t most_vertex_face_ = 0, most_edge_edge_ = 0;
  /// Why no child may answer any more ("its code changed during the run: ..."): every request is then an error.
  std::string changed_;
};

/// One plugin as a narrow phase or a strategy holds it: its description, its key values and ccdbench's settings,
/// and where it runs, in-process (`context`, with `library`) or, with isolate=on, in a child process (`isolated`).
struct PluginInstance {
  /// From a spec's keys (the plugin's, then host_keys).
  PluginInstance(const PluginDescription& description_, const narrowphase::SpecReader& keys);
  /// The resolved name (resolved_name).
  std::string name() const;
  /// Name, version, digest of every object of its code, where it ran and the floating-point environment of its
  /// calls, for every record's provenance.
  std::vector<std::pair<std::string, std::string>> provenance() const;

  const PluginDescription& description;
  std::vector<std::string> values;
  HostSettings host;
  std::shared_ptr<const Library> library;
  std::unique_ptr<Context> context;
  std::unique_ptr<IsolatedPlugin> isolated;
};

}  // namespace ccd::plugin
