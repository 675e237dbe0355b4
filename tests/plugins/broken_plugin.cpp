// Plugins broken on purpose, one per build (tests/plugins/CMakeLists.txt), to show that each break is reported as
// the plugin's and that nothing else of a run is lost. Each answers every query "contact at t = 0" (conservative,
// never late: every true contact is found) and every whole step with no pair, except:
//   BROKEN_CRASH_ON=N   its Nth query (counted in its process) dereferences a null pointer (SIGSEGV);
//   BROKEN_HANG_ON=N    its Nth query never returns;
//   BROKEN_NAN_TOI      reports its contacts with a TOI that is not a number;
//   BROKEN_ABI=V        says it was built for plugin ABI version V;
//   BROKEN_FACE_RANGE   its whole step also reports vertex 0 against a face one past the last;
//   BROKEN_SILENT       writes no outcome at all into its answers (it returns without a word);
//   ONE_THREAD          not broken, but not thread-safe (no CCDBENCH_THREAD_SAFE): it answers "error" to a query
//                       that comes from another thread than the first one did.
// and, for the plugin boundary (tests/plugins/boundary_test.cpp, docs/DESIGN.md §10):
//   (built with -Ofast) the plugin `ofast`: GCC links crtfastmath.o into it, which sets flush-to-zero and
//                       denormals-are-zero for the thread that loads it;
//   BROKEN_ROUNDING     every call leaves the rounding mode upward;
//   BROKEN_WRITES_INPUTS its whole step writes its end positions over its start positions (no motion) through the
//                       const pointers it is given, and its queries write over their rows;
//   BROKEN_EXIT_ON=N    its Nth call (query or step, counted in its process) calls exit(0); with BROKEN_ABORT,
//                       abort() instead, with BROKEN_ASSERT a failed assert, with BROKEN_ERRX errx(0, ...) (the C
//                       library's own exit, no symbol a program can interpose);
//   BROKEN_CHDIR        every call moves to the folder CCDBENCH_TEST_CHDIR names (or /);
//   BROKEN_FIRST_CALLS=N answers "contact" to every query, at t = 0 for its first N queries (counted in its process)
//                       and at the smallest double after them: its answers depend on what it was asked before, and
//                       it misses nothing (not thread-safe, so the order is the run's);
//   BROKEN_REPLACE_SELF_ON=N on its Nth query (counted in its process) replaces its own file with the one
//                       CCDBENCH_TEST_REPLACEMENT names, and then crashes: the next child loads other code;
//   BROKEN_CRASH_AT_LOAD its constructor raises SIGSEGV when the library is loaded;
//   BROKEN_HANG_AT_LOAD  its constructor never returns;
//   BROKEN_ERRORS_LATER=N answers "apart" to its first N queries and "error" after them: with errors=miss the same
//                       pairs are reported either way, and only the count of errors tells two passes apart.
// and, for isolation (tests/plugins/isolation_test.cpp):
//   BROKEN_FORK_RETURNS  answers each query by a hash of its rows (contact or apart, a TOI from the hash: every query
//                       its own answer, the same in any process); on its Nth query (counted in its process; N from
//                       CCDBENCH_TEST_FORK_ON, never when unset) it forks, and both processes return from the call,
//                       as a careless fork/exec does: two processes answer on one pipe. With CCDBENCH_TEST_PID_FILE
//                       set, the copy appends "copy PID forked" to it, and "copy PID called" at each later call;
//   BROKEN_FORK_AT_LOAD  its constructor forks a process that sleeps ten minutes in its process group, and appends
//                       its pid to the file CCDBENCH_TEST_PID_FILE names;
//   BROKEN_CREATE_ROUNDING its create leaves the rounding mode upward;
//   BROKEN_TOUCH         its create allocates and writes CCDBENCH_TEST_TOUCH_MB megabytes (default 1024), kept
//                       until destroy.
#ifdef BROKEN_ASSERT
#undef NDEBUG  // the assert must be there in a release build
#endif
#include <ccdbench/ccdbench_plugin.h>

#include <dlfcn.h>
#include <err.h>
#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cassert>
#include <cfenv>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

namespace {

#ifdef BROKEN_CRASH_AT_LOAD
struct CrashAtLoad {
  CrashAtLoad() { std::raise(SIGSEGV); }
} crash_at_load;
#endif
#ifdef BROKEN_FORK_AT_LOAD
struct ForkAtLoad {
  ForkAtLoad() {
    const pid_t pid = ::fork();
    if (pid == 0) {
      // Its standard streams to /dev/null: it holds nothing of the test's (a pipe the test reads to its end).
      const int null = ::open("/dev/null", O_RDWR);
      for (int fd = 0; fd < 3; ++fd) ::dup2(null, fd);
      std::this_thread::sleep_for(std::chrono::minutes(10));
      ::_exit(0);
    }
    if (const char* file = std::getenv("CCDBENCH_TEST_PID_FILE")) std::ofstream(file, std::ios::app) << pid << "\n";
  }
} fork_at_load;
#endif
#ifdef BROKEN_HANG_AT_LOAD
struct HangAtLoad {
  HangAtLoad() {
    while (true) std::this_thread::sleep_for(std::chrono::seconds(1));
  }
} hang_at_load;
#endif

int queries_answered = 0;
int calls = 0;
std::size_t face_count = 0;
std::size_t vertex_count = 0;

/// What every call of the boundary's broken plugins does besides answering.
void misbehave() {
  ++calls;
#ifdef BROKEN_ROUNDING
  std::fesetround(FE_UPWARD);
#endif
#ifdef BROKEN_EXIT_ON
  if (calls == BROKEN_EXIT_ON) {
#if defined(BROKEN_ABORT)
    std::abort();
#elif defined(BROKEN_ASSERT)
    assert(calls != BROKEN_EXIT_ON && "the broken plugin's assertion");
#elif defined(BROKEN_ERRX)
    errx(0, "the broken plugin ends its process with errx(0)");
#else
    std::exit(0);
#endif
  }
#endif
#ifdef BROKEN_CHDIR
  const char* folder = std::getenv("CCDBENCH_TEST_CHDIR");
  if (::chdir(folder != nullptr ? folder : "/") != 0) std::perror("broken plugin: chdir");
#endif
}

#ifdef BROKEN_REPLACE_SELF_ON
/// Writes the file CCDBENCH_TEST_REPLACEMENT names over this plugin's own file (a new file renamed over it, as a
/// build does).
void replace_self() {
  Dl_info self{};
  const char* replacement = std::getenv("CCDBENCH_TEST_REPLACEMENT");
  if (::dladdr(reinterpret_cast<void*>(&replace_self), &self) == 0 || replacement == nullptr) return;
  std::ifstream in(replacement, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string temporary = std::string(self.dli_fname) + ".new";
  std::ofstream(temporary, std::ios::binary) << bytes;
  std::rename(temporary.c_str(), self.dli_fname);
}
#endif

#ifdef BROKEN_TOUCH
std::vector<char> touched;
#endif

void* create(const char* const*, char*) {
#ifdef BROKEN_CREATE_ROUNDING
  std::fesetround(FE_UPWARD);
#endif
#ifdef BROKEN_TOUCH
  const char* megabytes = std::getenv("CCDBENCH_TEST_TOUCH_MB");
  touched.assign(static_cast<std::size_t>(megabytes ? std::atoll(megabytes) : 1024) << 20, 1);
#endif
  return &queries_answered;
}
void destroy(void*) {
#ifdef BROKEN_TOUCH
  std::vector<char>().swap(touched);
#endif
}

#ifdef ONE_THREAD
std::atomic<std::thread::id> first_thread{};
#endif

void answer(void*, const double* rows, double, ccdbench_answer* out) {
  ++queries_answered;
  misbehave();
#ifdef BROKEN_WRITES_INPUTS
  double* writable = const_cast<double*>(rows);
  for (int i = 0; i < 24; ++i) writable[i] = 0.0;
#else
  (void)rows;
#endif
#ifdef BROKEN_REPLACE_SELF_ON
  if (queries_answered == BROKEN_REPLACE_SELF_ON) {
    replace_self();
    std::abort();
  }
#endif
#ifdef BROKEN_ERRORS_LATER
  out->outcome = queries_answered <= BROKEN_ERRORS_LATER ? CCDBENCH_APART : CCDBENCH_ERROR;
  return;
#endif
#ifdef BROKEN_FORK_RETURNS
  static const int fork_on = std::getenv("CCDBENCH_TEST_FORK_ON") ? std::atoi(std::getenv("CCDBENCH_TEST_FORK_ON")) : 0;
  static bool copy = false;
  const char* calls = std::getenv("CCDBENCH_TEST_PID_FILE");
  if (copy && calls) std::ofstream(calls, std::ios::app) << "copy " << ::getpid() << " called\n";
  if (queries_answered == fork_on && ::fork() == 0) {
    copy = true;
    if (calls) std::ofstream(calls, std::ios::app) << "copy " << ::getpid() << " forked\n";
  }
  std::uint64_t hash = 1469598103934665603ull;  // FNV-1a over the rows' bytes
  const auto* bytes = reinterpret_cast<const unsigned char*>(rows);
  for (std::size_t i = 0; i < 24 * sizeof(double); ++i) hash = (hash ^ bytes[i]) * 1099511628211ull;
  out->outcome = (hash >> 7) % 2 == 0 ? CCDBENCH_CONTACT : CCDBENCH_APART;
  out->toi = static_cast<double>((hash >> 8) % 1000) / 1000.0;
  return;
#endif
#ifdef BROKEN_FIRST_CALLS
  out->outcome = CCDBENCH_CONTACT;
  out->toi = queries_answered <= BROKEN_FIRST_CALLS ? 0.0 : 4.9406564584124654e-324;
  return;
#endif
#ifdef ONE_THREAD
  std::thread::id none{};
  first_thread.compare_exchange_strong(none, std::this_thread::get_id());
  if (first_thread.load() != std::this_thread::get_id()) {
    out->outcome = CCDBENCH_ERROR;
    std::snprintf(out->message, CCDBENCH_MESSAGE_SIZE, "called from a second thread");
    return;
  }
#endif
#ifdef BROKEN_CRASH_ON
  if (queries_answered == BROKEN_CRASH_ON) {
    volatile int* null = nullptr;
    *null = 1;
  }
#endif
#ifdef BROKEN_HANG_ON
  if (queries_answered == BROKEN_HANG_ON) {
    while (true) std::this_thread::sleep_for(std::chrono::seconds(1));
  }
#endif
#ifdef BROKEN_SILENT
  return;
#endif
  out->outcome = CCDBENCH_CONTACT;
#ifdef BROKEN_NAN_TOI
  out->toi = std::nan("");
#else
  out->toi = 0.0;
#endif
}

int begin(void*, const ccdbench_scene* scene, char*) {
  face_count = scene->face_count;
  vertex_count = scene->vertex_count;
  return 0;
}

// The whole step: nothing, or (broken) a face index one past the last.
int step(void*, const ccdbench_step* step, const ccdbench_contacts* contacts, char*) {
  misbehave();
#ifdef BROKEN_WRITES_INPUTS
  double* start = const_cast<double*>(step->x0);
  for (std::size_t i = 0; i < 3 * vertex_count; ++i) start[i] = step->x1[i];
#else
  (void)step;
#endif
#ifdef BROKEN_FACE_RANGE
  contacts->vertex_face(contacts->host, 0, static_cast<std::uint32_t>(face_count), 0.0);
#else
  (void)contacts;
#endif
  return 0;
}

#ifdef BROKEN_ABI
constexpr std::uint32_t kAbi = BROKEN_ABI;
#else
constexpr std::uint32_t kAbi = CCDBENCH_PLUGIN_ABI_VERSION;
#endif

#if defined(ONE_THREAD) || defined(BROKEN_FIRST_CALLS) || defined(BROKEN_ERRORS_LATER)
constexpr std::uint32_t kCapabilities = CCDBENCH_REPORTS_TOI;
#else
constexpr std::uint32_t kCapabilities = CCDBENCH_REPORTS_TOI | CCDBENCH_THREAD_SAFE;
#endif

const ccdbench_plugin table = {sizeof(ccdbench_plugin),
                               kAbi,
                               "broken",
                               "0",
                               "broken on purpose (tests)",
                               kCapabilities,
                               nullptr,
                               0,
                               create,
                               destroy,
                               answer,
                               answer,
                               begin,
                               step,
                               nullptr};

}  // namespace

extern "C" CCDBENCH_PLUGIN_EXPORT const ccdbench_plugin* CCDBENCH_PLUGIN_ENTRY(std::uint32_t) { return &table; }
