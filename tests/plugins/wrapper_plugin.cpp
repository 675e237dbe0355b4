// A thin wrapper around a CCD library of its own (wrapper_dependency.cpp), as users write plugins: the answers come
// from the library, which the wrapper links and finds beside itself ($ORIGIN). Rebuilding the library changes what
// the plugin answers without changing the wrapper's file: the digest of a plugin's code must cover it
// (tests/plugins/boundary_test.cpp, docs/DESIGN.md §10 "Identity").
#include <ccdbench/ccdbench_plugin.h>

#include <cstdint>

extern "C" int ccdbench_test_dependency_answer();

namespace {

int context_token = 0;

void* create(const char* const*, char*) { return &context_token; }
void destroy(void*) {}

/// The library's answer for every query: contact at the start of the step (it finds every contact), or apart.
void answer(void*, const double*, double, ccdbench_answer* out) {
  out->outcome = ccdbench_test_dependency_answer() == 1 ? CCDBENCH_CONTACT : CCDBENCH_APART;
  out->toi = 0.0;
}

const ccdbench_plugin table = {sizeof(ccdbench_plugin),
                               CCDBENCH_PLUGIN_ABI_VERSION,
                               "wrapper",
                               "0",
                               "a wrapper whose answers come from the library it links (tests)",
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
