#pragma once
/// @file
/// The `ccdbench` commands behind the command line (main.cpp parses options into these structs).

#include "harness/queries/command.hpp"

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
