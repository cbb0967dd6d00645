#pragma once
// The one exception type of unjam: a message meant for the user (bad input, unreadable
// file, invalid parameter). The command-line tool prints it and exits non-zero.
#include <stdexcept>
#include <string>

namespace unjam {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace unjam
