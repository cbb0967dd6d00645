#include "cli/shards.hpp"

#include <algorithm>
#include <map>
#include <regex>

#include "cli/run_info.hpp"
#include "unjam/core/atomic_file.hpp"
#include "unjam/core/error.hpp"
#include "unjam/core/work_source.hpp"

namespace unjam::cli {

namespace fs = std::filesystem;

std::string shard_file_name(const std::string& prefix, int shard, int shards) {
  return prefix + "-" + std::to_string(shard) + "-of-" + std::to_string(shards) + ".json";
}

std::unique_ptr<DirLock> lock_output(const fs::path& dir, int shard, int shards) {
  const std::string name = shards > 1 ? ".unjam-shard-" + std::to_string(shard) + "-of-" + std::to_string(shards) + ".lock"
                                      : DirLock::kFileName;
  return std::make_unique<DirLock>(dir, command_line(), name);
}

std::map<int, fs::path> find_shard_files(const fs::path& dir, const std::string& prefix, int& shards) {
  // At most 9 digits, so that stoi cannot overflow; other names are not shards.
  const std::regex name(prefix + R"(-(\d{1,9})-of-(\d{1,9})\.json)");
  std::map<int, fs::path> found;
  if (fs::is_directory(dir))
    for (const fs::directory_entry& e : fs::directory_iterator(dir)) {
      std::smatch m;
      const std::string file = e.path().filename().string();
      if (!std::regex_match(file, m, name)) continue;
      const int k = std::stoi(m[2]);
      if (shards != 0 && k != shards)
        throw Error(dir.string() + " holds " + prefix + " files of " + std::to_string(shards) + " and of " +
                    std::to_string(k) + " shards; remove those of the other run");
      shards = k;
      found[std::stoi(m[1])] = e.path();
    }
  return found;
}

std::vector<ShardFile> read_shards(const fs::path& dir, const std::string& prefix) {
  int shards = 0;
  std::map<int, fs::path> found = find_shard_files(dir, prefix, shards);
  std::vector<ShardFile> out;
  for (int i = 0; i < shards; ++i) {
    if (!found.contains(i))
      throw Error(dir.string() + ": shard " + std::to_string(i) + "/" + std::to_string(shards) +
                  " is missing (" + shard_file_name(prefix, i, shards) +
                  "); run that shard's job (again: it resumes)");
    auto j = nlohmann::json::parse(read_file(found[i]), nullptr, false);
    if (j.is_discarded() || !j.is_object()) throw Error(found[i].string() + " is not a shard (not a JSON object)");
    out.push_back({found[i], i, shards, std::move(j)});
  }
  if (found.size() > static_cast<std::size_t>(shards))
    throw Error(dir.string() + " holds " + prefix + " files numbered beyond its " + std::to_string(shards) +
                " shards; remove those of the other run");
  return out;
}

void read_shard(const ShardFile& s, const std::function<void()>& read) {
  const auto damaged = [&s](const std::string& what) {
    return Error(s.file.string() + " is damaged (" + what + "); run shard " + std::to_string(s.shard) + "/" +
                 std::to_string(s.shards) + "'s job again or remove it");
  };
  try {
    read();
  } catch (const nlohmann::json::exception& e) {
    throw damaged(e.what());
  } catch (const Error& e) {
    throw damaged(e.what());
  }
}

double non_negative_number(const nlohmann::json& j, const std::string& key) {
  const double x = j.at(key).get<double>();  // JSON holds no NaN or infinity
  if (!(x >= 0.0)) throw Error(key + " is " + j.at(key).dump() + ", not >= 0");
  return x;
}

void claim_shard_contacts(const ShardFile& s, const std::vector<int>& contacts, const std::vector<int>& tasks,
                          const std::string& whole, std::vector<bool>& seen) {
  seen.resize(tasks.size(), false);
  for (const int k : contacts) {
    const auto at = std::lower_bound(tasks.begin(), tasks.end(), k);
    if (at == tasks.end() || *at != k) throw Error("contact " + std::to_string(k) + " is not one of " + whole);
    const int place = static_cast<int>(at - tasks.begin());
    if (!in_shard(place, s.shard, s.shards))
      throw Error("contact " + std::to_string(k) + " belongs to shard " + std::to_string(place % s.shards) +
                  ", not " + std::to_string(s.shard));
    if (seen[static_cast<std::size_t>(place)]) throw Error("contact " + std::to_string(k) + " is listed twice");
    seen[static_cast<std::size_t>(place)] = true;
  }
}

}  // namespace unjam::cli
