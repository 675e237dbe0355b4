// End-to-end tests of the ccdbench executable: what a user types, what a script reads.

#include "tests/support/cli.hpp"
#include "ccd/config.hpp"
#include "datasets/procedural_scenes.hpp"
#include "strategies/narrowphase_registry.hpp"
#include "strategies/registry.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace ccd {
namespace {

using testing::CommandResult;
using testing::read_json;
using testing::run_ccdbench;

nlohmann::json inspect_json(const std::filesystem::path& path) {
  const CommandResult result = run_ccdbench("inspect --json '" + path.string() + "'");
  EXPECT_EQ(result.exit_code, 0) << result.output;
  return nlohmann::json::parse(result.output);
}

TEST(Cli, HelpExplainsTheCommands) {
  const CommandResult help = run_ccdbench("--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.output.find("inspect"), std::string::npos) << help.output;
  const CommandResult inspect_help = run_ccdbench("inspect --help");
  EXPECT_NE(inspect_help.output.find("--json"), std::string::npos) << inspect_help.output;
  EXPECT_NE(run_ccdbench("").exit_code, 0);
  EXPECT_NE(run_ccdbench("no-such-command").exit_code, 0);
  EXPECT_EQ(run_ccdbench("--version").exit_code, 0);
}

/// Checks a listed entry's keys against the registry's declarations: names in order, values and defaults.
void expect_same_keys(const nlohmann::json& listed, const std::vector<narrowphase::KeySpec>& keys) {
  ASSERT_EQ(listed.size(), keys.size());
  for (std::size_t k = 0; k < keys.size(); ++k) {
    EXPECT_EQ(listed[k]["name"], keys[k].name);
    EXPECT_EQ(listed[k]["default"], keys[k].default_value) << keys[k].name;
    EXPECT_EQ(listed[k]["allowed"], keys[k].allowed()) << keys[k].name;
    EXPECT_FALSE(listed[k]["help"].get<std::string>().empty()) << keys[k].name;
    if (keys[k].kind == narrowphase::KeySpec::Kind::number || keys[k].kind == narrowphase::KeySpec::Kind::integer) {
      EXPECT_EQ(listed[k]["minimum"].get<double>(), keys[k].range.minimum) << keys[k].name;
      EXPECT_EQ(listed[k]["maximum"].get<double>(), keys[k].range.maximum) << keys[k].name;
    }
  }
}

/// Checks a listed section against a registry: the same entries in the same order, each with the same keys.
template <class Entry>
void expect_same_entries(const nlohmann::json& listed, const std::vector<Entry>& entries) {
  ASSERT_EQ(listed.size(), entries.size());
  for (std::size_t i = 0; i < entries.size(); ++i) {
    SCOPED_TRACE(entries[i].name);
    EXPECT_EQ(listed[i]["name"], entries[i].name);
    EXPECT_EQ(listed[i]["help"], entries[i].help);
    expect_same_keys(listed[i]["keys"], entries[i].keys);
  }
}

// `ccdbench strategies --json` is the registries as a script reads them: every strategy and narrow phase, in order,
// with every key's values and default; the table for people names them too, and `run --help` points to it.
TEST(Cli, StrategiesListsEveryEntryOfTheRegistries) {
  const CommandResult listed = run_ccdbench("strategies --json");
  ASSERT_EQ(listed.exit_code, 0) << listed.output;
  const nlohmann::json listing = nlohmann::json::parse(listed.output);
  const auto& strategies = strategies::strategy_entries();
  const auto& narrow_phases = narrowphase::narrow_phases();
  expect_same_entries(listing["strategies"], strategies);
  expect_same_entries(listing["narrow_phases"], narrow_phases);
  for (std::size_t i = 0; i < std::min(strategies.size(), listing["strategies"].size()); ++i) {
    EXPECT_EQ(listing["strategies"][i]["backends"].get<std::vector<std::string>>(), strategies[i].backends) << strategies[i].name;
    EXPECT_EQ(listing["strategies"][i]["baseline"], strategies[i].baseline) << strategies[i].name;
  }
  for (std::size_t i = 0; i < std::min(narrow_phases.size(), listing["narrow_phases"].size()); ++i) {
    EXPECT_EQ(listing["narrow_phases"][i]["conservative"], narrow_phases[i].conservative) << narrow_phases[i].name;
  }
  const CommandResult table = run_ccdbench("strategies");
  ASSERT_EQ(table.exit_code, 0);
  for (const auto& entry : strategies) EXPECT_NE(table.output.find(entry.name + ": "), std::string::npos) << entry.name;
  for (const auto& entry : narrow_phases) EXPECT_NE(table.output.find(entry.name + ": "), std::string::npos) << entry.name;
  EXPECT_NE(run_ccdbench("run --help").output.find("ccdbench strategies"), std::string::npos);
}

// Every run record carries the provenance a result from another machine needs to be reproduced: ccdbench's version
// and revision, the build type and flags, the compiler, every library's version, and for OpenCL cells the platform,
// device and driver; `ccdbench --version --verbose` prints the same.
TEST(Cli, EveryRecordCarriesItsProvenance) {
  testing::TempDir dir;
  ::setenv("CCDBENCH_CACHE_DIR", (dir / "cache").c_str(), 1);
  const std::string strategies = CCDBENCH_WITH_OPENCL ? "full,full:backend=opencl" : "full";
  const CommandResult run = run_ccdbench("run --suite ci --max-steps 1 --strategy " + strategies + " --out '" + (dir / "out").string() +
                                         "' --json '" + (dir / "summary.json").string() + "' --report '" + (dir / "report").string() + "'");
  ::unsetenv("CCDBENCH_CACHE_DIR");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const CommandResult verbose = run_ccdbench("--version --verbose");
  ASSERT_EQ(verbose.exit_code, 0);
  std::vector<nlohmann::json> records;
  for (const nlohmann::json& summary : read_json(dir / "summary.json")) records.push_back(summary);
  for (const nlohmann::json& step : read_json(dir / "report" / "steps.json")) records.push_back(step);
  ASSERT_FALSE(records.empty());
  for (const nlohmann::json& record : records) {
    ASSERT_TRUE(record.contains("provenance")) << record.dump();
    const nlohmann::json& provenance = record["provenance"];
    for (const char* item : {"ccdbench", "git_revision", "build_type", "cxx_flags", "compiler", "cgal", "gmp", "mpfr", "tbb", "fcl", "libccd",
                             "eigen", "nlohmann_json", "mpi", "opencl"}) {
      ASSERT_TRUE(provenance.contains(item) && !provenance[item].get<std::string>().empty()) << item << " in " << provenance.dump();
      EXPECT_NE(verbose.output.find(std::string(item) + ": " + provenance[item].get<std::string>()), std::string::npos) << item;
    }
    const bool opencl_cell = record["strategy"].get<std::string>().find(":backend=opencl") != std::string::npos;
    for (const char* item : {"opencl_platform", "opencl_device", "opencl_device_index", "opencl_driver"}) {
      EXPECT_EQ(provenance.contains(item), opencl_cell) << item << " in " << record["strategy"];
    }
  }
}

// A shape object is shown by its shape and size; its centre is not counted as a stray unused vertex.
TEST(Cli, InspectShowsShapesAndTheirSize) {
  testing::TempDir dir;
  ::setenv("CCDBENCH_CACHE_DIR", (dir / "cache").c_str(), 1);
  const CommandResult generated =
      run_ccdbench("generate fold --resolution 4 --frames 3 --set obstacles=shape --out '" + (dir / "fold").string() + "'");
  ASSERT_EQ(generated.exit_code, 0) << generated.output;
  const CommandResult inspected = run_ccdbench("inspect '" + (dir / "fold").string() + "'");
  ASSERT_EQ(inspected.exit_code, 0) << inspected.output;
  EXPECT_NE(inspected.output.find("(unused 0, and 2 shape centres)"), std::string::npos) << inspected.output;
  EXPECT_NE(inspected.output.find("object ball: shape (sphere, radius "), std::string::npos) << inspected.output;
  EXPECT_NE(inspected.output.find("object blade: shape (box, half extents ["), std::string::npos) << inspected.output;
  const nlohmann::json json = inspect_json(dir / "fold");
  EXPECT_EQ(json["objects"][2]["shape"], "sphere");
  const CommandResult cone = run_ccdbench("generate fold --frames 3 --set obstacles=cone --out '" + (dir / "x").string() + "'");
  EXPECT_EQ(cone.exit_code, 2);
  EXPECT_NE(cone.output.find("--set obstacles=cone: the value must be a number or one of: mesh, shape"), std::string::npos) << cone.output;
  const CommandResult flag = run_ccdbench("generate flag --frames 3 --set obstacles=shape --out '" + (dir / "x").string() + "'");
  EXPECT_NE(flag.output.find("scene 'flag' has no parameter 'obstacles'"), std::string::npos) << flag.output;
  ::unsetenv("CCDBENCH_CACHE_DIR");
}

TEST(Cli, InspectPrintsTheDataReadmeCountsForEveryFileOfTheSharedData) {
  CCD_REQUIRE_EXTERNAL_DATA(data);
  const auto queries = inspect_json(data / "sample-queries");
  EXPECT_EQ(queries["queries"], 324);
  EXPECT_EQ(queries["positives"], 160);
  EXPECT_EQ(inspect_json(data / "sample-queries/unit-tests/vertex-face/data_0_0.csv")["queries"], 125);

  struct Step {
    const char* name;
    const char* step;
    int vertices, faces, vf, vf_positives, ee, ee_positives;
  };
  for (const Step& s : {Step{"cloth-funnel", "227", 9450, 18484, 92, 27, 263, 107}, Step{"rod-twist", "3036", 39940, 79864, 801, 765, 4370, 4179}}) {
    SCOPED_TRACE(s.name);
    const auto base = data / "scalable-ccd-sample" / s.name;
    const auto step = inspect_json(base);
    EXPECT_EQ(step["type"], "sample_step");
    EXPECT_EQ(step["vertices"], s.vertices);
    EXPECT_EQ(step["faces"], s.faces);
    EXPECT_EQ(step["steps"], 1);
    EXPECT_GT(step["max_displacement"][0].get<double>(), 0.0);
    EXPECT_EQ(step["vf_queries"]["positives"], s.vf_positives);
    EXPECT_EQ(step["ee_queries"]["positives"], s.ee_positives);
    const std::string vf = std::string(s.step) + "vf", ee = std::string(s.step) + "ee";
    EXPECT_EQ(inspect_json(base / "frames" / (std::string(s.step) + ".ply"))["faces"], s.faces);
    EXPECT_EQ(inspect_json(base / "boxes" / (vf + ".json"))["pairs"], s.vf);
    EXPECT_EQ(inspect_json(base / "boxes" / (ee + ".json"))["pairs"], s.ee);
    EXPECT_EQ(inspect_json(base / "queries" / (vf + ".csv"))["positives"], s.vf_positives);
    EXPECT_EQ(inspect_json(base / "queries" / (ee + ".csv"))["queries"], s.ee);
    EXPECT_EQ(inspect_json(base / "mma_bool" / (vf + "_mma_bool.json"))["positives"], s.vf_positives);
    EXPECT_EQ(inspect_json(base / "mma_bool" / (ee + "_mma_bool.json"))["entries"], s.ee);
    EXPECT_EQ(inspect_json(base / "frames")["steps"], 1);
  }
}

TEST(Cli, BadInputExitsNonZeroNamingFileAndLine) {
  testing::TempDir dir;
  testing::write_text(dir / "vertex-face/bad.csv", "1,1,1,1,1,1,1\n1,1,1,0,1,1,1\n");
  const CommandResult result = run_ccdbench("inspect '" + (dir / "vertex-face/bad.csv").string() + "'");
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.output.find("bad.csv:line 2: column 4: zero denominator"), std::string::npos) << result.output;
  const CommandResult missing = run_ccdbench("inspect '" + (dir / "nothing.ply").string() + "'");
  EXPECT_NE(missing.exit_code, 0);
  testing::write_text(dir / "notes.txt", "hello");
  EXPECT_NE(run_ccdbench("inspect '" + (dir / "notes.txt").string() + "'").output.find("not a ccdbench input"), std::string::npos);
}

TEST(Cli, QueriesWithTheExactMethodScoreEverySharedQueryRight) {
  CCD_REQUIRE_EXTERNAL_DATA(data);
  testing::TempDir dir;
  const CommandResult result = run_ccdbench("queries '" + (data / "sample-queries").string() + "' '" + (data / "scalable-ccd-sample").string() +
                                            "' --method exact --json '" + (dir / "scores.json").string() + "'");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const nlohmann::json scores = read_json(dir / "scores.json");
  ASSERT_EQ(scores.size(), 9u);  // 8 files and the total
  const nlohmann::json& total = scores.back();
  EXPECT_EQ(total["file"], "(all)");
  EXPECT_EQ(total["method"], "exact");
  EXPECT_EQ(total["queries"], 324 + 92 + 263 + 801 + 4370);
  EXPECT_EQ(total["positives"], 160 + 27 + 107 + 765 + 4179);
  EXPECT_EQ(total["false_negatives"], 0);
  EXPECT_EQ(total["false_positives"], 0);
  for (const char* field : {"reported", "ns_per_query"}) EXPECT_TRUE(total.contains(field)) << field;
}

TEST(Cli, TruthOnASampleStepFindsEveryLabelledCollision) {
  CCD_REQUIRE_EXTERNAL_DATA(data);
  testing::TempDir dir;
  const CommandResult result =
      run_ccdbench("truth --sample '" + (data / "scalable-ccd-sample/cloth-funnel").string() + "' --json '" + (dir / "truth.json").string() + "'");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const nlohmann::json truth = read_json(dir / "truth.json");
  EXPECT_GE(truth["vf"].get<int>(), 27);
  EXPECT_GE(truth["ee"].get<int>(), 107);
  EXPECT_EQ(truth["sample"]["vf_found"], 27);
  EXPECT_EQ(truth["sample"]["ee_found"], 107);
  EXPECT_EQ(truth["decided_by_filter"].get<int>() + truth["decided_exactly"].get<int>(),
            truth["vf_pairs_enumerated"].get<int>() + truth["ee_pairs_enumerated"].get<int>());
  const auto frames = data / "scalable-ccd-sample/cloth-funnel/frames";
  const CommandResult by_frames = run_ccdbench("truth --frames '" + (frames / "227.ply").string() + "' '" + (frames / "228.ply").string() +
                                               "' --json '" + (dir / "frames.json").string() + "'");
  ASSERT_EQ(by_frames.exit_code, 0) << by_frames.output;
  EXPECT_EQ(read_json(dir / "frames.json")["vf"], truth["vf"]);
}

TEST(Cli, QueriesAndTruthRejectBadArguments) {
  testing::TempDir dir;
  testing::write_text(dir / "vertex-face/q.csv", "0,1,0,1,0,1,0\n0,1,0,1,0,1,0\n");
  EXPECT_NE(run_ccdbench("queries '" + dir.path().string() + "' --method nonsense").output.find("unknown method"), std::string::npos);
  EXPECT_EQ(run_ccdbench("queries '" + dir.path().string() + "'").exit_code, 2);
  EXPECT_NE(run_ccdbench("queries '" + dir.path().string() + "' --thickness -1").exit_code, 0);
  EXPECT_NE(run_ccdbench("truth").output.find("exactly one of"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir / "out.json"));
}

TEST(Cli, ScenesListsEveryBuiltInSceneAndGenerateCaches) {
  const CommandResult scenes = run_ccdbench("scenes");
  ASSERT_EQ(scenes.exit_code, 0);
  for (const char* name : {"spinning-ball", "drape", "flag", "twist", "funnel", "pile"}) {
    EXPECT_NE(scenes.output.find(std::string(name) + ":"), std::string::npos) << name;
  }
  testing::TempDir dir;
  const std::string generate = "generate spinning-ball --resolution 8 --frames 4 --out '" + dir.path().string() + "'";
  const CommandResult first = run_ccdbench(generate + " --report");
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_NE(first.output.find("min_distance_to_ball"), std::string::npos) << first.output;
  EXPECT_NE(first.output.find("generated in"), std::string::npos) << first.output;
  EXPECT_NE(run_ccdbench(generate).output.find("from the cache"), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(dir / "cloth/frame_0003.ply"));
  EXPECT_TRUE(std::filesystem::exists(dir / "ball/frame_0003.ply"));
  const auto inspected = inspect_json(dir.path());
  EXPECT_EQ(inspected["type"], "scene");
  EXPECT_EQ(inspected["steps"], 3);
  const CommandResult bad = run_ccdbench("generate flag --set wnd=3 --out '" + (dir / "x").string() + "'");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("no parameter 'wnd'"), std::string::npos) << bad.output;
}

// The command's plumbing on three families (the whole suite's misses are tests/strategies' ConservativeOnExtremes):
// rows for scripts, no miss by the conservative narrow phase, and the suite written as queries that the reference
// scores right.
TEST(Cli, StressPrintsFamiliesAndWritesTheSuiteAsQueries) {
  testing::TempDir dir;
  const CommandResult result = run_ccdbench("stress --method conservative --family coplanar-motion,subnormal,scaled-2^-1000 --json '" +
                                            (dir / "stress.json").string() + "' --write-queries '" + (dir / "suite").string() + "'");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const nlohmann::json rows = read_json(dir / "stress.json");
  bool saw_conservative_total = false;
  for (const auto& row : rows) {
    for (const char* field : {"family", "method", "false_negatives", "false_positives"}) ASSERT_TRUE(row.contains(field));
    if (row["method"].get<std::string>().rfind("conservative", 0) == 0) {
      EXPECT_EQ(row["false_negatives"], 0) << row.dump();
      saw_conservative_total = saw_conservative_total || row["family"] == "(all)";
    }
  }
  EXPECT_TRUE(saw_conservative_total);
  std::set<std::string> families;
  for (const auto& row : rows) families.insert(row["family"].get<std::string>());
  EXPECT_EQ(families, (std::set<std::string>{"coplanar-motion", "subnormal", "scaled-2^-1000", "(all)"}));
  EXPECT_NE(run_ccdbench("stress --family no-such-family").exit_code, 0);
  const CommandResult scored =
      run_ccdbench("queries '" + (dir / "suite").string() + "' --method exact --json '" + (dir / "scores.json").string() + "'");
  ASSERT_EQ(scored.exit_code, 0) << scored.output;
  EXPECT_EQ(read_json(dir / "scores.json").back()["false_negatives"], 0);
}

TEST(Cli, RunVerifiesWritesResultsAndResumes) {
  testing::TempDir dir;
  ::setenv("CCDBENCH_CACHE_DIR", (dir / "cache").c_str(), 1);
  const std::string base = "run --suite ci --strategy full --out '" + (dir / "out").string() + "' --json '" + (dir / "summary.json").string() + "'";
  const CommandResult first = run_ccdbench(base);
  ASSERT_EQ(first.exit_code, 0) << first.output;
  const nlohmann::json summary = read_json(dir / "summary.json");
  ASSERT_EQ(summary.size(), 3u);
  for (const auto& s : summary) {
    for (const char* field : {"scene",        "strategy",      "steps",         "ms_per_step",    "colliding", "colliding_by_objects", "reported",
                              "missed",       "missed_culled", "missed_tested", "false_alarms",   "machine",   "build_type",           "threads",
                              "git_revision", "executable",    "thickness",     "thickness_from", "key",       "finished_at"}) {
      EXPECT_TRUE(s.contains(field)) << field;
    }
    EXPECT_EQ(s["missed"], 0) << s.dump();
  }
  std::ifstream lines(dir / "out/results.jsonl");
  std::size_t records = 0;
  for (std::string line; std::getline(lines, line);) {
    EXPECT_NO_THROW(nlohmann::json::parse(line));
    ++records;
  }
  EXPECT_EQ(records, 3 + 4 + 23 + 23u);  // a summary per cell, a record per step
  // The shape scene's summary counts its face-shape pairs apart, and its contact with each shape.
  const nlohmann::json& shapes = summary[2];
  EXPECT_EQ(shapes["scene"], "fold-r8-f24-shapes");
  EXPECT_GT(shapes["colliding_face_shape"].get<std::size_t>(), 0u) << shapes.dump();
  EXPECT_EQ(shapes["missed_face_shape"], 0);
  EXPECT_GT(shapes["colliding_by_objects"]["sheet/ball"].get<std::size_t>(), 0u) << shapes.dump();
  EXPECT_GT(shapes["faces_in_contact_by_objects"]["sheet/blade"].get<std::size_t>(), 0u) << shapes.dump();
  const CommandResult again = run_ccdbench(base);
  EXPECT_NE(again.output.find("(resumed)"), std::string::npos) << again.output;
  EXPECT_EQ(run_ccdbench(base + " --fresh").output.find("(resumed)"), std::string::npos);
  ::unsetenv("CCDBENCH_CACHE_DIR");
}

TEST(Cli, RunJudgesFclByTrianglePairsAndRefusesItAtPositiveThickness) {
  if (!CCDBENCH_WITH_FCL) GTEST_SKIP() << "built without FCL (CCDBENCH_WITH_FCL=OFF)";
  testing::TempDir dir;
  ::setenv("CCDBENCH_CACHE_DIR", (dir / "cache").c_str(), 1);
  const std::string out = " --out '" + (dir / "out").string() + "'";
  // The ci suite's scenes have δ > 0: refused before any truth or timing, nothing written.
  const CommandResult refused = run_ccdbench("run --suite ci --strategy full,fcl" + out);
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.output.find("run with --thickness 0"), std::string::npos) << refused.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "results.jsonl"));
  // FCL's baselines model meshes only: the ci suite's shape scene is refused naming the shape.
  const CommandResult shapes = run_ccdbench("run --suite ci --thickness 0 --strategy fcl" + out);
  EXPECT_NE(shapes.exit_code, 0);
  EXPECT_NE(shapes.output.find("fcl does not model analytic shapes: object 'blade' is a box"), std::string::npos) << shapes.output;
  // The ci suite's mesh scenes, named by generator blocks.
  testing::write_text(dir / "ball.json", R"({"generator": {"name": "spinning-ball", "resolution": 8, "frames": 5}})");
  testing::write_text(dir / "fold.json", R"({"generator": {"name": "fold", "resolution": 8, "frames": 24}})");
  const CommandResult run =
      run_ccdbench("run --scene '" + (dir / "ball.json").string() + "' '" + (dir / "fold.json").string() +
                   "' --thickness 0 --max-steps 3 --strategy full,fcl:bv=aabb,fcl-bvh" + out + " --json '" + (dir / "s.json").string() + "'");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("fcl:bv=aabb (†)"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("judged by triangle pairs"), std::string::npos) << run.output;
  std::ifstream in(dir / "s.json");
  const nlohmann::json summaries = nlohmann::json::parse(in);
  for (const auto& s : summaries) {
    const bool fcl = s["strategy"].get<std::string>().rfind("fcl:", 0) == 0;
    EXPECT_EQ(s["judged_by"], fcl ? "triangle pairs" : "elementary pairs") << s["strategy"];
    if (s["strategy"].get<std::string>().rfind("fcl-bvh", 0) == 0) {
      EXPECT_EQ(s["missed"], 0) << s["scene"];
    }
  }
  ::unsetenv("CCDBENCH_CACHE_DIR");
}

}  // namespace
}  // namespace ccd

namespace ccd {
namespace {

// TOI accuracy is part of the verdict: the conservative narrow phase is never late, decided exactly against the
// reference's earliest contact, while cubic64 (which rounds its roots either way) is; so the count can fire.
// The TOI error's median and 99th percentile are those of the per-query errors: recomputed here from the answers
// file that the same run writes (every reported TOI and the exact one), by nearest rank.
TEST(CliToi, TheErrorsMedianAndP99AreThoseOfThePerQueryErrors) {
  CCD_REQUIRE_EXTERNAL_DATA(data);
  testing::TempDir dir;
  const CommandResult queries =
      testing::run_ccdbench("queries " + testing::quoted(data / "sample-queries") + " --toi --method conservative,advancement --json " +
                            testing::quoted(dir / "q.json") + " --write-answers " + testing::quoted(dir / "answers.csv"));
  ASSERT_EQ(queries.exit_code, 0) << queries.output;
  EXPECT_NE(queries.output.find("p99"), std::string::npos) << queries.output;
  std::map<std::string, std::vector<double>> errors;
  std::ifstream answers(dir / "answers.csv");
  std::string line;
  std::getline(answers, line);
  ASSERT_EQ(line, "file,index,method,hit,toi,label,exact_toi");
  while (std::getline(answers, line)) {
    std::vector<std::string> field;
    std::stringstream fields(line);
    for (std::string f; std::getline(fields, f, ',');) field.push_back(f);
    if (field.size() < 7 || field[3] != "1" || field[4].empty() || field[6].empty()) continue;
    errors[field[2]].push_back(std::abs(std::stod(field[4]) - std::stod(field[6])));
  }
  const auto nearest_rank = [](std::vector<double> values, double p) {
    std::sort(values.begin(), values.end());
    return values[static_cast<std::size_t>(std::ceil(p / 100 * static_cast<double>(values.size()))) - 1];
  };
  int checked = 0;
  for (const auto& row : testing::read_json(dir / "q.json")) {
    if (row["file"] != "(all)") continue;
    const std::vector<double>& e = errors[row["method"].get<std::string>()];
    ASSERT_EQ(row["toi_checked"].get<std::size_t>(), e.size()) << row.dump();
    ASSERT_GT(e.size(), 100u);
    EXPECT_DOUBLE_EQ(row["toi_error_median"].get<double>(), nearest_rank(e, 50)) << row.dump();
    EXPECT_DOUBLE_EQ(row["toi_error_p99"].get<double>(), nearest_rank(e, 99)) << row.dump();
    EXPECT_DOUBLE_EQ(row["toi_error_max"].get<double>(), nearest_rank(e, 100)) << row.dump();
    EXPECT_LT(row["toi_error_median"].get<double>(), row["toi_error_p99"].get<double>()) << "a distribution, not one value: " << row.dump();
    ++checked;
  }
  EXPECT_EQ(checked, 2);
}

TEST(CliToi, QueriesAndRunsCountLateTimesOfImpact) {
  CCD_REQUIRE_EXTERNAL_DATA(data);
  testing::TempDir dir;
  const CommandResult queries = testing::run_ccdbench("queries " + testing::quoted(data / "sample-queries") +
                                                      " --extremes --toi --method conservative,cubic64 --json " + testing::quoted(dir / "q.json"));
  ASSERT_EQ(queries.exit_code, 0) << queries.output;
  EXPECT_NE(queries.output.find("TOI late"), std::string::npos) << queries.output;
  std::size_t cubic_late = 0;
  for (const auto& row : testing::read_json(dir / "q.json")) {
    if (row["file"] != "(all)") continue;
    ASSERT_TRUE(row.contains("toi_late")) << row.dump();
    const bool conservative = row["method"].get<std::string>().rfind("conservative", 0) == 0;
    if (conservative) {
      EXPECT_EQ(row["toi_late"], 0) << row.dump();
      EXPECT_GT(row["toi_checked"].get<int>(), 100) << row.dump();
    } else {
      cubic_late = row["toi_late"].get<std::size_t>();
    }
  }
  EXPECT_GT(cubic_late, 0u) << "cubic64 is late on some queries: the count must be able to fire";

  ::setenv("CCDBENCH_CACHE_DIR", (dir / "cache").c_str(), 1);
  datasets::generate_procedural_scene({"fold", {{"resolution", 6}, {"frames", 12}}, dir / "s", {}, {}});
  const CommandResult run = testing::run_ccdbench("run --toi --thickness 0 --strategy full,full+cubic64,apccd --scene " + testing::quoted(dir / "s") +
                                                  " --out " + testing::quoted(dir / "out") + " --json " + testing::quoted(dir / "r.json"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("TOI late (error max / mean)"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("TOI error p99"), std::string::npos) << run.output;
  for (const auto& summary : testing::read_json(dir / "r.json")) {
    const std::string strategy = summary["strategy"];
    ASSERT_TRUE(summary.contains("toi_late")) << summary.dump();
    if (strategy.find("conservative") != std::string::npos) {
      EXPECT_EQ(summary["toi_late"], 0) << strategy;
      EXPECT_GT(summary["toi_checked"].get<int>(), 0) << strategy;
    }
  }
  EXPECT_EQ(
      testing::run_ccdbench("run --toi --verify none --scene " + testing::quoted(dir / "s") + " --out " + testing::quoted(dir / "out2")).exit_code,
      2);
  ::unsetenv("CCDBENCH_CACHE_DIR");
}

}  // namespace
}  // namespace ccd
