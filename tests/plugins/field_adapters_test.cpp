// The field's adapters (examples/plugins/field/, examples/plugins/tight_inclusion/; reports/field/README.md) hand
// each library its rows in the order the library documents and report its TOI as it returns it. Each plugin is asked
// pairs whose answer changes when the rows are handed in another order: a vertex that crosses a face at t = 1/4 is
// apart from the face if a face corner is taken for the vertex (BSC and TightCCD take the face first, the rest the
// vertex first), two edges that cross are apart if their endpoints are mixed, and a TOI of 3/4 instead of 1/4 is
// the step taken backwards (t1 before t0); a TOI left unwritten, or a plugin that stopped saying it reports one,
// fails too. A method that takes a minimum separation must answer by it; one that does not must refuse δ > 0.
//
// The plugins are built beside the project by scripts/field/build.sh (they need the libraries' sources, which CI does
// not have): each test skips with one line when its plugin is not in $CCDBENCH_FIELD_PLUGINS (default
// build/field/plugins).

#include "strategies/plugin/ccdbench_plugin.h"
#include "tests/support/cli.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <dlfcn.h>

#include <cfenv>
#include <cstdlib>
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

namespace ccd {
namespace {

/// A field plugin and what its library gives: a TOI, and a minimum separation.
struct FieldPlugin {
  const char* name;
  const char* file;
  bool reports_toi;
  bool takes_thickness;
};

void PrintTo(const FieldPlugin& plugin, std::ostream* out) { *out << plugin.name; }

const FieldPlugin kFieldPlugins[] = {
    {"tight_inclusion", "libtight_inclusion_plugin.so", true, true},
    {"ipc_tight_inclusion", "libipc_tight_inclusion_plugin.so", true, true},
    {"ipc_additive", "libipc_additive_plugin.so", true, true},
    {"fprf", "libfprf_plugin.so", true, true},
    {"msrf", "libmsrf_plugin.so", true, true},
    {"root_parity", "libroot_parity_plugin.so", false, false},
    {"bsc", "libbsc_plugin.so", false, false},
    {"rational_root_parity", "librational_root_parity_plugin.so", false, false},
    {"tight_ccd", "libtight_ccd_plugin.so", false, false},
    {"uirf", "libuirf_plugin.so", true, false},
    {"irf", "libirf_plugin.so", true, false},
};

/// When the crossing pairs below first touch: a quarter of the step.
constexpr double kContactTime = 0.25;
/// How much earlier than the contact a TOI may be: ipc-toolkit's AdditiveCCD stops where the distance is a tenth of
/// the initial one (0.1 of the 1 unit here, at 0.225), its TightInclusionCCD 1e-4 short of contact; the others are
/// within their tolerance (1e-6) of it. A TOI taken backwards (0.75) or never written (the adapter's 1) is far out.
constexpr double kEarliestAcceptedToi = 0.2;
/// How much later than the contact a TOI may be: the root finders' rounding, far below any order mistake.
constexpr double kLatestAcceptedToi = kContactTime + 1e-9;
/// Where the descending vertex below stops above the face (a fifth of where it starts: out of the gap AdditiveCCD
/// calls a contact, a tenth), and a thickness that covers it.
constexpr double kHoverHeight = 0.2;
constexpr double kCoveringThickness = 0.3;

using Rows = std::vector<double>;

/// 8 points (t = 0, then t = 1) as the ABI's 24 doubles.
Rows rows(std::initializer_list<std::initializer_list<double>> points) {
  Rows r;
  for (const auto& p : points) r.insert(r.end(), p);
  return r;
}

// A vertex falling through the face (0,0,0), (1,0,0), (0,1,0) at t = 1/4 (z = 1 - 4t): taken in another order, a face
// corner (static, at y = 0 or 1) would be the point, and the moving triangle spans y in [0, 0.25]: no contact.
const Rows kVertexThroughFace = rows({{0.25, 0.25, 1}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.25, 0.25, -3}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
// The same vertex passing beside the face: apart in any order.
const Rows kVertexBesideFace = rows({{2.25, 0.25, 1}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2.25, 0.25, -3}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
// A vertex coming down onto the face and stopping kHoverHeight above it: apart at δ = 0, in contact at
// kCoveringThickness (from t = 0.7 / 0.8, where it crosses into that band).
const Rows kVertexOverFace = rows({{0.25, 0.25, 1}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.25, 0.25, kHoverHeight}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
// Edge b falling across edge a (the x axis) at t = 1/4: with a's and b's endpoints mixed ((ea0, eb0), (ea1, eb1)),
// the two segments lie at x <= 0 and x >= 0 and meet x = 0 at y = -1 and y = 1: no contact.
const Rows kEdgeAcrossEdge = rows({{-1, 0, 0}, {1, 0, 0}, {0, -1, 1}, {0, 1, 1}, {-1, 0, 0}, {1, 0, 0}, {0, -1, -3}, {0, 1, -3}});

/// The folder scripts/field/build.sh installs the plugins into.
std::filesystem::path plugin_folder() {
  const char* set = std::getenv("CCDBENCH_FIELD_PLUGINS");
  return set != nullptr && *set != '\0' ? std::filesystem::path(set) : std::filesystem::path("build/field/plugins");
}

class FieldAdapter : public ::testing::TestWithParam<FieldPlugin> {
 protected:
  void SetUp() override {
    const std::filesystem::path path = plugin_folder() / GetParam().file;
    if (!std::filesystem::exists(path)) {
      GTEST_SKIP() << "no " << path.string() << ": its library's sources are needed (scripts/field/build.sh, reports/field/README.md)";
    }
    library_ = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    ASSERT_NE(library_, nullptr) << dlerror();
    const auto entry = reinterpret_cast<ccdbench_plugin_entry>(dlsym(library_, CCDBENCH_PLUGIN_ENTRY_NAME));
    ASSERT_NE(entry, nullptr) << path << " exports no " << CCDBENCH_PLUGIN_ENTRY_NAME;
    table_ = entry(CCDBENCH_PLUGIN_ABI_VERSION);
    ASSERT_NE(table_, nullptr);
    char error[CCDBENCH_MESSAGE_SIZE] = {};
    context_ = table_->create(nullptr, error);
    ASSERT_NE(context_, nullptr) << error;
  }
  void TearDown() override {
    if (context_ != nullptr) table_->destroy(context_);
    // The libraries are left loaded: some register what outlives an unload (loggers, statics).
  }

  /// One answer, in a floating-point environment of its own (root parity and BSC change the rounding mode).
  ccdbench_answer ask(bool vertex_face, const Rows& r, double thickness) const {
    std::fenv_t saved;
    std::fegetenv(&saved);
    ccdbench_answer answer{};
    answer.toi = -1;
    (vertex_face ? table_->vertex_face : table_->edge_edge)(context_, r.data(), thickness, &answer);
    std::fesetenv(&saved);
    return answer;
  }

  /// A contact with its TOI, when the plugin says it has one, at the contact of the crossing pairs.
  void expect_contact_at_a_quarter(bool vertex_face, const Rows& r) const {
    const ccdbench_answer answer = ask(vertex_face, r, 0);
    ASSERT_EQ(answer.outcome, CCDBENCH_CONTACT) << (vertex_face ? "vertex-face" : "edge-edge") << ": " << answer.message;
    if (GetParam().reports_toi) {
      EXPECT_GE(answer.toi, kEarliestAcceptedToi) << "its TOI is too early for the library's";
      EXPECT_LE(answer.toi, kLatestAcceptedToi)
          << "its TOI is later than the contact at 1/4: dropped (left at 1), or the step taken from t = 1 (3/4)";
    }
  }

  void* library_ = nullptr;
  const ccdbench_plugin* table_ = nullptr;
  void* context_ = nullptr;
};

TEST_P(FieldAdapter, SaysWhatItsLibraryGives) {
  EXPECT_EQ((table_->capabilities & CCDBENCH_REPORTS_TOI) != 0, GetParam().reports_toi);
  EXPECT_NE(table_->vertex_face, nullptr);
  EXPECT_NE(table_->edge_edge, nullptr);
}

TEST_P(FieldAdapter, HandsAVertexAndAFaceInTheLibrarysOrder) {
  expect_contact_at_a_quarter(true, kVertexThroughFace);
  EXPECT_EQ(ask(true, kVertexBesideFace, 0).outcome, CCDBENCH_APART);
}

TEST_P(FieldAdapter, HandsTwoEdgesInTheLibrarysOrder) { expect_contact_at_a_quarter(false, kEdgeAcrossEdge); }

TEST_P(FieldAdapter, AnswersByTheMinimumSeparationOrRefusesIt) {
  EXPECT_EQ(ask(true, kVertexOverFace, 0).outcome, CCDBENCH_APART);
  const ccdbench_answer covered = ask(true, kVertexOverFace, kCoveringThickness);
  if (GetParam().takes_thickness) {
    EXPECT_EQ(covered.outcome, CCDBENCH_CONTACT) << covered.message;
  } else {
    EXPECT_EQ(covered.outcome, CCDBENCH_ERROR) << "a method without a minimum separation must not answer at δ > 0";
  }
}

// Scalable CCD's whole step (examples/plugins/scalable_ccd/; reports/field/README.md, "On the GPU"): ccdbench hands
// it the fold, a sheet and a rigid blade, and every pair it reports must be one the scene lets collide, in the
// scene's ids: a vertex-face pair with its indices swapped, an edge-edge pair given by edge indices instead of their
// vertices, or a pair of the blade with itself (the library knows no objects; the adapter leaves those out) would be
// the plugin's errors, and the pairs it names would not be the colliding ones. Whether it misses is the report's
// finding, not this test's (on this scene it does, and its answers change between calls, as in its own ccd()). Runs where the plugin was built and a CUDA GPU is; skipped with one line otherwise.
TEST(ScalableCcd, ReportsTheScenesPairsInItsIds) {
  const std::filesystem::path path = plugin_folder() / "libscalable_ccd_plugin.so";
  if (!std::filesystem::exists(path)) {
    GTEST_SKIP() << "no " << path.string() << ": built by scripts/field/build.sh scalable_ccd, on a machine with nvcc";
  }
  const testing::TempDir dir;
  const std::filesystem::path json = dir / "cells.json";
  const auto run = testing::run_ccdbench("run --scene " + testing::quoted(testing::small_fold(dir / "fold8")) +
                                         " --thickness scene,0 --toi --strategy plugin:" + testing::quoted(path) + " --json " +
                                         testing::quoted(json) + " --out " + testing::quoted(dir / "out"));
  if (run.exit_code == 2 && run.output.find("its configuration was refused: cudaFree(0)") != std::string::npos) {
    GTEST_SKIP() << "no CUDA GPU here: " << run.output.substr(run.output.find("cudaFree(0)"));
  }
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json cells = testing::read_json(json);
  ASSERT_EQ(cells.size(), 2u) << "the scene's δ and δ = 0";
  for (const nlohmann::json& cell : cells) {
    SCOPED_TRACE("δ = " + std::to_string(cell["thickness"].get<double>()));
    ASSERT_TRUE(cell["verified"].get<bool>());
    ASSERT_GT(cell["colliding"].get<double>(), 0) << "a step with no colliding pair proves nothing";
    EXPECT_EQ(cell["errors"].get<double>(), 0) << "pairs the scene does not have, or does not let collide";
    // Some of what it reports is true contact: pairs named in the wrong ids would all be false alarms (how many it
    // finds is the library's: its answers change from call to call, reports/field/README.md).
    EXPECT_GT(cell["reported"].get<double>() - cell["false_alarms"].get<double>(), 0) << cell.dump();
  }
}

/// The test's name: the plugin's.
std::string field_plugin_name(const ::testing::TestParamInfo<FieldPlugin>& param) { return param.param.name; }

INSTANTIATE_TEST_SUITE_P(Field, FieldAdapter, ::testing::ValuesIn(kFieldPlugins), field_plugin_name);

}  // namespace
}  // namespace ccd
