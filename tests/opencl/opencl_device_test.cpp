// OpenCL devices and their contexts, on PoCL (or whatever device OpenCL offers first): choice and refusal of a device,
// the contexts strategies lease and give back (opencl::lease_context, Strategy::prepare), and how a step on several
// devices deals its queries into ranges. The answers themselves are opencl_test.cpp's.

#include "datasets/scene_sequence.hpp"
#include "harness/run.hpp"
#include "strategies/opencl/full_opencl.hpp"
#include "strategies/opencl/pipeline.hpp"
#include "strategies/opencl/runtime.hpp"
#include "strategies/registry.hpp"
#include "tests/support/cli.hpp"
#include "tests/support/strategy_runs.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace ccd {
namespace {

TEST(OpenClDevice, ADeviceWithoutDoublePrecisionIsRefusedSayingSo) {
  opencl::DeviceInfo device;
  device.name = "a float-only GPU";
  device.fp64 = false;
  try {
    opencl::require_double_precision(device);
    FAIL() << "accepted a device without fp64";
  } catch (const std::invalid_argument& refusal) {
    EXPECT_NE(std::string(refusal.what()).find("no double precision (cl_khr_fp64)"), std::string::npos) << refusal.what();
  }
  device.fp64 = true;
  device.fp64_denormals = false;
  EXPECT_THROW(opencl::require_double_precision(device), std::invalid_argument);
  device.fp64_denormals = true;
  EXPECT_NO_THROW(opencl::require_double_precision(device));
}

// A sweep makes a strategy per cell: the context each one leases is the one the last gave back, not a new one, and
// two strategies alive at once never share one (their queues and kernels' arguments are their own).
TEST(OpenClDevice, AContextGivenBackIsTheNextLeaseAndTwoHeldAtOnceAreTwo) {
  opencl::release_idle_contexts();  // (whatever tests before this one in the process left)
  const opencl::DeviceInfo device = opencl::choose_device(opencl::list_devices(), "");
  const std::string defines = opencl::kernel_defines(64, 0);
  opencl::Context* first_held = nullptr;
  {
    opencl::ContextLease first = opencl::lease_context(device, defines);
    first_held = first.get();
    first->arithmetic_checked = true;  // as a strategy leaves it; a new context starts unchecked
    opencl::ContextLease second = opencl::lease_context(device, defines);
    EXPECT_NE(second.get(), first.get());
    EXPECT_FALSE(second->arithmetic_checked);
    EXPECT_NE(second->context(), first->context());
  }
  // Both are idle now; the next lease takes one of them (the last given back: `first`, released after `second`).
  opencl::ContextLease again = opencl::lease_context(device, defines);
  EXPECT_EQ(again.get(), first_held);
  EXPECT_TRUE(again->arithmetic_checked) << "a new context, not the one given back";
}

// What an MPI rank does while rank 0 plans: a strategy prepared and gone leaves its device's context, checked, for the
// first strategy on that device, which makes none of its own (fails when prepare readies nothing).
TEST(OpenClDevice, APreparedStrategyLeavesItsContextToTheNextOnItsDevice) {
  const datasets::SceneSequence loaded = harness::suite_scenes("ci").front().load();
  const auto frames = testing::all_frames(loaded);
  opencl::release_idle_contexts();                             // (whatever tests before this one in the process left)
  std::vector<std::unique_ptr<strategies::Strategy>> running;  // each holds its context: none idle for the next
  for (const std::string spec : {"full:backend=opencl", "apccd:backend=opencl"}) {
    SCOPED_TRACE(spec);
    strategies::make_strategy(spec)->prepare();
    const std::size_t made = opencl::contexts_made();
    running.push_back(strategies::make_strategy(spec));
    running.back()->init(loaded.scene(), frames[0]);
    running.back()->step({&loaded.scene(), 0, frames[0], frames[1]}, false);
    EXPECT_EQ(opencl::contexts_made(), made) << "the strategy made a context of its own";
  }
}

// A step on several devices deals its queries into ranges: every query once, and each range holds every part of the
// step alike (a contact-rich run of faces is spread over all of them), whatever the count.
TEST(OpenClDevice, QueriesAreDealtIntoRangesOfEveryPartOfTheStep) {
  for (const auto& [count, ranges] : std::vector<std::pair<std::size_t, std::size_t>>{{1'000'000, 8}, {300, 4}, {5, 8}, {0, 2}, {4096, 1}}) {
    SCOPED_TRACE(std::to_string(count) + " queries into " + std::to_string(ranges) + " ranges");
    const auto [order, starts] = opencl::deal_into_ranges(count, ranges);
    ASSERT_EQ(starts.size(), ranges + 1);
    EXPECT_EQ(starts.front(), 0u);
    EXPECT_EQ(starts.back(), count);
    std::vector<std::size_t> sorted = order;
    std::sort(sorted.begin(), sorted.end());
    std::vector<std::size_t> every(count);
    std::iota(every.begin(), every.end(), 0);
    EXPECT_EQ(sorted, every) << "not every query once";
    if (count < 1000) continue;
    for (std::size_t r = 0; r < ranges; ++r) {
      // A range's queries come from each eighth of the step, in about equal numbers.
      std::vector<std::size_t> per_eighth(8);
      for (std::size_t k = starts[r]; k < starts[r + 1]; ++k) ++per_eighth[order[k] * 8 / count];
      const auto [low, high] = std::minmax_element(per_eighth.begin(), per_eighth.end());
      EXPECT_GT(*low, 0u) << "range " << r;
      // Blocks are dealt whole (up to 1024 queries), and an eighth's edge cuts one: a range's eighths differ by at
      // most two blocks.
      constexpr std::size_t kTwoBlocks = 2 * 1024;
      EXPECT_LE(*high - *low, kTwoBlocks) << "range " << r;
    }
  }
}

TEST(OpenClDevice, ChoiceByIndexOrNameAndClearErrors) {
  std::vector<opencl::DeviceInfo> devices(2);
  devices[0].index = 0;
  devices[0].name = "cpu-device";
  devices[1].index = 1;
  devices[1].name = "Big GPU";
  devices[1].is_gpu = true;
  EXPECT_EQ(opencl::choose_device(devices, "").index, 1u);  // the first GPU
  EXPECT_EQ(opencl::choose_device(devices, "0").index, 0u);
  EXPECT_EQ(opencl::choose_device(devices, "Big").index, 1u);
  EXPECT_THROW(opencl::choose_device(devices, "7"), std::invalid_argument);
  EXPECT_THROW(opencl::choose_device(devices, "Tiny"), std::invalid_argument);
  EXPECT_THROW(opencl::choose_device({}, ""), std::invalid_argument);
  // The ranks of a node take its GPUs in turn (a second GPU for turn 1), its devices where it has no GPU; a named
  // device is every rank's.
  devices.push_back(devices[1]);
  devices[2].index = 2;
  EXPECT_EQ(opencl::choose_device(devices, "", {0, 2}).index, 1u);
  EXPECT_EQ(opencl::choose_device(devices, "", {1, 2}).index, 2u);
  EXPECT_EQ(opencl::choose_device(devices, "", {2, 3}).index, 1u);  // three ranks, two GPUs: the third shares the first
  EXPECT_EQ(opencl::choose_device(devices, "0", {1, 2}).index, 0u);
  devices[1].is_gpu = devices[2].is_gpu = false;
  EXPECT_EQ(opencl::choose_device(devices, "", {1, 3}).index, 1u);
}

TEST(OpenClDevice, TheResolvedSpecNamesTheDeviceAndWrongKeysAreRefused) {
  const auto devices = strategies::opencl_devices();
  ASSERT_FALSE(devices.empty()) << "no OpenCL device: scripts/setup.sh installs PoCL";
  const std::string name = strategies::make_strategy("full:backend=opencl:device=0")->name();
  EXPECT_NE(name.find(":backend=opencl:device=" + devices[0].name), std::string::npos) << name;
  EXPECT_THROW(strategies::make_strategy("full+advancement:backend=opencl"), std::invalid_argument);
  EXPECT_THROW(strategies::make_strategy("full:backend=cuda"), std::invalid_argument);
  EXPECT_THROW(strategies::make_strategy("full:device=0"), std::invalid_argument);
  EXPECT_THROW(strategies::make_strategy("full:backend=opencl:device_iterations=-1"), std::invalid_argument);
  EXPECT_THROW(strategies::make_strategy("full:device_iterations=10"), std::invalid_argument);
  EXPECT_THROW(strategies::make_strategy("apccd+advancement:backend=opencl"), std::invalid_argument);
  EXPECT_THROW(strategies::make_strategy("apccd:device=0"), std::invalid_argument);
  const std::string apccd = strategies::make_strategy("apccd:backend=opencl:device=0:local=1.0000000001")->name();
  EXPECT_NE(apccd.find(":local=1.0000000001:"), std::string::npos) << apccd;
  EXPECT_NE(apccd.find(":backend=opencl:device=" + devices[0].name + ":device_iterations=200"), std::string::npos) << apccd;
  EXPECT_EQ(strategies::make_strategy("full:backend=cpu")->name(), strategies::make_strategy("full")->name());
}

TEST(OpenClDevice, DevicesListsThemForPeopleAndScripts) {
  const testing::CommandResult table = testing::run_ccdbench("devices");
  EXPECT_EQ(table.exit_code, 0) << table.output;
  EXPECT_NE(table.output.find("compute units"), std::string::npos) << table.output;
  const testing::CommandResult json = testing::run_ccdbench("devices --json");
  EXPECT_EQ(json.exit_code, 0) << json.output;
  EXPECT_NE(json.output.find("\"fp64\":true"), std::string::npos) << json.output;
}

}  // namespace
}  // namespace ccd
