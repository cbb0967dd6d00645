#include "unjam/campaign/distributor.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <thread>

#include "unjam/core/error.hpp"

#if UNJAM_WITH_MPI
#include <mpi.h>
#endif

namespace unjam {
namespace {

// The world size the launcher announces (Open MPI, PMI/Slurm, PMIx), 0 if none.
int launcher_size() {
  for (const char* var : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"})
    if (const char* v = std::getenv(var)) return std::atoi(v);
  return 0;
}

}  // namespace

bool launched_by_mpi() { return launcher_size() > 0; }

std::pair<int, int> parse_shard(const std::string& text) {
  const auto slash = text.find('/');
  try {
    if (slash != std::string::npos) {
      std::size_t used_i = 0, used_k = 0;
      const int i = std::stoi(text.substr(0, slash), &used_i);
      const int k = std::stoi(text.substr(slash + 1), &used_k);
      if (used_i == slash && used_k == text.size() - slash - 1 && k >= 1 && i >= 0 && i < k)
        return {i, k};
    }
  } catch (const std::exception&) {
  }
  throw Error("--shard takes i/K with 0 <= i < K (got '" + text + "')");
}

#if UNJAM_WITH_MPI

namespace {

bool g_started = false;

void start_mpi() {
  if (g_started) return;
  int provided = 0;
  MPI_Init_thread(nullptr, nullptr, MPI_THREAD_SERIALIZED, &provided);
  if (provided < MPI_THREAD_SERIALIZED)
    throw Error("the MPI library does not support MPI_THREAD_SERIALIZED");
  g_started = true;
}

[[noreturn]] void abort_job(const std::exception& e) {
  std::fprintf(stderr, "unjam: error: %s\n", e.what());
  std::fflush(stderr);
  MPI_Abort(MPI_COMM_WORLD, 1);
  std::abort();
}

// Message tags of loop `round`: requests (worker -> rank 0) and replies.
int request_tag(int round) { return 100 + 2 * round; }
int reply_tag(int round) { return 101 + 2 * round; }

// A worker's message: its want (tasks; -1: it leaves the loop), its load, its results
// (cancelled ones flagged: rank 0 counts them as not done).
std::string encode_request(int want, const RankLoad& load, const std::vector<TaskResult>& results) {
  ByteWriter w;
  w.put<std::int32_t>(want).put<std::int32_t>(load.threads).put<double>(load.busy_seconds);
  w.put<std::uint64_t>(results.size());
  for (const TaskResult& r : results)
    w.put<std::int32_t>(r.task).put<std::uint8_t>(r.cancelled).put_array(r.bytes.data(), r.bytes.size());
  return w.take();
}

// Sleeps between polls, 20 us at first, doubling up to 1 ms while nothing comes: a blocking
// wait of Open MPI spins, and would take a core from the probes of this node's other ranks
// and threads (docs/benchmarks.md, "Campaigns over MPI ranks").
class Backoff {
 public:
  void wait() {
    std::this_thread::sleep_for(std::chrono::microseconds(us_));
    us_ = std::min(2 * us_, 1000);
  }

 private:
  int us_ = 20;
};

// The next message of `tag` from `source` (or MPI_ANY_SOURCE), polled.
std::string receive(int source, int tag, int* from = nullptr) {
  MPI_Status status;
  int flag = 0;
  for (Backoff backoff;; backoff.wait()) {
    MPI_Iprobe(source, tag, MPI_COMM_WORLD, &flag, &status);
    if (flag) break;
  }
  int count = 0;
  MPI_Get_count(&status, MPI_BYTE, &count);
  std::string bytes(static_cast<std::size_t>(count), '\0');
  MPI_Recv(bytes.data(), count, MPI_BYTE, status.MPI_SOURCE, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  if (from) *from = status.MPI_SOURCE;
  return bytes;
}

void send(const std::string& bytes, int dest, int tag) {
  MPI_Send(bytes.data(), static_cast<int>(bytes.size()), MPI_BYTE, dest, tag, MPI_COMM_WORLD);
}

// A worker's threads: each take sends the results put since the last one and asks rank 0
// for tasks (one thread at a time on the wire: MPI_THREAD_SERIALIZED). Cancelled results
// travel too, so that rank 0 knows those tasks are not done.
class WorkerSource : public WorkSource {
 public:
  WorkerSource(const WorkLoop& loop, RankLoad& load, int round) : loop_(loop), load_(load), round_(round) {}
  std::vector<int> take(int max) override {
    const std::lock_guard lock(mutex_);
    if (finished_ || (loop_.should_stop && loop_.should_stop())) {
      finished_ = true;
      return {};
    }
    send(encode_request(max, load_, pending_), 0, request_tag(round_));
    pending_.clear();
    const std::string reply = receive(0, reply_tag(round_));
    ByteReader r(reply);
    std::vector<int> tasks = r.get_array<int>();
    if (tasks.empty()) finished_ = true;
    else clock_.taken();
    return tasks;
  }
  void put(std::vector<TaskResult> results) override {
    const std::lock_guard lock(mutex_);
    clock_.put(load_, static_cast<std::size_t>(std::count_if(results.begin(), results.end(),
                                                             [](const TaskResult& r) { return !r.cancelled; })));
    for (TaskResult& r : results) pending_.push_back(std::move(r));
  }
  // After every thread is done: the last results, and this rank leaves the loop.
  void leave() {
    send(encode_request(-1, load_, pending_), 0, request_tag(round_));
    pending_.clear();
  }

 private:
  const WorkLoop& loop_;
  RankLoad& load_;
  int round_;
  BusyClock clock_;
  std::mutex mutex_;
  std::vector<TaskResult> pending_;
  bool finished_ = false;
};

class MpiDistributor : public WorkDistributor {
 public:
  MpiDistributor() {
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &ranks_);
    loads_.resize(ranks_);
    for (int r = 0; r < ranks_; ++r) loads_[r].rank = r;
    loads_[rank_].threads = omp_get_max_threads();
  }
  bool gathers() const override { return rank_ == 0; }
  int rank() const override { return rank_; }
  int ranks() const override { return ranks_; }
  std::vector<RankLoad> loads() const override {
    return rank_ == 0 ? loads_ : std::vector<RankLoad>{loads_[rank_]};
  }

  bool run(const std::vector<int>& tasks, const WorkLoop& loop) override {
    const int round = ++round_;
    try {
      if (rank_ != 0) {
        WorkerSource source(loop, loads_[rank_], round);
        loop.work(source);
        source.leave();
        return false;
      }
      TaskQueue queue(tasks, loop);
      std::mutex mutex;
      QueueSource source(queue, loop, loads_[0], mutex);
      std::thread server([&] { serve(queue, loop, mutex, round); });
      try {
        loop.work(source);
      } catch (const std::exception& e) {
        abort_job(e);  // the server thread cannot be joined while workers still ask
      }
      server.join();
      return queue.finished();
    } catch (const std::exception& e) {
      abort_job(e);
    }
  }

 private:
  // Rank 0's server: answers requests until every worker has left the loop (polling, as
  // every receive here, so that rank 0's own probes keep their core).
  void serve(TaskQueue& queue, const WorkLoop& loop, std::mutex& mutex, int round) {
    try {
      int left = ranks_ - 1;
      while (left > 0) {
        int from = 0;
        const std::string msg = receive(MPI_ANY_SOURCE, request_tag(round), &from);
        ByteReader r(msg);
        const int want = r.get<std::int32_t>();
        const int threads = r.get<std::int32_t>();
        const double busy = r.get<double>();
        std::vector<TaskResult> results(r.get<std::uint64_t>());
        for (TaskResult& res : results) {
          res.task = r.get<std::int32_t>();
          res.cancelled = r.get<std::uint8_t>() != 0;
          const std::vector<char> bytes = r.get_array<char>();
          res.bytes.assign(bytes.begin(), bytes.end());
        }
        std::vector<int> tasks;
        {
          // The loads under the gathering's lock: a checkpoint taken in the gathering reads
          // them (run_checkpointed_campaign).
          const std::lock_guard lock(mutex);
          RankLoad& load = loads_[from];
          load.threads = threads;
          load.busy_seconds = busy;
          queue.cancelled(drop_cancelled(results));
          load.tasks += static_cast<long long>(results.size());
          if (!results.empty()) loop.gather(results);
          if (want >= 0) tasks = queue.next(want);
        }
        if (want < 0) {
          --left;
          continue;
        }
        ByteWriter w;
        w.put_array(tasks.data(), tasks.size());
        send(w.take(), from, reply_tag(round));
      }
    } catch (const std::exception& e) {
      abort_job(e);
    }
  }

  int rank_ = 0, ranks_ = 1, round_ = 0;
  std::vector<RankLoad> loads_;
};

}  // namespace

bool mpi_available() { return true; }

std::unique_ptr<WorkDistributor> make_distributor(int shard, int shards) {
  if (launched_by_mpi()) {
    start_mpi();
    int ranks = 1;
    MPI_Comm_size(MPI_COMM_WORLD, &ranks);
    if (ranks > 1) {
      if (shards > 1) throw Error("--shard is for separate jobs; under mpirun the ranks share the work");
      return std::make_unique<MpiDistributor>();
    }
  }
  return std::make_unique<LocalDistributor>(shard, shards);
}

void end_mpi_job(int exit_code) {
  if (!g_started) return;
  int ranks = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  // MPI_Finalize waits for every rank (spinning): the workers wait here, polled, while rank 0
  // writes the outputs. After a failure, the ranks that do not come within 2 s (still in a
  // loop, waiting for this one) are stopped by MPI_Abort; after an orderly stop (Ctrl-C,
  // --stop-after: every rank left the loops) all come and the job ends cleanly.
  MPI_Request barrier;
  MPI_Ibarrier(MPI_COMM_WORLD, &barrier);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  int done = 0;
  for (Backoff backoff;; backoff.wait()) {
    MPI_Test(&barrier, &done, MPI_STATUS_IGNORE);
    if (done) break;
    if (exit_code != 0 && ranks > 1 && std::chrono::steady_clock::now() > deadline)
      MPI_Abort(MPI_COMM_WORLD, exit_code);
  }
  MPI_Finalize();
  g_started = false;
}

#else  // a build without MPI

bool mpi_available() { return false; }

std::unique_ptr<WorkDistributor> make_distributor(int shard, int shards) {
  if (launcher_size() > 1)
    throw Error("this unjam was built without MPI (CMake option UNJAM_MPI off): under mpirun every "
                "rank would compute the whole campaign; rebuild with Open MPI installed, or use "
                "--shard i/K and `unjam merge`");
  return std::make_unique<LocalDistributor>(shard, shards);
}

void end_mpi_job(int) {}

#endif

}  // namespace unjam
