#include "unjam/protocol/gas.hpp"

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "unjam/core/error.hpp"

namespace unjam {

int min_jamming_grains(const GasSettings& s) {
  const double phi_max = M_PI / std::sqrt(12.0);
  const double mean_R2 = (s.R_min * s.R_min + s.R_min * s.R_max + s.R_max * s.R_max) / 3.0;  // uniform R
  return static_cast<int>(std::ceil(16.0 * s.R_max * s.R_max * phi_max / (M_PI * mean_R2)));
}

Packing make_gas(const GasSettings& s) {
  if (!(s.R_min > 0.0) || !(s.R_max >= s.R_min))
    throw Error("radii must satisfy 0 < R_min <= R_max");
  if (s.N < min_jamming_grains(s))
    throw Error("the number of disks must be at least " + std::to_string(min_jamming_grains(s)) + " (got " +
                std::to_string(s.N) + "): fewer cannot jam in a periodic cell, whose side would have to "
                "shrink below 4 R_max, where a pair touches through two periodic images");
  // Random sequential placement jams near phi ~ 0.55; above 0.45 it may not finish.
  if (!(s.phi > 0.0) || s.phi > 0.45)
    throw Error("the gas packing fraction must be in (0, 0.45] (got " + std::to_string(s.phi) + ")");

  std::mt19937_64 rng(s.seed);
  std::uniform_real_distribution<double> radius(s.R_min, s.R_max), unit(0.0, 1.0);
  Packing p;
  p.particles.resize(static_cast<std::size_t>(s.N));
  for (int i = 0; i < s.N; ++i) p.particles.radius[i] = radius(rng);
  const double L = std::sqrt(p.particles.area() / s.phi);
  p.cell = {L, L};

  // Random sequential placement, with a grid of buckets of side >= 2 R_max to find
  // the already placed neighbours of a trial position.
  const int nb = std::max(1, static_cast<int>(L / (2.0 * s.R_max)));
  const double side = L / nb;
  std::vector<std::vector<int>> bucket(static_cast<std::size_t>(nb) * nb);
  const auto bucket_of = [&](double x, double y) {
    const int bx = std::min(nb - 1, static_cast<int>(x / side));
    const int by = std::min(nb - 1, static_cast<int>(y / side));
    return std::pair{bx, by};
  };
  const auto clear_of = [&](int j, const Vec2& r, double Ri) {
    const double reach = Ri + p.particles.radius[j];
    return p.cell.min_image(p.particles.position(j) - r).squaredNorm() >= reach * reach;
  };
  // Is r free of the disks placed so far? With fewer than 3 buckets a side the 3x3
  // neighbourhood would see some twice, so small cells check every placed disk.
  const auto is_free = [&](int i, const Vec2& r) {
    const double Ri = p.particles.radius[i];
    if (nb < 3) {
      for (int j = 0; j < i; ++j)
        if (!clear_of(j, r, Ri)) return false;
      return true;
    }
    const auto [bx, by] = bucket_of(r.x(), r.y());
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        for (const int j : bucket[((by + dy + nb) % nb) * nb + (bx + dx + nb) % nb])
          if (!clear_of(j, r, Ri)) return false;
    return true;
  };
  constexpr int kMaxTrials = 100000;
  for (int i = 0; i < s.N; ++i) {
    bool placed = false;
    for (int trial = 0; trial < kMaxTrials && !placed; ++trial) {
      const Vec2 r{unit(rng) * L, unit(rng) * L};
      if (!is_free(i, r)) continue;
      p.particles.x[i] = r.x();
      p.particles.y[i] = r.y();
      const auto [bx, by] = bucket_of(r.x(), r.y());
      bucket[by * nb + bx].push_back(i);
      placed = true;
    }
    if (!placed) throw Error("could not place disk " + std::to_string(i) + " in the gas; lower --phi-gas");
  }
  p.meta.seed = s.seed;
  return p;
}

}  // namespace unjam
