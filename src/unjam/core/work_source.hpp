#pragma once
// Loops over independent tasks (probes, force-bound LPs) whose tasks may be handed out to the
// threads of one process or to the ranks of an MPI job (campaign/mpi_distributor.hpp), with
// every result gathered in one place (docs/ARCHITECTURE.md, "Campaigns").
//
//   WorkDistributor::run(tasks, loop): the gathering process (rank 0, or the only process)
//     hands `tasks` out in their order, on request, a few at a time (dynamic load balance);
//   loop.work(source): what every process computes: take tasks, compute them, put results;
//   loop.gather(results): called on the gathering process only, one call at a time, with the
//     results of one put of any process.
//
// A task whose compute was abandoned (it threw Cancelled, unjam/core/error.hpp) comes back as
// TaskResult::cancelled: it is not gathered and not counted as done, and run() then reports
// the loop as not finished (a resumed run computes the task again).
//
// A result is a byte string (ByteWriter / ByteReader), so that it can travel between
// processes. Gathering must not depend on the order in which results arrive; callers keep
// results sorted by task and use exact (fixed-point) sums, so the outputs are the same bytes
// for any number of processes and threads.
#include <chrono>
#include <cstdint>
#include <cstring>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include <omp.h>

#include "unjam/core/error.hpp"

namespace unjam {

struct TaskResult {
  int task = -1;
  std::string bytes;
  bool cancelled = false;  // abandoned (no bytes): dropped before gather, the loop not finished
};

// Removes the cancelled results of `results` (keeping the order of the others); returns how
// many there were.
std::size_t drop_cancelled(std::vector<TaskResult>& results);

// This process's side of a loop: thread safe.
class WorkSource {
 public:
  virtual ~WorkSource() = default;
  // Up to `max` tasks for the calling thread; empty when none is left (or the loop stops).
  virtual std::vector<int> take(int max) = 0;
  // The results of tasks this thread took (it times the compute between take and put),
  // cancelled ones included.
  virtual void put(std::vector<TaskResult> results) = 0;
};

struct WorkLoop {
  std::function<void(WorkSource&)> work;                 // every process
  std::function<void(std::vector<TaskResult>&)> gather;  // gathering process, finished tasks only
  // Gathering process: called once per task as it comes up to be handed out; true drops it
  // (the caller settles it without a result). May be empty.
  std::function<bool(int task)> skip;
  // Polled before tasks are handed out; once true, no more are (on any process). May be empty.
  std::function<bool()> should_stop;
  // The task's place in the whole list of the loop's tasks, the same in every run of it
  // (a probe campaign's: the contact's place among its targets); it decides the task's shard
  // (in_shard). Empty: the task itself (a list of every contact, 0 to N_c - 1).
  std::function<int(int task)> place;
};

// Tasks and compute time of one process over the loops run so far.
struct RankLoad {
  int rank = 0;
  int threads = 1;
  long long tasks = 0;  // finished (not cancelled)
  double busy_seconds = 0.0;  // summed over threads, from take to put
};

class WorkDistributor {
 public:
  virtual ~WorkDistributor() = default;
  // Whether this process gathers (and writes the outputs).
  virtual bool gathers() const = 0;
  virtual int rank() const = 0;
  virtual int ranks() const = 0;
  // Runs one loop; `tasks` is read on the gathering process only. Returns when every process
  // is done with the loop; on the gathering process, true if every task was handed out
  // (none left when should_stop turned true) and none of them was cancelled.
  virtual bool run(const std::vector<int>& tasks, const WorkLoop& loop) = 0;
  // Per process, on the gathering process (elsewhere: this process only).
  virtual std::vector<RankLoad> loads() const = 0;
};

// The task queue of the gathering process: hands tasks out in order, drops skipped ones,
// refuses once should_stop holds, counts the tasks that came back cancelled. Not thread safe
// (its owner locks).
class TaskQueue {
 public:
  TaskQueue(const std::vector<int>& tasks, const WorkLoop& loop) : tasks_(tasks), loop_(loop) {}
  std::vector<int> next(int max);
  bool exhausted() const { return next_ == tasks_.size(); }
  // Tasks handed out that came back cancelled (not done).
  void cancelled(std::size_t n) { cancelled_ += n; }
  // Every task handed out, and each one done.
  bool finished() const { return exhausted() && cancelled_ == 0; }

 private:
  const std::vector<int>& tasks_;
  const WorkLoop& loop_;
  std::size_t next_ = 0;
  std::size_t cancelled_ = 0;
};

// Times the compute of the threads of one process: from a thread's take to its put.
class BusyClock {
 public:
  void taken();
  void put(RankLoad& load, std::size_t results);
};

// The gathering process's own threads: tasks from the queue, results gathered at once, both
// under `mutex` (shared with whatever else hands out tasks of the queue: the MPI server).
class QueueSource : public WorkSource {
 public:
  QueueSource(TaskQueue& queue, const WorkLoop& loop, RankLoad& load, std::mutex& mutex)
      : queue_(queue), loop_(loop), load_(load), mutex_(mutex) {}
  std::vector<int> take(int max) override;
  void put(std::vector<TaskResult> results) override;

 private:
  TaskQueue& queue_;
  const WorkLoop& loop_;
  RankLoad& load_;
  BusyClock clock_;
  std::mutex& mutex_;
};

// Whether the task at `place` in its loop's whole list (WorkLoop::place) belongs to shard
// `shard` of `shards` (`--shard i/K`): place mod K == i. So the K shards hold the list in turn,
// evenly (a sample of contacts too, whatever their numbers), and the split is the same when a
// shard resumes.
inline bool in_shard(int place, int shard, int shards) { return place % shards == shard; }

// One process; with shards > 1 it keeps only the tasks in its shard (in_shard of the task's
// place: the split of a scheduler job array, `--shard i/K`).
class LocalDistributor : public WorkDistributor {
 public:
  explicit LocalDistributor(int shard = 0, int shards = 1);
  bool gathers() const override { return true; }
  int rank() const override { return 0; }
  int ranks() const override { return 1; }
  bool run(const std::vector<int>& tasks, const WorkLoop& loop) override;
  std::vector<RankLoad> loads() const override { return {load_}; }

 private:
  int shard_, shards_;
  RankLoad load_;
};

// Runs source until it is empty on `threads` OpenMP threads: each thread takes `chunk` tasks
// at a time, computes each with solve(state, task) -> result bytes using its own state (from
// make_state()), and puts their results. A solve that throws Cancelled gives a cancelled
// result (the thread goes on taking: the loop's should_stop ends it). The first other
// exception stops every thread from taking more and is rethrown.
template <class MakeState, class Solve>
void work_off(WorkSource& source, int threads, int chunk, MakeState make_state, Solve solve) {
  std::exception_ptr error;
  std::mutex error_mutex;
  bool failed = false;
#pragma omp parallel num_threads(std::max(1, threads))
  {
    try {
      auto state = make_state();
      for (;;) {
        {
          const std::lock_guard lock(error_mutex);
          if (failed) break;
        }
        const std::vector<int> tasks = source.take(chunk);
        if (tasks.empty()) break;
        std::vector<TaskResult> results;
        for (const int t : tasks) {
          try {
            results.push_back({t, solve(state, t)});
          } catch (const Cancelled&) {
            results.push_back({t, {}, true});
          }
        }
        source.put(std::move(results));
      }
    } catch (...) {
      const std::lock_guard lock(error_mutex);
      if (!failed) error = std::current_exception();
      failed = true;
    }
  }
  if (error) std::rethrow_exception(error);
}

// Plain values and arrays of them as bytes (the layout of this machine: all processes of a
// job run the same build).
class ByteWriter {
 public:
  template <class T>
  ByteWriter& put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    bytes_.append(reinterpret_cast<const char*>(&v), sizeof v);
    return *this;
  }
  template <class T>
  ByteWriter& put_array(const T* data, std::size_t n) {
    static_assert(std::is_trivially_copyable_v<T>);
    put(static_cast<std::uint64_t>(n));
    bytes_.append(reinterpret_cast<const char*>(data), n * sizeof(T));
    return *this;
  }
  std::string take() { return std::move(bytes_); }

 private:
  std::string bytes_;
};

class ByteReader {
 public:
  explicit ByteReader(std::string_view bytes) : bytes_(bytes) {}
  template <class T>
  T get() {
    static_assert(std::is_trivially_copyable_v<T>);
    T v;
    std::memcpy(&v, raw(sizeof v), sizeof v);
    return v;
  }
  template <class T>
  std::vector<T> get_array() {
    const auto n = get<std::uint64_t>();
    if (n > bytes_.size()) throw Error("work result is truncated");
    std::vector<T> v(n);
    if (n > 0) std::memcpy(v.data(), raw(n * sizeof(T)), n * sizeof(T));
    return v;
  }
  bool done() const { return pos_ == bytes_.size(); }

 private:
  const char* raw(std::size_t n) {
    if (pos_ + n > bytes_.size()) throw Error("work result is truncated");
    const char* p = bytes_.data() + pos_;
    pos_ += n;
    return p;
  }
  std::string_view bytes_;
  std::size_t pos_ = 0;
};

}  // namespace unjam
