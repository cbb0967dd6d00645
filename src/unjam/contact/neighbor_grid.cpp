#include "unjam/contact/neighbor_grid.hpp"

#include <algorithm>
#include <cmath>

namespace unjam {
namespace {

bool is_near(const Particles& p, const Cell& cell, int a, int b, double max_gap) {
  const Vec2 l = cell.min_image(p.position(b) - p.position(a));
  const double reach = p.radius[a] + p.radius[b] + max_gap;
  return l.squaredNorm() < reach * reach;
}

}  // namespace

std::vector<std::pair<int, int>> find_near_pairs(const Particles& p, const Cell& cell,
                                                 double max_gap) {
  const int n = static_cast<int>(p.size());
  std::vector<std::pair<int, int>> pairs;
  if (n < 2) return pairs;
  const double R_max = *std::max_element(p.radius.begin(), p.radius.end());
  const double reach = 2.0 * R_max + std::max(max_gap, 0.0);
  // Cells of side >= reach; at least 3 per side so the 3x3 neighbourhood has no duplicates.
  const int nx = static_cast<int>(std::floor(cell.Lx / reach));
  const int ny = static_cast<int>(std::floor(cell.Ly / reach));
  if (nx < 3 || ny < 3) {  // small cell: all pairs
    for (int a = 0; a < n; ++a)
      for (int b = a + 1; b < n; ++b)
        if (is_near(p, cell, a, b, max_gap)) pairs.emplace_back(a, b);
    return pairs;
  }
  // Counting sort of the grains into cells (head/next lists would scatter memory).
  const auto cell_of = [&](int i) {
    int cx = static_cast<int>(p.x[i] / cell.Lx * nx);
    int cy = static_cast<int>(p.y[i] / cell.Ly * ny);
    cx = std::clamp(cx, 0, nx - 1);
    cy = std::clamp(cy, 0, ny - 1);
    return cy * nx + cx;
  };
  std::vector<int> start(static_cast<std::size_t>(nx) * ny + 1, 0), of(n), members(n);
  for (int i = 0; i < n; ++i) ++start[(of[i] = cell_of(i)) + 1];
  for (std::size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int i = 0; i < n; ++i) members[fill[of[i]]++] = i;
  }
  for (int cy = 0; cy < ny; ++cy) {
    for (int cx = 0; cx < nx; ++cx) {
      const int c = cy * nx + cx;
      // Half of the 3x3 neighbourhood (this cell and 4 neighbours) visits every cell pair once.
      static constexpr int kHalf[5][2] = {{0, 0}, {1, 0}, {-1, 1}, {0, 1}, {1, 1}};
      for (const auto& d : kHalf) {
        const int c2 = ((cy + d[1] + ny) % ny) * nx + (cx + d[0] + nx) % nx;
        for (int s = start[c]; s < start[c + 1]; ++s) {
          const int i = members[s];
          const int s2_begin = (c2 == c) ? s + 1 : start[c2];
          for (int s2 = s2_begin; s2 < start[c2 + 1]; ++s2) {
            const int j = members[s2];
            if (is_near(p, cell, i, j, max_gap)) pairs.emplace_back(std::min(i, j), std::max(i, j));
          }
        }
      }
    }
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

}  // namespace unjam
