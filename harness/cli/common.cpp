#include "ccd/config.hpp"
#include "harness/cli/cli.hpp"

#include <iostream>

namespace ccd::cli {

int refuse(const std::string& where, const std::string& reason) {
  std::cerr << "ccdbench: error: command line:" << where << (where.empty() ? " " : ": ") << reason << '\n';
  return 2;
}

void add_isolation_flags(CLI::App* command, Shared& shared) {
  command->add_flag("--isolate", shared.isolate,
                    "run every plugin whose spec does not say isolate=off in a child process (the default): a crash, an\n"
                    "exit or a hang is that query's or step's error, and the run goes on");
  command->add_flag("--in-process", shared.in_process,
                    "run every plugin whose spec does not say isolate=on inside ccdbench (faster for tiny queries; a\n"
                    "crash ends the run, an exit or a hang past timeout= ends it with status 1: docs/audit.md)");
}

void make_absolute(std::filesystem::path& output) {
#if CCDBENCH_GUARD_CHDIR
  output = std::filesystem::absolute(output);
#else
  (void)output;
#endif
}

void make_absolute(std::optional<std::filesystem::path>& output) {
  if (output) make_absolute(*output);
}

}  // namespace ccd::cli
