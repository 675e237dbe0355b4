// The registries of strategies and narrow phases: every entry's keys and their defaults, resolved names, and the
// cell keys made from them.

#include "strategies/registry.hpp"
#include "ccd/config.hpp"
#include "harness/cell_store.hpp"
#include "strategies/narrowphase_registry.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <set>

namespace ccd {
namespace {

using strategies::make_strategy;

harness::CellKey key_of(const std::string& spec) {
  harness::CellKey key;
  key.scene = "scene";
  key.scene_content = "content";
  key.strategy = make_strategy(spec)->name();
  return key;
}

// Resolved names are cell keys: two specs whose numbers differ in any bit must resolve to different names, so a
// cell kept for one is never reused for the other. Before every number printed in its shortest round-trip form,
// tolerance=1e-6 and tolerance=1.0000001e-6 both printed as 1e-06.
TEST(Registry, TwoSpecsThatDifferInANumberNeverShareACellKey) {
  const std::vector<std::pair<std::string, std::string>> pairs = {
      {"full+conservative:tolerance=1e-6", "full+conservative:tolerance=1.0000001e-6"},
      {"full+cubic64:eta=1e-6", "full+cubic64:eta=1.0000001e-6"},
      {"full+cubic32:eta=0.001", "full+cubic32:eta=0.0010000001"},
      {"full+advancement:eta=1e-6", "full+advancement:eta=1.0000001e-6"},
      {"apccd:local=1", "apccd:local=1.0000001"},
      {"apccd+cubic64:global=0.25:eta=2e-6", "apccd+cubic64:global=0.25:eta=2.0000000000000004e-6"}};
  for (const auto& [a, b] : pairs) {
    SCOPED_TRACE(a + " / " + b);
    EXPECT_NE(make_strategy(a)->name(), make_strategy(b)->name());
    EXPECT_NE(harness::cell_file_name(key_of(a)), harness::cell_file_name(key_of(b)));
  }
}

// The names of every default stay what earlier results were recorded under (tests/baselines, reports).
TEST(Registry, DefaultsPrintAsBefore) {
  EXPECT_EQ(make_strategy("full")->name(), "full+conservative:tolerance=1e-10:toi_tolerance=1e-06:max_iterations=20000");
  EXPECT_EQ(make_strategy("full+cubic64")->name(), "full+cubic64:eta=1e-06");
  EXPECT_EQ(make_strategy("brute+cubic32")->name(), "brute+cubic32:eta=1e-06");
  EXPECT_EQ(make_strategy("full+advancement")->name(), "full+advancement:eta=1e-06:max_iterations=1000");
  EXPECT_EQ(
      make_strategy("apccd")->name(),
      "apccd+conservative:tolerance=1e-10:toi_tolerance=1e-06:max_iterations=20000:skip=on:nf_min=1:nf_max=8:local=1:global=0.25:dangling_max=0.05:"
      "pending_max=4:inflation_max=0.5:heuristic=on:object_pairs=fresh:history=off");
  EXPECT_EQ(make_strategy("full+cubic64:filter=on")->name(), "full+cubic64:eta=1e-06:filter=on");
}

// A name read back resolves to itself: a resolved name is a spec that gives the same strategy.
TEST(Registry, EveryResolvedNameResolvesToItself) {
  for (const char* spec : {"full", "full+cubic64:eta=0.125", "brute+advancement:max_iterations=7", "apccd:history=step:nf_max=3",
                           "apccd+cubic32:skip=off:object_pairs=session"}) {
    const std::string name = make_strategy(spec)->name();
    EXPECT_EQ(make_strategy(name)->name(), name) << spec;
  }
}

// Every entry's keys take their own defaults, and every key of every entry is refused out of its values.
TEST(Registry, EveryKeyAcceptsItsDefaultAndNamesItsValues) {
  for (const narrowphase::NarrowPhaseEntry& entry : narrowphase::narrow_phases()) {
    SCOPED_TRACE(entry.name);
    EXPECT_FALSE(entry.help.empty());
    narrowphase::SpecParameters defaults;
    for (const narrowphase::KeySpec& key : entry.keys) defaults[key.name] = key.default_value;
    const auto made = narrowphase::make_narrow_phase(entry.name, defaults);
    EXPECT_EQ(made->name(), narrowphase::make_narrow_phase(entry.name)->name());
    EXPECT_EQ(made->conservative(), entry.conservative);
    EXPECT_EQ(made->name().substr(0, entry.name.size()), entry.name);
  }
  std::set<std::string> names;
  for (const strategies::StrategyEntry& entry : strategies::strategy_entries()) {
    SCOPED_TRACE(entry.name);
    EXPECT_TRUE(names.insert(entry.name).second) << "two entries named " << entry.name;
    EXPECT_FALSE(entry.help.empty());
    if (!entry.unavailable.empty()) continue;
    for (const narrowphase::KeySpec& key : entry.keys) {
      if (key.kind == narrowphase::KeySpec::Kind::text) continue;
      const std::string bad = key.kind == narrowphase::KeySpec::Kind::choice ? "no-such-value" : "1e300";
      const std::string message = testing::error_message<std::invalid_argument>([&] { make_strategy(entry.name + ":" + key.name + "=" + bad); });
      EXPECT_NE(message.find(key.name + "=" + bad + " must be"), std::string::npos) << message;
    }
  }
}

// The OpenCL backend's keys belong to backend=opencl: on the CPU they are refused, not ignored.
TEST(Registry, DeviceKeysNeedTheOpenClBackend) {
  for (const char* spec : {"full:device=0", "apccd:device_iterations=5", "full:list_start=1", "full:sub_boxes=8"}) {
    const std::string message = testing::error_message<std::invalid_argument>([&] { make_strategy(spec); });
    EXPECT_NE(message.find("needs backend=opencl"), std::string::npos) << spec << ": " << message;
  }
  EXPECT_THROW(make_strategy("brute:backend=opencl"), std::invalid_argument);
}

// A run plans and keeps its cells by the name the strategy will have, without making it (registry.hpp's resolved_name,
// from each entry's resolve): it must be the made strategy's name, for every strategy, backend and narrow phase (the
// cell's first pass checks it too, and ends the run where they differ).
TEST(Registry, TheResolvedNameIsTheMadeStrategysName) {
  std::vector<std::string> specs = {"full",
                                    "full+cubic64:eta=0.125",
                                    "full+cubic32",
                                    "full:filter=on",
                                    "full+advancement:max_iterations=7",
                                    "brute",
                                    "brute+cubic64",
                                    "apccd",
                                    "apccd:skip=off:nf_max=5:history=step",
                                    "apccd+cubic32:object_pairs=session"};
  if (CCDBENCH_WITH_FCL) specs.insert(specs.end(), {"fcl", "fcl:bv=obbrss", "fcl-bvh+cubic64:bv=kdop24"});
  if (CCDBENCH_WITH_OPENCL) {
    specs.insert(specs.end(), {"full:backend=opencl", "full+cubic64:backend=opencl:list_start=64", "full:backend=opencl:filter=on:sub_boxes=16",
                               "apccd:backend=opencl:device_iterations=9", "apccd+cubic64:backend=opencl"});
  }
  for (const std::string& text : specs) {
    const strategies::StrategySpec spec = strategies::parse_strategy_spec(text);
    EXPECT_EQ(strategies::resolved_name(spec), make_strategy(spec)->name()) << text;
    EXPECT_EQ(spec.text, text);
    EXPECT_EQ(spec.entry->name, strategies::strategy_names_of(text).name);
  }
}

// validate says what making the strategy would refuse, making nothing.
TEST(Registry, ValidateRefusesWhatMakingWouldRefuse) {
  std::vector<std::string> specs = {"full:device=0", "apccd:nf_min=5:nf_max=2", "full:sub_boxes=8", "nosuch", "full+nosuch", "fcl+cubic64",
                                    "full:nosuch=1"};
  if (CCDBENCH_WITH_OPENCL) specs.insert(specs.end(), {"full+advancement:backend=opencl", "full:backend=opencl:device=999"});
  for (const std::string& text : specs) {
    const std::string by_make = testing::error_message<std::invalid_argument>([&] { make_strategy(text); });
    const std::string by_validate =
        testing::error_message<std::invalid_argument>([&] { strategies::validate(strategies::parse_strategy_spec(text)); });
    EXPECT_FALSE(by_make.empty()) << text;
    EXPECT_EQ(by_validate, by_make) << text;
  }
}

}  // namespace
}  // namespace ccd
