#include "harness/run/record_fields.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace ccd::harness {

using nlohmann::json;

namespace {

/// What a field of a record must be.
enum class FieldKind {
  string,
  number,
  real,
  count,
  numbers,
  object,
  boolean,
  number_or_null,
  string_or_null,
  numbers_by_name,
  counts_by_name,
  counters
};

struct RecordField {
  const char* name;
  FieldKind kind;
  bool required;
  /// Required when the summary is read for compare (its time), optional for the gate.
  bool compared = false;
};

/// The fields of a record's environment (RecordEnvironment), in every step record and summary.
const std::vector<RecordField> kEnvironmentFields = {{"machine", FieldKind::string, false},      {"build_type", FieldKind::string, false},
                                                     {"git_revision", FieldKind::string, false}, {"executable", FieldKind::string, false},
                                                     {"provenance", FieldKind::object, false},   {"threads", FieldKind::count, false},
                                                     {"rank", FieldKind::count, false},          {"schema", FieldKind::count, false}};

/// The counts of a verdict (VerdictCounts), in a step record and in a summary.
const std::vector<RecordField> kVerdictFields = {{"colliding", FieldKind::count, false},        {"missed", FieldKind::count, false},
                                                 {"missed_culled", FieldKind::count, false},    {"missed_tested", FieldKind::count, false},
                                                 {"false_alarms", FieldKind::count, false},     {"colliding_face_shape", FieldKind::count, false},
                                                 {"missed_face_shape", FieldKind::count, false}};

/// Every field of a summary that its reader reads (records.cpp from_json) beside its verdict's counts and its
/// environment, checked before it reads them: a reader then never meets a field of another kind. Its identity and
/// step count are required.
const std::vector<RecordField> kSummaryFields = {{"scene", FieldKind::string, true},
                                                 {"strategy", FieldKind::string, true},
                                                 {"thickness", FieldKind::number, true},
                                                 {"thickness_from", FieldKind::string, true},
                                                 {"steps", FieldKind::count, true},
                                                 {"ms_per_step", FieldKind::number, false, true},
                                                 {"spec", FieldKind::string, false},
                                                 {"triangles", FieldKind::count, false},
                                                 {"vertices", FieldKind::count, false},
                                                 {"ms_per_step_mean", FieldKind::number, false},
                                                 // A step's time less its stages' can be below 0 by the clocks' grain.
                                                 {"unattributed_ms_mean", FieldKind::real, false},
                                                 {"setup_ms", FieldKind::number, false},
                                                 {"ms_per_repeat", FieldKind::numbers, false},
                                                 {"stage_ms", FieldKind::numbers_by_name, false},
                                                 {"stage_ms_mean", FieldKind::numbers_by_name, false},
                                                 {"counters", FieldKind::counters, false},
                                                 {"candidate_pairs", FieldKind::number, false},
                                                 {"elementary_tests", FieldKind::number, false},
                                                 {"kept_bytes", FieldKind::number, false},
                                                 {"history_bytes", FieldKind::number, false},
                                                 {"device_bytes", FieldKind::number, false},
                                                 {"host_peak_bytes", FieldKind::number, false},
                                                 {"host_peak_of", FieldKind::string, false},
                                                 {"child_peak_bytes", FieldKind::number, false},
                                                 {"reported", FieldKind::count, false},
                                                 {"judged_by", FieldKind::string, false},
                                                 {"verified", FieldKind::boolean, false},
                                                 {"repeats", FieldKind::count, false},
                                                 {"cell", FieldKind::string, false},
                                                 {"miss_causes", FieldKind::counts_by_name, false},
                                                 {"colliding_by_objects", FieldKind::counts_by_name, false},
                                                 {"faces_in_contact_by_objects", FieldKind::counts_by_name, false},
                                                 {"errors", FieldKind::count, false},
                                                 {"errors_written", FieldKind::string, false},
                                                 {"toi_checked", FieldKind::count, false},
                                                 {"toi_late", FieldKind::count, false},
                                                 {"toi_missing", FieldKind::count, false},
                                                 {"toi_error_max", FieldKind::number_or_null, false},
                                                 {"toi_error_mean", FieldKind::number_or_null, false},
                                                 {"toi_error_median", FieldKind::number_or_null, false},
                                                 {"toi_error_p99", FieldKind::number_or_null, false},
                                                 {"nondeterministic_at_step", FieldKind::count, false},
                                                 {"resumed", FieldKind::boolean, false},
                                                 {"interleave_group", FieldKind::string, false},
                                                 {"key", FieldKind::object, false},
                                                 {"finished_at", FieldKind::string, false},
                                                 {"speedup", FieldKind::number_or_null, false},
                                                 {"speedup_over", FieldKind::string_or_null, false}};

/// Every field of a step record that its reader reads beside its verdict's counts and its environment, but its
/// strategy's counters (every other field: numbers).
const std::vector<RecordField> kStepFields = {{"scene", FieldKind::string, true},
                                              {"thickness", FieldKind::number, true},
                                              {"strategy", FieldKind::string, true},
                                              {"step", FieldKind::count, true},
                                              {"ms", FieldKind::number, false},
                                              {"ms_repeats", FieldKind::numbers, false},
                                              {"stages", FieldKind::numbers_by_name, false},
                                              {"candidate_pairs", FieldKind::count, false},
                                              {"elementary_tests", FieldKind::count, false},
                                              {"kept_bytes", FieldKind::count, false},
                                              {"history_bytes", FieldKind::count, false},
                                              {"device_bytes", FieldKind::count, false},
                                              {"reported", FieldKind::count, false},
                                              {"answers", FieldKind::string, false},
                                              {"errors", FieldKind::count, false},
                                              {"error_first", FieldKind::string, false},
                                              {"toi_checked", FieldKind::count, false},
                                              {"toi_late", FieldKind::count, false},
                                              {"toi_error_max", FieldKind::number, false}};

bool has_kind(const json& value, FieldKind kind) {
  const auto all_of = [&](FieldKind each) { return std::all_of(value.begin(), value.end(), [&](const json& v) { return has_kind(v, each); }); };
  switch (kind) {
    case FieldKind::string: return value.is_string();
    case FieldKind::number: return value.is_number() && std::isfinite(value.get<double>()) && value.get<double>() >= 0;
    case FieldKind::real: return value.is_number() && std::isfinite(value.get<double>());
    // Read from text a count is unsigned; a record made in memory may hold it signed.
    case FieldKind::count: return value.is_number_unsigned() || (value.is_number_integer() && value.get<std::int64_t>() >= 0);
    case FieldKind::numbers: return value.is_array() && all_of(FieldKind::number);
    case FieldKind::object: return value.is_object();
    case FieldKind::boolean: return value.is_boolean();
    case FieldKind::number_or_null: return value.is_null() || has_kind(value, FieldKind::number);
    case FieldKind::string_or_null: return value.is_null() || value.is_string();
    case FieldKind::numbers_by_name: return value.is_object() && all_of(FieldKind::number);
    case FieldKind::counts_by_name: return value.is_object() && all_of(FieldKind::count);
    case FieldKind::counters:
      return value.is_object() && std::all_of(value.begin(), value.end(), [](const json& c) {
               return c.is_object() && c.contains("mean") && c.contains("max") && has_kind(c["mean"], FieldKind::real) &&
                      has_kind(c["max"], FieldKind::real);
             });
  }
  return false;
}

const char* kind_name(FieldKind kind) {
  switch (kind) {
    case FieldKind::string: return "a string";
    case FieldKind::number: return "a finite number >= 0";
    case FieldKind::real: return "a finite number";
    case FieldKind::count: return "an integer >= 0";
    case FieldKind::numbers: return "an array of finite numbers >= 0";
    case FieldKind::object: return "an object";
    case FieldKind::boolean: return "true or false";
    case FieldKind::number_or_null: return "a finite number >= 0 or null";
    case FieldKind::string_or_null: return "a string or null";
    case FieldKind::numbers_by_name: return "an object of finite numbers >= 0";
    case FieldKind::counts_by_name: return "an object of integers >= 0";
    case FieldKind::counters: return "an object of {mean, max} finite numbers";
  }
  return "";
}

void check_fields(const json& record, const std::vector<RecordField>& fields, bool compared, const std::filesystem::path& file,
                  const std::string& where, const char* what) {
  if (!record.is_object()) throw InputError(file, where, std::string("a ") + what + " must be an object");
  for (const std::vector<RecordField>* list : {&fields, &kVerdictFields, &kEnvironmentFields}) {
    for (const RecordField& field : *list) {
      if (!record.contains(field.name)) {
        if (field.required || (compared && field.compared))
          throw InputError(file, where, std::string("a ") + what + " without '" + field.name + "': not a result of `run`");
        continue;
      }
      if (!has_kind(record[field.name], field.kind)) {
        throw InputError(file, where + "." + field.name, std::string("must be ") + kind_name(field.kind) + ", got " + record[field.name].dump());
      }
    }
  }
}

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

/// The record read by its one reader; what that reader refuses (a field of another kind than the reader takes) is
/// the file's error.
template <class Record>
Record read(const json& record, const std::filesystem::path& file, const std::string& where, const char* what) {
  try {
    return record.get<Record>();
  } catch (const json::exception& error) {
    throw InputError(file, where, std::string("not a ") + what + " of `run`: " + error.what());
  } catch (const std::invalid_argument& error) {
    throw InputError(file, where, std::string("not a ") + what + " of `run`: " + error.what());
  }
}

}  // namespace

CellSummary read_summary(const json& record, const std::filesystem::path& file, const std::string& where, SummaryUse use) {
  check_fields(record, kSummaryFields, use == SummaryUse::compare, file, where, "summary");
  return read<CellSummary>(record, file, where, "summary");
}

StepRecord read_step_record(const json& record, const std::filesystem::path& file, const std::string& where) {
  check_fields(record, kStepFields, false, file, where, "step record");
  check_missed_pairs(record, file, where);
  return read<StepRecord>(record, file, where, "step record");
}

CellRecord read_cell_record(const json& cell, const std::filesystem::path& file) { return read<CellRecord>(cell, file, {}, "cell"); }

}  // namespace ccd::harness
