#pragma once
// One writer per output directory: an advisory lock (flock) on DIR/.unjam.lock, held while
// alive and released by the kernel when the process ends, also when it is killed. The lock
// file records the holder's process id and command line, which a refused second writer
// names in its message. Taking the lock also removes the temporary files that stopped
// writers left in the directory (core/atomic_file.hpp).
#include <filesystem>
#include <string>

namespace unjam {

class DirLock {
 public:
  static constexpr const char* kFileName = ".unjam.lock";

  // Creates `dir` if needed and locks it; throws unjam::Error naming the process that holds
  // the lock ("... is in use by process 1234 (unjam probe ...)"). Writers of separate files
  // in one directory (the shards of a job array, `--shard i/K`) each lock their own `name`.
  DirLock(const std::filesystem::path& dir, const std::string& command, const std::string& name = kFileName);
  ~DirLock();
  DirLock(const DirLock&) = delete;
  DirLock& operator=(const DirLock&) = delete;


 private:
  int fd_ = -1;
};

}  // namespace unjam
