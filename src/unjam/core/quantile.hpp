#pragma once
// Order statistics of a sample.
#include <algorithm>
#include <cstddef>
#include <vector>

namespace unjam {

// Linear-interpolation quantile q in [0, 1] of x (non-empty): the median is q = 0.5.
inline double quantile(std::vector<double> x, double q) {
  std::sort(x.begin(), x.end());
  const double pos = q * (static_cast<double>(x.size()) - 1.0);
  const std::size_t i = static_cast<std::size_t>(pos);
  if (i + 1 >= x.size()) return x.back();
  return x[i] + (pos - static_cast<double>(i)) * (x[i + 1] - x[i]);
}

}  // namespace unjam
