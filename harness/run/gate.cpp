#include "ccd/config.hpp"
#include "core/error.hpp"
#include "core/number_text.hpp"
#include "harness/run.hpp"
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
  bool operator==(const GateKey&) const = default;
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

/// An entry's δ as the baseline writes it: "scene" or the number.
json thickness_json(const GateKey& key) { return key.thickness ? json(*key.thickness) : json("scene"); }

/// An entry as --write-baseline writes it (parse_baseline reads it).
json entry_json(const BaselineEntry& entry) {
  json j = {{"scene", entry.key.scene},
            {"strategy", entry.key.strategy},
            {"thickness", thickness_json(entry.key)},
            {"max_missed", entry.max_missed},
            {"max_errors", entry.max_errors}};
  for (auto [name, field] : {std::pair{"steps", &entry.steps}, {"colliding", &entry.colliding}, {"max_toi_late", &entry.max_toi_late}}) {
    if (*field) j[name] = **field;
  }
  if (entry.allow_nondeterministic) j["allow_nondeterministic"] = true;
  return j;
}

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
      if (other.key == parsed.key) {
        throw InputError(file, where, "repeats the entry for " + parsed.key.describe());
      }
    }
    entries.push_back(std::move(parsed));
  }
  return entries;
}

/// Why a result cannot be gated whatever its entry says, or "": `check` fails it and `--write-baseline` refuses it,
/// for the same reasons.
std::string why_not_gateable(const CellSummary& result, const GateOptions& options) {
  if (!result.verified) return "not verified (run with --verify exact)";
  if (!result.verdict) return "no colliding or missed count (a `ccdbench run --json` summary, verified)";
  if (result.verdict->colliding == 0) return "no colliding pair in any step, so it cannot miss: this cell gates nothing";
#if CCDBENCH_GUARD_GATE
  if (!result.errors_counted) return "the results say nothing of errors (made by an older ccdbench: run it again)";
  // A plugin's kept cell holds answers the plugin gave in an earlier run, which may differ from what it gives now
  // (docs/DESIGN.md §10 "Kept cells"): they stand for this run's only where the person gating says so.
  if (result.resumed && strategies::runs_plugin(result.strategy) && !options.allow_resumed) {
    return "its answers were kept from an earlier run (run --resume), not given by the plugin in this run (rerun without --resume, "
           "or check --allow-resumed to gate them)";
  }
#else
  (void)options;
#endif
  return {};
}

/// Every reason a result fails its entry (none: it passes), each in words.
std::vector<std::string> failures(const CellSummary& result, const BaselineEntry& entry, const GateOptions& options) {
  if (const std::string why = why_not_gateable(result, options); !why.empty()) return {why};
  std::vector<std::string> reasons;
  const CellVerdict& verdict = *result.verdict;
  if (entry.steps && result.steps != *entry.steps) {
    reasons.push_back(std::to_string(result.steps) + " steps, the baseline pins " + std::to_string(*entry.steps));
  }
  if (entry.colliding && verdict.colliding != *entry.colliding) {
    reasons.push_back(std::to_string(verdict.colliding) + " colliding pairs, the baseline pins " + std::to_string(*entry.colliding) +
                      " (the scene or the truth changed: check why before updating the baseline)");
  }
  if (entry.max_toi_late && !verdict.toi) {
    reasons.push_back("the baseline gates late TOIs but the results have none (run with --toi)");
  } else if (entry.max_toi_late && verdict.toi->late > *entry.max_toi_late) {
    reasons.push_back(std::to_string(verdict.toi->late) + " TOIs later than the exact earliest contact, baseline allows " +
                      std::to_string(*entry.max_toi_late));
  }
#if CCDBENCH_GUARD_GATE
  if (result.errors > entry.max_errors) {
    reasons.push_back(std::to_string(result.errors) + " answers could not be taken (errors: crashes, hangs, refused answers), baseline allows " +
                      std::to_string(entry.max_errors) + " (max_errors)");
  }
  if (result.nondeterministic_at_step && !entry.allow_nondeterministic) {
    reasons.push_back("its answers differed between two passes of step " + std::to_string(*result.nondeterministic_at_step) +
                      " (nondeterministic; baseline entry allow_nondeterministic: true accepts it)");
  }
#endif
  if (verdict.missed > entry.max_missed) {
    reasons.push_back("missed " + std::to_string(verdict.missed) + " of " + std::to_string(verdict.colliding) + " (culled " +
                      std::to_string(verdict.missed_culled) + ", tested " + std::to_string(verdict.missed_tested) + "), baseline allows " +
                      std::to_string(entry.max_missed));
  }
  return reasons;
}

/// A result's δ as its name shows it: "scene's 0.0080..." or the number, to 17 digits.
std::string thickness_shown(const CellSummary& result) {
  std::ostringstream t;
  t << (result.thickness_from_scene ? "scene's " : "") << std::setprecision(17) << result.thickness;
  return t.str();
}

/// The result's line: matched with its one entry, and judged.
GateLine gate_result(const CellSummary& result, const std::vector<BaselineEntry>& entries, std::vector<std::size_t>& matches,
                     const GateOptions& options) {
  // Named by the strategy as the run was given it (a plugin's resolved name is long and holds its path).
  GateLine line{result.scene + " / " + result.given() + " / δ " + thickness_shown(result), {}, {}};
  const BaselineEntry* entry = nullptr;
  std::size_t entries_matched = 0;
  for (std::size_t e = 0; e < entries.size(); ++e) {
    const GateKey& gate = entries[e].key;
    const bool same_thickness = gate.thickness ? *gate.thickness == result.thickness : result.thickness_from_scene;
    // By the resolved name, or by the spec as the run was given it: a plugin's resolved name holds its absolute
    // path and its file's digest, which a baseline kept in a plugin's own repository cannot know.
    const bool same_strategy = gate.strategy == result.strategy || gate.strategy == result.given();
    if (gate.scene == result.scene && same_strategy && same_thickness) {
      entry = &entries[e];
      ++matches[e];
      ++entries_matched;
    }
  }
  if (!entry) {
    line.failures.push_back("not in the baseline (every gated cell needs an entry)");
  } else if (entries_matched > 1) {
    // The scene's own δ equals a numeric entry's: which entry gates it would be an accident of order.
    line.failures.push_back("matches " + std::to_string(entries_matched) + " baseline entries (make them distinct)");
  } else {
    line.failures = failures(result, *entry, options);
    if (line.failures.empty()) {
      line.passed = "missed " + std::to_string(result.verdict->missed) + " of " + std::to_string(result.verdict->colliding) +
                    " <= " + std::to_string(entry->max_missed);
    }
  }
  return line;
}

}  // namespace

bool GateVerdict::passed() const {
  return std::none_of(lines.begin(), lines.end(), [](const GateLine& line) { return !line.failures.empty(); });
}

GateVerdict gate_results(const json& baseline, const std::filesystem::path& baseline_file, const std::vector<GateResults>& results,
                         const GateOptions& options) {
  const std::vector<BaselineEntry> entries = parse_baseline(baseline, baseline_file);
  GateVerdict verdict;
  if (std::all_of(results.begin(), results.end(), [](const GateResults& file) { return file.summaries.empty(); })) {
    verdict.lines.push_back({{}, {"the results are empty: nothing was gated"}, {}});
  }
  std::vector<std::size_t> matches(entries.size(), 0);
  for (const GateResults& file : results) {
    for (const CellSummary& result : file.summaries) verdict.lines.push_back(gate_result(result, entries, matches, options));
  }
  for (std::size_t e = 0; e < entries.size(); ++e) {
    if (matches[e] == 0) {
      verdict.lines.push_back({entries[e].key.describe(), {"in the baseline but has no result"}, {}});
    } else if (matches[e] > 1) {
      verdict.lines.push_back({entries[e].key.describe(), {std::to_string(matches[e]) + " results for one entry"}, {}});
    }
  }
  return verdict;
}

std::vector<std::string> gate_lines(const GateVerdict& verdict) {
  std::vector<std::string> lines;
  for (const GateLine& line : verdict.lines) {
    for (const std::string& reason : line.failures) lines.push_back("FAIL " + (line.name.empty() ? reason : line.name + ": " + reason));
    if (line.failures.empty()) lines.push_back("ok   " + line.name + ": " + line.passed);
  }
  return lines;
}

std::vector<GateResults> select_results(const std::vector<GateResults>& results, const std::vector<std::string>& strategies, std::ostream& out) {
  std::vector<GateResults> kept;
  std::vector<bool> found(strategies.size(), false);
  std::size_t left = 0;
  for (const GateResults& file : results) {
    GateResults selected{file.file, {}};
    for (const CellSummary& result : file.summaries) {
      bool wanted = false;
      for (std::size_t k = 0; k < strategies.size(); ++k) {
        if (result.spec == strategies[k] || result.strategy == strategies[k]) found[k] = wanted = true;
      }
      if (wanted) {
        selected.summaries.push_back(result);
      } else {
        ++left;
      }
    }
    kept.push_back(std::move(selected));
  }
  for (std::size_t k = 0; k < strategies.size(); ++k) {
    if (!found[k]) throw InputError(results.empty() ? std::filesystem::path() : results.front().file, {}, "no result of --strategy " + strategies[k]);
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

json write_baseline(const std::vector<GateResults>& results, const BaselineMargin& margin, const GateOptions& options, std::ostream& warnings) {
  std::vector<BaselineEntry> entries;
  for (const GateResults& file : results) {
    for (std::size_t i = 0; i < file.summaries.size(); ++i) {
      const CellSummary& result = file.summaries[i];
      const std::string where = "entry " + std::to_string(i);
      // The strategy as the user gave it: a plugin's resolved name holds its absolute path and its file's digest,
      // which would tie the baseline to one checkout and one build.
      BaselineEntry entry;
      entry.key = {result.scene, result.given(), result.thickness_from_scene ? std::nullopt : std::optional<double>(result.thickness)};
      const std::string name = result.scene + " / " + entry.key.strategy + " / δ " + thickness_json(entry.key).dump();
      // What check would refuse whatever the entry, an entry cannot make pass: refused here for the same reason.
      if (const std::string why = why_not_gateable(result, options); !why.empty())
        throw InputError(file.file, where, name + ": " + why + " (check refuses it too)");
      for (const BaselineEntry& other : entries) {
        if (other.key == entry.key) throw InputError(file.file, where, name + ": a second result for one cell");
      }
      const CellVerdict& verdict = *result.verdict;
      entry.max_missed = margin.allow(verdict.missed);
      entry.steps = result.steps;
      entry.colliding = verdict.colliding;
      entry.max_errors = margin.allow(result.errors);
      if (verdict.toi) entry.max_toi_late = margin.allow(verdict.toi->late);
      if (result.nondeterministic_at_step) {
        warnings << "ccdbench: warning: " << name << ": its answers differed between two passes of step " << *result.nondeterministic_at_step
                 << "; check fails it until its entry says allow_nondeterministic: true (find out why first)\n";
      }
      entries.push_back(std::move(entry));
    }
  }
  if (entries.empty())
    throw InputError(results.empty() ? std::filesystem::path() : results.front().file, {}, "no results: nothing to write a baseline of");
  json baseline = json::array();
  for (const BaselineEntry& entry : entries) baseline.push_back(entry_json(entry));
  return baseline;
}

}  // namespace ccd::harness
