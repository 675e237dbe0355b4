// The C library's ways out of the process and of its working directory, as a plugin calling them in-process reaches
// them (docs/DESIGN.md §10, strategies/plugin/call_guard.hpp). The program defines and exports these symbols
// (harness/CMakeLists.txt: --export-dynamic-symbol), so that a plugin's calls bind to them before the C library's;
// outside a plugin call each goes on to the C library's own (the next definition after this program's), so that
// ccdbench and the libraries it uses are unaffected.
//   exit, _exit, _Exit, quick_exit, abort, and a failed assert (__assert_fail) inside a call: the run ends naming the
//     plugin, the call and where, with status 1 (a plugin that ended the process used to end the run with its status,
//     0 and no table). The C library's own internal aborts (stack protector, fortify, malloc checks) reach no symbol:
//     call_guard.cpp's signal handler names those;
//   chdir, fchdir inside a call: refused (-1, EPERM) and the call's error: the run's paths stay the run's.
// Only the ccdbench program has them: a test binary that calls a plugin directly does not catch these.

#include "ccd/config.hpp"
#include "strategies/plugin/call_guard.hpp"

#include <dlfcn.h>

#include <cerrno>
#include <string>

namespace {

/// The next definitions after this program's (the C library's, or a sanitizer's in front of it), looked up once at
/// start-up: never on the way out, where the dynamic loader's lock may be held (a plugin's constructor running
/// inside dlopen) and a lookup would wait for ever.
struct NextDefinitions {
  void (*exit)(int) = nullptr;
  void (*exit_now)(int) = nullptr;
  void (*exit_fast)(int) = nullptr;
  void (*quick_exit)(int) = nullptr;
  void (*abort)() = nullptr;
  void (*assert_fail)(const char*, const char*, unsigned int, const char*) = nullptr;
  void (*assert_perror_fail)(int, const char*, unsigned int, const char*) = nullptr;
  int (*chdir)(const char*) = nullptr;
  int (*fchdir)(int) = nullptr;

  NextDefinitions() {
    auto next = [](auto& pointer, const char* name) {
      pointer = reinterpret_cast<std::remove_reference_t<decltype(pointer)>>(::dlsym(RTLD_NEXT, name));
    };
    next(exit, "exit");
    next(exit_now, "_exit");
    next(exit_fast, "_Exit");
    next(quick_exit, "quick_exit");
    next(abort, "abort");
    next(assert_fail, "__assert_fail");
    next(assert_perror_fail, "__assert_perror_fail");
    next(chdir, "chdir");
    next(fchdir, "fchdir");
  }
};

/// Looked up at the first use; the global below makes that first use start-up, before main.
const NextDefinitions& next() {
  static const NextDefinitions definitions;
  return definitions;
}
[[maybe_unused]] const NextDefinitions& looked_up_at_start = next();

bool in_plugin_call() { return ccd::plugin::current_plugin_call() != nullptr; }

}  // namespace

extern "C" {

#if CCDBENCH_GUARD_EXIT
void exit(int status) noexcept {
  if (in_plugin_call()) ccd::plugin::end_run_for_plugin("called exit(" + std::to_string(status) + ")");
  next().exit(status);
  __builtin_unreachable();
}

void _exit(int status) {
  if (in_plugin_call()) ccd::plugin::end_run_for_plugin("called _exit(" + std::to_string(status) + ")");
  next().exit_now(status);
  __builtin_unreachable();
}

void _Exit(int status) noexcept {
  if (in_plugin_call()) ccd::plugin::end_run_for_plugin("called _Exit(" + std::to_string(status) + ")");
  next().exit_fast(status);
  __builtin_unreachable();
}

void quick_exit(int status) noexcept {
  if (in_plugin_call()) ccd::plugin::end_run_for_plugin("called quick_exit(" + std::to_string(status) + ")");
  next().quick_exit(status);
  __builtin_unreachable();
}

void abort() noexcept {
  if (in_plugin_call()) ccd::plugin::end_run_for_plugin("called abort()");
  next().abort();
  __builtin_unreachable();
}

void __assert_fail(const char* assertion, const char* file, unsigned int line, const char* function) noexcept {
  if (in_plugin_call()) {
    ccd::plugin::end_run_for_plugin(std::string("failed an assertion (") + file + ":" + std::to_string(line) + ": " + assertion + ")");
  }
  next().assert_fail(assertion, file, line, function);
  __builtin_unreachable();
}

void __assert_perror_fail(int error, const char* file, unsigned int line, const char* function) noexcept {
  if (in_plugin_call()) {
    ccd::plugin::end_run_for_plugin(std::string("failed an assertion (") + file + ":" + std::to_string(line) + ": errno " + std::to_string(error) +
                                    ")");
  }
  next().assert_perror_fail(error, file, line, function);
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
  return next().chdir(path);
}

int fchdir(int fd) noexcept {
  if (ccd::plugin::PluginCall* call = ccd::plugin::current_plugin_call()) {
    call->refuse("it called fchdir(" + std::to_string(fd) + "), which ccdbench refuses in-process (the run's working directory is the run's)");
    errno = EPERM;
    return -1;
  }
  return next().fchdir(fd);
}
#endif
}
