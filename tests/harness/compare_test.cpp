// `compare` on fixed synthetic result files (docs/ci-regression.md): verdicts, time verdicts, what may be compared,
// malformed input. The rank tests it uses are rank_test_test.cpp; the gate's round trips with real runs,
// gate_round_trip_test.cpp.

#include "tests/support/cli.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <sstream>

namespace ccd {
namespace {

using testing::quoted;
using testing::read_json;
using testing::run_ccdbench;

/// A cell's records as `run --out` writes them into results.jsonl: three steps, a plugin built at some digest.
struct SyntheticCell {
  std::string scene = "s";
  std::string spec = "plugin:my.so";
  std::string digest = "0123456789abcdef0123456789abcdef";
  std::size_t missed = 0;
  /// Each step's missed pairs: (kind, ids).
  std::vector<std::vector<std::pair<std::string, std::vector<int>>>> missed_pairs = {{}, {}, {}};
  std::vector<std::string> answers = {"a0", "a1", "a2"};
  std::vector<double> ms_per_repeat = {30, 31, 29, 30.5, 29.5};
  std::string machine = "m1";
  /// What its verdicts are of (the scene's content digest in its key) and where its times were made.
  std::string scene_content = "c0";
  std::size_t threads = 2;
  /// `run --interleave`: the group whose passes ran in turn.
  std::optional<std::string> interleave_group;

  std::string resolved() const {
    return spec.rfind("plugin:", 0) == 0 ? "plugin:/abs/" + spec.substr(7) + ":digest=" + digest + ":isolate=on" : spec;
  }

  std::string lines() const {
    std::string text;
    std::size_t total = 0;
    for (std::size_t k = 0; k < 3; ++k) {
      nlohmann::json pairs = nlohmann::json::array();
      for (const auto& [kind, ids] : missed_pairs[k]) {
        std::vector<double> rows(24);
        for (std::size_t i = 0; i < 24; ++i) rows[i] = 0.125 * static_cast<double>(i) + ids[0];
        pairs.push_back({{"kind", kind}, {"ids", ids}, {"rows", rows}});
      }
      total += pairs.size();
      nlohmann::json step = {{"record", "step"}, {"schema", 2},           {"scene", scene},         {"thickness", 0.01}, {"strategy", resolved()},
                             {"step", k},        {"answers", answers[k]}, {"missed", pairs.size()}, {"colliding", 10}};
      if (!pairs.empty()) step["missed_pairs"] = pairs;
      text += step.dump() + "\n";
    }
    std::vector<double> sorted = ms_per_repeat;
    std::sort(sorted.begin(), sorted.end());
    const nlohmann::json summary = {{"record", "summary"},
                                    {"schema", 2},
                                    {"scene", scene},
                                    {"strategy", resolved()},
                                    {"spec", spec},
                                    {"thickness", 0.01},
                                    {"thickness_from", "scene"},
                                    {"steps", 3},
                                    {"ms_per_step", sorted[sorted.size() / 2] / 3},
                                    {"ms_per_repeat", ms_per_repeat},
                                    {"verified", true},
                                    {"colliding", 30},
                                    {"missed", std::max(missed, total)},
                                    {"false_alarms", 2},
                                    {"errors", 0},
                                    {"host_peak_bytes", 1 << 20},
                                    {"key", {{"scene_content", scene_content}, {"steps", 3}}},
                                    {"machine", machine},
                                    {"threads", threads},
                                    {"executable", "e0"},
                                    {"build_type", "Release"},
                                    {"provenance", {{"compiler", "GNU 12.2.0"}, {"cxx_flags", "-O2"}}}};
    nlohmann::json record = summary;
    if (interleave_group) record["interleave_group"] = *interleave_group;
    return text + record.dump() + "\n";
  }
};

class Compare : public ::testing::Test {
 protected:
  std::filesystem::path write(const std::string& name, const std::vector<SyntheticCell>& cells) {
    std::string text;
    for (const SyntheticCell& cell : cells) text += cell.lines();
    testing::write_text(dir_ / name, text);
    return dir_ / name;
  }
  testing::CommandResult compare(const std::filesystem::path& base, const std::filesystem::path& head, const std::string& extra = {}) {
    return run_ccdbench("compare " + quoted(base) + " " + quoted(head) + " --replay " + quoted(dir_ / "replay") + " " + extra);
  }
  testing::TempDir dir_;
};

TEST_F(Compare, ARunComparedWithItselfShowsNoChange) {
  const auto base = write("base.jsonl", {SyntheticCell{}});
  const auto result = compare(base, base, "--json " + quoted(dir_ / "c.json") + " --markdown " + quoted(dir_ / "c.md"));
  EXPECT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("no verdict got worse"), std::string::npos) << result.output;
  EXPECT_EQ(result.output.find("WORSE"), std::string::npos) << result.output;
  EXPECT_EQ(result.output.find("answers changed"), std::string::npos) << result.output;
  EXPECT_EQ(result.output.find("only in"), std::string::npos) << result.output;
  const nlohmann::json document = read_json(dir_ / "c.json");
  ASSERT_EQ(document["cells"].size(), 1u);
  EXPECT_FALSE(document["cells"][0]["worse"]);
  EXPECT_FALSE(document["cells"][0].contains("time"));  // one record on both sides: nothing to test
  EXPECT_NE(result.output.find("one record on both sides: times not tested"), std::string::npos) << result.output;
  EXPECT_TRUE(std::filesystem::exists(dir_ / "c.md"));
}

TEST_F(Compare, OneMoreMissedPairExits1NamingTheCellAndThePair) {
  SyntheticCell before;
  before.missed_pairs = {{{"vf", {4, 9}}}, {}, {}};
  SyntheticCell after = before;
  after.digest = "fedcba9876543210fedcba9876543210";
  after.missed_pairs[2] = {{"ee", {1, 2, 7, 8}}};
  after.answers[2] = "b2";
  const auto result = compare(write("base.jsonl", {before}), write("head.jsonl", {after}), "--json " + quoted(dir_ / "c.json"));
  EXPECT_EQ(result.exit_code, 1) << result.output;
  EXPECT_NE(result.output.find("s / plugin:my.so / δ scene's 0.01:"), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("missed 1 → 2"), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("newly missed at step 2: ee [1,2,7,8]"), std::string::npos) << result.output;
  EXPECT_EQ(result.output.find("newly missed at step 0"), std::string::npos) << result.output;  // an old miss
  EXPECT_NE(result.output.find("answers changed on 1 step: 2"), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("plugin code changed: digest 0123456789abcdef0123456789abcdef → fedcba9876543210fedcba9876543210"), std::string::npos)
      << result.output;
  EXPECT_NE(result.output.find("a verdict got WORSE"), std::string::npos) << result.output;
  const nlohmann::json document = read_json(dir_ / "c.json");
  EXPECT_TRUE(document["cells"][0]["worse"]);
  ASSERT_EQ(document["cells"][0]["newly_missed"].size(), 1u);
  EXPECT_EQ(document["cells"][0]["newly_missed"][0]["ids"], nlohmann::json({1, 2, 7, 8}));
  // Counts are written as the integers the records hold.
  EXPECT_EQ(document["cells"][0]["missed"], nlohmann::json({{"base", 1}, {"head", 2}}));
  EXPECT_TRUE(document["cells"][0]["missed"]["head"].is_number_unsigned()) << document["cells"][0].dump();
  // The pair written to replay, as a query file `queries` reads.
  const std::filesystem::path replay = dir_ / "replay";
  ASSERT_TRUE(std::filesystem::exists(replay)) << result.output;
  std::filesystem::path written;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(replay)) {
    if (entry.is_regular_file()) written = entry.path();
  }
  EXPECT_EQ(written.filename(), "newly-missed.csv");
  EXPECT_EQ(written.parent_path().filename(), "edge-edge");
  const auto replayed = run_ccdbench("queries " + quoted(written.parent_path().parent_path()) + " --method exact --thickness 0.01");
  EXPECT_EQ(replayed.exit_code, 0) << replayed.output;
  // Fewer misses is no regression.
  EXPECT_EQ(compare(dir_ / "head.jsonl", dir_ / "base.jsonl").exit_code, 0);
}

TEST_F(Compare, TimesWithinTheNoiseAreNotFlaggedATwofoldSlowdownIs) {
  // Two runs apart: tested and shown, never gated (their passes do not sample the drift between the runs).
  SyntheticCell base;
  SyntheticCell noisy = base;
  noisy.ms_per_repeat = {30.4, 29.8, 31.2, 29.2, 30.1};
  const auto same = compare(write("base.jsonl", {base}), write("noisy.jsonl", {noisy}), "--fail-on-slower");
  EXPECT_EQ(same.exit_code, 0) << same.output;
  EXPECT_NE(same.output.find("time within noise"), std::string::npos) << same.output;
  SyntheticCell slow = base;
  for (double& ms : slow.ms_per_repeat) ms *= 2;
  const auto slower = compare(dir_ / "base.jsonl", write("slow.jsonl", {slow}), "--fail-on-slower");
  EXPECT_EQ(slower.exit_code, 0) << slower.output;
  EXPECT_NE(slower.output.find("2.00x"), std::string::npos) << slower.output;
  EXPECT_NE(slower.output.find("0.0079 apart"), std::string::npos) << slower.output;  // 2 / C(10, 5)
  EXPECT_NE(slower.output.find("slower beyond noise (runs apart: not gated)"), std::string::npos) << slower.output;
  EXPECT_NE(slower.output.find("1 cell of two runs apart called slower, not gated"), std::string::npos) << slower.output;
  // Three passes a side cannot reach p < 0.05 (2 / C(6, 3) = 0.1): it says so rather than flag nothing silently.
  SyntheticCell few = base, few_slow = slow;
  few.ms_per_repeat.resize(3);
  few_slow.ms_per_repeat.resize(3);
  const auto too_few = compare(write("few.jsonl", {few}), write("few_slow.jsonl", {few_slow}), "--fail-on-slower");
  EXPECT_EQ(too_few.exit_code, 0) << too_few.output;
  EXPECT_NE(too_few.output.find("times cannot be told apart: 3 and 3 passes give p >= 0.1, and with 1 cell apart it must be below 0.05"),
            std::string::npos)
      << too_few.output;
  // Another machine: verdicts only, and the times said to be not comparable (exit 3 unless allowed).
  SyntheticCell elsewhere = slow;
  elsewhere.machine = "m2";
  const auto other = compare(dir_ / "base.jsonl", write("elsewhere.jsonl", {elsewhere}), "--fail-on-slower");
  EXPECT_EQ(other.exit_code, 3) << other.output;
  EXPECT_NE(other.output.find("times not compared: the machine differs (m1, m2)"), std::string::npos) << other.output;
  EXPECT_EQ(compare(dir_ / "base.jsonl", dir_ / "elsewhere.jsonl", "--fail-on-slower --allow-incomparable").exit_code, 0);
}

// Passes that ran in turn (run --interleave: one group on both sides) are tested pair by pair and gated: a drift
// of the whole machine (every pass of both 1.3x slower from the fifth on) is no slowdown, 1.25x on every pair is.
TEST_F(Compare, InterleavedPassesAreTestedPairByPairAndGated) {
  SyntheticCell base;
  base.spec = "plugin:base/my.so";
  base.interleave_group = "run-1/0";
  base.ms_per_repeat = {30, 31, 29, 30.5, 29.5, 30.2, 29.8, 30.6, 29.4};
  for (std::size_t i = 4; i < base.ms_per_repeat.size(); ++i) base.ms_per_repeat[i] *= 1.3;
  SyntheticCell drifted = base;
  drifted.spec = "plugin:head/my.so";
  const std::vector<double> noise = {1.01, 0.99, 1.02, 0.98, 1.01, 0.99, 1.0, 1.03, 0.97};
  for (std::size_t i = 0; i < noise.size(); ++i) drifted.ms_per_repeat[i] *= noise[i];
  const std::string pair = "--pair plugin:base/my.so plugin:head/my.so --fail-on-slower";
  const auto same = compare(write("same.jsonl", {base, drifted}), dir_ / "same.jsonl", pair);
  EXPECT_EQ(same.exit_code, 0) << same.output;
  EXPECT_NE(same.output.find("paired"), std::string::npos) << same.output;
  EXPECT_NE(same.output.find("time within noise"), std::string::npos) << same.output;
  SyntheticCell slowed = drifted;
  for (double& ms : slowed.ms_per_repeat) ms *= 1.25;
  const auto slower = compare(write("slowed.jsonl", {base, slowed}), dir_ / "slowed.jsonl", pair + " --json " + quoted(dir_ / "c.json"));
  EXPECT_EQ(slower.exit_code, 1) << slower.output;
  EXPECT_NE(slower.output.find("1.25x"), std::string::npos) << slower.output;
  EXPECT_NE(slower.output.find("0.0039 paired"), std::string::npos) << slower.output;  // 2 / 2^9
  EXPECT_NE(slower.output.find("a cell got slower beyond the noise"), std::string::npos) << slower.output;
  const nlohmann::json time = read_json(dir_ / "c.json")["cells"][0]["time"];
  EXPECT_EQ(time["test"], "wilcoxon signed-rank");
  EXPECT_TRUE(time["paired"].get<bool>());
  // A steady 5% (no noise band) under a machine that drifts by half from pass to pass: the pairs see it, a test over
  // the passes of two runs cannot.
  SyntheticCell swinging = base;
  swinging.ms_per_repeat = {30, 45, 33, 50, 36, 48, 31, 44, 39};
  SyntheticCell steady = swinging;
  steady.spec = "plugin:head/my.so";
  for (double& ms : steady.ms_per_repeat) ms *= 1.05;
  const std::string no_band = pair + " --noise-band 0";
  EXPECT_EQ(compare(write("steady.jsonl", {swinging, steady}), dir_ / "steady.jsonl", no_band).exit_code, 1);
  steady.interleave_group = "run-2/0";
  const auto steady_apart = compare(write("steady-apart.jsonl", {swinging, steady}), dir_ / "steady-apart.jsonl", no_band);
  EXPECT_EQ(steady_apart.exit_code, 0) << steady_apart.output;
  EXPECT_NE(steady_apart.output.find("time within noise"), std::string::npos) << steady_apart.output;
  // The same passes from two groups (two runs) are apart: the drift then hides in the rank test, and nothing is gated.
  SyntheticCell other_run = slowed;
  other_run.interleave_group = "run-2/0";
  const auto apart = compare(write("apart.jsonl", {base, other_run}), dir_ / "apart.jsonl", pair);
  EXPECT_EQ(apart.exit_code, 0) << apart.output;
  EXPECT_NE(apart.output.find("times from two runs apart, not gated"), std::string::npos) << apart.output;
}

// Holm: one cell 1.25x slower on all 9 pairs (p = 2/2^9) is flagged alone, but not among 20 paired cells, where the
// smallest p must be below 0.05 / 20 (which 9 pairs cannot give, and compare says so).
TEST_F(Compare, TheCellsTestedAreOneFamily) {
  std::vector<SyntheticCell> cells;
  for (int k = 0; k < 20; ++k) {
    SyntheticCell base;
    // Appended, not "s" + std::to_string(k): GCC 12 warns (-Wrestrict) on that form, wrongly.
    base.scene = std::string("s").append(std::to_string(k));
    base.spec = "plugin:base/my.so";
    base.interleave_group = std::string("run-1/").append(std::to_string(k));
    base.ms_per_repeat = {30, 31, 29, 30.5, 29.5, 30.2, 29.8, 30.6, 29.4};
    SyntheticCell head = base;
    head.spec = "plugin:head/my.so";
    for (std::size_t i = 0; i < head.ms_per_repeat.size(); ++i) head.ms_per_repeat[i] *= 1.25 + 0.001 * static_cast<double>(i);
    cells.push_back(base);
    cells.push_back(head);
  }
  const std::string pair = "--pair plugin:base/my.so plugin:head/my.so --fail-on-slower";
  const auto one = compare(write("one.jsonl", {cells[0], cells[1]}), dir_ / "one.jsonl", pair);
  EXPECT_EQ(one.exit_code, 1) << one.output;
  const auto twenty = compare(write("twenty.jsonl", cells), dir_ / "twenty.jsonl", pair);
  EXPECT_EQ(twenty.exit_code, 0) << twenty.output;
  EXPECT_EQ(twenty.output.find("slower beyond noise"), std::string::npos) << twenty.output;
  EXPECT_NE(twenty.output.find("0.078 paired"), std::string::npos) << twenty.output;  // 20 x 2/2^9
  EXPECT_NE(twenty.output.find("with 20 cells paired it must be below 0.0025"), std::string::npos) << twenty.output;
}

// Route 3 of the gate issue: another scene under one label (same name, another content) has verdicts of another
// input: compared as if one, 49 of 49 missed looked "same or better" than 104 of 341. Not compared now, said on the
// row, and exit 3 unless allowed; a worse verdict there is no verdict at all.
TEST_F(Compare, AnotherSceneUnderOneLabelIsNotComparable) {
  SyntheticCell base;
  base.missed_pairs = {{{"vf", {4, 9}}, {"vf", {5, 9}}}, {}, {}};
  SyntheticCell other;
  other.scene_content = "c1";
  const auto result = compare(write("base.jsonl", {base}), write("other.jsonl", {other}), "--json " + quoted(dir_ / "c.json"));
  EXPECT_EQ(result.exit_code, 3) << result.output;
  EXPECT_NE(result.output.find("NOT COMPARABLE: the scene's content differs (c0, c1): another scene under one label"), std::string::npos)
      << result.output;
  EXPECT_EQ(result.output.find("same or better"), std::string::npos) << result.output;
  EXPECT_EQ(read_json(dir_ / "c.json")["cells"][0]["verdicts_not_comparable"], "the scene's content differs (c0, c1): another scene under one label");
  EXPECT_EQ(compare(dir_ / "base.jsonl", dir_ / "other.jsonl", "--allow-incomparable").exit_code, 0);
  // A record that does not say what its input was (no key) is not comparable either.
  std::string text;
  std::istringstream lines(SyntheticCell{}.lines());
  for (std::string line; std::getline(lines, line);) {
    nlohmann::json record = nlohmann::json::parse(line);
    record.erase("key");
    text += record.dump() + "\n";
  }
  testing::write_text(dir_ / "unkeyed.jsonl", text);
  const auto unknown = compare(dir_ / "base.jsonl", dir_ / "unkeyed.jsonl");
  EXPECT_EQ(unknown.exit_code, 3) << unknown.output;
  EXPECT_NE(unknown.output.find("the head does not say what its input was"), std::string::npos) << unknown.output;
}

// Route 4: times of another thread count were compared ("0.86x p 0.016 faster beyond noise"): not now, named on the
// row, kept out of --fail-on-slower, exit 3 unless allowed.
TEST_F(Compare, AnotherThreadCountMakesTimesNotComparable) {
  SyntheticCell base;
  SyntheticCell one_thread = base;
  one_thread.threads = 1;
  for (double& ms : one_thread.ms_per_repeat) ms *= 2;
  const auto result = compare(write("base.jsonl", {base}), write("one.jsonl", {one_thread}), "--fail-on-slower");
  EXPECT_EQ(result.exit_code, 3) << result.output;
  EXPECT_NE(result.output.find("same or better, times not comparable: the thread count differs (2, 1)"), std::string::npos) << result.output;
  EXPECT_EQ(result.output.find("slower beyond noise"), std::string::npos) << result.output;
  EXPECT_EQ(compare(dir_ / "base.jsonl", dir_ / "one.jsonl", "--fail-on-slower --allow-incomparable").exit_code, 0);
}

TEST_F(Compare, PairsMatchTwoBuildsOfOneRunAndCellsOnOneSideAreListed) {
  SyntheticCell base_build, head_build, full;
  base_build.spec = "plugin:base/my.so";
  head_build.spec = "plugin:head/my.so";
  head_build.missed_pairs = {{}, {{"vf", {3, 5}}}, {}};
  full.spec = "full";
  const auto one_run = write("one.jsonl", {base_build, head_build, full});
  const auto paired = compare(one_run, one_run, "--pair plugin:base/my.so plugin:head/my.so");
  EXPECT_EQ(paired.exit_code, 1) << paired.output;
  EXPECT_NE(paired.output.find("s / plugin:base/my.so → plugin:head/my.so / δ scene's 0.01:"), std::string::npos) << paired.output;
  EXPECT_NE(paired.output.find("newly missed at step 1: vf [3,5]"), std::string::npos) << paired.output;
  EXPECT_EQ(paired.output.find("only in"), std::string::npos) << paired.output;
  // Unpaired, the base's build is a cell the head lost: a verdict it cannot show.
  const auto unpaired = compare(write("base.jsonl", {base_build, full}), write("head.jsonl", {head_build, full}));
  EXPECT_EQ(unpaired.exit_code, 1) << unpaired.output;
  EXPECT_NE(unpaired.output.find("only in the base: s / plugin:base/my.so"), std::string::npos) << unpaired.output;
  EXPECT_NE(unpaired.output.find("only in the head: s / plugin:head/my.so"), std::string::npos) << unpaired.output;
  // A cell only the head has is no regression.
  EXPECT_EQ(compare(write("full.jsonl", {full}), dir_ / "head.jsonl").exit_code, 0);
  // A pair that names no cell is refused, never a comparison of nothing.
  const auto misspelt = compare(one_run, one_run, "--pair plugin:base/my.so plugin:hed/my.so");
  EXPECT_EQ(misspelt.exit_code, 2) << misspelt.output;
  EXPECT_NE(misspelt.output.find("no cell of plugin:hed/my.so"), std::string::npos) << misspelt.output;
}

TEST_F(Compare, AVerdictTheHeadLacksIsWorseAndRecordsOfSchema1MatchByResolvedName) {
  SyntheticCell base;
  const auto base_file = write("base.jsonl", {base});
  // A head run without --verify exact: its cells have no missed count.
  std::string text;
  std::istringstream in(base.lines());
  for (std::string line; std::getline(in, line);) {
    nlohmann::json record = nlohmann::json::parse(line);
    record.erase("missed");
    text += record.dump() + "\n";
  }
  testing::write_text(dir_ / "unverified.jsonl", text);
  const auto lacking = compare(base_file, dir_ / "unverified.jsonl");
  EXPECT_EQ(lacking.exit_code, 1) << lacking.output;
  EXPECT_NE(lacking.output.find("the head has no missed"), std::string::npos) << lacking.output;
  // TOIs checked without their late count (a record made by hand) are not 0 late.
  auto with_tois = [&](const char* name, bool late) {
    std::string lines;
    std::istringstream records(base.lines());
    for (std::string line; std::getline(records, line);) {
      nlohmann::json record = nlohmann::json::parse(line);
      if (record["record"] == "summary") {
        record["toi_checked"] = 30;
        if (late) record["toi_late"] = 0;
      }
      lines += record.dump() + "\n";
    }
    testing::write_text(dir_ / name, lines);
    return dir_ / name;
  };
  const auto no_late = compare(with_tois("late.jsonl", true), with_tois("checked.jsonl", false));
  EXPECT_EQ(no_late.exit_code, 1) << no_late.output;
  EXPECT_NE(no_late.output.find("the head has no toi_late"), std::string::npos) << no_late.output;
  // Schema 1 (no spec): matched by the resolved name, and still compared.
  SyntheticCell worse = base;
  worse.missed_pairs[0] = {{"vf", {1, 1}}};
  std::string old_text;
  std::istringstream old_in(base.lines());
  for (std::string line; std::getline(old_in, line);) {
    nlohmann::json record = nlohmann::json::parse(line);
    for (const char* field : {"schema", "spec", "ms_per_repeat", "missed_pairs"}) record.erase(field);
    old_text += record.dump() + "\n";
  }
  testing::write_text(dir_ / "schema1.jsonl", old_text);
  const auto old = compare(dir_ / "schema1.jsonl", write("worse.jsonl", {worse}));
  EXPECT_EQ(old.exit_code, 1) << old.output;
  EXPECT_NE(old.output.find("missed 0 → 1"), std::string::npos) << old.output;
  EXPECT_NE(old.output.find("cells matched by resolved name"), std::string::npos) << old.output;
}

TEST_F(Compare, MalformedFieldsAreBadInputAndNothingIsWritten) {
  SyntheticCell before, after;
  after.missed_pairs = {{{"vf", {2, 3}}}, {}, {}};
  const auto base = write("base.jsonl", {before});
  const std::string good = after.lines();
  struct Case {
    std::string from, to, where;
  };
  // Each: a field of the head's records made wrong, and where the refusal must point.
  const std::vector<Case> cases = {{"\"thickness\":0.01,\"thickness_from\"", "\"thickness\":\"0.01\",\"thickness_from\"", "line 4.thickness"},
                                   {"\"ms_per_repeat\":[30.0", "\"ms_per_repeat\":[null", "line 4.ms_per_repeat"},
                                   {"\"missed\":1,", "\"missed\":\"1\",", "line 1.missed"},
                                   {"\"ids\":[2,3]", "\"ids\":[2]", "line 1.missed_pairs[0].ids"},
                                   {"\"answers\":\"a1\"", "\"answers\":5", "line 2.answers"}};
  for (const Case& c : cases) {
    std::string text = good;
    const std::size_t at = text.find(c.from);
    ASSERT_NE(at, std::string::npos) << c.from << " in " << text;
    text.replace(at, c.from.size(), c.to);
    testing::write_text(dir_ / "head.jsonl", text);
    std::filesystem::remove_all(dir_ / "replay");
    const auto refused = compare(base, dir_ / "head.jsonl", "--markdown " + quoted(dir_ / "c.md"));
    EXPECT_EQ(refused.exit_code, 2) << c.to << ": " << refused.output;
    EXPECT_NE(refused.output.find("head.jsonl:" + c.where + ": "), std::string::npos) << c.to << ": " << refused.output;
    EXPECT_FALSE(std::filesystem::exists(dir_ / "c.md"));
    EXPECT_FALSE(std::filesystem::exists(dir_ / "replay"));
  }
  testing::write_text(dir_ / "empty.jsonl", "");
  const auto empty = compare(base, dir_ / "empty.jsonl");
  EXPECT_EQ(empty.exit_code, 2) << empty.output;
  EXPECT_NE(empty.output.find("no summary of any cell"), std::string::npos) << empty.output;
}

TEST_F(Compare, RefusesWhatIsNotAResultSet) {
  testing::write_text(dir_ / "junk.jsonl", "{\"record\": \"summary\", \"scene\": \"s\"}\n");
  const auto junk = compare(dir_ / "junk.jsonl", dir_ / "junk.jsonl");
  EXPECT_EQ(junk.exit_code, 2) << junk.output;
  EXPECT_NE(junk.output.find("junk.jsonl:line 1: a summary without 'strategy'"), std::string::npos) << junk.output;
  const auto folder = compare(dir_.path(), dir_.path());
  EXPECT_EQ(folder.exit_code, 2) << folder.output;
  EXPECT_NE(folder.output.find("no results.jsonl"), std::string::npos) << folder.output;
}

}  // namespace
}  // namespace ccd
