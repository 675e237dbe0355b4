#include "harness/run/record_fields.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace ccd::harness {

using nlohmann::json;

namespace {

/// What a field of a record must be.
enum class FieldKind { string, number, count, numbers, object, boolean, number_or_null };

struct RecordField {
  const char* name;
  FieldKind kind;
  bool required;
  /// Required when the summary is read for compare (its steps and time), optional for the gate.
  bool compared = false;
};

/// Every field of a summary that check or compare reads, checked before its reader reads it.
const std::vector<RecordField> kSummaryFields = {{"scene", FieldKind::string, true},
                                                 {"strategy", FieldKind::string, true},
                                                 {"thickness", FieldKind::number, true},
                                                 {"thickness_from", FieldKind::string, true},
                                                 {"steps", FieldKind::count, false, true},
                                                 {"ms_per_step", FieldKind::number, false, true},
                                                 {"spec", FieldKind::string, false},
                                                 {"ms_per_repeat", FieldKind::numbers, false},
                                                 {"verified", FieldKind::boolean, false},
                                                 {"colliding", FieldKind::count, false},
                                                 {"missed", FieldKind::count, false},
                                                 {"missed_culled", FieldKind::count, false},
                                                 {"missed_tested", FieldKind::count, false},
                                                 {"false_alarms", FieldKind::count, false},
                                                 {"errors", FieldKind::count, false},
                                                 {"toi_late", FieldKind::count, false},
                                                 {"toi_error_max", FieldKind::number_or_null, false},
                                                 {"toi_error_median", FieldKind::number_or_null, false},
                                                 {"toi_error_p99", FieldKind::number_or_null, false},
                                                 {"host_peak_bytes", FieldKind::number, false},
                                                 {"device_bytes", FieldKind::number, false},
                                                 {"nondeterministic_at_step", FieldKind::count, false},
                                                 {"resumed", FieldKind::boolean, false},
                                                 {"interleave_group", FieldKind::string, false},
                                                 {"key", FieldKind::object, false},
                                                 {"finished_at", FieldKind::string, false},
                                                 {"machine", FieldKind::string, false},
                                                 {"build_type", FieldKind::string, false},
                                                 {"provenance", FieldKind::object, false}};

/// Every field of a step record that compare reads.
const std::vector<RecordField> kStepFields = {{"scene", FieldKind::string, true},
                                              {"thickness", FieldKind::number, true},
                                              {"strategy", FieldKind::string, true},
                                              {"step", FieldKind::count, true},
                                              {"answers", FieldKind::string, false},
                                              {"missed", FieldKind::count, false},
                                              {"missed_face_shape", FieldKind::count, false}};

bool has_kind(const json& value, FieldKind kind) {
  switch (kind) {
    case FieldKind::string: return value.is_string();
    case FieldKind::number: return value.is_number() && std::isfinite(value.get<double>()) && value.get<double>() >= 0;
    case FieldKind::count: return value.is_number_unsigned();
    case FieldKind::numbers:
      return value.is_array() && std::all_of(value.begin(), value.end(), [](const json& v) { return has_kind(v, FieldKind::number); });
    case FieldKind::object: return value.is_object();
    case FieldKind::boolean: return value.is_boolean();
    case FieldKind::number_or_null: return value.is_null() || has_kind(value, FieldKind::number);
  }
  return false;
}

const char* kind_name(FieldKind kind) {
  switch (kind) {
    case FieldKind::string: return "a string";
    case FieldKind::number: return "a finite number >= 0";
    case FieldKind::count: return "an integer >= 0";
    case FieldKind::numbers: return "an array of finite numbers >= 0";
    case FieldKind::object: return "an object";
    case FieldKind::boolean: return "true or false";
    case FieldKind::number_or_null: return "a finite number >= 0 or null";
  }
  return "";
}

void check_fields(const json& record, const std::vector<RecordField>& fields, bool compared, const std::filesystem::path& file,
                  const std::string& where, const char* what) {
  if (!record.is_object()) throw InputError(file, where, std::string("a ") + what + " must be an object");
  for (const RecordField& field : fields) {
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
