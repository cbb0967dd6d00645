#pragma once
// The outputs of a scheduler job array (`--shard i/K`, one job each): every finished shard
// writes OUT/<prefix>-i-of-K.json, and `unjam merge` joins the K of them into the outputs
// one run would write (README, "On a cluster").
#include <filesystem>
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

// The K shard files of `prefix` in `dir`, parsed, in shard order; empty if there is none.
// Throws unjam::Error if shards are missing or of different K.
std::vector<nlohmann::json> read_shards(const std::filesystem::path& dir, const std::string& prefix);

// The merges, from the commands that write the shards (cmd_probe.cpp, cmd_bounds.cpp);
// each does nothing without shards and returns whether it merged.
bool merge_probe_shards(const std::string& dir, const std::string& out);
bool merge_bounds_shards(const std::string& dir, const std::string& out);

}  // namespace unjam::cli
