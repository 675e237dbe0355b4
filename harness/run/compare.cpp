#include "harness/run/compare.hpp"

#include "core/error.hpp"
#include "datasets/atomic_file.hpp"
#include "datasets/query_file.hpp"
#include "harness/cell_store.hpp"
#include "harness/rank_test.hpp"
#include "harness/run/cells.hpp"
#include "harness/run/comparability.hpp"
#include "harness/run/result_set.hpp"
#include "harness/statistics.hpp"
#include "harness/table.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <ostream>
#include <set>
#include <sstream>
#include <tuple>

namespace ccd::harness {

using nlohmann::json;

namespace {

/// "fold / full / δ scene's 0.008" or "... / δ 0".
std::string cell_name(const CellSummary& s, const std::string& spec) {
  return s.scene + " / " + spec + " / δ " + (s.thickness_from_scene ? "scene's " : "") + significant(s.thickness, 6);
}

/// What matches a cell: scene, δ (the scene's own, or the number) and the spec.
std::string match_key(const CellSummary& s, const std::string& spec) {
  return s.scene + "|" + (s.thickness_from_scene ? std::string("scene") : json(s.thickness).dump()) + "|" + spec;
}

/// The measures compare shows, in its table's order (column, digits shown: -1 all; scale: what the value is divided
/// by to be shown) and in --json, and those whose rise is a verdict that got worse. Every measure compare reads is
/// one of these.
struct ShownMeasure {
  const Measure* measure;
  const char* column;  // nullptr: in --json only
  int digits;
  double scale;
  bool judged;
};
const std::vector<ShownMeasure> kShown = {{&measures::missed, "missed", -1, 1, true},
                                          {&measures::errors, "errors", -1, 1, true},
                                          {&measures::false_alarms, "false alarms", -1, 1, false},
                                          {&measures::toi_late, "TOI late", -1, 1, true},
                                          {&measures::toi_error_median, "TOI error p50", 3, 1, false},
                                          {&measures::toi_error_p99, "p99", 3, 1, false},
                                          {&measures::toi_error_max, nullptr, -1, 1, false},
                                          {&measures::host_peak_bytes, "MiB host peak", 4, 1024.0 * 1024.0, false},
                                          {&measures::device_bytes, nullptr, -1, 1, false},
                                          {&measures::ms_per_step, "ms/step", 4, 1, false}};

/// "3 → 4" (or "3" when equal, "-" when unknown on a side).
std::string change(std::optional<double> before, std::optional<double> after, int digits = -1) {
  auto text = [&](std::optional<double> v) { return !v ? std::string("-") : digits < 0 ? significant(*v, 15) : significant(*v, digits); };
  if (before && after && *before == *after) return text(before);
  return text(before) + " → " + text(after);
}

/// The digest in a resolved plugin spec ("...:digest=HEX:..."), or "".
std::string digest_in(const std::string& name) {
  const std::size_t at = name.find(":digest=");
  return at == std::string::npos ? std::string() : name.substr(at + 8, 32);
}

/// A missed pair's identity: its kind and ids.
std::string pair_identity(const MissedPair& pair) { return pair.kind() + json(pair.ids).dump(); }

/// The smallest two-sided p-value the exact test can give for samples of n and m: 2 / C(n + m, n).
double smallest_p(std::size_t n, std::size_t m) {
  double rankings = 1;
  for (std::size_t k = 1; k <= n; ++k) rankings = rankings * static_cast<double>(m + k) / static_cast<double>(k);
  return std::min(1.0, 2.0 / rankings);
}

struct CellComparison {
  std::string name;
  CellSummary base, head;
  bool worse = false, slower = false, faster = false;
  /// Why its verdicts (inputs_differ) or its times (times_differ) cannot be compared, "" when they can.
  std::string inputs_differ, times_differ;
  std::vector<std::string> notes;
  std::vector<std::size_t> changed_steps;
  /// The pairs the head misses and the base did not, by step: the records as the head kept them (missed_pair_record).
  std::vector<std::pair<std::size_t, MissedPair>> newly_missed;
  std::optional<RankTest> time_test;
  /// Its passes ran in turn with the other side's (one `run --interleave`): tested pair by pair, and gated.
  bool paired = false;
  /// The time test's p adjusted for every cell whose times this comparison tests (Holm): what is compared with alpha.
  double p_family = 1;
  double ratio = 0;
};

void compare_steps(const ResultSet& base, const ResultSet& head, CellComparison& cell) {
  const auto base_steps = base.steps.find(steps_key(cell.base.scene, cell.base.thickness, cell.base.strategy));
  const auto head_steps = head.steps.find(steps_key(cell.head.scene, cell.head.thickness, cell.head.strategy));
  if (base_steps == base.steps.end() || head_steps == head.steps.end()) return;
  std::vector<std::size_t> unlisted;  // steps with more missed pairs than their records keep
  for (const auto& [k, head_step] : head_steps->second) {
    const auto other = base_steps->second.find(k);
    if (other == base_steps->second.end()) continue;
    const StepRecord& base_step = other->second;
    if (base_step.answers.value_or("") != head_step.answers.value_or("")) cell.changed_steps.push_back(k);
    if (!head_step.verdict || !head_step.verdict->missed_pairs) continue;
    // Each side keeps only its first missed pairs (kKeptMissedPairs): beyond them a pair's status is not known.
    const std::vector<MissedPair> kept_base =
        base_step.verdict ? base_step.verdict->missed_pairs.value_or(std::vector<MissedPair>()) : std::vector<MissedPair>();
    const std::vector<MissedPair>& kept_head = *head_step.verdict->missed_pairs;
    // A step's missed count includes face-shape contacts, which are kept as no pair.
    auto pairs_missed = [](const StepRecord& step) {
      if (!step.verdict) return std::size_t{0};
      return step.verdict->missed - std::min(step.verdict->missed, step.verdict->missed_face_shape.value_or(0));
    };
    if (pairs_missed(base_step) > kept_base.size() || pairs_missed(head_step) > kept_head.size()) {
      unlisted.push_back(k);
      continue;
    }
    std::set<std::string> before;
    for (const MissedPair& pair : kept_base) before.insert(pair_identity(pair));
    for (const MissedPair& pair : kept_head) {
      if (before.count(pair_identity(pair)) == 0) cell.newly_missed.emplace_back(k, pair);
    }
  }
  if (!unlisted.empty()) {
    std::string steps;
    for (std::size_t i = 0; i < std::min<std::size_t>(unlisted.size(), 20); ++i) steps += (i ? " " : "") + std::to_string(unlisted[i]);
    cell.notes.push_back(std::to_string(unlisted.size()) + " step" + (unlisted.size() == 1 ? "" : "s") +
                         " with more missed pairs than a record keeps (" + std::to_string(kKeptMissedPairs) +
                         "), whose newly missed pairs are not listed: " + steps + (unlisted.size() > 20 ? " ..." : ""));
  }
}

CellComparison compare_cell(const ResultSet& base_set, const ResultSet& head_set, const CellSummary& base, const CellSummary& head,
                            const std::string& name) {
  CellComparison cell;
  cell.name = name;
  cell.base = base;
  cell.head = head;
  // Verdicts of different inputs say nothing of a change: the cell is shown, not judged.
  cell.inputs_differ = inputs_differ(base, head);
  if (!cell.inputs_differ.empty()) {
    cell.notes.push_back("not compared: " + cell.inputs_differ);
    return cell;
  }
  for (const ShownMeasure& shown : kShown) {
    if (!shown.judged) continue;
    const Measure* measure = shown.measure;
    const auto b = measure->of(base), h = measure->of(head);
    if (b && h && *h > *b) {
      cell.worse = true;
      cell.notes.push_back(std::string(measure->name) + " " + change(b, h));
    } else if (b && !h) {
      // A verdict the base has and the head does not (a head run without --verify exact or --toi) cannot be said
      // not to have got worse.
      cell.worse = true;
      cell.notes.push_back(std::string("the head has no ") + measure->name + " (the base has " + change(b, b) + "): run it with --verify exact" +
                           (measure == &measures::toi_late ? " --toi" : ""));
    }
  }
  if (head.nondeterministic_at_step && !base.nondeterministic_at_step) {
    cell.worse = true;
    cell.notes.push_back("answers now change between passes (step " + std::to_string(*head.nondeterministic_at_step) + ")");
  }
  if (base.strategy != head.strategy) {
    const std::string b = digest_in(base.strategy), h = digest_in(head.strategy);
    cell.notes.push_back(!b.empty() && !h.empty() && b != h ? "plugin code changed: digest " + b + " → " + h : "resolved strategy changed");
  }
  compare_steps(base_set, head_set, cell);
  cell.times_differ = times_differ(base, head);
  if (json(base) == json(head)) {
    // A cell of a run compared with that run (one outside --pair): nothing to test, and no place in the family.
    cell.notes.push_back("one record on both sides: times not tested");
  } else if (!cell.times_differ.empty()) {
    cell.notes.push_back("times not compared: " + cell.times_differ);
  } else if (!base.ms_per_repeat.empty() && !head.ms_per_repeat.empty()) {
    const std::vector<double>&base_times = base.ms_per_repeat, &head_times = head.ms_per_repeat;
    // The paired test takes the logs of the passes' ratios: every time positive.
    const auto positive = [](const std::vector<double>& times) { return std::all_of(times.begin(), times.end(), [](double t) { return t > 0; }); };
    cell.paired = base.interleave_group && head.interleave_group == base.interleave_group && base_times.size() == head_times.size() &&
                  positive(base_times) && positive(head_times);
    if (cell.paired) {
      // Pass i of each side ran one after the other: the ratio is the median of the passes' ratios.
      cell.time_test = wilcoxon_signed_rank(base_times, head_times);
      std::vector<double> ratios;
      for (std::size_t i = 0; i < base_times.size(); ++i) ratios.push_back(head_times[i] / base_times[i]);
      cell.ratio = median(ratios);
    } else {
      cell.time_test = mann_whitney(base_times, head_times);
      cell.ratio = base.ms_per_step > 0 ? head.ms_per_step / base.ms_per_step : 0;
      cell.notes.push_back(
          "times from two runs apart, not gated: their passes are not independent of the machine's drift between the runs, "
          "which no test over them sees (run base and head in one invocation with --interleave)");
    }
  } else {
    cell.notes.push_back("times not tested: a side has no per-repeat times (records of schema 1)");
  }
  return cell;
}

/// The time verdicts of the cells whose times were tested, in two families: the paired cells (passes in turn, the
/// ones gated) and the cells of runs apart. Each p is adjusted for its family's size (Holm), so that a comparison of
/// identical code calls any paired cell slower or faster with probability at most alpha (docs/ci-regression.md,
/// "Time verdicts"); and the noise band.
void judge_times(std::vector<CellComparison>& cells, const CompareOptions& options) {
  for (const bool paired : {true, false}) {
    std::vector<double> p;
    for (const CellComparison& c : cells) {
      if (c.time_test && c.paired == paired) p.push_back(c.time_test->p);
    }
    const std::vector<double> adjusted = holm_adjusted(p);
    std::size_t k = 0;
    for (CellComparison& c : cells) {
      if (!c.time_test || c.paired != paired) continue;
      c.p_family = adjusted[k++];
      c.slower = c.p_family < options.alpha && c.ratio > 1 + options.noise_band;
      c.faster = c.p_family < options.alpha && c.ratio < 1 / (1 + options.noise_band);
      const std::size_t base_passes = c.base.ms_per_repeat.size(), head_passes = c.head.ms_per_repeat.size();
      const double smallest = paired ? smallest_signed_rank_p(base_passes) : smallest_p(base_passes, head_passes);
      if (smallest * static_cast<double>(p.size()) >= options.alpha) {
        c.notes.push_back("times cannot be told apart: " + std::to_string(base_passes) + " and " + std::to_string(head_passes) +
                          " passes give p >= " + significant(smallest, 2) + ", and with " + std::to_string(p.size()) + " cell" +
                          (p.size() == 1 ? "" : "s") + (paired ? " paired" : " apart") + " it must be below " +
                          significant(options.alpha / static_cast<double>(p.size()), 2) + " (run both with more --repeat)");
      }
    }
  }
}

Table comparison_table(const std::vector<CellComparison>& cells) {
  using Align = Table::Align;
  std::vector<Table::Column> columns = {{"cell"}};
  for (const ShownMeasure& shown : kShown) {
    if (shown.column) columns.push_back({shown.column, Align::right});
  }
  for (const char* column : {"head/base", "p (Holm)"}) columns.push_back({column, Align::right});
  columns.push_back({"verdict"});
  Table table(std::move(columns));
  for (const CellComparison& c : cells) {
    std::string verdict = c.worse ? "WORSE" : "same or better";
    if (!c.inputs_differ.empty()) {
      verdict = "NOT COMPARABLE: " + c.inputs_differ;
    } else if (!c.times_differ.empty()) {
      verdict += ", times not comparable: " + c.times_differ;
    } else if (c.time_test) {
      verdict += c.slower ? ", slower beyond noise" : c.faster ? ", faster beyond noise" : ", time within noise";
      if (!c.paired && (c.slower || c.faster)) verdict += " (runs apart: not gated)";
    }
    std::vector<std::string> row = {c.name};
    for (const ShownMeasure& shown : kShown) {
      if (!shown.column) continue;
      const auto scaled = [&](std::optional<double> v) { return v ? std::optional<double>(*v / shown.scale) : std::nullopt; };
      row.push_back(change(scaled(shown.measure->of(c.base)), scaled(shown.measure->of(c.head)), shown.digits));
    }
    row.push_back(c.time_test ? fixed(c.ratio, 2) + "x" : "-");
    row.push_back(c.time_test ? significant(c.p_family, 2) + (c.paired ? " paired" : " apart") : "-");
    row.push_back(verdict);
    table.add_row(std::move(row));
  }
  return table;
}

/// Details under the table: notes, changed steps, newly missed pairs (and where they were written).
std::string details(const std::vector<CellComparison>& cells, const std::map<std::string, std::filesystem::path>& written) {
  std::ostringstream text;
  for (const CellComparison& c : cells) {
    if (c.notes.empty() && c.changed_steps.empty() && c.newly_missed.empty()) continue;
    text << c.name << ":\n";
    for (const std::string& note : c.notes) text << "  " << note << "\n";
    if (!c.changed_steps.empty()) {
      text << "  answers changed on " << c.changed_steps.size() << " step" << (c.changed_steps.size() == 1 ? "" : "s") << ":";
      for (std::size_t i = 0; i < std::min<std::size_t>(c.changed_steps.size(), 20); ++i) text << " " << c.changed_steps[i];
      text << (c.changed_steps.size() > 20 ? " ..." : "") << "\n";
    }
    for (const auto& [step, pair] : c.newly_missed)
      text << "  newly missed at step " << step << ": " << pair.kind() << " " << json(pair.ids).dump() << "\n";
    if (const auto it = written.find(c.name); it != written.end()) {
      // The pairs collide at the cell's δ: they are replayed at it.
      text << "  written to replay: ccdbench queries " << it->second.string() << " --thickness " << significant(c.head.thickness, 17) << "\n";
    }
  }
  return text.str();
}

/// The replay folders compare writes: ROOT/cell-NUMBER-SCENE-at-δ/{vertex-face,edge-edge}/newly-missed.csv.
constexpr const char* kReplayFile = "newly-missed.csv";

/// Removes the files an earlier compare wrote under `root` (its cell folders' newly-missed.csv, then the folders
/// left empty): the folder then holds this comparison's pairs alone. Nothing else is touched.
void clear_replay(const std::filesystem::path& root) {
  std::error_code error;
  if (!std::filesystem::is_directory(root, error)) return;
  for (const auto& entry : std::filesystem::directory_iterator(root, error)) {
    if (!entry.is_directory() || entry.path().filename().string().rfind("cell-", 0) != 0) continue;
    for (const char* kind : {"vertex-face", "edge-edge"}) {
      std::filesystem::remove(entry.path() / kind / kReplayFile, error);
      std::filesystem::remove(entry.path() / kind, error);  // only when empty
    }
    std::filesystem::remove(entry.path(), error);  // only when empty
  }
}

/// The newly missed pairs of the `number`th cell compared as query files. Their truth is 1 at the cell's δ (they
/// collide there, as run's --misses files do), which the folder's name says and the replay command passes.
std::filesystem::path write_replay(const CellComparison& c, std::size_t number, const std::filesystem::path& root) {
  const std::filesystem::path folder =
      root / ("cell-" + std::to_string(number) + "-" + safe_path_component(c.head.scene.substr(0, 100)) + "-at-" + significant(c.head.thickness, 17));
  std::vector<datasets::Query> vertex_face, edge_edge;
  for (const auto& [step, pair] : c.newly_missed) {
    datasets::Query query;
    const std::array<double, 24>& rows = pair.rows;  // 24 finite numbers (checked when read)
    for (int i = 0; i < 8; ++i) {
      for (int k = 0; k < 3; ++k) {
        const double value = rows[static_cast<std::size_t>(3 * i + k)];
        query.rounded[i][k] = value;
        query.exact[i][k] = mpq_class(value);
      }
    }
    query.truth = true;
    (pair.vertex_face ? vertex_face : edge_edge).push_back(std::move(query));
  }
  // Labelled at the cell's δ, which the files say (a replay at another δ is told its labels are not for it).
  const double thickness = c.head.thickness;
  if (!vertex_face.empty()) datasets::write_query_file(folder / "vertex-face" / kReplayFile, vertex_face, thickness);
  if (!edge_edge.empty()) datasets::write_query_file(folder / "edge-edge" / kReplayFile, edge_edge, thickness);
  return folder;
}

/// The comparison as Markdown, for a pull request's comment.
void write_markdown(const std::filesystem::path& path, bool worse, const Table& table, const std::string& more,
                    const std::vector<std::string>& only_base, const std::vector<std::string>& only_head) {
  datasets::AtomicFile file(path, std::ios::out);
  file.stream() << "### ccdbench compare\n\n" << (worse ? "**A verdict got worse.**" : "No verdict got worse.") << "\n\n";
  table.print_markdown(file.stream());
  if (!more.empty()) file.stream() << "\n```\n" << more << "```\n";
  for (const std::string& name : only_base) file.stream() << "\n- only in the base (the head lost it): " << name;
  for (const std::string& name : only_head) file.stream() << "\n- only in the head: " << name;
  file.stream() << "\n";
  file.commit();
}

/// The comparison as JSON, for scripts.
void write_comparison_json(const std::filesystem::path& path, const std::vector<CellComparison>& cells, const std::vector<std::string>& only_base,
                           const std::vector<std::string>& only_head) {
  json document = json::array();
  for (const CellComparison& c : cells) {
    json row = {{"cell", c.name},
                {"worse", c.worse},
                {"slower_beyond_noise", c.slower},
                {"faster_beyond_noise", c.faster},
                {"verdicts_not_comparable", c.inputs_differ.empty() ? json() : json(c.inputs_differ)},
                {"times_not_comparable", c.times_differ.empty() ? json() : json(c.times_differ)},
                {"notes", c.notes},
                {"changed_steps", c.changed_steps}};
    for (const ShownMeasure& shown : kShown) {
      const Measure& m = *shown.measure;
      // A count is written as the integer the records hold.
      const auto value = [&](std::optional<double> v) { return !v ? json() : m.count ? json(static_cast<std::uint64_t>(*v)) : json(*v); };
      row[m.name] = {{"base", value(m.of(c.base))}, {"head", value(m.of(c.head))}};
    }
    if (c.time_test) {
      row["time"] = {{"ratio", c.ratio},   {"p", c.time_test->p},         {"p_family", c.p_family},
                     {"paired", c.paired}, {"statistic", c.time_test->u}, {"test", c.paired ? "wilcoxon signed-rank" : "mann-whitney u"}};
    }
    json missed = json::array();
    // Listed by kind and ids; their coordinates are in the replay files.
    for (const auto& [step, pair] : c.newly_missed) missed.push_back({{"step", step}, {"kind", pair.kind()}, {"ids", pair.ids}});
    row["newly_missed"] = missed;
    document.push_back(row);
  }
  datasets::write_json_file(path, json{{"cells", document}, {"only_in_base", only_base}, {"only_in_head", only_head}});
}

}  // namespace

int run_compare(const CompareOptions& options, std::ostream& out) {
  if (options.markdown) datasets::require_writable_file(*options.markdown);
  if (options.json) datasets::require_writable_file(*options.json);
  const ResultSet base = read_result_set(options.base), head = read_result_set(options.head);
  // Records of schema 1 carry no spec: then every cell is matched by its resolved name (built-in strategies still
  // match; a plugin's resolved name holds its path and digest, so its two builds do not).
  const auto without_spec = [](const ResultSet& set) {
    return std::any_of(set.summaries.begin(), set.summaries.end(), [](const CellSummary& s) { return s.spec.empty(); });
  };
  const bool by_resolved = without_spec(base) || without_spec(head);
  auto given = [&](const CellSummary& s) { return by_resolved ? s.strategy : s.given(); };
  for (const auto& [b, h] : options.pairs) {
    for (const auto& [set, spec] : {std::pair{&base, b}, {&head, h}}) {
      if (std::none_of(set->summaries.begin(), set->summaries.end(), [&](const CellSummary& s) { return given(s) == spec; })) {
        throw InputError(set->path, {}, "--pair " + b + " " + h + ": no cell of " + spec + " here (the strategy as run's --strategy gave it)");
      }
    }
  }
  // Which spec of a side a cell is matched by: as given, or paired.
  auto matched_spec = [&](const std::string& spec, bool base_side) {
    for (const auto& [b, h] : options.pairs) {
      if (spec == (base_side ? b : h)) return b + " → " + h;
    }
    return spec;
  };
  // With pairs, a side's cells of the other side's spec are not compared (in one run's results, the head's build
  // on the base side and the base's build on the head side).
  auto left_out = [&](const std::string& spec, bool base_side) {
    bool other = false, own = false;
    for (const auto& [b, h] : options.pairs) {
      other = other || spec == (base_side ? h : b);
      own = own || spec == (base_side ? b : h);
    }
    return other && !own;
  };
  std::map<std::string, const CellSummary*> base_cells, head_cells;
  std::vector<std::string> order;
  for (const auto& [set, cells, base_side] : {std::tuple{&base, &base_cells, true}, {&head, &head_cells, false}}) {
    for (const CellSummary& s : set->summaries) {
      if (left_out(given(s), base_side)) continue;
      const std::string key = match_key(s, matched_spec(given(s), base_side));
      if (!cells->emplace(key, &s).second) {
        throw InputError(set->path, {}, "two cells match as " + cell_name(s, given(s)) + " (one strategy given twice?)");
      }
      if (base_side || base_cells.count(key) == 0) order.push_back(key);
    }
  }
  std::vector<CellComparison> cells;
  std::vector<std::string> only_base, only_head;
  for (const std::string& key : order) {
    const auto b = base_cells.find(key), h = head_cells.find(key);
    if (b == base_cells.end()) {
      only_head.push_back(cell_name(*h->second, given(*h->second)));
    } else if (h == head_cells.end()) {
      only_base.push_back(cell_name(*b->second, given(*b->second)));
    } else {
      const std::string spec = matched_spec(given(*b->second), true);
      cells.push_back(compare_cell(base, head, *b->second, *h->second, cell_name(*h->second, spec)));
    }
  }
  judge_times(cells, options);
  if (!options.replay.empty()) clear_replay(options.replay);
  std::map<std::string, std::filesystem::path> written;
  for (std::size_t k = 0; k < cells.size(); ++k) {
    if (!cells[k].newly_missed.empty()) written[cells[k].name] = write_replay(cells[k], k + 1, options.replay);
  }
  const Table table = comparison_table(cells);
  table.print(out);
  out << details(cells, written);
  for (const std::string& name : only_base) out << "only in the base: " << name << " (the head lost it: a verdict it cannot show)\n";
  for (const std::string& name : only_head) out << "only in the head: " << name << "\n";
  if (!base.has_steps || !head.has_steps) out << "steps not compared: a side has no step records (give run's --out folder or its results.jsonl)\n";
  if (by_resolved) out << "cells matched by resolved name: a side's records are of schema 1 (no spec)\n";
  for (const ResultSet* set : {&base, &head}) {
    if (set->replaced > 0)
      out << set->path.string() << ": " << set->replaced << " earlier result(s) of a cell left out (the latest of each is compared)\n";
  }
  // A cell the base had and the head lacks is a verdict the head cannot show.
  const bool worse = !only_base.empty() || std::any_of(cells.begin(), cells.end(), [](const CellComparison& c) { return c.worse; });
  // Only times of passes that ran in turn are gated (the notes say why the others are not).
  const bool slower = std::any_of(cells.begin(), cells.end(), [](const CellComparison& c) { return c.slower && c.paired; });
  const auto slower_apart = std::count_if(cells.begin(), cells.end(), [](const CellComparison& c) { return c.slower && !c.paired; });
  const auto not_comparable =
      std::count_if(cells.begin(), cells.end(), [](const CellComparison& c) { return !c.inputs_differ.empty() || !c.times_differ.empty(); });
  if (options.markdown) write_markdown(*options.markdown, worse, table, details(cells, written), only_base, only_head);
  if (options.json) write_comparison_json(*options.json, cells, only_base, only_head);
  out << "compare: " << (worse ? "a verdict got WORSE" : "no verdict got worse") << (slower ? "; a cell got slower beyond the noise" : "");
  if (slower_apart > 0) {
    out << "; " << slower_apart << " cell" << (slower_apart == 1 ? "" : "s")
        << " of two runs apart called slower, not gated (run base and head with --interleave)";
  }
  if (not_comparable > 0) {
    out << "; " << not_comparable << " cell" << (not_comparable == 1 ? "" : "s") << " not comparable (verdicts or times, named on the row)"
        << (options.allow_incomparable ? ", allowed" : ": --allow-incomparable accepts that");
  }
  out << "\n";
  if (worse || (options.fail_on_slower && slower)) return 1;
  return not_comparable > 0 && !options.allow_incomparable ? 3 : 0;
}

}  // namespace ccd::harness
