#include "cli/shards.hpp"

#include <map>
#include <regex>

#include "cli/run_info.hpp"
#include "unjam/core/atomic_file.hpp"
#include "unjam/core/error.hpp"

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

std::vector<nlohmann::json> read_shards(const fs::path& dir, const std::string& prefix) {
  const std::regex name(prefix + R"(-(\d+)-of-(\d+)\.json)");
  std::map<int, fs::path> found;
  int shards = 0;
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
  std::vector<nlohmann::json> out;
  for (int i = 0; i < shards; ++i) {
    if (!found.contains(i))
      throw Error(dir.string() + ": shard " + std::to_string(i) + "/" + std::to_string(shards) +
                  " is missing (" + shard_file_name(prefix, i, shards) +
                  "); run that shard's job (again: it resumes)");
    const auto j = nlohmann::json::parse(read_file(found[i]), nullptr, false);
    if (j.is_discarded()) throw Error(found[i].string() + " is not valid JSON");
    out.push_back(j);
  }
  return out;
}

}  // namespace unjam::cli
