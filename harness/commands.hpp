#pragma once
/// @file
/// The `ccdbench` commands behind the command line (main.cpp parses options into these structs).

#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

namespace ccd::harness {

struct InspectOptions {
  std::vector<std::filesystem::path> paths;
  bool json = false;
};
int run_inspect(const InspectOptions& options, std::ostream& out);

struct QueriesOptions {
  std::vector<std::filesystem::path> paths;
  std::vector<std::string> methods{"exact"};
  double thickness = 0.0;
  int repeats = 1;
  std::optional<std::filesystem::path> json;
  /// Vary each narrow phase's accuracy parameter (see sweep_methods).
  bool sweep = false;
  /// Also score the extremes suite (labelled by the reference at zero thickness) as one more data set.
  bool extremes = false;
  /// Score files without truth labels (their FN and FP are unknown, shown as '-'); otherwise such a file is an error.
  bool allow_unlabelled = false;
  /// Compare TOIs with the exact earliest contact.
  bool toi = false;
  /// Rescale every query (and δ) by 2^scale_exponent first.
  int scale_exponent = 0;
  /// Write README.md and scores.json into this folder, with `command_line` above the table.
  std::optional<std::filesystem::path> report;
  /// Write every method's answers as an answer file (query_answers.hpp).
  std::optional<std::filesystem::path> write_answers;
  /// Where queries without an answer (faults) are written as query files.
  std::filesystem::path faults = "ccdbench-faults";
  std::string command_line;
};
/// Scores every method on every discovered query file; prints a table. Exit status 0.
int run_queries(const QueriesOptions& options, std::ostream& out);

struct TruthOptions {
  /// Exactly one source: two frame files, a scene file and step, or a sample step folder.
  std::vector<std::filesystem::path> frames;
  std::optional<std::filesystem::path> scene;
  std::size_t step = 0;
  /// With a scene: steps step .. step+steps-1 (0: to the last), one work item each (spread over MPI ranks), each
  /// step's truth also stored in the truth cache that `run` reads.
  std::size_t steps = 1;
  std::optional<std::filesystem::path> sample;
  std::optional<double> thickness;
  bool toi = false;
  std::optional<std::filesystem::path> json;
};
/// Whole-step truth with counts and statistics; with a sample step, also the comparison with its truth.
int run_truth(const TruthOptions& options, std::ostream& out);

struct StressOptions {
  /// Narrow-phase specs (main.cpp's default: every narrow phase of the registry).
  std::vector<std::string> methods;
  std::uint64_t seed = 1;
  /// Only these families of the suite (empty: every family).
  std::vector<std::string> families;
  std::optional<std::filesystem::path> json;
  std::optional<std::filesystem::path> write_queries;
};
/// Runs the narrow phases on the extremes suite and prints family x variant -> false negatives and positives.
int run_stress_command(const StressOptions& options, std::ostream& out);

/// Lists the built-in procedural scenes with their parameters and defaults.
int run_scenes(std::ostream& out);

/// `ccdbench devices`: the OpenCL platforms and devices (index, name, compute units, memory, fp64), as a table or
/// as JSON lines (one object per device). Exit 2 when this build has no OpenCL.
int run_devices(bool json, std::ostream& out);

struct GenerateOptions {
  std::string name;
  std::optional<double> resolution, frames, seed, first_frame;
  /// Any scene parameter as NAME=VALUE.
  std::vector<std::string> settings;
  std::filesystem::path out;
  /// Print the scene's per-frame measurements.
  bool report = false;
};
/// Simulates a built-in scene into a folder (or finds it there already, generated with the same parameters).
int run_generate(const GenerateOptions& options, std::ostream& out);

}  // namespace ccd::harness
