// The C library's ways out of the process and of its working directory, as a plugin calling them in-process reaches
// them (docs/DESIGN.md §10, strategies/plugin/call_guard.hpp). The program defines and exports these symbols
// (harness/CMakeLists.txt: --export-dynamic-symbol), so that a plugin's calls bind to them before the C library's;
// outside a plugin call each goes on to the C library's own (the next definition after this program's), so that
// ccdbench and the libraries it uses are unaffected.
//   exit, _exit, _Exit, quick_exit, abort inside a call: the run ends naming the plugin, the call and where, with
//     status 1 (a plugin that ended the process used to end the run with its status, 0 and no table);
//   chdir, fchdir inside a call: refused (-1, EPERM) and the call's error: the run's paths stay the run's.
// Only the ccdbench program has them: a test binary that calls a plugin directly does not catch these.

#include "ccd/config.hpp"
#include "strategies/plugin/call_guard.hpp"

#include <dlfcn.h>

#include <cerrno>
#include <string>

namespace {

/// The next definition of `name` after this program's: the C library's (or a sanitizer's in front of it).
template <class Function>
Function next_definition(const char* name) {
  return reinterpret_cast<Function>(::dlsym(RTLD_NEXT, name));
}

}  // namespace

extern "C" {

#if CCDBENCH_GUARD_EXIT
void exit(int status) noexcept {
  if (ccd::plugin::current_plugin_call() != nullptr) ccd::plugin::end_run_for_plugin("called exit(" + std::to_string(status) + ")");
  next_definition<void (*)(int)>("exit")(status);
  __builtin_unreachable();
}

void _exit(int status) {
  if (ccd::plugin::current_plugin_call() != nullptr) ccd::plugin::end_run_for_plugin("called _exit(" + std::to_string(status) + ")");
  next_definition<void (*)(int)>("_exit")(status);
  __builtin_unreachable();
}

void _Exit(int status) noexcept {
  if (ccd::plugin::current_plugin_call() != nullptr) ccd::plugin::end_run_for_plugin("called _Exit(" + std::to_string(status) + ")");
  next_definition<void (*)(int)>("_Exit")(status);
  __builtin_unreachable();
}

void quick_exit(int status) noexcept {
  if (ccd::plugin::current_plugin_call() != nullptr) ccd::plugin::end_run_for_plugin("called quick_exit(" + std::to_string(status) + ")");
  next_definition<void (*)(int)>("quick_exit")(status);
  __builtin_unreachable();
}

void abort() noexcept {
  if (ccd::plugin::current_plugin_call() != nullptr) ccd::plugin::end_run_for_plugin("called abort()");
  next_definition<void (*)()>("abort")();
  __builtin_unreachable();
}
#endif

#if CCDBENCH_GUARD_CHDIR
int chdir(const char* path) noexcept {
  if (ccd::plugin::PluginCall* call = ccd::plugin::current_plugin_call()) {
    call->refuse(std::string("it called chdir(\"") + path + "\"), which ccdbench refuses in-process (the run's working directory is the run's)");
    errno = EPERM;
    return -1;
  }
  return next_definition<int (*)(const char*)>("chdir")(path);
}

int fchdir(int fd) noexcept {
  if (ccd::plugin::PluginCall* call = ccd::plugin::current_plugin_call()) {
    call->refuse("it called fchdir(" + std::to_string(fd) + "), which ccdbench refuses in-process (the run's working directory is the run's)");
    errno = EPERM;
    return -1;
  }
  return next_definition<int (*)(int)>("fchdir")(fd);
}
#endif
}
