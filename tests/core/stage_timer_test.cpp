#include "core/stage_timer.hpp"

#include <gtest/gtest.h>

namespace ccd {
namespace {

TEST(StageTimes, AccumulatesPerStageInFirstSeenOrder) {
  StageTimes times;
  times.add("refit", 1.5);
  times.add("traversal", 2.0);
  times.add("refit", 0.5);
  ASSERT_EQ(times.entries().size(), 2u);
  EXPECT_EQ(times.entries()[0].first, "refit");
  EXPECT_EQ(times.milliseconds("refit"), 2.0);
  EXPECT_EQ(times.milliseconds("narrow phase"), 0.0);
  EXPECT_EQ(times.total_milliseconds(), 4.0);
}

TEST(StageTimes, ScopedTimerRecordsItsStage) {
  StageTimes times;
  { ScopedStageTimer timer(times, "update"); }
  ASSERT_EQ(times.entries().size(), 1u);
  EXPECT_GE(times.milliseconds("update"), 0.0);
}

}  // namespace
}  // namespace ccd
