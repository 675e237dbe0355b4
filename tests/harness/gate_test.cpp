// `ccdbench check`: the CI gate must be able to fail, and fails whenever a cell gates nothing.

#include "harness/run/record_fields.hpp"
#include "tests/support/cli.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

namespace ccd {
namespace {

using testing::quoted;
using testing::run_ccdbench;

/// A verified summary as `ccdbench run --json` writes it (only the fields the gate reads).
nlohmann::json summary(const std::string& strategy, std::size_t missed, std::size_t colliding, const std::string& thickness_from = "scene",
                       double thickness = 0.01) {
  return {{"scene", "s"},     {"strategy", strategy},    {"thickness", thickness}, {"thickness_from", thickness_from}, {"verified", true},
          {"missed", missed}, {"missed_culled", missed}, {"missed_tested", 0},     {"colliding", colliding},           {"errors", 0},
          {"steps", 4}};
}

nlohmann::json entry(const std::string& strategy, const nlohmann::json& max_missed, const nlohmann::json& thickness = "scene") {
  return {{"scene", "s"}, {"strategy", strategy}, {"thickness", thickness}, {"max_missed", max_missed}};
}

class Gate : public ::testing::Test {
 protected:
  // Vectors, not nlohmann::json: a braced list of one object would make that object, not an array of it.
  testing::CommandResult check(const std::vector<nlohmann::json>& baseline, const std::vector<nlohmann::json>& results) {
    testing::write_text(dir_ / "baseline.json", nlohmann::json(baseline).dump());
    testing::write_text(dir_ / "results.json", nlohmann::json(results).dump());
    return run_ccdbench("check --baseline " + quoted(dir_ / "baseline.json") + " " + quoted(dir_ / "results.json"));
  }
  testing::TempDir dir_;
};

TEST_F(Gate, PassesWithinTheBaselineAndFailsOneMissBeyondIt) {
  const std::vector<nlohmann::json> results = {summary("full+cubic64", 3, 10), summary("full", 0, 10)};
  const auto loose = check({entry("full+cubic64", 3), entry("full", 0)}, results);
  EXPECT_EQ(loose.exit_code, 0) << loose.output;
  const auto tight = check({entry("full+cubic64", 2), entry("full", 0)}, results);
  EXPECT_EQ(tight.exit_code, 1) << tight.output;
  EXPECT_NE(tight.output.find("FAIL s / full+cubic64 / δ scene's 0.01: missed 3 of 10"), std::string::npos) << tight.output;
}

TEST_F(Gate, FailsAResultWithoutAnEntryAndAnEntryWithoutAResult) {
  const auto absent = check({entry("full", 0)}, {summary("full", 0, 10), summary("apccd", 0, 10)});
  EXPECT_EQ(absent.exit_code, 1);
  EXPECT_NE(absent.output.find("apccd / δ scene's 0.01: not in the baseline"), std::string::npos) << absent.output;
  const auto orphan = check({entry("full", 0), entry("apccd", 0)}, {summary("full", 0, 10)});
  EXPECT_EQ(orphan.exit_code, 1);
  EXPECT_NE(orphan.output.find("apccd / δ scene's: in the baseline but has no result"), std::string::npos) << orphan.output;
}

// Errors (answers a plugin could not give: crashes, hangs, refused answers) and answers that changed between two
// passes are verdicts: a cell with either fails unless its entry allows them, whatever the plugin's errors= key did
// with the misses (a method that hung on every colliding pair, counted as hits, misses nothing).
TEST_F(Gate, ErrorsAndNondeterminismFailACellUnlessItsEntryAllowsThem) {
  nlohmann::json erring = summary("plugin:p", 0, 10);
  erring["errors"] = 5;
  const auto failed = check({entry("plugin:p", 0)}, {erring});
  EXPECT_EQ(failed.exit_code, 1) << failed.output;
  EXPECT_NE(failed.output.find("FAIL s / plugin:p / δ scene's 0.01: 5 answers could not be taken"), std::string::npos) << failed.output;
  nlohmann::json allowing = entry("plugin:p", 0);
  allowing["max_errors"] = 5;
  EXPECT_EQ(check({allowing}, {erring}).exit_code, 0);
  allowing["max_errors"] = 4;
  EXPECT_EQ(check({allowing}, {erring}).exit_code, 1);

  nlohmann::json changing = summary("plugin:p", 0, 10);
  changing["nondeterministic_at_step"] = 2;
  const auto nondeterministic = check({entry("plugin:p", 0)}, {changing});
  EXPECT_EQ(nondeterministic.exit_code, 1) << nondeterministic.output;
  EXPECT_NE(nondeterministic.output.find("answers differed between two passes of step 2"), std::string::npos) << nondeterministic.output;
  nlohmann::json allowed = entry("plugin:p", 0);
  allowed["allow_nondeterministic"] = true;
  EXPECT_EQ(check({allowed}, {changing}).exit_code, 0);

  // A result that says nothing of errors cannot be gated on them; malformed allowances are bad input.
  nlohmann::json silent = summary("plugin:p", 0, 10);
  silent.erase("errors");
  EXPECT_EQ(check({entry("plugin:p", 0)}, {silent}).exit_code, 1);
  allowed["allow_nondeterministic"] = "yes";
  EXPECT_EQ(check({allowed}, {changing}).exit_code, 2);
  allowing["max_errors"] = -1;
  EXPECT_EQ(check({allowing}, {erring}).exit_code, 2);
}

// A summary read back without its errors counted is written back so (the C++ API hands its record on, a kept cell
// is rewritten): never as 0 errors, which the gate would take.
TEST(Records, ASummaryWithoutErrorsIsWrittenBackWithoutThem) {
  nlohmann::json record = summary("plugin:p", 0, 10);
  record.erase("errors");
  const harness::CellSummary read = harness::read_summary(record, "r.json", "entry 0", harness::SummaryUse::gate);
  EXPECT_FALSE(read.errors_counted);
  EXPECT_FALSE(nlohmann::json(read).contains("errors")) << nlohmann::json(read).dump();
  record["errors"] = 0;
  EXPECT_EQ(nlohmann::json(harness::read_summary(record, "r.json", "entry 0", harness::SummaryUse::gate))["errors"], 0);
}

TEST_F(Gate, FailsEmptyResults) {
  const auto empty = check({entry("full", 0)}, {});
  EXPECT_EQ(empty.exit_code, 1);
  EXPECT_NE(empty.output.find("the results are empty"), std::string::npos) << empty.output;
}

// A cell without a colliding pair cannot miss: it would pass whatever the strategy does.
TEST_F(Gate, FailsACellWithoutCollidingPairs) {
  const auto nothing = check({entry("full", 0)}, {summary("full", 0, 0)});
  EXPECT_EQ(nothing.exit_code, 1);
  EXPECT_NE(nothing.output.find("no colliding pair"), std::string::npos) << nothing.output;
}

TEST_F(Gate, EntriesNameTheThickness) {
  const nlohmann::json at_zero = summary("full", 0, 10, "command line", 0.0);
  EXPECT_EQ(check({entry("full", 0)}, {at_zero}).exit_code, 1) << "a scene-δ entry must not gate a δ = 0 cell";
  const auto matched = check({entry("full", 0, 0.0)}, {at_zero});
  EXPECT_EQ(matched.exit_code, 0) << matched.output;
  EXPECT_EQ(check({entry("full", 0, 0.5)}, {at_zero}).exit_code, 1);
  // Both δ of one scene and strategy in one baseline, the results given as two files.
  testing::write_text(dir_ / "baseline.json", nlohmann::json::array({entry("full", 0), entry("full", 0, 0.0)}).dump());
  testing::write_text(dir_ / "delta.json", nlohmann::json::array({summary("full", 0, 10)}).dump());
  testing::write_text(dir_ / "zero.json", nlohmann::json::array({at_zero}).dump());
  const auto both =
      run_ccdbench("check --baseline " + quoted(dir_ / "baseline.json") + " " + quoted(dir_ / "delta.json") + " " + quoted(dir_ / "zero.json"));
  EXPECT_EQ(both.exit_code, 0) << both.output;
}

// Pins: a shorter run (--max-steps) or a truth that shrank must not pass, nor late TOIs beyond the baseline; and a
// result two entries match (a scene whose own δ is 0 beside an entry for δ = 0) is ambiguous, not judged by one.
TEST_F(Gate, PinsStepsCollidingAndLateToisAndRefusesAmbiguousEntries) {
  nlohmann::json result = summary("full", 0, 10);
  result["steps"] = 7;
  nlohmann::json pinned = entry("full", 0);
  pinned["steps"] = 7;
  pinned["colliding"] = 10;
  EXPECT_EQ(check({pinned}, {result}).exit_code, 0);
  result["steps"] = 1;
  const auto shorter = check({pinned}, {result});
  EXPECT_EQ(shorter.exit_code, 1);
  EXPECT_NE(shorter.output.find("1 steps, the baseline pins 7"), std::string::npos) << shorter.output;
  result["steps"] = 7;
  result["colliding"] = 9;
  EXPECT_EQ(check({pinned}, {result}).exit_code, 1) << "a truth that shrank must not pass";
  result["colliding"] = 10;
  pinned["max_toi_late"] = 0;
  const auto no_toi = check({pinned}, {result});
  EXPECT_EQ(no_toi.exit_code, 1);
  EXPECT_NE(no_toi.output.find("run with --toi"), std::string::npos) << no_toi.output;
  // Checked TOIs without their late count say nothing of late ones: never 0 late.
  result["toi_checked"] = 5;
  const auto no_late = check({pinned}, {result});
  EXPECT_EQ(no_late.exit_code, 1) << no_late.output;
  EXPECT_NE(no_late.output.find("run with --toi"), std::string::npos) << no_late.output;
  result["toi_late"] = 2;
  EXPECT_EQ(check({pinned}, {result}).exit_code, 1);
  result["toi_late"] = 0;
  EXPECT_EQ(check({pinned}, {result}).exit_code, 0);
  const nlohmann::json zero_scene = summary("full", 0, 10, "scene", 0.0);
  const auto ambiguous = check({entry("full", 0), entry("full", 5, 0.0)}, {zero_scene});
  EXPECT_EQ(ambiguous.exit_code, 1);
  EXPECT_NE(ambiguous.output.find("matches 2 baseline entries"), std::string::npos) << ambiguous.output;
}

// max_missed: -1 used to wrap to 2^64 - 1 and pass any number of misses.
TEST_F(Gate, RefusesBaselineValuesOutOfRangeAsMalformed) {
  const std::vector<nlohmann::json> results = {summary("full", 5, 10)};
  for (const nlohmann::json& bad : std::vector<nlohmann::json>{-1, 1.5, "3", 1e30, nullptr}) {
    const auto refused = check({entry("full", bad)}, results);
    EXPECT_EQ(refused.exit_code, 2) << bad.dump() << ": " << refused.output;
    EXPECT_NE(refused.output.find("baseline.json:entry 0.max_missed: must be an integer >= 0"), std::string::npos) << refused.output;
  }
  const auto no_thickness = check({nlohmann::json{{"scene", "s"}, {"strategy", "full"}, {"max_missed", 0}}}, results);
  EXPECT_EQ(no_thickness.exit_code, 2) << no_thickness.output;
  const auto typo = check({nlohmann::json{{"scene", "s"}, {"strategy", "full"}, {"thickness", "scene"}, {"max_mised", 9}}}, results);
  EXPECT_EQ(typo.exit_code, 2) << typo.output;
  EXPECT_NE(typo.output.find("unknown key 'max_mised'"), std::string::npos) << typo.output;
}

TEST_F(Gate, MalformedFilesExitTwoAndAFailedGateOne) {
  testing::write_text(dir_ / "broken.json", "[{\"scene\": ");
  testing::write_text(dir_ / "baseline.json", nlohmann::json::array({entry("full", 0)}).dump());
  const auto broken = run_ccdbench("check --baseline " + quoted(dir_ / "baseline.json") + " " + quoted(dir_ / "broken.json"));
  EXPECT_EQ(broken.exit_code, 2) << broken.output;
  EXPECT_NE(broken.output.find("broken.json:line 1: malformed JSON"), std::string::npos) << broken.output;
  const auto not_summaries = check({entry("full", 0)}, {nlohmann::json{{"scene", "s"}}});
  EXPECT_EQ(not_summaries.exit_code, 2) << not_summaries.output;
  // Every field the reader reads is checked, named where it is wrong; a summary without its steps is not one of
  // `run` (they would be read as 0, which a baseline could then pin).
  nlohmann::json no_steps = summary("full", 0, 10);
  no_steps.erase("steps");
  const auto stepless = check({entry("full", 0)}, {no_steps});
  EXPECT_EQ(stepless.exit_code, 2) << stepless.output;
  EXPECT_NE(stepless.output.find("results.json:entry 0: a summary without 'steps'"), std::string::npos) << stepless.output;
  for (const auto& [field, bad] : std::vector<std::pair<std::string, nlohmann::json>>{
           {"triangles", "x"}, {"counters", {{"nf", {{"mean", 1}}}}}, {"miss_causes", 5}, {"toi_checked", -3}, {"colliding_face_shape", -1}}) {
    nlohmann::json malformed = summary("full", 0, 10);
    malformed[field] = bad;
    const auto refused = check({entry("full", 0)}, {malformed});
    EXPECT_EQ(refused.exit_code, 2) << field << ": " << refused.output;
    EXPECT_NE(refused.output.find("results.json:entry 0." + field + ": must be "), std::string::npos) << refused.output;
  }
  const auto missing = run_ccdbench("check --baseline " + quoted(dir_ / "baseline.json") + " " + quoted(dir_ / "none.json"));
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
  EXPECT_EQ(check({entry("full", 0)}, {summary("full", 1, 10)}).exit_code, 1);
}

// A cell that fails several ways shows every one (it showed the first: 2,534 late TOIs hid 2,662 missed pairs).
TEST_F(Gate, EveryReasonACellFailsIsShown) {
  nlohmann::json result = summary("full", 5, 10);
  result["toi_late"] = 7;
  result["errors"] = 2;
  nlohmann::json pinned = entry("full", 0);
  pinned["max_toi_late"] = 0;
  const auto failed = check({pinned}, {result});
  EXPECT_EQ(failed.exit_code, 1) << failed.output;
  for (const char* reason : {": 7 TOIs later than the exact earliest contact", ": 2 answers could not be taken", ": missed 5 of 10"}) {
    EXPECT_NE(failed.output.find("FAIL s / full / δ scene's 0.01" + std::string(reason)), std::string::npos) << reason << "\n" << failed.output;
  }
}

// check reads what compare reads: a run's --out folder and its results.jsonl (the latest summary of each cell), as well
// as its --json array.
TEST_F(Gate, ReadsARunsOutFolderAndItsResultsLog) {
  const std::filesystem::path fold = testing::small_fold(dir_ / "fold8", 4);
  const auto ran = run_ccdbench("run --scene " + quoted(fold) + " --thickness 0 --strategy full,full+cubic64 --out " + quoted(dir_ / "out") +
                                " --json " + quoted(dir_ / "r.json"));
  ASSERT_EQ(ran.exit_code, 0) << ran.output;
  ASSERT_EQ(run_ccdbench("check --write-baseline " + quoted(dir_ / "b.json") + " " + quoted(dir_ / "r.json")).exit_code, 0);
  for (const std::filesystem::path& results : {dir_ / "out", dir_ / "out" / "results.jsonl", dir_ / "r.json"}) {
    const auto gate = run_ccdbench("check --baseline " + quoted(dir_ / "b.json") + " " + quoted(results));
    EXPECT_EQ(gate.exit_code, 0) << results << "\n" << gate.output;
    EXPECT_NE(gate.output.find("ok   fold8 / full+cubic64 / δ 0"), std::string::npos) << gate.output;
  }
  // A results.jsonl that is not one: bad input where it is.
  testing::write_text(dir_ / "bad.jsonl", "{\"record\": \"summary\", \"scene\": 1}\n");
  const auto bad = run_ccdbench("check --baseline " + quoted(dir_ / "b.json") + " " + quoted(dir_ / "bad.jsonl"));
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("bad.jsonl:line 1.scene: must be a string"), std::string::npos) << bad.output;
}

// A field of the wrong type is bad input where it is (it was a raw type_error, exit 1), before any line is gated.
TEST_F(Gate, AWrongTypedFieldIsBadInputWhereItIs) {
  const std::vector<std::pair<const char*, nlohmann::json>> wrong = {{"verified", "yes"}, {"missed", -1}, {"colliding", "10"},
                                                                     {"errors", 1.5},     {"resumed", 1}, {"nondeterministic_at_step", "2"}};
  for (const auto& [field, value] : wrong) {
    nlohmann::json result = summary("full", 0, 10);
    result[field] = value;
    const auto refused = check({entry("full", 0)}, {summary("full", 0, 10), result});
    EXPECT_EQ(refused.exit_code, 2) << field << ": " << refused.output;
    EXPECT_NE(refused.output.find("results.json:entry 1." + std::string(field) + ": must be "), std::string::npos) << refused.output;
    EXPECT_EQ(refused.output.find("ok   s"), std::string::npos) << "gated before the file was read whole: " << refused.output;
  }
}

// --write-baseline refuses what check would fail whatever the entry says: it used to accept a result without an
// errors count, whose baseline check then refused.
TEST_F(Gate, WritingABaselineRefusesWhatCheckRefuses) {
  auto write = [&](const nlohmann::json& result) {
    testing::write_text(dir_ / "results.json", nlohmann::json::array({result}).dump());
    return run_ccdbench("check --write-baseline " + quoted(dir_ / "baseline.json") + " " + quoted(dir_ / "results.json"));
  };
  nlohmann::json good = summary("full", 0, 10);
  good["steps"] = 3;
  ASSERT_EQ(write(good).exit_code, 0);
  nlohmann::json silent = good;
  silent.erase("errors");
  const auto refused = write(silent);
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_NE(refused.output.find("the results say nothing of errors"), std::string::npos) << refused.output;
  EXPECT_EQ(check({entry("full", 0)}, {silent}).exit_code, 1) << "check refuses it too";
  nlohmann::json unverified = good;
  unverified["verified"] = false;
  EXPECT_EQ(write(unverified).exit_code, 2);
}

}  // namespace
}  // namespace ccd
