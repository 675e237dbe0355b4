#include "harness/run/result_set.hpp"

#include "core/error.hpp"
#include "datasets/input_file.hpp"
#include "harness/run/record_fields.hpp"

#include <cmath>
#include <fstream>

namespace ccd::harness {

using nlohmann::json;

namespace {

/// Every field compare reads, checked before anything is compared or written (run/record_fields.hpp).
const std::vector<RecordField> kSummaryFields = {{"scene", FieldKind::string, true},
                                                 {"strategy", FieldKind::string, true},
                                                 {"thickness", FieldKind::number, true},
                                                 {"thickness_from", FieldKind::string, true},
                                                 {"steps", FieldKind::count, true},
                                                 {"ms_per_step", FieldKind::number, true},
                                                 {"spec", FieldKind::string, false},
                                                 {"ms_per_repeat", FieldKind::numbers, false},
                                                 {"missed", FieldKind::count, false},
                                                 {"errors", FieldKind::count, false},
                                                 {"toi_late", FieldKind::count, false},
                                                 {"false_alarms", FieldKind::count, false},
                                                 {"colliding", FieldKind::count, false},
                                                 {"verified", FieldKind::boolean, false},
                                                 {"host_peak_bytes", FieldKind::number, false},
                                                 {"device_bytes", FieldKind::number, false},
                                                 {"toi_error_max", FieldKind::number_or_null, false},
                                                 {"toi_error_median", FieldKind::number_or_null, false},
                                                 {"toi_error_p99", FieldKind::number_or_null, false},
                                                 {"nondeterministic_at_step", FieldKind::count, false},
                                                 {"key", FieldKind::object, false},
                                                 {"finished_at", FieldKind::string, false},
                                                 {"machine", FieldKind::string, false},
                                                 {"build_type", FieldKind::string, false},
                                                 {"provenance", FieldKind::object, false}};

const std::vector<RecordField> kStepFields = {{"scene", FieldKind::string, true},
                                              {"thickness", FieldKind::number, true},
                                              {"strategy", FieldKind::string, true},
                                              {"step", FieldKind::count, true},
                                              {"answers", FieldKind::string, false},
                                              {"missed", FieldKind::count, false},
                                              {"missed_face_shape", FieldKind::count, false}};

/// A kept missed pair: {kind: "vf" (ids v, f) or "ee" (ids a0, a1, b0, b1), rows: its 24 coordinates}.
void check_missed_pairs(const json& record, const std::filesystem::path& file, const std::string& where) {
  if (!record.contains("missed_pairs")) return;
  const json& pairs = record["missed_pairs"];
  if (!pairs.is_array()) throw InputError(file, where + ".missed_pairs", "must be an array");
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const json& pair = pairs[i];
    const std::string at = where + ".missed_pairs[" + std::to_string(i) + "]";
    const bool vf = pair.is_object() && pair.value("kind", "") == "vf", ee = pair.is_object() && pair.value("kind", "") == "ee";
    if (!vf && !ee) throw InputError(file, at, "must be an object of kind \"vf\" or \"ee\"");
    const json& ids = pair.contains("ids") ? pair["ids"] : json();
    if (!ids.is_array() || ids.size() != (vf ? 2u : 4u) ||
        !std::all_of(ids.begin(), ids.end(), [](const json& id) { return id.is_number_unsigned(); })) {
      throw InputError(file, at + ".ids", std::string("must be ") + (vf ? "2" : "4") + " integers >= 0");
    }
    const json& rows = pair.contains("rows") ? pair["rows"] : json();
    if (!rows.is_array() || rows.size() != 24 ||
        !std::all_of(rows.begin(), rows.end(), [](const json& v) { return v.is_number() && std::isfinite(v.get<double>()); })) {
      throw InputError(file, at + ".rows", "must be 24 finite numbers");
    }
  }
}

/// Of two summaries of one cell (an --out folder keeps each run's), the later: by finished_at, else the one read last.
bool later(const json& candidate, const json& kept) { return candidate.value("finished_at", "") >= kept.value("finished_at", ""); }

}  // namespace

std::string steps_key(const json& record) { return record["scene"].dump() + "|" + record["thickness"].dump() + "|" + record["strategy"].dump(); }

ResultSet read_result_set(const std::filesystem::path& given) {
  ResultSet set;
  set.path = given;
  std::filesystem::path file = given;
  if (std::filesystem::is_directory(given)) file = given / "results.jsonl";
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file, {}, std::filesystem::is_directory(given) ? "no results.jsonl: not a run's --out folder" : "cannot be read");
  std::vector<json> summaries;
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
        throw InputError(file, where, std::string("not JSON: ") + error.what());
      }
      const std::string kind =
          record.is_object() && record.contains("record") && record["record"].is_string() ? record["record"].get<std::string>() : "";
      if (kind == "summary") {
        check_record_fields(record, kSummaryFields, file, where, "summary");
        summaries.push_back(std::move(record));
      } else if (kind == "step") {
        check_record_fields(record, kStepFields, file, where, "step record");
        check_missed_pairs(record, file, where);
        const std::string key = steps_key(record);
        const std::size_t step = record["step"].get<std::size_t>();
        set.steps[key][step] = std::move(record);
        set.has_steps = true;
      } else {
        throw InputError(file, where, "neither a step record nor a summary of `run`");
      }
    }
  } else {
    const json document = datasets::read_json_file(file, "results file");
    if (!document.is_array()) throw InputError(file, {}, "must be a JSON array of summaries (`run --json`) or a results.jsonl");
    for (std::size_t i = 0; i < document.size(); ++i) {
      check_record_fields(document[i], kSummaryFields, file, "entry " + std::to_string(i), "summary");
      summaries.push_back(document[i]);
    }
  }
  if (summaries.empty()) throw InputError(file, {}, "no summary of any cell: nothing to compare (a run that finished no cell?)");
  // One summary per cell (scene, δ, resolved strategy): the latest.
  std::map<std::string, std::size_t> kept;
  for (json& summary : summaries) {
    const std::string key = steps_key(summary);
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
