// The task loop of campaigns (core/work_source.hpp): a task whose compute is abandoned
// (Cancelled) is neither gathered nor counted as done, and the loop reports it is not finished.
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <set>
#include <string>
#include <vector>

#include "unjam/core/campaign_time.hpp"
#include "unjam/core/error.hpp"
#include "unjam/core/work_source.hpp"

namespace unjam {
namespace {

// Runs tasks 0..n-1 over `dist` on two threads; task `cancel` (-1: none) throws Cancelled.
// Returns the gathered tasks (each checked to carry its own bytes) and whether run() finished.
std::pair<std::set<int>, bool> run_tasks(WorkDistributor& dist, int n, int cancel) {
  std::vector<int> tasks(n);
  std::iota(tasks.begin(), tasks.end(), 0);
  std::set<int> gathered;
  WorkLoop loop;
  loop.work = [&](WorkSource& source) {
    work_off(source, 2, 1, [] { return 0; }, [&](int&, int t) {
      if (t == cancel) throw Cancelled();
      return std::to_string(t);
    });
  };
  loop.gather = [&](std::vector<TaskResult>& results) {
    for (const TaskResult& r : results) {
      EXPECT_FALSE(r.cancelled);
      EXPECT_EQ(r.bytes, std::to_string(r.task));
      EXPECT_TRUE(gathered.insert(r.task).second) << "task " << r.task << " gathered twice";
    }
  };
  const bool finished = dist.run(tasks, loop);
  return {gathered, finished};
}

TEST(WorkSource, DropCancelledKeepsTheOrderOfTheOthers) {
  std::vector<TaskResult> r = {{3, "a"}, {1, {}, true}, {7, "b"}, {2, {}, true}, {5, "c"}};
  EXPECT_EQ(drop_cancelled(r), 2u);
  ASSERT_EQ(r.size(), 3u);
  EXPECT_EQ(r[0].task, 3);
  EXPECT_EQ(r[1].task, 7);
  EXPECT_EQ(r[2].task, 5);
}

TEST(WorkSource, CancelledTaskIsNotGatheredNorCountedAndTheLoopIsNotFinished) {
  {
    LocalDistributor local;
    const auto [gathered, finished] = run_tasks(local, 12, -1);
    EXPECT_TRUE(finished);
    EXPECT_EQ(gathered.size(), 12u);
    EXPECT_EQ(local.loads().at(0).tasks, 12);
  }
  LocalDistributor local;
  const auto [gathered, finished] = run_tasks(local, 12, 4);
  EXPECT_FALSE(finished);
  EXPECT_EQ(gathered.size(), 11u);
  EXPECT_EQ(gathered.count(4), 0u);
  EXPECT_EQ(local.loads().at(0).tasks, 11);
}

TEST(WorkSource, CancelledTaskOfAShardLeavesTheShardNotFinished) {
  LocalDistributor shard(1, 3);  // tasks 1, 4, 7, 10
  const auto [gathered, finished] = run_tasks(shard, 12, 7);
  EXPECT_FALSE(finished);
  EXPECT_EQ(gathered, (std::set<int>{1, 4, 10}));
  LocalDistributor other(0, 3);  // the cancelled task is not one of its own
  const auto [mine, done] = run_tasks(other, 12, 7);
  EXPECT_TRUE(done);
  EXPECT_EQ(mine, (std::set<int>{0, 3, 6, 9}));
}

// The ETA of a resumed campaign comes from every run's busy seconds per task: 107 probes in
// 12 240 busy s (two earlier runs) and one more of 654 s in this run, on 2 threads, leave 192
// probes at (12 240 + 654) / 108 s each, two at a time.
TEST(CampaignEta, IsEveryRunsBusyTimePerTaskOverTheWorkers) {
  const CampaignTime so_far = CampaignTime{2, 6100.0, 12240.0, 0} + CampaignTime{1, 654.0, 654.0, 0};
  EXPECT_DOUBLE_EQ(campaign_eta(so_far, 108, 192, 2), 192.0 * 12894.0 / 108.0 / 2.0);
  EXPECT_DOUBLE_EQ(campaign_eta(so_far, 108, 192, 1), 192.0 * 12894.0 / 108.0);
  // Untimed tasks (a checkpoint that did not record its time) are left out of the pace.
  const CampaignTime partly = CampaignTime{0, 0.0, 0.0, 100} + CampaignTime{1, 50.0, 100.0, 0};
  EXPECT_DOUBLE_EQ(campaign_eta(partly, 110, 40, 2), 40.0 * 100.0 / 10.0 / 2.0);
  EXPECT_DOUBLE_EQ(campaign_eta(so_far, 300, 0, 2), 0.0);
  // Unknown before any timed task, and without workers.
  EXPECT_EQ(campaign_eta(CampaignTime{1, 5.0, 0.0, 0}, 0, 300, 2), -1.0);
  EXPECT_EQ(campaign_eta(partly, 100, 40, 2), -1.0);
  EXPECT_EQ(campaign_eta(so_far, 108, 192, 0), -1.0);
}

}  // namespace
}  // namespace unjam
