// ccdbench: the command line of the harness.

#include "ccd/config.hpp"
#include "core/error.hpp"
#include "harness/cli/cli.hpp"
#include "harness/run/provenance.hpp"
#include "harness/work_queue.hpp"
#include "strategies/plugin/isolation.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <tbb/global_control.h>

#include <algorithm>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <optional>
#include <vector>

namespace {

constexpr const char* kDescription =
    "ccdbench: continuous collision detection of deforming triangle meshes, measured against an exact reference.\n"
    "Every strategy's collision sets are compared with exact truth (rational and algebraic arithmetic), so a\n"
    "reported '0 missed' is a checked statement. Commands print tables for people; --json gives the same for\n"
    "scripts. Bad input (or a bad option) stops with FILE:WHERE: REASON and exit status 2, before anything is\n"
    "written; `check` exits 1 when the gate fails. Under mpirun (mpirun -n N --bind-to none ccdbench ...), run,\n"
    "truth and queries spread their work over the ranks; the output is that of one process (docs/mpi.md).";

/// At most this many worker threads: far beyond any machine this runs on, and small enough that TBB's per-thread
/// state stays a few megabytes (--threads 1e8 would ask it for gigabytes).
constexpr std::size_t kMaxThreads = 1024;

std::string version_text() {
  return std::string("ccdbench ") + CCDBENCH_VERSION + " (" + CCDBENCH_BUILD_TYPE + "; OpenCL " + (CCDBENCH_WITH_OPENCL ? "on" : "off") + ", FCL " +
         (CCDBENCH_WITH_FCL ? "on" : "off") + ", MPI " + (CCDBENCH_WITH_MPI ? "on" : "off") +
         (std::string(CCDBENCH_GUARDS_OFF).empty() ? "" : std::string("; plugin-boundary guards OFF: ") + CCDBENCH_GUARDS_OFF + ", a test build") +
         ")";
}

}  // namespace

int run_command_line(int argc, char** argv);

int main(int argc, char** argv) {
  // A plugin's child process (strategies/plugin/isolation.hpp) answers on its pipes and is no rank of anything:
  // handled before MPI is started, so a crash of the plugin never touches the run's ranks.
  if (argc >= 2 && std::string(argv[1]) == ccd::plugin::kPluginHostCommand) return ccd::plugin::serve_plugin(argc, argv);
  // Under mpirun every rank parses the same command line; rank 0 plans and prints, the others work
  // (harness/work_queue.hpp). A failure that one rank alone sees ends every rank, never leaves them waiting.
  const ccd::harness::RankSession ranks(argc, argv);
  const int status = run_command_line(argc, argv);
  if (status != 0) ccd::harness::RankSession::end_all_ranks(status);
  return status;
}

/// The commands, each added to the app by its own file (harness/cli/).
std::vector<ccd::cli::Command> add_commands(CLI::App& app, ccd::cli::Shared& shared) {
  using namespace ccd::cli;
  return {add_inspect(app), add_queries(app, shared), add_truth(app),      add_stress(app, shared), add_run(app, shared), add_check(app),
          add_compare(app), add_scenes(app),          add_strategies(app), add_devices(app),        add_generate(app)};
}

/// Runs the command parsed, every failure reported as its kind says: bad input and options only the command can
/// judge exit 2, anything else 1.
int run_guarded(const std::function<int()>& command) {
  try {
    return command();
  } catch (const ccd::InputError& error) {
    std::cerr << "ccdbench: error: " << error.what() << '\n';
    return 2;
  } catch (const std::invalid_argument& error) {
    // Options that only the command's own code can judge (an unknown method, a generator parameter).
    return ccd::cli::refuse({}, error.what());
  } catch (const std::filesystem::filesystem_error& error) {
    // A folder that cannot be listed or a path too long: the path and the system's reason, as bad input.
    std::cerr << "ccdbench: error: " << error.path1().string() << ": " << error.code().message() << '\n';
    return 2;
  } catch (const std::bad_alloc&) {
    std::cerr << "ccdbench: error: out of memory: the input or a parameter asks for more than this machine has\n";
    return 2;
  } catch (const std::exception& error) {
    std::cerr << "ccdbench: error: " << error.what() << '\n';
    return 1;
  }
}

int print_version(bool verbose) {
  std::cout << version_text() << '\n';
  if (verbose) {
    const nlohmann::json provenance = ccd::harness::build_provenance();
    for (const auto& [name, value] : provenance.items())
      std::cout << "  " << name << ": " << (value.is_string() ? value.get<std::string>() : value.dump()) << '\n';
  }
  return 0;
}

int run_command_line(int argc, char** argv) {
  CLI::App app(kDescription, "ccdbench");
  bool version = false, verbose = false;
  app.add_flag("--version", version, "print ccdbench's version and which optional parts it was built with");
  app.add_flag("--verbose", verbose,
               "with --version: also the build's provenance, as every result records it (revision, build type and flags,\n"
               "compiler, and the version of every library)");
  app.require_subcommand(0, 1);
  std::size_t threads = 0;
  app.add_option(
         "--threads", threads,
         "worker threads for every command, 1 to " + std::to_string(kMaxThreads) + " (default: all cores); verdicts never depend on it, timings do")
      ->check(CLI::Range(std::size_t{1}, kMaxThreads));
  ccd::cli::Shared shared;
  shared.command_line = "build/release/bin/ccdbench";
  for (int i = 1; i < argc; ++i) shared.command_line += std::string(" ") + argv[i];
  const std::vector<ccd::cli::Command> commands = add_commands(app, shared);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& help) {
    return app.exit(help);
  } catch (const CLI::CallForAllHelp& help) {
    return app.exit(help);
  } catch (const CLI::ParseError& error) {
    return ccd::cli::refuse({}, error.what() + std::string(" (see ccdbench --help)"));
  }
  if (shared.isolate && shared.in_process) return ccd::cli::refuse({}, "--isolate and --in-process say opposite things: give one");
  // Before any plugin's entry is made (its keys' defaults are read then).
  ccd::plugin::set_default_isolation(!shared.in_process);
  if (version) return print_version(verbose);
  const auto parsed = std::find_if(commands.begin(), commands.end(), [](const ccd::cli::Command& command) { return command.app->parsed(); });
  if (parsed == commands.end()) return ccd::cli::refuse({}, "a command is required (see ccdbench --help)");
  std::optional<tbb::global_control> thread_limit;
  if (threads > 0) thread_limit.emplace(tbb::global_control::max_allowed_parallelism, threads);
#if CCDBENCH_GUARD_CHDIR
  // The caches (first used after plugins may have run) by absolute path: a working directory moved by a plugin (a
  // chdir by system call, which no interposer sees) cannot swap them. Outputs and scenes are made absolute by their
  // commands.
  if (const char* cache = std::getenv("CCDBENCH_CACHE_DIR"); cache != nullptr && *cache != '\0') {
    ::setenv("CCDBENCH_CACHE_DIR", std::filesystem::absolute(cache).c_str(), 1);
  }
#endif
  if (ccd::harness::rank_info().size > 1 && !parsed->spread_over_ranks) {
    return ccd::harness::rank_info().rank == 0
               ? ccd::cli::refuse({}, "only run, truth and queries are spread over MPI ranks: run this command without mpirun")
               : 2;
  }
  return run_guarded(parsed->run);
}
