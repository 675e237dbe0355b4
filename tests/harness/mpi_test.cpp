// `mpirun -n N ccdbench run|truth|queries` (harness/work_queue.hpp): the same verdicts and counts as one process,
// work really spread over the ranks, and a run whose rank dies completed by a rerun with the same results.
// OpenMPI refuses root without the two OMPI_ALLOW_* variables: they are set here, for these commands only.

#include "ccd/config.hpp"
#include "harness/run.hpp"
#include "tests/support/cli.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <map>
#include <set>

namespace ccd {
namespace {

using testing::quoted;
using testing::read_json;
using testing::run_command;

/// `mpirun -n RANKS ccdbench --threads 1 ARGUMENTS`, more ranks than cores allowed.
/// With `fault` ("RANK:EVENT:N", tests/support/fault_injection.cpp) the injector is preloaded into the ranks alone
/// (ASan's check that its runtime comes first among the libraries is off for them: the injector comes first).
/// LeakSanitizer is told to ignore what OpenMPI's own libraries keep at exit (tests/lsan_openmpi.supp; only ASan
/// builds read it). For it to see those libraries in a leak's stack, OpenMPI and PMIx keep their plugins loaded
/// (a plugin closed before exit is an "<unknown module>" no suppression can name) and LeakSanitizer unwinds
/// without frame pointers, which OpenMPI's libraries are built without.
testing::CommandResult mpirun(int ranks, const std::string& arguments, const std::string& fault = {}) {
  const std::string injector = fault.empty() ? std::string()
                                             : " -x LD_PRELOAD=" + quoted(CCDBENCH_FAULT_INJECTION) + " -x CCDBENCH_FAULT=" + fault +
                                                   " -x ASAN_OPTIONS=verify_asan_link_order=0";
  const std::string command =
      "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "
      "OMPI_MCA_mca_base_component_disable_dlclose=1 PMIX_MCA_mca_base_component_disable_dlclose=1 "
      "LSAN_OPTIONS=fast_unwind_on_malloc=0:suppressions=" +
      quoted(std::filesystem::path(CCDBENCH_SOURCE_DIR) / "tests" / "lsan_openmpi.supp") + " " + CCDBENCH_MPIEXEC " -n " + std::to_string(ranks) +
      " --oversubscribe --bind-to none" + injector + " " CCDBENCH_EXECUTABLE " --threads 1 " + arguments;
  return run_command(command);
}

/// Every field of a summary that must not depend on where and how fast a cell ran (docs/mpi.md: the rest are
/// timings, host, rank, threads and when it finished).
nlohmann::json verdict(const nlohmann::json& summary) {
  nlohmann::json kept;
  for (const char* field :
       {"scene",           "strategy",         "triangles",     "steps",          "thickness",        "thickness_from", "verified",
        "colliding",       "missed",           "missed_culled", "missed_tested",  "false_alarms",     "miss_causes",    "reported",
        "candidate_pairs", "elementary_tests", "kept_bytes",    "history_bytes",  "device_bytes",     "judged_by",      "toi_checked",
        "toi_late",        "toi_missing",      "toi_error_max", "toi_error_mean", "toi_error_median", "toi_error_p99"}) {
    if (summary.contains(field)) kept[field] = summary[field];
  }
  return kept;
}

/// These tests keep the truth cache of the environment (scripts/test.sh sets build/cache): the ci suite's truth
/// they compute is the truth the CI gate's own run of the suite reads afterwards, so CI computes it once.
class Mpi : public ::testing::Test {
 protected:
  /// The ci suite's summaries from `ranks` ranks into OUT (0: a plain process, without mpirun). Each test starts with a plain run: it fills the truth cache, so that the runs under mpirun,
  /// whose LeakSanitizer unwinds slowly in the ASan build, read their truth instead of computing it.
  testing::CommandResult run_suite(int ranks, const std::string& out, const std::string& extra = {}) {
    const std::string arguments = "run --suite ci --toi --strategy full,apccd,full+cubic64 " + extra + " --out " + quoted(dir_ / out) + " --json " +
                                  quoted(dir_ / (out + ".json"));
    if (ranks == 0) return run_command(std::string(CCDBENCH_EXECUTABLE) + " --threads 1 " + arguments);
    return mpirun(ranks, arguments);
  }

  /// The same three strategies on a small kinematic fold (6 × 6, 8 frames: it collides at its δ), for the tests
  /// of dying ranks, which run several times; `fault` as mpirun's.
  testing::CommandResult run_fold(int ranks, const std::string& out, const std::string& fault = {}) {
    if (!std::filesystem::exists(dir_ / "fold")) {
      const auto generated =
          run_command(std::string(CCDBENCH_EXECUTABLE) + " generate fold --resolution 6 --frames 8 --out " + quoted(dir_ / "fold"));
      EXPECT_EQ(generated.exit_code, 0) << generated.output;
    }
    const std::string arguments = "run --scene " + quoted(dir_ / "fold") + " --toi --strategy full,apccd,full+cubic64 --out " + quoted(dir_ / out) +
                                  " --json " + quoted(dir_ / (out + ".json"));
    if (ranks == 0) return run_command(std::string(CCDBENCH_EXECUTABLE) + " --threads 1 " + arguments);
    return mpirun(ranks, arguments, fault);
  }

  nlohmann::json summaries(const std::string& out) { return read_json(dir_ / (out + ".json")); }

  /// Expects every cell of `b` to have the verdict of the same cell of `a`; returns a's colliding pairs, so that a
  /// test can check there was something to compare.
  static std::size_t expect_same_verdicts(const nlohmann::json& a, const nlohmann::json& b) {
    EXPECT_EQ(b.size(), a.size());
    std::size_t colliding = 0;
    for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
      EXPECT_EQ(verdict(a[i]), verdict(b[i])) << "cell " << i;
      colliding += a[i]["colliding"].get<std::size_t>();
    }
    return colliding;
  }

  std::size_t cell_files(const std::string& out) {
    std::size_t count = 0;
    for (const auto& entry : std::filesystem::directory_iterator(dir_ / out / "cells")) count += entry.is_regular_file() ? 1 : 0;
    return count;
  }

  testing::TempDir dir_;
};

TEST_F(Mpi, TwoRanksGiveEveryVerdictAndCountOfOne) {
  // One rank under mpirun is tested by TruthAndQueriesOverRanksAreThoseOfOneProcess; here two ranks against a plain
  // process (the suite under mpirun is the slowest part of CI's ASan run).
  const auto plain = run_suite(0, "plain");
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  const auto two = run_suite(2, "two");
  ASSERT_EQ(two.exit_code, 0) << two.output;
  const nlohmann::json p = summaries("plain"), b = summaries("two");
  ASSERT_EQ(p.size(), 3 * harness::suite_scenes("ci").size());  // every scene with each of three strategies
  ASSERT_EQ(b.size(), p.size());
  EXPECT_GT(expect_same_verdicts(p, b), 0u) << "cells without colliding pairs would compare nothing";
  std::set<int> ranks;
  for (std::size_t i = 0; i < p.size(); ++i) {
    ranks.insert(b[i]["rank"].get<int>());
    EXPECT_EQ(p[i]["rank"], 0);
  }
  EXPECT_EQ(ranks, (std::set<int>{0, 1})) << "the work was not spread over both ranks:\n" << two.output;
}

// The ranks of a node take its OpenCL devices in turn by their node-local rank (from MPI, not the launcher), and each
// record names the device its cell ran on: PoCL asked for two CPU devices stands in for a node's two GPUs. Fails if
// both ranks take device 0.
TEST_F(Mpi, TheRanksOfANodeTakeItsDevicesInTurn) {
  if (!CCDBENCH_WITH_OPENCL) GTEST_SKIP() << "built without OpenCL";
  const testing::ScopedVariable two_devices("POCL_DEVICES", "pthread pthread");  // for the listing and both ranks
  const auto listed = run_command(CCDBENCH_EXECUTABLE " devices");
  if (listed.exit_code != 0 || listed.output.find("\n1: ") == std::string::npos) GTEST_SKIP() << "PoCL gives no two devices here:\n" << listed.output;
  const auto generated = run_command(std::string(CCDBENCH_EXECUTABLE) + " generate fold --resolution 6 --frames 8 --out " + quoted(dir_ / "fold"));
  ASSERT_EQ(generated.exit_code, 0) << generated.output;
  const std::string arguments = "run --scene " + quoted(dir_ / "fold") +
                                " --thickness scene,0 --strategy full:backend=opencl,full+cubic64:backend=opencl --out " + quoted(dir_ / "two") +
                                " --json " + quoted(dir_ / "two.json");
  const auto two = mpirun(2, arguments);
  ASSERT_EQ(two.exit_code, 0) << two.output;
  std::set<int> ranks;
  for (const nlohmann::json& cell : summaries("two")) {
    const int rank = cell["rank"].get<int>();
    ranks.insert(rank);
    // One node: a rank's node-local rank is its rank, and its turn the device of that index.
    EXPECT_EQ(cell["provenance"]["opencl_device_index"], std::to_string(rank)) << cell["strategy"] << " on rank " << rank;
  }
  EXPECT_EQ(ranks, (std::set<int>{0, 1})) << "the work was not spread over both ranks: this proves nothing\n" << two.output;
  EXPECT_EQ(two.output.find("in turn: this one"), std::string::npos) << "two ranks, two devices: none is shared\n" << two.output;
}

// One step over several devices in one process (full:backend=opencl:device=0+1, or device=all: a node's GPUs): each
// device takes ranges of the step's queries, and the answers are those of one device, step by step (the digest of
// the reported pairs and their TOIs, and the elementary tests). PoCL asked for two CPU devices stands in for two GPUs.
// Fails if a device's part of a step is lost or counted twice, or if the split changes a pair's answer.
TEST(OpenClDevices, AStepSplitOverTwoDevicesGivesTheAnswersOfOne) {
  if (!CCDBENCH_WITH_OPENCL) GTEST_SKIP() << "built without OpenCL";
  const testing::ScopedVariable two_devices("POCL_DEVICES", "pthread pthread");
  const auto listed = run_command(CCDBENCH_EXECUTABLE " devices");
  if (listed.exit_code != 0 || listed.output.find("\n1: ") == std::string::npos) GTEST_SKIP() << "PoCL gives no two devices here:\n" << listed.output;
  const testing::TempDir dir;
  const auto generated = run_command(std::string(CCDBENCH_EXECUTABLE) + " generate fold --resolution 12 --frames 6 --out " + quoted(dir / "fold"));
  ASSERT_EQ(generated.exit_code, 0) << generated.output;
  // Step records by (strategy without its device, δ, step): answers digest and elementary tests.
  auto steps_of = [&](const std::string& device) {
    const std::string out = "out-" + device;
    const auto run =
        run_command(std::string(CCDBENCH_EXECUTABLE) + " --threads 2 run --scene " + quoted(dir / "fold") +
                    " --thickness scene,0 --strategy full:backend=opencl:device=" + device + ",full+cubic64:backend=opencl:device=" + device +
                    " --out " + quoted(dir / out) + " --json " + quoted(dir / (out + ".json")));
    EXPECT_EQ(run.exit_code, 0) << run.output;
    std::map<std::string, std::string> steps;
    for (const nlohmann::json& record : testing::read_json_lines(dir / out / "results.jsonl")) {
      if (record.value("record", "") != "step") continue;
      std::string strategy = record["strategy"].get<std::string>();
      strategy = strategy.substr(0, strategy.find(":device="));
      steps[strategy + " δ " + record["thickness"].dump() + " step " + record["step"].dump()] =
          record["answers"].get<std::string>() + " " + record["elementary_tests"].dump();
    }
    for (const nlohmann::json& cell : read_json(dir / (out + ".json"))) {
      EXPECT_EQ(cell["provenance"]["opencl_device_index"], device == "0" ? "0" : "0+1") << cell["strategy"];
      EXPECT_GT(cell["colliding"].get<double>(), 0) << "a cell without a colliding pair proves nothing";
    }
    return steps;
  };
  const auto one = steps_of("0");
  const auto two = steps_of("0+1");
  ASSERT_EQ(one.size(), 2u * 2u * 5u) << "two strategies, two δ, five steps";
  EXPECT_EQ(two, one);
  EXPECT_EQ(steps_of("all"), one) << "device=all: every device of a machine without a GPU";
}

TEST_F(Mpi, PluginsGiveTheVerdictsOfOneProcess) {
  // The template plugin in both forms (its whole step, and its queries behind ccdbench's broad phase), one of them in
  // a child process: each rank loads the plugin itself, and the verdicts are those of one process.
  const std::string p = "plugin:" + (std::filesystem::path(CCDBENCH_PLUGIN_DIR) / "libmy_ccd.so").string();
  if (!std::filesystem::exists(dir_ / "fold")) {
    const auto generated = run_command(std::string(CCDBENCH_EXECUTABLE) + " generate fold --resolution 6 --frames 8 --out " + quoted(dir_ / "fold"));
    ASSERT_EQ(generated.exit_code, 0) << generated.output;
  }
  auto run = [&](int ranks, const std::string& out) {
    const std::string arguments = "run --scene " + quoted(dir_ / "fold") + " --thickness 0,scene --toi --strategy " + p + ",full+" + p +
                                  ":isolate=on --out " + quoted(dir_ / out) + " --json " + quoted(dir_ / (out + ".json"));
    return ranks == 0 ? run_command(std::string(CCDBENCH_EXECUTABLE) + " --threads 1 " + arguments) : mpirun(ranks, arguments);
  };
  const auto plain = run(0, "plain");
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  const auto two = run(2, "two");
  ASSERT_EQ(two.exit_code, 0) << two.output;
  ASSERT_EQ(summaries("plain").size(), 4u);
  EXPECT_GT(expect_same_verdicts(summaries("plain"), summaries("two")), 0u);
  for (const nlohmann::json& cell : summaries("two")) EXPECT_EQ(cell["errors"], 0) << cell["strategy"];
}

TEST_F(Mpi, TruthAndQueriesOverRanksAreThoseOfOneProcess) {
  // With --toi: the TOI error percentiles of the totals need every rank's per-query errors, not its summary.
  CCD_REQUIRE_EXTERNAL_DATA(data_dir);
  const std::filesystem::path data = data_dir / "sample-queries";
  const auto one = mpirun(1, "queries " + quoted(data) + " --toi --method cubic64,conservative --json " + quoted(dir_ / "q1.json"));
  const auto two = mpirun(2, "queries " + quoted(data) + " --toi --method cubic64,conservative --json " + quoted(dir_ / "q2.json"));
  ASSERT_EQ(one.exit_code, 0) << one.output;
  ASSERT_EQ(two.exit_code, 0) << two.output;
  nlohmann::json a = read_json(dir_ / "q1.json"), b = read_json(dir_ / "q2.json");
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 2u);
  for (std::size_t i = 0; i < a.size(); ++i) {
    a[i].erase("ns_per_query");
    b[i].erase("ns_per_query");
    EXPECT_EQ(a[i], b[i]) << "row " << i;
  }
  EXPECT_EQ(a.back()["queries"].get<std::size_t>(), testing::shared_query_count("sample-queries"));
  EXPECT_GT(a.back()["positives"].get<std::size_t>(), 0u);

  const auto generated = run_command(std::string(CCDBENCH_EXECUTABLE) + " generate fold --resolution 6 --frames 8 --out " + quoted(dir_ / "fold"));
  ASSERT_EQ(generated.exit_code, 0) << generated.output;
  const auto t1 = mpirun(1, "truth --scene " + quoted(dir_ / "fold") + " --steps 0 --json " + quoted(dir_ / "t1.json"));
  const auto t2 = mpirun(2, "truth --scene " + quoted(dir_ / "fold") + " --steps 0 --json " + quoted(dir_ / "t2.json"));
  ASSERT_EQ(t1.exit_code, 0) << t1.output;
  ASSERT_EQ(t2.exit_code, 0) << t2.output;
  const nlohmann::json s1 = read_json(dir_ / "t1.json"), s2 = read_json(dir_ / "t2.json");
  ASSERT_EQ(s1.size(), 7u);
  ASSERT_EQ(s2.size(), s1.size());
  std::size_t colliding = 0;
  for (std::size_t k = 0; k < s1.size(); ++k) {
    for (const char* field : {"index", "vf", "ee", "vf_pairs_enumerated", "ee_pairs_enumerated", "decided_by_filter", "decided_exactly"}) {
      EXPECT_EQ(s1[k][field], s2[k][field]) << "step " << k << " " << field;
    }
    colliding += s1[k]["vf"].get<std::size_t>() + s1[k]["ee"].get<std::size_t>();
  }
  EXPECT_GT(colliding, 0u);
}

// A worker rank dies (the injector ends it, as a kill would) when it receives its first work item: the run fails,
// mpirun names the rank, rank 0 says where the finished cells are, and a rerun on two ranks completes with the
// results of an undisturbed run.
TEST_F(Mpi, ARerunCompletesWhatADeadWorkerRankLeft) {
  const auto reference = run_fold(0, "reference");
  ASSERT_EQ(reference.exit_code, 0) << reference.output;
  const auto failed = run_fold(2, "out", "1:message:1");
  EXPECT_NE(failed.exit_code, 0) << failed.output;
  EXPECT_NE(failed.output.find("fault injection: rank 1 ends"), std::string::npos) << failed.output;
  EXPECT_NE(failed.output.find("finished cells are kept in"), std::string::npos) << failed.output;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "out.json")) << "a failed run must not write its summary";
  const std::size_t kept = cell_files("out");
  EXPECT_LT(kept, 3u);
  const auto rerun = run_fold(2, "out");
  ASSERT_EQ(rerun.exit_code, 0) << rerun.output;
  std::size_t said_kept = 0;
  for (std::size_t at = 0; (at = rerun.output.find("kept from an earlier run", at)) != std::string::npos; ++at) ++said_kept;
  EXPECT_EQ(said_kept, kept) << rerun.output;
  const nlohmann::json a = summaries("reference"), b = summaries("out");
  ASSERT_EQ(a.size(), 3u);
  ASSERT_EQ(b.size(), a.size());
  EXPECT_GT(expect_same_verdicts(a, b), 0u);
}

// Rank 0 dies right after writing its second cell (deterministic: it writes every rank's cells): exactly those two
// are kept, and a rerun on one process reuses them and runs the third.
TEST_F(Mpi, ARerunOnOneProcessCompletesWhatADeadRankZeroLeft) {
  const auto reference = run_fold(0, "reference");
  ASSERT_EQ(reference.exit_code, 0) << reference.output;
  const auto failed = run_fold(2, "out", "0:cell:2");
  EXPECT_NE(failed.exit_code, 0) << failed.output;
  EXPECT_NE(failed.output.find("fault injection: rank 0 ends at its cell number 2"), std::string::npos) << failed.output;
  EXPECT_EQ(cell_files("out"), 2u) << failed.output;
  const auto rerun = run_fold(1, "out");
  ASSERT_EQ(rerun.exit_code, 0) << rerun.output;
  const nlohmann::json a = summaries("reference"), b = summaries("out");
  ASSERT_EQ(b.size(), a.size());
  EXPECT_GT(expect_same_verdicts(a, b), 0u);
  std::size_t resumed = 0;
  for (const nlohmann::json& cell : b) resumed += cell.value("resumed", false) ? 1 : 0;
  EXPECT_EQ(resumed, 2u);
}

}  // namespace
}  // namespace ccd
