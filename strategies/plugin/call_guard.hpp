#pragma once
/// @file
/// Every in-process call into a plugin goes through a PluginCall (docs/DESIGN.md §10 "In-process"): what the code
/// under audit can do to the process around its answer is detected, named as that plugin's error, and undone.
/// - The floating-point environment: each call runs in the environment the plugin's load left (a library built with
///   GCC's fast-math options has flush-to-zero there, and is judged as it would run in its user's program); ccdbench's own
///   is put back after every call, and a call that leaves another environment than it was given is that call's
///   error, naming the change. ccdbench's code never runs in the plugin's environment.
/// - chdir and fchdir inside a call are refused (they fail with EPERM) and are that call's error: the run's working
///   directory is the run's (harness/interposers.cpp, in the ccdbench program, routes them here).
/// - exit, _exit, quick_exit and abort inside a call end the run with a message naming the plugin, what it was
///   doing and where, and a non-zero status, instead of a silent exit 0; the cells finished before are kept.
/// - A call that runs past its plugin's `timeout` ends the run the same way (a watchdog thread).
/// Anything else a plugin does in-process is not guaranteed; isolation (isolate=on) contains it.

#include "strategies/plugin/fp_environment.hpp"

#include <cstddef>
#include <string>

namespace ccd::plugin {

/// What every call into one plugin needs: its name for messages, the environment its calls run in, its timeout.
struct CallSite {
  /// "plugin NAME (PATH)".
  std::string plugin;
  /// The floating-point environment its load left, which its calls are given.
  FpEnvironment environment;
  double timeout_seconds = 10;
};

/// One call into a plugin on this thread, from construction to `finish`: the plugin's environment installed,
/// chdir refused, exit caught and the timeout watched.
class PluginCall {
 public:
  /// `what`: a phrase for messages, "a vertex-face query", "its step", "begin" (a string that outlives the call).
  PluginCall(const CallSite& site, const char* what);
  ~PluginCall();
  PluginCall(const PluginCall&) = delete;
  PluginCall& operator=(const PluginCall&) = delete;

  /// Ends the call (puts ccdbench's floating-point environment back) and returns what the plugin did beside its
  /// answer that makes the call its error ("it left the floating-point environment changed: ...", "it called
  /// chdir(...)"), or "" when nothing.
  std::string finish();

  const CallSite& site() const { return site_; }
  const char* what() const { return what_; }
  /// A refusal made during the call (chdir); the first one is kept.
  void refuse(const std::string& why);
  /// The environment the plugin left when the call finished (after `finish`).
  const FpEnvironment& left() const { return left_; }
  /// What was refused during the call ("" when nothing).
  const std::string& refused() const { return refused_; }

 private:
  const CallSite& site_;
  const char* what_;
  FpEnvironment harness_;
  FpEnvironment left_;
  std::string refused_;
  bool finished_ = false;
};

/// How long loading a plugin (its libraries, its constructors, its entry point) may take before it is called hung.
inline constexpr double kLoadSeconds = 120;

/// Loading a plugin (dlopen, its entry point): chdir refused and exit caught as in a call; the floating-point
/// environment the load leaves is returned by `finish` (it is the plugin's from then on), and ccdbench's put back.
class PluginLoad {
 public:
  explicit PluginLoad(std::string plugin);
  ~PluginLoad();
  PluginLoad(const PluginLoad&) = delete;
  PluginLoad& operator=(const PluginLoad&) = delete;
  struct Finished {
    /// The environment the load left: its calls' from now on (ccdbench's is installed again).
    FpEnvironment environment;
    /// What the load did that ccdbench refused ("" when nothing).
    std::string refused;
  };
  Finished finish();

 private:
  CallSite site_;
  PluginCall call_;
};

/// Runs `call` (a call into the plugin) as a PluginCall: returns the call's fault ("" when none), a C++ exception
/// thrown through the plugin's C functions among them.
template <class Call>
std::string guarded_call(const CallSite& site, const char* what, Call&& call) {
  PluginCall guard(site, what);
  std::string thrown;
  try {
    call();
  } catch (const std::exception& error) {
    thrown = std::string("it threw a C++ exception through the C ABI: ") + error.what();
  } catch (...) {
    thrown = "it threw an exception through the C ABI";
  }
  std::string fault = guard.finish();
  if (!thrown.empty()) fault = fault.empty() ? thrown : thrown + "; " + fault;
  return fault;
}

/// What the process is doing, for messages about a plugin that ended it: set by the harness ("cell fold8 /
/// full+plugin:libx.so, step 3 of 7", "file sample.csv") and, per item, `set_activity_item` ("query 17").
void set_activity(const std::string& text, const char* item_name = nullptr);
void set_activity_item(std::size_t item);

/// The call in progress on this thread, or nullptr (harness/interposers.cpp asks); always nullptr in a plugin's child
/// process, where the plugin's exits and crashes are its own and the parent sees them.
PluginCall* current_plugin_call();

/// Says that this process is a plugin's child process (isolation.hpp): nothing is guarded here.
void set_plugin_host_process();

/// Ends the process because the plugin of the current call did `what` ("called exit(0)"): prints which plugin, what
/// it was doing, and where, on stderr, and exits with status 1. The cells finished so far are on disk already.
[[noreturn]] void end_run_for_plugin(const std::string& what);

}  // namespace ccd::plugin
