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
#include <ccdbench/ccdbench_plugin.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <thread>

namespace {

int queries_answered = 0;
std::size_t face_count = 0;

void* create(const char* const*, char*) { return &queries_answered; }
void destroy(void*) {}

#ifdef ONE_THREAD
std::atomic<std::thread::id> first_thread{};
#endif

void answer(void*, const double*, double, ccdbench_answer* out) {
  ++queries_answered;
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
  return 0;
}

// The whole step: nothing, or (broken) a face index one past the last.
int step(void*, const ccdbench_step*, const ccdbench_contacts* contacts, char*) {
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

#ifdef ONE_THREAD
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
