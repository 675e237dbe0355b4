// A plugin whose answers depend on what its digest does not cover (docs/DESIGN.md §10 "Kept cells"), one build per
// cause (tests/plugins/CMakeLists.txt). It answers every query "contact at t = 0" (conservative, never late: it misses
// nothing) unless its cause says to miss, and then "apart" (it misses every colliding pair); its file and the
// libraries it links are the same bytes either way:
//   OUTSIDE_ENVIRONMENT  the environment variable CCDBENCH_TEST_MISS is set;
//   OUTSIDE_FILE         a file named `miss` lies beside the plugin;
//   OUTSIDE_OPENED       the library it opens itself in create, libbroken_dependency.so beside it (one of the two
//                        builds of wrapper_dependency.cpp), answers 0.
// Each reads its cause in create. The fourth cause, LD_PRELOAD of a library that interposes a symbol of one the
// plugin links, needs no build of its own: the wrapper plugin (wrapper_plugin.cpp) with the other build of its
// library preloaded.
#include <ccdbench/ccdbench_plugin.h>

#include <dlfcn.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

namespace {

bool misses = false;

/// The path of a file in the folder this plugin was loaded from.
std::string beside_self(const char* name) {
  Dl_info self{};
  if (::dladdr(reinterpret_cast<void*>(&beside_self), &self) == 0 || self.dli_fname == nullptr) return name;
  const std::string path = self.dli_fname;
  const std::size_t slash = path.rfind('/');
  return (slash == std::string::npos ? std::string() : path.substr(0, slash + 1)) + name;
}

void* create(const char* const*, char* error) {
#if defined(OUTSIDE_ENVIRONMENT)
  misses = std::getenv("CCDBENCH_TEST_MISS") != nullptr;
#elif defined(OUTSIDE_FILE)
  misses = std::ifstream(beside_self("miss")).good();
#elif defined(OUTSIDE_OPENED)
  void* library = ::dlopen(beside_self("libbroken_dependency.so").c_str(), RTLD_NOW | RTLD_LOCAL);
  const auto answer = library ? reinterpret_cast<int (*)()>(::dlsym(library, "ccdbench_test_dependency_answer")) : nullptr;
  if (answer == nullptr) {
    std::snprintf(error, CCDBENCH_MESSAGE_SIZE, "cannot open libbroken_dependency.so beside the plugin");
    return nullptr;
  }
  misses = answer() == 0;
#else
#error "build with one of OUTSIDE_ENVIRONMENT, OUTSIDE_FILE, OUTSIDE_OPENED"
#endif
  (void)error;
  return &misses;
}

void destroy(void*) {}

void answer(void*, const double*, double, ccdbench_answer* out) {
  out->outcome = misses ? CCDBENCH_APART : CCDBENCH_CONTACT;
  out->toi = 0.0;
}

const ccdbench_plugin table = {sizeof(ccdbench_plugin),
                               CCDBENCH_PLUGIN_ABI_VERSION,
                               "outside-inputs",
                               "0",
                               "answers that depend on what its digest does not cover (tests)",
                               CCDBENCH_REPORTS_TOI | CCDBENCH_THREAD_SAFE,
                               nullptr,
                               0,
                               create,
                               destroy,
                               answer,
                               answer,
                               nullptr,
                               nullptr,
                               nullptr};

}  // namespace

extern "C" CCDBENCH_PLUGIN_EXPORT const ccdbench_plugin* CCDBENCH_PLUGIN_ENTRY(std::uint32_t) { return &table; }
