#include "harness/run/comparability.hpp"

#include <algorithm>
#include <array>
#include <set>
#include <tuple>

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

/// The field of a cell's key that says what its input was (CellKey::to_json).
constexpr const char* kSceneContent = "scene_content";

/// Provenance fields that name the code under audit: what a comparison of two builds of a plugin changes on purpose.
constexpr std::array<const char*, 4> kCodeUnderAudit = {"plugin", "plugin_digest", "plugin_objects", "plugin_environment_at_load"};

}  // namespace

std::string inputs_differ(const CellSummary& base, const CellSummary& head) {
  const json base_key = base.key.value_or(json()), head_key = head.key.value_or(json());
  const bool base_says = base_key.is_object() && base_key.contains(kSceneContent),
             head_says = head_key.is_object() && head_key.contains(kSceneContent);
  if (!base_says || !head_says) {
    return std::string("the ") + (base_says ? "head" : "base") +
           " does not say what its input was (no key with the scene's content: a record made by hand or by an older ccdbench)";
  }
  if (std::string why = differs("the scene's content", base_key[kSceneContent], head_key[kSceneContent]); !why.empty()) {
    return why + ": another scene under one label";
  }
  if (std::string why = differs("the step count", base.steps, head.steps); !why.empty()) return why;
  return differs("δ", base.thickness, head.thickness);
}

std::string times_differ(const CellSummary& base, const CellSummary& head) {
  const RecordEnvironment &b = base.environment, &h = head.environment;
  for (const auto& [name, base_value, head_value] : {std::tuple{"the machine", json(b.machine), json(h.machine)},
                                                     {"the thread count", json(b.threads), json(h.threads)},
                                                     {"the build type", json(b.build_type), json(h.build_type)},
                                                     {"the executable", json(b.executable), json(h.executable)}}) {
    if (std::string why = differs(name, base_value, head_value); !why.empty()) return why;
  }
  std::set<std::string> names;
  for (const json* provenance : {&b.provenance, &h.provenance}) {
    if (!provenance->is_object()) continue;
    for (const auto& item : provenance->items()) names.insert(item.key());
  }
  for (const std::string& name : names) {
    if (std::find(kCodeUnderAudit.begin(), kCodeUnderAudit.end(), name) != kCodeUnderAudit.end()) continue;
    const std::string shown = "the " + name + " of the provenance";
    if (std::string why = differs(shown, field_of(b.provenance, name.c_str()), field_of(h.provenance, name.c_str())); !why.empty()) return why;
  }
  return {};
}

}  // namespace ccd::harness
