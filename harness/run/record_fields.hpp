#pragma once
/// @file
/// What a record of `run` read back from a file must hold for a reader (`check`, `compare`) to take it: each field
/// the reader reads, of the kind it reads it as. A record that is not so is bad input (FILE:WHERE: REASON, exit 2),
/// checked before anything is judged or written, never a raw type error nor a verdict.

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace ccd::harness {

/// What a field of a record must be.
enum class FieldKind { string, number, count, numbers, object, boolean, number_or_null };

struct RecordField {
  const char* name;
  FieldKind kind;
  bool required;
};

/// Checks every field of `fields` in `record` (an object): a required one must be there, and any that is there must
/// be of its kind. @throws InputError(file, WHERE.FIELD, "must be ..., got VALUE"), or (file, where, ...) for a
/// missing field or a record that is not an object; `what` names the record ("summary", "step record").
void check_record_fields(const nlohmann::json& record, const std::vector<RecordField>& fields, const std::filesystem::path& file,
                         const std::string& where, const char* what);

}  // namespace ccd::harness
