#pragma once
// The outputs of a scheduler job array (`--shard i/K`, one job each): every finished shard
// writes OUT/<prefix>-i-of-K.json, and `unjam merge` joins the K of them into the outputs
// one run would write (README, "On a cluster").
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "unjam/core/dir_lock.hpp"

namespace unjam::cli {

// "<prefix>-i-of-K.json"
std::string shard_file_name(const std::string& prefix, int shard, int shards);

// The lock of what this process writes in `dir` (core/dir_lock.hpp): the directory's, or with
// shards > 1 the shard's own (the shards of a job array write side by side).
std::unique_ptr<DirLock> lock_output(const std::filesystem::path& dir, int shard, int shards);

// One shard file: its name, its place i of K in the job array, and its JSON.
struct ShardFile {
  std::filesystem::path file;
  int shard = 0;
  int shards = 1;
  nlohmann::json json;
};

// The files <prefix>-i-of-K.json in `dir` by i, with K in `shards` (left as it is if there is
// none). Throws unjam::Error if they are of another K than each other or than `shards` (if
// not 0 on entry).
std::map<int, std::filesystem::path> find_shard_files(const std::filesystem::path& dir, const std::string& prefix,
                                                      int& shards);

// The K shard files of `prefix` in `dir`, parsed, in shard order; empty if there is none.
// Throws unjam::Error if shards are missing or of different K, or one is not JSON.
std::vector<ShardFile> read_shards(const std::filesystem::path& dir, const std::string& prefix);

// Runs `read` on shard `s`; a key it lacks, a value of the wrong type (nlohmann's exceptions)
// or an unjam::Error of `read` becomes
//   unjam::Error("<file> is damaged (<what>); run shard i/K's job again or remove it").
void read_shard(const ShardFile& s, const std::function<void()>& read);

// The JSON number j[key] if it is >= 0 (a time, in s); throws unjam::Error otherwise.
double non_negative_number(const nlohmann::json& j, const std::string& key);

// Checks that the contacts `contacts` of shard `s` are tasks of its campaign (`tasks`, sorted:
// every contact 0 to N_c - 1 of the force bounds, the targets of a probe campaign; `whole` names
// them in the error, e.g. "the packing's 81"), that they are in the shard (the task at place p
// belongs to shard p mod K, core/work_source's in_shard) and not in `seen` (by place: the
// contacts of the shards read before it), and adds them to `seen`; throws unjam::Error
// otherwise.
void claim_shard_contacts(const ShardFile& s, const std::vector<int>& contacts, const std::vector<int>& tasks,
                          const std::string& whole, std::vector<bool>& seen);

// `unjam merge --status` (campaign_status.cpp): prints how far the probe campaign whose files
// are in `out` (default: `dir`) has got, from those files alone: each shard of a job array
// (finished, n of m probes so far with its checkpoint's age, not started, unreadable) or the
// whole campaign's checkpoint, the probes done, the busy time and the busy time left at that
// pace; a campaign that has finished (probe_summary.json, no checkpoint) is said to have.
// Reads with the settings the files record; changes nothing. Returns false if there is no
// probe campaign in `out`.
bool print_probe_status(const std::string& dir, const std::string& out);
// The same for the force bounds in `out` (`unjam bounds`, whole or `--shard i/K`), in LP values
// (fn_min and fn_max of each contact): finished shards, checkpoints, not started; a run that has
// finished (bounds.json, no checkpoint) is said to have. Returns false if there is none.
bool print_bounds_status(const std::string& dir, const std::string& out);

// The merges, from the commands that write the shards (cmd_probe.cpp, cmd_bounds.cpp);
// each does nothing without shards and returns whether it merged.
bool merge_probe_shards(const std::string& dir, const std::string& out);
bool merge_bounds_shards(const std::string& dir, const std::string& out);

}  // namespace unjam::cli
