#pragma once
/// @file
/// What `compare` may compare between two summaries of one cell (docs/DESIGN.md §5, "Comparing runs"): verdicts only
/// between cells of the same input (the scene's content, the steps, δ), times only between records of the same
/// machine, thread count, build, executable and library versions. Anything else is not comparable, said on the
/// cell's row, kept out of every verdict and of --fail-on-slower, and makes compare exit 3 unless allowed.

#include "harness/run/records.hpp"

#include <nlohmann/json.hpp>

#include <string>

namespace ccd::harness {

/// Why the verdicts of two summaries of one cell are not of the same input, in words ("the scene's content differs
/// (...)"), or "" when they are. A summary that does not say what its input was (no `key`) cannot be compared.
std::string inputs_differ(const CellSummary& base, const CellSummary& head);

/// Why the times of two summaries may not be compared ("the thread count differs (2, 1)"), or "" when they may: the machine,
/// the thread count, the build type, the executable's digest and every library version in `provenance` but those
/// naming the code under audit (a plugin's name, digest and objects, which a comparison of two builds changes).
std::string times_differ(const CellSummary& base, const CellSummary& head);

}  // namespace ccd::harness
