#pragma once
// Shared by the libFuzzer targets (docs/testing.md, "Fuzzing"): the fixtures as seeds, and
// the failure of an input that was accepted but is not valid.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "unjam/core/atomic_file.hpp"

namespace unjam::fuzz {

// `<target> --write-seeds DIR` writes the seed corpus into DIR and exits (before libFuzzer
// parses its flags); every other command line goes to libFuzzer.
template <typename Seeds>
void write_seeds_if_asked(int argc, char** argv, Seeds seeds) {
  if (argc != 3 || std::string(argv[1]) != "--write-seeds") return;
  const std::filesystem::path dir = argv[2];
  std::filesystem::create_directories(dir);
  const std::vector<std::string> all = seeds();
  for (std::size_t k = 0; k < all.size(); ++k)
    std::ofstream(dir / ("seed-" + std::to_string(k)), std::ios::binary) << all[k];
  std::printf("%zu seeds written to %s\n", all.size(), dir.c_str());
  std::exit(0);
}

inline std::string fixture_file(const std::string& packing, const std::string& file) {
  return read_file(std::filesystem::path(UNJAM_FIXTURES_DIR) / packing / file);
}

// An accepted input that breaks the reader's contract: reported as a crash (the input is saved).
[[noreturn]] inline void accepted_invalid(const std::string& why) {
  std::fprintf(stderr, "accepted an invalid input: %s\n", why.c_str());
  std::abort();
}

}  // namespace unjam::fuzz
