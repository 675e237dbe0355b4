#include "harness/run/record_fields.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>

namespace ccd::harness {
namespace {

bool has_kind(const nlohmann::json& value, FieldKind kind) {
  switch (kind) {
    case FieldKind::string: return value.is_string();
    case FieldKind::number: return value.is_number() && std::isfinite(value.get<double>()) && value.get<double>() >= 0;
    case FieldKind::count: return value.is_number_unsigned();
    case FieldKind::numbers:
      return value.is_array() && std::all_of(value.begin(), value.end(), [](const nlohmann::json& v) { return has_kind(v, FieldKind::number); });
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

}  // namespace

void check_record_fields(const nlohmann::json& record, const std::vector<RecordField>& fields, const std::filesystem::path& file,
                         const std::string& where, const char* what) {
  if (!record.is_object()) throw InputError(file, where, std::string("a ") + what + " must be an object");
  for (const RecordField& field : fields) {
    if (!record.contains(field.name)) {
      if (field.required) throw InputError(file, where, std::string("a ") + what + " without '" + field.name + "': not a result of `run`");
      continue;
    }
    if (!has_kind(record[field.name], field.kind)) {
      throw InputError(file, where + "." + field.name, std::string("must be ") + kind_name(field.kind) + ", got " + record[field.name].dump());
    }
  }
}

}  // namespace ccd::harness
