#include "harness/run/comparability.hpp"

#include <algorithm>
#include <array>
#include <set>

namespace ccd::harness {
namespace {

using nlohmann::json;

/// "NAME differs (BASE, HEAD)", or "" when the two values are equal.
std::string differs(const std::string& name, const json& base, const json& head) {
  if (base == head) return {};
  auto shown = [](const json& value) {
    const std::string text = value.is_null() ? std::string("none") : value.is_string() ? value.get<std::string>() : value.dump();
    return text.size() > 60 ? text.substr(0, 57) + "..." : text;
  };
  return name + " differs (" + shown(base) + ", " + shown(head) + ")";
}

json field_of(const json& s, const char* name) { return s.is_object() && s.contains(name) ? s[name] : json(); }

/// Provenance fields that name the code under audit: what a comparison of two builds of a plugin changes on purpose.
constexpr std::array<const char*, 4> kCodeUnderAudit = {"plugin", "plugin_digest", "plugin_objects", "plugin_environment_at_load"};

}  // namespace

std::string inputs_differ(const json& base, const json& head) {
  const json base_key = field_of(base, "key"), head_key = field_of(head, "key");
  if (!base_key.is_object() || !head_key.is_object() || !base_key.contains("scene_content") || !head_key.contains("scene_content")) {
    return std::string("the ") + (base_key.is_object() && base_key.contains("scene_content") ? "head" : "base") +
           " does not say what its input was (no key with the scene's content: a record made by hand or by an older ccdbench)";
  }
  if (std::string why = differs("the scene's content", base_key["scene_content"], head_key["scene_content"]); !why.empty()) {
    return why + ": another scene under one label";
  }
  if (std::string why = differs("the step count", field_of(base, "steps"), field_of(head, "steps")); !why.empty()) return why;
  return differs("δ", field_of(base, "thickness"), field_of(head, "thickness"));
}

std::string times_differ(const json& base, const json& head) {
  for (const auto& [field, name] :
       {std::pair{"machine", "the machine"}, {"threads", "the thread count"}, {"build_type", "the build type"}, {"executable", "the executable"}}) {
    if (std::string why = differs(name, field_of(base, field), field_of(head, field)); !why.empty()) return why;
  }
  const json base_provenance = field_of(base, "provenance"), head_provenance = field_of(head, "provenance");
  std::set<std::string> names;
  for (const json* provenance : {&base_provenance, &head_provenance}) {
    if (!provenance->is_object()) continue;
    for (const auto& item : provenance->items()) names.insert(item.key());
  }
  for (const std::string& name : names) {
    if (std::find(kCodeUnderAudit.begin(), kCodeUnderAudit.end(), name) != kCodeUnderAudit.end()) continue;
    const std::string shown = "the " + name + " of the provenance";
    if (std::string why = differs(shown, field_of(base_provenance, name.c_str()), field_of(head_provenance, name.c_str())); !why.empty()) return why;
  }
  return {};
}

}  // namespace ccd::harness
