#include "strategies/plugin/call_guard.hpp"

#include "ccd/config.hpp"

#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
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

std::mutex activity_mutex;
std::string activity_text;
const char* activity_item_name = nullptr;
std::atomic<std::size_t> activity_item{std::numeric_limits<std::size_t>::max()};

/// "cell fold8 / full+plugin:x, step 3, query 17", as far as the harness said.
std::string where_now() {
  std::unique_lock lock(activity_mutex, std::try_to_lock);  // never wait here: the process is about to end
  if (!lock.owns_lock()) return "";
  std::string text = activity_text;
  const std::size_t item = activity_item.load(std::memory_order_relaxed);
  if (activity_item_name != nullptr && item != std::numeric_limits<std::size_t>::max()) {
    text += (text.empty() ? "" : ", ") + std::string(activity_item_name) + " " + std::to_string(item);
  }
  return text;
}

std::int64_t now_nanoseconds() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

#if CCDBENCH_GUARD_TIMEOUT
/// The watchdog's view of one thread: the deadline of its call in progress (0: none) and that call. Each thread
/// that calls a plugin registers one slot, kept until the process ends (threads are few and long-lived: TBB's).
struct Slot {
  std::atomic<std::int64_t> deadline{0};
  std::atomic<const PluginCall*> call{nullptr};
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
        const PluginCall* call = slot->call.load(std::memory_order_acquire);
        if (deadline == 0 || now < deadline || call == nullptr) continue;
        // The call's site lives as long as its plugin; the call itself may just have returned, and then its
        // deadline would be 0 by the next look: look once more before ending anything.
        if (slot->deadline.load(std::memory_order_acquire) != deadline) continue;
        char seconds[32];
        std::snprintf(seconds, sizeof seconds, "%g", call->site().timeout_seconds);
        const std::string where = where_now();
        std::fprintf(stderr,
                     "ccdbench: error: %s: %s did not return within its timeout of %s s%s%s: in-process, a call that does not return ends "
                     "the run (run it isolated, isolate=on, to make it that call's error); the cells finished before are kept\n",
                     call->site().plugin.c_str(), call->what(), seconds, where.empty() ? "" : " during ", where.c_str());
        std::fflush(stderr);
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
#if CCDBENCH_GUARD_FENV
  if (site_.environment != harness_) site_.environment.install();
#endif
  current_call = this;
#if CCDBENCH_GUARD_TIMEOUT
  Slot& slot = Watchdog::instance().slot_of_this_thread();
  slot.call.store(this, std::memory_order_release);
  slot.deadline.store(now_nanoseconds() + static_cast<std::int64_t>(site_.timeout_seconds * 1e9), std::memory_order_release);
#endif
}

PluginCall::~PluginCall() {
  if (!finished_) finish();
}

void PluginCall::refuse(const std::string& why) {
  if (refused_.empty()) refused_ = why;
}

std::string PluginCall::finish() {
  if (finished_) return refused_;
  finished_ = true;
#if CCDBENCH_GUARD_TIMEOUT
  Slot& slot = Watchdog::instance().slot_of_this_thread();
  slot.deadline.store(0, std::memory_order_release);
  slot.call.store(nullptr, std::memory_order_release);
#endif
  current_call = nullptr;
  std::string fault = refused_;
#if CCDBENCH_GUARD_FENV
  const FpEnvironment after = FpEnvironment::current();
  if (after != site_.environment) {
    const std::string change = "it left the floating-point environment changed: " + describe_change(site_.environment, after);
    fault = fault.empty() ? change : fault + "; " + change;
  }
  if (after != harness_) harness_.install();
#endif
  return fault;
}

PluginLoad::PluginLoad(std::string plugin) : site_{std::move(plugin), FpEnvironment::current(), 600}, call_(site_, "its load") {}

PluginLoad::~PluginLoad() = default;

FpEnvironment PluginLoad::finish(std::string& refused) {
  const FpEnvironment left = FpEnvironment::current();
  std::string fault = call_.finish();
  // What the load left is the plugin's environment from now on, not an error of the load.
  const std::size_t change = fault.find("it left the floating-point environment changed");
  if (change != std::string::npos) fault = fault.substr(0, change == 0 ? 0 : change - 2);
  refused = fault;
#if CCDBENCH_GUARD_FENV
  return left;
#else
  // Without the guard the load's environment is not kept apart: calls run in whatever the thread has.
  (void)left;
  return FpEnvironment::current();
#endif
}

void set_activity(const std::string& text, const char* item_name) {
  std::lock_guard lock(activity_mutex);
  activity_text = text;
  activity_item_name = item_name;
  activity_item.store(std::numeric_limits<std::size_t>::max(), std::memory_order_relaxed);
}

void set_activity_item(std::size_t item) { activity_item.store(item, std::memory_order_relaxed); }

PluginCall* current_plugin_call() { return current_call; }

void end_run_for_plugin(const std::string& what) {
  const PluginCall* call = current_call;
  const std::string where = where_now();
  std::fprintf(stderr,
               "ccdbench: error: %s %s during %s%s%s: in-process, a plugin that ends the process ends the run (run it isolated, "
               "isolate=on, to make it that call's error); the cells finished before are kept\n",
               call ? call->site().plugin.c_str() : "a plugin", what.c_str(), call ? call->what() : "a call", where.empty() ? "" : ", ",
               where.c_str());
  std::fflush(stderr);
  exit_now(1);
}

}  // namespace ccd::plugin
