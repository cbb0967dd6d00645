#include "unjam/core/dir_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "unjam/core/atomic_file.hpp"
#include "unjam/core/error.hpp"

namespace unjam {

DirLock::DirLock(const std::filesystem::path& dir, const std::string& command, const std::string& name) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw Error("cannot create directory " + dir.string() + ": " + ec.message());
  const std::filesystem::path path = dir / name;
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) throw Error("cannot open the lock file " + path.string() + ": " + std::strerror(errno));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int why = errno;
    ::close(fd_);
    fd_ = -1;
    if (why != EWOULDBLOCK) throw Error("cannot lock " + path.string() + ": " + std::strerror(why));
    std::string holder;
    try {
      holder = read_file(path);
    } catch (const Error&) {
    }
    while (!holder.empty() && (holder.back() == '\n' || holder.back() == ' ')) holder.pop_back();
    const auto sep = holder.find(' ');
    const std::string who = holder.empty() ? "another process"
                                           : "process " + holder.substr(0, sep) +
                                                 (sep == std::string::npos ? "" : " (" + holder.substr(sep + 1) + ")");
    throw Error(dir.string() + " is in use by " + who + ", which writes there; wait for it to finish or stop it");
  }
  const std::string record = std::to_string(::getpid()) + " " + command + "\n";
  if (::ftruncate(fd_, 0) == 0) {
    [[maybe_unused]] const ssize_t w = ::pwrite(fd_, record.data(), record.size(), 0);
  }
  remove_stale_temporaries(dir);
}

DirLock::~DirLock() {
  if (fd_ >= 0) ::close(fd_);  // closing releases the lock
}

}  // namespace unjam
