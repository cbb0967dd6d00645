#pragma once
// The one exception type of unjam: a message meant for the user (bad input, unreadable
// file, invalid parameter). The command-line tool prints it and exits non-zero (README,
// "Exit codes").
#include <stdexcept>
#include <string>

namespace unjam {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

// A run stopped on request (Ctrl-C, SIGTERM) after saving its state: running the same
// command again (or `pack --resume`) continues it. The tool exits with its own code.
class Interrupted : public Error {
 public:
  explicit Interrupted(const std::string& what) : Error(what) {}
};

// A computation abandoned on request: a long one (a probe) polls a cancel predicate at cheap
// points and throws this once the predicate returns true. It has no result; a campaign
// reports the task as not done (TaskResult::cancelled) and a resumed run computes it again.
class Cancelled : public Interrupted {
 public:
  Cancelled() : Interrupted("cancelled on request") {}
};

}  // namespace unjam
