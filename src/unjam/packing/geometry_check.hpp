#pragma once
// The geometric consistency of a packing's contact rows with its grains and cell
// (docs/packing-format.md, "Geometric check"). For every contact a-b:
//   branch vector  l = r_b - r_a (minimum image) within tol_l of the positions' value,
//   normal         n = l / |l| within kNormalTol,
//   gap            gap = |l| - R_a - R_b within kGapTol (R_a + R_b),
//   neighbours     gap <= R_a + R_b (the pair is at most one contact distance apart),
// and no pair listed twice (in either order). tol_l is kBranchTolStatic (R_a + R_b) for a
// static packing, whose contacts are detected at its final positions, and
// kBranchTolMoving (R_a + R_b) for a stopped compaction, whose contacts are those of the
// last time step's start (the grains have moved by one step since: v dt + lambda dt |l|).
// Every mismatch is measured relative to its tolerance; a ratio above 1 is refused.
#include <cstddef>
#include <optional>
#include <string>

#include "unjam/packing/packing.hpp"

namespace unjam {

inline constexpr double kBranchTolStatic = 1e-6;  // x (R_a + R_b)
inline constexpr double kBranchTolMoving = 0.5;   // x (R_a + R_b)
inline constexpr double kNormalTol = 1e-6;        // | n - l / |l| |
inline constexpr double kGapTol = 1e-6;           // x (R_a + R_b)

struct GeometryReport {
  double max_branch_mismatch = 0.0;  // max |l - l(positions)| (length)
  double max_normal_mismatch = 0.0;  // max |n - l / |l||
  double max_gap_mismatch = 0.0;     // max |gap - (|l| - R_a - R_b)| (length)
  // The contact whose mismatch is largest relative to its tolerance, and that ratio.
  std::optional<std::size_t> worst_contact;
  double worst_ratio = 0.0;
  std::string worst_what;  // e.g. "branch vector (lx, ly) = (...) but the positions give (...)"
  // Two rows of the same pair, if any (the first and its repeat).
  std::optional<std::pair<std::size_t, std::size_t>> duplicate;

  bool ok() const { return worst_ratio <= 1.0 && !duplicate; }
};

GeometryReport check_geometry(const Packing& packing);

}  // namespace unjam
