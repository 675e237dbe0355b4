#pragma once
/// @file
/// The command line (harness/main.cpp): one file per command, each adding its subcommand to the app and returning
/// what runs it once parsed: options in, the harness's calls, output out.

#include <CLI/CLI.hpp>

#include <filesystem>
#include <functional>
#include <optional>
#include <string>

namespace ccd::cli {

/// What every command shares: where plugins run when their spec does not say, and the command line as typed (for
/// the reports that print the command that made them).
struct Shared {
  bool isolate = false, in_process = false;
  std::string command_line;
};

/// A command of the app: its subcommand, and what runs it when it is the one parsed. Under mpirun only the
/// commands spread over the ranks may run.
struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
  bool spread_over_ranks = false;
};

Command add_inspect(CLI::App& app);
Command add_queries(CLI::App& app, Shared& shared);
Command add_truth(CLI::App& app);
Command add_stress(CLI::App& app, Shared& shared);
Command add_run(CLI::App& app, Shared& shared);
Command add_check(CLI::App& app);
Command add_compare(CLI::App& app);
Command add_scenes(CLI::App& app);
Command add_strategies(CLI::App& app);
Command add_devices(CLI::App& app);
Command add_generate(CLI::App& app);

/// A refusal of the command line, in the same FILE:WHERE: REASON form as bad input; returns exit status 2.
int refuse(const std::string& where, const std::string& reason);

/// --isolate and --in-process on a command that may run plugins.
void add_isolation_flags(CLI::App* command, Shared& shared);

/// An output named by its absolute path before any plugin is loaded (docs/DESIGN.md §10): no working directory a
/// plugin might move to can send results elsewhere.
void make_absolute(std::filesystem::path& output);
void make_absolute(std::optional<std::filesystem::path>& output);

/// Timed passes a command may be asked for.
inline constexpr int kMaxRepeats = 1000;

}  // namespace ccd::cli
