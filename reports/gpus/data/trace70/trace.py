# Applies the phase trace (stderr "trace R EPOCH_MS EVENT") to a source tree: a probe build only, never committed.
import re, sys
root = sys.argv[1]
def patch(path, old, new, count=1):
    p = root + "/" + path
    s = open(p).read()
    assert s.count(old) >= 1, (path, old)
    s = s.replace(old, new, count)
    open(p, "w").write(s)
helper = '''
#include <chrono>
#include <cstdio>
#include <unistd.h>
namespace ccd_trace {
inline void at(const char* event, const std::string& what = {}) {
  const long long ms = std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  std::fprintf(stderr, "trace %d %lld.%03lld %s %s\\n", (int)::getpid(), ms / 1000, ms % 1000, event, what.c_str());
}
}
'''
patch("harness/work_queue.hpp", "namespace ccd::harness {", helper + "namespace ccd::harness {")
patch("harness/main.cpp", "  const ccd::harness::RankSession ranks(argc, argv);", "  ccd_trace::at(\"main\");\n  const ccd::harness::RankSession ranks(argc, argv);\n  ccd_trace::at(\"mpi-init\");")
patch("harness/run.cpp", "  const DeviceWarmUp warm_up(options_.strategies);  // while rank 0 plans every scene\n  plan_every_scene();",
      "  const DeviceWarmUp warm_up(options_.strategies);  // while rank 0 plans every scene\n  ccd_trace::at(\"plan-start\");\n  plan_every_scene();\n  ccd_trace::at(\"plan-end\");")
patch("harness/run.cpp", "  SceneData& data = store_.get(task.at(\"scene\").get<std::size_t>());",
      "  ccd_trace::at(\"item-start\", task.value(\"spec\", std::string()) + \" \" + std::to_string(task.at(\"scene\").get<std::size_t>()));\n  SceneData& data = store_.get(task.at(\"scene\").get<std::size_t>());\n  ccd_trace::at(\"loaded\");")
patch("harness/run.cpp", "    return json(run_cell(data, spec_named(task.at(\"spec\")), options_, data.steps, task.at(\"file\"), progress, task.at(\"strategy\"))).dump();",
      "    auto record = run_cell(data, spec_named(task.at(\"spec\")), options_, data.steps, task.at(\"file\"), progress, task.at(\"strategy\"));\n    ccd_trace::at(\"cell-done\", std::to_string(record.summary.setup_ms) + \" \" + std::to_string(record.summary.ms_per_step_mean * record.summary.steps));\n    std::string text = json(record).dump();\n    ccd_trace::at(\"dumped\", std::to_string(text.size()));\n    return text;")
patch("harness/run.cpp", "void Benchmark::item_done(std::size_t index, const std::string& text, int rank) {",
      "void Benchmark::item_done(std::size_t index, const std::string& text, int rank) {\n  ccd_trace::at(\"done-recv\", std::to_string(rank));\n  struct TraceEnd { ~TraceEnd() { ccd_trace::at(\"done-written\"); } } trace_end;")
patch("harness/run.cpp", "  distribute(items_, work(), done);\n  say_on_termination({});\n  results_log_.finish(std::cerr);",
      "  distribute(items_, work(), done);\n  ccd_trace::at(\"distributed\");\n  say_on_termination({});\n  results_log_.finish(std::cerr);\n  ccd_trace::at(\"log-finished\");")
patch("harness/run.cpp", "    const DeviceWarmUp warm_up(options.strategies);  // while rank 0 plans\n    distribute({}, benchmark.work(), {});",
      "    const DeviceWarmUp warm_up(options.strategies);  // while rank 0 plans\n    ccd_trace::at(\"serve-start\");\n    distribute({}, benchmark.work(), {});\n    ccd_trace::at(\"served\");")
patch("harness/run.cpp", "        for (const strategies::StrategySpec& spec : specs) {\n            const auto backend",
      "        struct W { ~W() { ccd_trace::at(\"warm-done\"); } } w;\n        for (const strategies::StrategySpec& spec : specs) {\n            const auto backend")
patch("harness/work_queue.cpp", "RankSession::~RankSession() {\n#if CCDBENCH_WITH_MPI\n  if (g_mpi_started) MPI_Finalize();",
      "RankSession::~RankSession() {\n#if CCDBENCH_WITH_MPI\n  ccd_trace::at(\"finalize\");\n  if (g_mpi_started) MPI_Finalize();\n  ccd_trace::at(\"finalized\");")
print("patched", root)
