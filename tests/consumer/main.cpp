// Reads a packing with the installed library and prints its statistics.
#include <cstdio>

#include "unjam/analysis/packing_stats.hpp"
#include "unjam/core/version.hpp"
#include "unjam/packing/packing_io.hpp"

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  const unjam::Packing p = unjam::read_packing(argv[1]);
  const unjam::PackingStats s = unjam::compute_packing_stats(p);
  std::printf("unjam %s: N %zu phi %.6f z %.4f\n", unjam::kVersion, s.N, s.phi, s.z);
  return 0;
}
