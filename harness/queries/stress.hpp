#pragma once
/// @file
/// `ccdbench stress`: every narrow-phase variant on the extremes suite, labelled by the exact reference, at δ = 0
/// and at each case's δ > 0.

#include "datasets/extremes_suite.hpp"

#include <nlohmann/json_fwd.hpp>

#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

namespace ccd::harness {

struct StressRow {
  std::string family;
  std::string method;
  /// "zero" or "positive" (each case's own δ > 0).
  std::string thickness;
  std::size_t queries = 0;
  std::size_t positives = 0;
  std::size_t false_negatives = 0;
  std::size_t false_positives = 0;
  /// Cases the method gave no answer to (a plugin's error, crash or hang): counted apart, and for FN and FP as the
  /// plugin's `errors` key says.
  std::size_t errors = 0;
  /// Names of the missed cases (for the regression library), at most 10.
  std::vector<std::string> missed;
};

nlohmann::json to_json(const StressRow& row);

/// Runs `methods` (narrow-phase specs) on the suite; one row per family x method x thickness pass, then one
/// "(all)" row per method x pass.
std::vector<StressRow> run_stress(const std::vector<datasets::ExtremeQuery>& suite, const std::vector<std::string>& methods);

void print_stress(const std::vector<StressRow>& rows, std::ostream& out);

/// The suite as two in-memory query files ("extremes-suite/vertex-face", ".../edge-edge") with the reference's
/// zero-thickness truth.
std::vector<datasets::QueryFile> extremes_query_files(const std::vector<datasets::ExtremeQuery>& suite);

/// Writes the suite as rational query files (DIR/vertex-face/extremes.csv, DIR/edge-edge/extremes.csv) with the
/// zero-thickness truth of the reference in column 7, so any tool can be scored on it.
void write_extremes_queries(const std::vector<datasets::ExtremeQuery>& suite, const std::filesystem::path& directory);

}  // namespace ccd::harness
