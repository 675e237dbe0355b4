#include "ccd/config.hpp"
#include "core/error.hpp"
#include "core/number_text.hpp"
#include "harness/run.hpp"
#include "harness/run/record_fields.hpp"
#include "strategies/registry.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <stdexcept>
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

/// Every field the gate reads of a result, checked before it is gated (run/record_fields.hpp).
const std::vector<RecordField> kGatedFields = {{"scene", FieldKind::string, true},         {"strategy", FieldKind::string, true},
                                               {"thickness", FieldKind::number, true},     {"thickness_from", FieldKind::string, true},
                                               {"spec", FieldKind::string, false},         {"verified", FieldKind::boolean, false},
                                               {"steps", FieldKind::count, false},         {"colliding", FieldKind::count, false},
                                               {"missed", FieldKind::count, false},        {"missed_culled", FieldKind::count, false},
                                               {"missed_tested", FieldKind::count, false}, {"errors", FieldKind::count, false},
                                               {"toi_late", FieldKind::count, false},      {"nondeterministic_at_step", FieldKind::count, false},
                                               {"resumed", FieldKind::boolean, false}};

/// Why a result cannot be gated whatever its entry says, or "": `check` fails it and `--write-baseline` refuses it,
/// for the same reasons.
std::string why_not_gateable(const json& result, const GateOptions& options) {
  if (!result.value("verified", false) || !result.contains("missed")) return "not verified (run with --verify exact)";
  if (!result.contains("colliding")) return "no colliding count (a `ccdbench run --json` summary, verified)";
  if (result["colliding"] == 0) return "no colliding pair in any step, so it cannot miss: this cell gates nothing";
#if CCDBENCH_GUARD_GATE
  if (!result.contains("errors")) return "the results say nothing of errors (made by an older ccdbench: run it again)";
  // A plugin's kept cell holds answers the plugin gave in an earlier run, which may differ from what it gives now
  // (docs/DESIGN.md §10 "Kept cells"): they stand for this run's only where the person gating says so.
  if (result.value("resumed", false) && strategies::runs_plugin(result["strategy"].get<std::string>()) && !options.allow_resumed) {
    return "its answers were kept from an earlier run (run --resume), not given by the plugin in this run (rerun without --resume, "
           "or check --allow-resumed to gate them)";
  }
#else
  (void)options;
#endif
  return {};
}

/// Every reason a result fails its entry (none: it passes), each in words.
std::vector<std::string> failures(const json& result, const BaselineEntry& entry, const std::filesystem::path& results_file, const std::string& where,
                                  const GateOptions& options) {
  if (const std::string why = why_not_gateable(result, options); !why.empty()) return {why};
  std::vector<std::string> reasons;
  const std::uint64_t missed = result_count(result, "missed", results_file, where);
  const std::uint64_t colliding = result_count(result, "colliding", results_file, where);
  if (entry.steps && result_count(result, "steps", results_file, where) != *entry.steps) {
    reasons.push_back(result["steps"].dump() + " steps, the baseline pins " + std::to_string(*entry.steps));
  }
  if (entry.colliding && colliding != *entry.colliding) {
    reasons.push_back(std::to_string(colliding) + " colliding pairs, the baseline pins " + std::to_string(*entry.colliding) +
                      " (the scene or the truth changed: check why before updating the baseline)");
  }
  if (entry.max_toi_late && !result.contains("toi_late")) {
    reasons.push_back("the baseline gates late TOIs but the results have none (run with --toi)");
  } else if (entry.max_toi_late && result_count(result, "toi_late", results_file, where) > *entry.max_toi_late) {
    reasons.push_back(result["toi_late"].dump() + " TOIs later than the exact earliest contact, baseline allows " +
                      std::to_string(*entry.max_toi_late));
  }
#if CCDBENCH_GUARD_GATE
  if (const std::uint64_t errors = result_count(result, "errors", results_file, where); errors > entry.max_errors) {
    reasons.push_back(std::to_string(errors) + " answers could not be taken (errors: crashes, hangs, refused answers), baseline allows " +
                      std::to_string(entry.max_errors) + " (max_errors)");
  }
  if (result.contains("nondeterministic_at_step") && !entry.allow_nondeterministic) {
    reasons.push_back("its answers differed between two passes of step " + result["nondeterministic_at_step"].dump() +
                      " (nondeterministic; baseline entry allow_nondeterministic: true accepts it)");
  }
#endif
  if (missed > entry.max_missed) {
    reasons.push_back("missed " + std::to_string(missed) + " of " + std::to_string(colliding) + " (culled " +
                      result.value("missed_culled", json(0)).dump() + ", tested " + result.value("missed_tested", json(0)).dump() +
                      "), baseline allows " + std::to_string(entry.max_missed));
  }
  return reasons;
}

/// Gates one result against its entry: prints a FAIL line for every reason it fails (a maintainer sees them all at
/// once), or its ok line; returns whether it passes.
bool gate_result(const json& result, const BaselineEntry& entry, const std::filesystem::path& results_file, const std::string& where,
                 const std::string& name, const GateOptions& options, std::ostream& out) {
  const std::vector<std::string> reasons = failures(result, entry, results_file, where, options);
  for (const std::string& reason : reasons) out << "FAIL " << name << ": " << reason << "\n";
  if (!reasons.empty()) return false;
  out << "ok   " << name << ": missed " << result["missed"].dump() << " of " << result["colliding"].dump() << " <= " << entry.max_missed << "\n";
  return true;
}

/// Every result of a results file (a `run --json` array), its fields checked. @throws InputError for a file that is
/// not such an array or a result that is not a summary of `run`.
void check_results_file(const std::filesystem::path& file, const json& document) {
  if (!document.is_array()) throw InputError(file, {}, "must be a JSON array (a `ccdbench run --json` file)");
  for (std::size_t i = 0; i < document.size(); ++i) check_record_fields(document[i], kGatedFields, file, "entry " + std::to_string(i), "summary");
}

}  // namespace

bool check_against_baseline(const json& baseline, const std::filesystem::path& baseline_file,
                            const std::vector<std::pair<std::filesystem::path, json>>& results_files, const GateOptions& options, std::ostream& out) {
  const std::vector<BaselineEntry> entries = parse_baseline(baseline, baseline_file);
  std::vector<std::tuple<std::filesystem::path, std::size_t, const json*>> results;
  for (const auto& [file, document] : results_files) {
    check_results_file(file, document);
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
    // Named by the strategy as the run was given it (a plugin's resolved name is long and holds its path).
    const std::string shown = result.contains("spec") && result["spec"].is_string() ? result["spec"].get<std::string>() : key.strategy;
    const std::string name = key.scene + " / " + shown + " / δ " + (scene_thickness ? "scene's " : "") + [&] {
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
    if (!gate_result(result, *entry, results_file, where, name, options, out)) ok = false;
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

std::vector<std::pair<std::filesystem::path, json>> select_results(const std::vector<std::pair<std::filesystem::path, json>>& results,
                                                                   const std::vector<std::string>& strategies, std::ostream& out) {
  std::vector<std::pair<std::filesystem::path, json>> kept;
  std::vector<bool> found(strategies.size(), false);
  std::size_t left = 0;
  for (const auto& [file, document] : results) {
    if (!document.is_array()) throw InputError(file, {}, "must be a JSON array (a `ccdbench run --json` file)");
    json selected = json::array();
    for (const json& result : document) {
      bool wanted = false;
      for (std::size_t k = 0; k < strategies.size(); ++k) {
        const bool same =
            (result.contains("spec") && result["spec"] == strategies[k]) || (result.contains("strategy") && result["strategy"] == strategies[k]);
        if (same) found[k] = wanted = true;
      }
      if (wanted) {
        selected.push_back(result);
      } else {
        ++left;
      }
    }
    kept.emplace_back(file, std::move(selected));
  }
  for (std::size_t k = 0; k < strategies.size(); ++k) {
    if (!found[k])
      throw InputError(results.empty() ? std::filesystem::path() : results.front().first, {}, "no result of --strategy " + strategies[k]);
  }
  if (left > 0) out << "left out: " << left << " result" << (left == 1 ? "" : "s") << " of other strategies than --strategy names\n";
  return kept;
}

BaselineMargin BaselineMargin::parse(const std::string& text) {
  BaselineMargin margin;
  const bool percent = !text.empty() && text.back() == '%';
  const std::string number = percent ? text.substr(0, text.size() - 1) : text;
  std::size_t used = 0;
  try {
    if (percent) {
      const std::optional<double> parsed = parse_double(number);
      used = parsed ? number.size() : 0;
      margin.percent = parsed.value_or(0.0);
    } else if (!number.empty() && number[0] != '-' && number[0] != '+') {
      margin.count = std::stoull(number, &used);
    }
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != number.size() || !(margin.percent >= 0 && margin.percent <= 1000)) {
    throw std::invalid_argument("--margin " + text + ": must be a count (an integer >= 0) or a percentage (P%, 0 <= P <= 1000)");
  }
  return margin;
}

std::uint64_t BaselineMargin::allow(std::uint64_t value) const {
  return value + count + static_cast<std::uint64_t>(std::ceil(static_cast<double>(value) * percent / 100.0));
}

json write_baseline(const std::vector<std::pair<std::filesystem::path, json>>& results_files, const BaselineMargin& margin,
                    const GateOptions& options, std::ostream& warnings) {
  json baseline = json::array();
  std::vector<std::string> seen;
  for (const auto& [file, document] : results_files) {
    check_results_file(file, document);
    for (std::size_t i = 0; i < document.size(); ++i) {
      const json& result = document[i];
      const std::string where = "entry " + std::to_string(i);
      // The strategy as the user gave it: a plugin's resolved name holds its absolute path and its file's digest,
      // which would tie the baseline to one checkout and one build.
      const std::string strategy =
          result.contains("spec") && result["spec"].is_string() ? result["spec"].get<std::string>() : result["strategy"].get<std::string>();
      const bool scene_thickness = result["thickness_from"] == "scene";
      const json thickness = scene_thickness ? json("scene") : result["thickness"];
      const std::string name = result["scene"].get<std::string>() + " / " + strategy + " / δ " + thickness.dump();
      // What check would refuse whatever the entry, an entry cannot make pass: refused here for the same reason.
      if (const std::string why = why_not_gateable(result, options); !why.empty())
        throw InputError(file, where, name + ": " + why + " (check refuses it too)");
      const std::uint64_t colliding = result_count(result, "colliding", file, where);
      const std::string key = result["scene"].get<std::string>() + "|" + strategy + "|" + thickness.dump();
      if (std::find(seen.begin(), seen.end(), key) != seen.end()) throw InputError(file, where, name + ": a second result for one cell");
      seen.push_back(key);
      json entry = {{"scene", result["scene"]},
                    {"strategy", strategy},
                    {"thickness", thickness},
                    {"max_missed", margin.allow(result_count(result, "missed", file, where))},
                    {"steps", result_count(result, "steps", file, where)},
                    {"colliding", colliding}};
      entry["max_errors"] = margin.allow(result_count(result, "errors", file, where));
      if (result.contains("toi_late")) entry["max_toi_late"] = margin.allow(result_count(result, "toi_late", file, where));
      if (result.contains("nondeterministic_at_step")) {
        warnings << "ccdbench: warning: " << name << ": its answers differed between two passes of step " << result["nondeterministic_at_step"].dump()
                 << "; check fails it until its entry says allow_nondeterministic: true (find out why first)\n";
      }
      baseline.push_back(std::move(entry));
    }
  }
  if (baseline.empty())
    throw InputError(results_files.empty() ? std::filesystem::path() : results_files.front().first, {}, "no results: nothing to write a baseline of");
  return baseline;
}

}  // namespace ccd::harness
