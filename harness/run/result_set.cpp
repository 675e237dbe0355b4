#include "harness/run/result_set.hpp"

#include "core/error.hpp"
#include "datasets/atomic_file.hpp"
#include "datasets/input_file.hpp"

#include <fstream>

namespace ccd::harness {

using nlohmann::json;

namespace {

/// Of two summaries of one cell (an --out folder keeps each run's), the later: by finished_at, else the one read last.
bool later(const CellSummary& candidate, const CellSummary& kept) { return candidate.finished_at >= kept.finished_at; }

/// A results.jsonl line's kind ("summary", "step"), or "".
std::string record_kind(const json& record) {
  return record.is_object() && record.contains("record") && record["record"].is_string() ? record["record"].get<std::string>() : "";
}

}  // namespace

std::string steps_key(const std::string& scene, double thickness, const std::string& strategy) {
  return json(scene).dump() + "|" + json(thickness).dump() + "|" + json(strategy).dump();
}

std::vector<CellSummary> read_summaries(const json& document, const std::filesystem::path& file, SummaryUse use) {
  if (!document.is_array()) throw InputError(file, {}, "must be a JSON array of summaries (`run --json`) or a results.jsonl");
  std::vector<CellSummary> summaries;
  for (std::size_t i = 0; i < document.size(); ++i) summaries.push_back(read_summary(document[i], file, "entry " + std::to_string(i), use));
  return summaries;
}

ResultSet read_result_set(const std::filesystem::path& given, SummaryUse use) {
  ResultSet set;
  set.path = given;
  std::filesystem::path file = given;
  if (std::filesystem::is_directory(given)) file = given / kResultsLogFile;
  // A run appends to its --out's results.jsonl under the folder's lock (harness/cell_store.hpp): read between appends.
  const datasets::SharedFileLock between_appends(file.parent_path() / kResultsLockFile);
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file, {}, std::filesystem::is_directory(given) ? "no results.jsonl: not a run's --out folder" : "cannot be read");
  std::vector<CellSummary> summaries;
  if (file.extension() == ".jsonl") {
    std::size_t line_number = 0;
    for (std::string line; std::getline(in, line);) {
      ++line_number;
      if (line.empty()) continue;
      const std::string where = "line " + std::to_string(line_number);
      json record;
      try {
        record = json::parse(line);
      } catch (const json::parse_error& error) {
        // A line without its end is the last, cut short: a run killed while it appended a cell.
        if (in.eof())
          throw InputError(file, where, "cut short (a run was killed while it wrote this line); the next run into its folder rebuilds the log");
        throw InputError(file, where, std::string("not JSON: ") + error.what());
      }
      const std::string kind = record_kind(record);
      if (kind == "summary") {
        summaries.push_back(read_summary(record, file, where, use));
      } else if (kind == "step") {
        StepRecord step = read_step_record(record, file, where);
        const std::size_t index = step.step;
        set.steps[steps_key(step.scene, step.thickness, step.strategy)][index] = std::move(step);
        set.has_steps = true;
      } else {
        throw InputError(file, where, "neither a step record nor a summary of `run`");
      }
    }
  } else {
    summaries = read_summaries(datasets::read_json_file(file, "results file"), file, use);
  }
  if (summaries.empty()) throw InputError(file, {}, "no summary of any cell: nothing to compare (a run that finished no cell?)");
  // One summary per cell (scene, δ, resolved strategy): the latest.
  std::map<std::string, std::size_t> kept;
  for (CellSummary& summary : summaries) {
    const std::string key = steps_key(summary.scene, summary.thickness, summary.strategy);
    const auto it = kept.find(key);
    if (it == kept.end()) {
      kept.emplace(key, set.summaries.size());
      set.summaries.push_back(std::move(summary));
    } else {
      ++set.replaced;
      if (later(summary, set.summaries[it->second])) set.summaries[it->second] = std::move(summary);
    }
  }
  return set;
}

}  // namespace ccd::harness
