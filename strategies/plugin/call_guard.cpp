#include "strategies/plugin/call_guard.hpp"

#include "ccd/config.hpp"

#include <signal.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace ccd::plugin {
namespace {

/// Ends the process at once with `status`: the system call itself, since the program's _exit is interposed
/// (harness/interposers.cpp) and would come back here.
[[noreturn]] void exit_now(int status) {
  ::syscall(SYS_exit_group, status);
  __builtin_unreachable();
}

thread_local PluginCall* current_call = nullptr;
/// A plugin's child process (set_plugin_host_process).
std::atomic<bool> plugin_host_process{false};

std::mutex activity_mutex;
std::string activity_text;
const char* activity_item_name = nullptr;
std::atomic<std::size_t> activity_item{std::numeric_limits<std::size_t>::max()};

/// "cell fold8 / full+plugin:x, step 3, query 17", as far as the harness said, into `out`. No allocation and no
/// waiting: the process is about to end, and the plugin may hang holding the allocator's or stdio's lock.
void where_now(char* out, std::size_t size) {
  out[0] = '\0';
  std::unique_lock lock(activity_mutex, std::try_to_lock);
  if (!lock.owns_lock()) return;
  const std::size_t item = activity_item.load(std::memory_order_relaxed);
  if (activity_item_name != nullptr && item != std::numeric_limits<std::size_t>::max()) {
    std::snprintf(out, size, "%s%s%s %zu", activity_text.c_str(), activity_text.empty() ? "" : ", ", activity_item_name, item);
  } else {
    std::snprintf(out, size, "%s", activity_text.c_str());
  }
}

std::int64_t now_nanoseconds() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// Writes text on stderr from a signal handler (no allocation, no lock).
void write_raw(const char* text) {
  if (text == nullptr) return;
  for (std::size_t left = std::strlen(text); left > 0;) {
    const ssize_t written = ::write(STDERR_FILENO, text, left);
    if (written <= 0) return;
    text += written;
    left -= static_cast<std::size_t>(written);
  }
}

/// The signals a crashing plugin ends the process with (the C library's own aborts among them: a failed stack
/// protector or fortify check, a corrupt heap), and what was there before ccdbench's handler.
constexpr int kCrashSignals[] = {SIGABRT, SIGSEGV, SIGBUS, SIGILL, SIGFPE};
struct sigaction previous_handlers[sizeof kCrashSignals / sizeof kCrashSignals[0]];

/// A crash inside a plugin call ends the run naming the plugin and its call, status 1; any other goes on to the
/// handler that was there before (a sanitizer's) or the default.
void on_crash(int signal, siginfo_t* info, void* context) {
  if (const PluginCall* call = current_plugin_call()) {
    write_raw("ccdbench: error: ");
    write_raw(call->site().plugin.c_str());
    write_raw(" crashed with signal ");
    char number[8] = {};
    std::snprintf(number, sizeof number, "%d", signal);
    write_raw(number);
    write_raw(" during ");
    write_raw(call->what());
    write_raw(
        ": in-process, a plugin that crashes ends the run (run it isolated, isolate=on, to make it that call's error); the cells "
        "finished before are kept\n");
    exit_now(1);
  }
  for (std::size_t k = 0; k < sizeof kCrashSignals / sizeof kCrashSignals[0]; ++k) {
    if (kCrashSignals[k] != signal) continue;
    const struct sigaction& before = previous_handlers[k];
    if ((before.sa_flags & SA_SIGINFO) != 0 && before.sa_sigaction != nullptr) {
      before.sa_sigaction(signal, info, context);
      return;
    }
    if (before.sa_handler != SIG_DFL && before.sa_handler != SIG_IGN && before.sa_handler != nullptr) {
      before.sa_handler(signal);
      return;
    }
    ::signal(signal, SIG_DFL);
    ::raise(signal);
    return;
  }
}

/// The C library's own ways to exit (err, errx, and whatever calls its internal exit) reach no interposed symbol, but
/// they run the atexit handlers on the exiting thread: one inside a plugin call ends the run as an exit would.
void on_exit_inside_a_call() {
  if (current_plugin_call() != nullptr) end_run_for_plugin("ended the process (through the C library's exit)");
}

/// Installed once, at the first in-process call: a process without in-process plugins keeps its handlers as they were.
void install_crash_handlers() {
#if CCDBENCH_GUARD_EXIT
  static std::once_flag once;
  std::call_once(once, [] {
    std::atexit(on_exit_inside_a_call);
    for (std::size_t k = 0; k < sizeof kCrashSignals / sizeof kCrashSignals[0]; ++k) {
      struct sigaction action {};
      action.sa_sigaction = on_crash;
      action.sa_flags = SA_SIGINFO | SA_ONSTACK;
      sigemptyset(&action.sa_mask);
      ::sigaction(kCrashSignals[k], &action, &previous_handlers[k]);
    }
  });
#endif
}

#if CCDBENCH_GUARD_TIMEOUT
/// The watchdog's view of one thread: the deadline of its call in progress (0: none) and what the call is (its site
/// lives as long as its plugin, its `what` is a literal: both outlive the call). Each thread that calls a plugin
/// registers one slot, kept until the process ends (threads are few and long-lived: TBB's).
struct Slot {
  std::atomic<std::int64_t> deadline{0};
  std::atomic<const CallSite*> site{nullptr};
  std::atomic<const char*> what{nullptr};
};

class Watchdog {
 public:
  static Watchdog& instance() {
    static Watchdog* watchdog = new Watchdog();  // never destroyed: its thread runs until the process ends
    return *watchdog;
  }

  Slot& slot_of_this_thread() {
    thread_local Slot* slot = nullptr;
    if (slot == nullptr) {
      std::lock_guard lock(mutex_);
      slots_.push_back(std::make_unique<Slot>());
      slot = slots_.back().get();
      if (!started_) {
        started_ = true;
        std::thread([this] { watch(); }).detach();
      }
    }
    return *slot;
  }

 private:
  /// How often the watchdog looks: a call past its timeout ends the run at most this late.
  static constexpr std::chrono::milliseconds kPeriod{50};

  void watch() {
    while (true) {
      std::this_thread::sleep_for(kPeriod);
      const std::int64_t now = now_nanoseconds();
      std::lock_guard lock(mutex_);
      for (const auto& slot : slots_) {
        const std::int64_t deadline = slot->deadline.load(std::memory_order_acquire);
        const CallSite* site = slot->site.load(std::memory_order_acquire);
        const char* what = slot->what.load(std::memory_order_acquire);
        if (deadline == 0 || now < deadline || site == nullptr) continue;
        // The call may just have returned (its deadline is then 0, or another call's): look once more.
        if (slot->deadline.load(std::memory_order_acquire) != deadline) continue;
        // Written with write(2) from a buffer of its own: a hung plugin may hold stderr's lock or the allocator's.
        char where[1024];
        where_now(where, sizeof where);
        char message[2048];
        std::snprintf(message, sizeof message,
                      "ccdbench: error: %s: %s did not return within its timeout of %g s%s%s: in-process, a call that does not return ends "
                      "the run (run it isolated, isolate=on, to make it that call's error); the cells finished before are kept\n",
                      site->plugin.c_str(), what != nullptr ? what : "a call", site->timeout_seconds, where[0] ? " during " : "", where);
        write_raw(message);
        exit_now(1);
      }
    }
  }

  std::mutex mutex_;
  std::vector<std::unique_ptr<Slot>> slots_;
  bool started_ = false;
};
#endif

}  // namespace

PluginCall::PluginCall(const CallSite& site, const char* what) : site_(site), what_(what), harness_(FpEnvironment::current()) {
  install_crash_handlers();
#if CCDBENCH_GUARD_TIMEOUT
  Slot& slot = Watchdog::instance().slot_of_this_thread();
  slot.site.store(&site_, std::memory_order_release);
  slot.what.store(what_, std::memory_order_release);
  slot.deadline.store(now_nanoseconds() + static_cast<std::int64_t>(site_.timeout_seconds * 1e9), std::memory_order_release);
#endif
  current_call = this;
  // Last, after every piece of ccdbench's own work here: from now on the thread computes as the plugin's load set.
#if CCDBENCH_GUARD_FENV
  if (site_.environment != harness_) site_.environment.install();
#endif
}

PluginCall::~PluginCall() {
  if (finished_) return;
  try {
    finish();
  } catch (...) {
    // finish only builds a message: without memory for it the call still ends, ccdbench's environment put back.
    harness_.install();
    current_call = nullptr;
  }
}

void PluginCall::refuse(const std::string& why) {
  if (refused_.empty()) refused_ = why;
}

std::string PluginCall::finish() {
  if (finished_) return refused_;
  finished_ = true;
  // First of all: ccdbench's environment back, before any of its own work.
  left_ = FpEnvironment::current();
#if CCDBENCH_GUARD_FENV
  if (left_ != harness_) harness_.install();
#endif
  current_call = nullptr;
#if CCDBENCH_GUARD_TIMEOUT
  Slot& slot = Watchdog::instance().slot_of_this_thread();
  slot.deadline.store(0, std::memory_order_release);
  slot.site.store(nullptr, std::memory_order_release);
  slot.what.store(nullptr, std::memory_order_release);
#endif
  std::string fault = refused_;
#if CCDBENCH_GUARD_FENV
  if (left_ != site_.environment) {
    const std::string change = "it left the floating-point environment changed: " + describe_change(site_.environment, left_);
    fault = fault.empty() ? change : fault + "; " + change;
  }
#endif
  return fault;
}

PluginLoad::PluginLoad(std::string plugin) : site_{std::move(plugin), FpEnvironment::current(), kLoadSeconds}, call_(site_, "its load") {}

PluginLoad::~PluginLoad() = default;

PluginLoad::Finished PluginLoad::finish() {
  call_.finish();
  // What the load left is the plugin's environment from now on, not an error of the load: only refusals count.
  Finished finished;
  finished.refused = call_.refused();
#if CCDBENCH_GUARD_FENV
  finished.environment = call_.left();
#else
  // Without the guard the load's environment is not kept apart: calls run in whatever the thread has.
  finished.environment = FpEnvironment::current();
#endif
  return finished;
}

void set_activity(const std::string& text, const char* item_name) {
  std::lock_guard lock(activity_mutex);
  activity_text = text;
  activity_item_name = item_name;
  activity_item.store(std::numeric_limits<std::size_t>::max(), std::memory_order_relaxed);
}

void set_activity_item(std::size_t item) { activity_item.store(item, std::memory_order_relaxed); }

PluginCall* current_plugin_call() { return plugin_host_process.load(std::memory_order_relaxed) ? nullptr : current_call; }

void set_plugin_host_process() { plugin_host_process = true; }

void end_run_for_plugin(const std::string& what) {
  const PluginCall* call = current_call;
  char where[1024];
  where_now(where, sizeof where);
  char message[2048];
  std::snprintf(message, sizeof message,
                "ccdbench: error: %s %s during %s%s%s: in-process, a plugin that ends the process ends the run (run it isolated, "
                "isolate=on, to make it that call's error); the cells finished before are kept\n",
                call ? call->site().plugin.c_str() : "a plugin", what.c_str(), call ? call->what() : "a call", where[0] ? ", " : "", where);
  write_raw(message);
  exit_now(1);
}

}  // namespace ccd::plugin
