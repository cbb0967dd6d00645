#include "unjam/core/work_source.hpp"

#include <algorithm>

namespace unjam {

std::vector<int> TaskQueue::next(int max) {
  std::vector<int> out;
  while (static_cast<int>(out.size()) < max && next_ < tasks_.size()) {
    if (loop_.should_stop && loop_.should_stop()) break;
    const int t = tasks_[next_++];
    if (loop_.skip && loop_.skip(t)) continue;
    out.push_back(t);
  }
  return out;
}

std::size_t drop_cancelled(std::vector<TaskResult>& results) {
  const auto kept = std::remove_if(results.begin(), results.end(), [](const TaskResult& r) { return r.cancelled; });
  const auto n = static_cast<std::size_t>(results.end() - kept);
  results.erase(kept, results.end());
  return n;
}

namespace {
thread_local std::chrono::steady_clock::time_point t_taken;
}  // namespace

void BusyClock::taken() { t_taken = std::chrono::steady_clock::now(); }

void BusyClock::put(RankLoad& load, std::size_t results) {
  load.busy_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t_taken).count();
  load.tasks += static_cast<long long>(results);
}

std::vector<int> QueueSource::take(int max) {
  const std::lock_guard lock(mutex_);
  std::vector<int> tasks = queue_.next(max);
  if (!tasks.empty()) clock_.taken();
  return tasks;
}

void QueueSource::put(std::vector<TaskResult> results) {
  const std::lock_guard lock(mutex_);
  queue_.cancelled(drop_cancelled(results));
  clock_.put(load_, results.size());
  if (!results.empty()) loop_.gather(results);
}

LocalDistributor::LocalDistributor(int shard, int shards) : shard_(shard), shards_(shards) {
  if (shards < 1 || shard < 0 || shard >= shards)
    throw Error("--shard i/K needs K >= 1 and 0 <= i < K (got " + std::to_string(shard) + "/" +
                std::to_string(shards) + ")");
  load_.threads = omp_get_max_threads();
}

bool LocalDistributor::run(const std::vector<int>& tasks, const WorkLoop& loop) {
  std::vector<int> mine;
  for (const int t : tasks)
    if (in_shard(loop.place ? loop.place(t) : t, shard_, shards_)) mine.push_back(t);
  TaskQueue queue(mine, loop);
  std::mutex mutex;
  QueueSource source(queue, loop, load_, mutex);
  loop.work(source);
  return queue.finished();
}

}  // namespace unjam
