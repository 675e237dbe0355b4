// The template's method (examples/plugin/my_ccd.cpp) as a change might slow it down: the same answers, every call
// taking CCDBENCH_TEST_SLOWDOWN times as long (default 1.25; it spins after the call for the time the call took times
// the factor less one). Every call: each query (`queries`, `run --strategy full+plugin:...`) and each whole step
// (`run --strategy plugin:...`), so that the strategy `plugin:` is that much slower as a whole, not only its share
// of a step. What the time verdict of `compare` must flag (scripts/time-verdicts.sh counts how often it does, and
// how often it flags two runs of the same code). Built under the template's plugin name: a rebuild of the user's
// method, not another method.
#include <ccdbench/ccdbench_plugin.hpp>

#include <chrono>
#include <cstdlib>

// The template's plugin, built as it is, under another entry point: this file's entry hands out its table with each
// call slowed.
#undef CCDBENCH_PLUGIN_ENTRY
#define CCDBENCH_PLUGIN_ENTRY ccdbench_template_entry
#include "examples/plugin/my_ccd.cpp"
#undef CCDBENCH_PLUGIN_ENTRY
#define CCDBENCH_PLUGIN_ENTRY ccdbench_plugin_init_v1

namespace {

/// The factor every call's time is multiplied by, read once.
double slowdown() {
  static const double factor = [] {
    const char* text = std::getenv("CCDBENCH_TEST_SLOWDOWN");
    return text && *text ? std::atof(text) : 1.25;
  }();
  return factor;
}

/// Runs `call`, then spins until it has taken slowdown() times its own time.
template <class Call>
auto slowed(Call&& call) {
  const auto start = std::chrono::steady_clock::now();
  const auto answer = call();
  const auto took = std::chrono::steady_clock::now() - start;
  const auto until = start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(took * slowdown());
  while (std::chrono::steady_clock::now() < until) {
  }
  return answer;
}

const ccdbench_plugin& template_table() { return *ccdbench_template_entry(CCDBENCH_PLUGIN_ABI_VERSION); }

void slowed_vertex_face(void* context, const double* rows, double thickness, ccdbench_answer* answer) {
  slowed([&] {
    template_table().vertex_face(context, rows, thickness, answer);
    return 0;
  });
}

void slowed_edge_edge(void* context, const double* rows, double thickness, ccdbench_answer* answer) {
  slowed([&] {
    template_table().edge_edge(context, rows, thickness, answer);
    return 0;
  });
}

int slowed_step(void* context, const struct ccdbench_step* step, const ccdbench_contacts* contacts, char* error) {
  return slowed([&] { return template_table().step(context, step, contacts, error); });
}

const ccdbench_plugin slowed_table = [] {
  ccdbench_plugin table = template_table();
  table.vertex_face = slowed_vertex_face;
  table.edge_edge = slowed_edge_edge;
  table.step = slowed_step;
  return table;
}();

}  // namespace

extern "C" CCDBENCH_PLUGIN_EXPORT const ccdbench_plugin* CCDBENCH_PLUGIN_ENTRY(uint32_t host_abi_version) {
  return host_abi_version == CCDBENCH_PLUGIN_ABI_VERSION ? &slowed_table : nullptr;
}
