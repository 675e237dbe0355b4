#include "ccd/config.hpp"
#include "core/error.hpp"
#include "harness/run.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <tuple>

namespace ccd::harness {

using nlohmann::json;

namespace {

/// A gated cell's identity: (scene, strategy, δ). δ is "scene" (the scene's own) or the number the cell ran at.
struct GateKey {
  std::string scene, strategy;
  std::optional<double> thickness;  // nullopt: the scene's own

  std::string describe() const {
    std::ostringstream text;
    text << scene << " / " << strategy << " / δ " << (thickness ? "" : "scene's");
    if (thickness) text << std::setprecision(17) << *thickness;
    return text.str();
  }
};

struct BaselineEntry {
  GateKey key;
  std::uint64_t max_missed = 0;
  /// Optional pins: the cell must have exactly these steps and colliding pairs (a shorter run or a shrunken truth
  /// must not pass), and at most max_toi_late late TOIs (the results must then come from a run with --toi).
  std::optional<std::uint64_t> steps, colliding, max_toi_late;
  /// Answers the strategy could not give (a plugin's errors, crashes, hangs; `error` in answer files) are verdicts
  /// too: at most this many (default 0), however the plugin's `errors` key counted them.
  std::uint64_t max_errors = 0;
  /// Answers that differed between two passes of the same steps fail the cell unless this says they may.
  bool allow_nondeterministic = false;
};

std::vector<BaselineEntry> parse_baseline(const json& baseline, const std::filesystem::path& file) {
  if (!baseline.is_array()) throw InputError(file, {}, "a baseline is a JSON array of {scene, strategy, thickness, max_missed}");
  std::vector<BaselineEntry> entries;
  for (std::size_t i = 0; i < baseline.size(); ++i) {
    const json& entry = baseline[i];
    const std::string where = "entry " + std::to_string(i);
    if (!entry.is_object()) throw InputError(file, where, "must be an object");
    static const std::vector<std::string> kKeys = {
        "scene", "strategy", "thickness", "max_missed", "steps", "colliding", "max_toi_late", "max_errors", "allow_nondeterministic"};
    for (const auto& item : entry.items()) {
      if (std::find(kKeys.begin(), kKeys.end(), item.key()) == kKeys.end()) {
        throw InputError(
            file, where,
            "unknown key '" + item.key() +
                "' (allowed: scene, strategy, thickness, max_missed, steps, colliding, max_toi_late, max_errors, allow_nondeterministic)");
      }
    }
    BaselineEntry parsed;
    if (!entry.contains("scene") || !entry["scene"].is_string()) throw InputError(file, where + ".scene", "must be a string");
    if (!entry.contains("strategy") || !entry["strategy"].is_string()) throw InputError(file, where + ".strategy", "must be a string");
    parsed.key.scene = entry["scene"];
    parsed.key.strategy = entry["strategy"];
    if (!entry.contains("thickness")) throw InputError(file, where, "missing 'thickness': \"scene\" (the scene's own δ) or a number");
    const json& thickness = entry["thickness"];
    if (thickness.is_string() && thickness == "scene") {
      parsed.key.thickness = std::nullopt;
    } else if (thickness.is_number() && std::isfinite(thickness.get<double>()) && thickness.get<double>() >= 0) {
      parsed.key.thickness = thickness.get<double>();
    } else {
      throw InputError(file, where + ".thickness", "must be \"scene\" or a finite number >= 0");
    }
    if (!entry.contains("max_missed") || !entry["max_missed"].is_number_unsigned()) {
      throw InputError(file, where + ".max_missed",
                       "must be an integer >= 0, got " + (entry.contains("max_missed") ? entry["max_missed"].dump() : std::string("nothing")));
    }
    parsed.max_missed = entry["max_missed"].get<std::uint64_t>();
    for (auto [name, field] : {std::pair{"steps", &parsed.steps}, {"colliding", &parsed.colliding}, {"max_toi_late", &parsed.max_toi_late}}) {
      if (!entry.contains(name)) continue;
      if (!entry[name].is_number_unsigned()) throw InputError(file, where + "." + name, "must be an integer >= 0");
      *field = entry[name].get<std::uint64_t>();
    }
    if (entry.contains("max_errors")) {
      if (!entry["max_errors"].is_number_unsigned()) throw InputError(file, where + ".max_errors", "must be an integer >= 0");
      parsed.max_errors = entry["max_errors"].get<std::uint64_t>();
    }
    if (entry.contains("allow_nondeterministic")) {
      if (!entry["allow_nondeterministic"].is_boolean()) throw InputError(file, where + ".allow_nondeterministic", "must be true or false");
      parsed.allow_nondeterministic = entry["allow_nondeterministic"].get<bool>();
    }
    for (const BaselineEntry& other : entries) {
      if (other.key.scene == parsed.key.scene && other.key.strategy == parsed.key.strategy && other.key.thickness == parsed.key.thickness) {
        throw InputError(file, where, "repeats the entry for " + parsed.key.describe());
      }
    }
    entries.push_back(std::move(parsed));
  }
  return entries;
}

std::uint64_t result_count(const json& result, const char* field, const std::filesystem::path& file, const std::string& where) {
  if (!result.contains(field) || !result[field].is_number_unsigned()) {
    throw InputError(file, where + "." + field, "must be an integer >= 0 (a `ccdbench run --json` summary, verified)");
  }
  return result[field].get<std::uint64_t>();
}

}  // namespace

bool check_against_baseline(const json& baseline, const std::filesystem::path& baseline_file,
                            const std::vector<std::pair<std::filesystem::path, json>>& results_files, std::ostream& out) {
  const std::vector<BaselineEntry> entries = parse_baseline(baseline, baseline_file);
  std::vector<std::tuple<std::filesystem::path, std::size_t, const json*>> results;
  for (const auto& [file, document] : results_files) {
    if (!document.is_array()) throw InputError(file, {}, "must be a JSON array (a `ccdbench run --json` file)");
    for (std::size_t i = 0; i < document.size(); ++i) results.emplace_back(file, i, &document[i]);
  }
  bool ok = true;
  if (results.empty()) {
    out << "FAIL the results are empty: nothing was gated\n";
    ok = false;
  }
  std::vector<std::size_t> matches(entries.size(), 0);
  for (const auto& [results_file, i, result_pointer] : results) {
    const json& result = *result_pointer;
    const std::string where = "entry " + std::to_string(i);
    if (!result.is_object() || !result.contains("scene") || !result["scene"].is_string() || !result.contains("strategy") ||
        !result["strategy"].is_string() || !result.contains("thickness") || !result["thickness"].is_number() || !result.contains("thickness_from") ||
        !result["thickness_from"].is_string()) {
      throw InputError(results_file, where, "not a summary of `ccdbench run --json` (scene, strategy, thickness, thickness_from)");
    }
    const GateKey key{result["scene"], result["strategy"], result["thickness"].get<double>()};
    const bool scene_thickness = result["thickness_from"] == "scene";
    const BaselineEntry* entry = nullptr;
    std::size_t entries_matched = 0;
    for (std::size_t e = 0; e < entries.size(); ++e) {
      const GateKey& gate = entries[e].key;
      const bool same_thickness = gate.thickness ? *gate.thickness == *key.thickness : scene_thickness;
      // By the resolved name, or by the spec as the run was given it: a plugin's resolved name holds its absolute
      // path and its file's digest, which a baseline kept in a plugin's own repository cannot know.
      const bool same_strategy =
          gate.strategy == key.strategy || (result.contains("spec") && result["spec"].is_string() && gate.strategy == result["spec"]);
      if (gate.scene == key.scene && same_strategy && same_thickness) {
        entry = &entries[e];
        ++matches[e];
        ++entries_matched;
      }
    }
    const std::string name = key.scene + " / " + key.strategy + " / δ " + (scene_thickness ? "scene's " : "") + [&] {
      std::ostringstream t;
      t << std::setprecision(17) << *key.thickness;
      return t.str();
    }();
    if (!entry) {
      out << "FAIL " << name << ": not in the baseline (every gated cell needs an entry)\n";
      ok = false;
      continue;
    }
    if (entries_matched > 1) {
      // The scene's own δ equals a numeric entry's: which entry gates it would be an accident of order.
      out << "FAIL " << name << ": matches " << entries_matched << " baseline entries (make them distinct)\n";
      ok = false;
      continue;
    }
    if (!result.value("verified", false) || !result.contains("missed")) {
      out << "FAIL " << name << ": not verified (run with --verify exact)\n";
      ok = false;
      continue;
    }
    const std::uint64_t missed = result_count(result, "missed", results_file, where);
    const std::uint64_t colliding = result_count(result, "colliding", results_file, where);
    if (entry->steps && result_count(result, "steps", results_file, where) != *entry->steps) {
      out << "FAIL " << name << ": " << result["steps"].dump() << " steps, the baseline pins " << *entry->steps << "\n";
      ok = false;
    } else if (entry->colliding && colliding != *entry->colliding) {
      out << "FAIL " << name << ": " << colliding << " colliding pairs, the baseline pins " << *entry->colliding
          << " (the scene or the truth changed: check why before updating the baseline)\n";
      ok = false;
    } else if (entry->max_toi_late && !result.contains("toi_late")) {
      out << "FAIL " << name << ": the baseline gates late TOIs but the results have none (run with --toi)\n";
      ok = false;
    } else if (entry->max_toi_late && result_count(result, "toi_late", results_file, where) > *entry->max_toi_late) {
      out << "FAIL " << name << ": " << result["toi_late"].dump() << " TOIs later than the exact earliest contact, "
          << "baseline allows " << *entry->max_toi_late << "\n";
      ok = false;
    } else if (colliding == 0) {
      out << "FAIL " << name << ": no colliding pair in any step, so it cannot miss: this cell gates nothing\n";
      ok = false;
#if CCDBENCH_GUARD_GATE
    } else if (!result.contains("errors")) {
      out << "FAIL " << name << ": the results say nothing of errors (made by an older ccdbench: run it again)\n";
      ok = false;
    } else if (const std::uint64_t errors = result_count(result, "errors", results_file, where); errors > entry->max_errors) {
      out << "FAIL " << name << ": " << errors << " answers could not be taken (errors: crashes, hangs, refused answers), baseline allows "
          << entry->max_errors << " (max_errors)\n";
      ok = false;
    } else if (result.contains("nondeterministic_at_step") && !entry->allow_nondeterministic) {
      out << "FAIL " << name << ": its answers differed between two passes of step " << result["nondeterministic_at_step"].dump()
          << " (nondeterministic; baseline entry allow_nondeterministic: true accepts it)\n";
      ok = false;
#endif
    } else if (missed > entry->max_missed) {
      out << "FAIL " << name << ": missed " << missed << " of " << colliding << " (culled " << result.value("missed_culled", json(0)).dump()
          << ", tested " << result.value("missed_tested", json(0)).dump() << "), baseline allows " << entry->max_missed << "\n";
      ok = false;
    } else {
      out << "ok   " << name << ": missed " << missed << " of " << colliding << " <= " << entry->max_missed << "\n";
    }
  }
  for (std::size_t e = 0; e < entries.size(); ++e) {
    if (matches[e] == 0) {
      out << "FAIL " << entries[e].key.describe() << ": in the baseline but has no result\n";
      ok = false;
    } else if (matches[e] > 1) {
      out << "FAIL " << entries[e].key.describe() << ": " << matches[e] << " results for one entry\n";
      ok = false;
    }
  }
  return ok;
}

}  // namespace ccd::harness
