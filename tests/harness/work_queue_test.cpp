// The work queue's order (harness/work_queue.hpp): of the items ready, the costliest is handed out first.

#include "harness/work_queue.hpp"

#include <gtest/gtest.h>

namespace ccd::harness {
namespace {

// Longest first: a 5 s cell planned last started last and ran alone for its 5 s while three ranks idled (the paper
// sweep on 4 GPUs). An item waits for the items it names, whatever its cost; equal costs keep plan order.
TEST(WorkQueue, HandsOutTheCostliestReadyItemFirst) {
  const std::vector<WorkItem> items = {{"truth", {}, 10}, {"small", {}, 1}, {"large", {0}, 50}, {"medium", {}, 5}, {"medium again", {}, 5}};
  std::vector<bool> waiting(items.size(), true), finished(items.size(), false);
  std::vector<std::string> order;
  while (const std::optional<std::size_t> next = next_ready_item(items, waiting, finished)) {
    order.push_back(items[*next].payload);
    waiting[*next] = false;
    finished[*next] = true;
  }
  EXPECT_EQ(order, (std::vector<std::string>{"truth", "large", "medium", "medium again", "small"}));
  // Nothing ready while what an item waits for runs.
  std::vector<bool> only_large(items.size(), false), none(items.size(), false);
  only_large[2] = true;
  EXPECT_FALSE(next_ready_item(items, only_large, none).has_value());
}

// Of equally costly items, a rank gets one of the scene it worked on last: the paper sweep's cells of one scene at
// two δ cost the same, and a rank that took the other scene's would load its 100 frames for nothing. Cost still comes
// first: a costlier item of another scene goes before.
TEST(WorkQueue, OfEqualCostsARankKeepsToItsScene) {
  const std::vector<WorkItem> items = {{"a", {}, 5, 0}, {"b", {}, 5, 1}, {"a again", {}, 5, 0}, {"c", {}, 9, 2}, {"b again", {}, 5, 1}};
  std::vector<bool> waiting(items.size(), true), finished(items.size(), false);
  auto take = [&](std::optional<std::size_t> group) {
    const std::optional<std::size_t> next = next_ready_item(items, waiting, finished, group);
    waiting.at(next.value()) = false;
    return items[*next].payload;
  };
  EXPECT_EQ(take(1), "c");
  EXPECT_EQ(take(1), "b");
  EXPECT_EQ(take(1), "b again");
  EXPECT_EQ(take(1), "a") << "none of its scene left: plan order";
  EXPECT_EQ(take(std::nullopt), "a again");
}

}  // namespace
}  // namespace ccd::harness
