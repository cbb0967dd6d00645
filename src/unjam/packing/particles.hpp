#pragma once
// The grains: rigid disks, stored as a structure of arrays (the solver's hot data).
#include <algorithm>
#include <cstddef>
#include <vector>

#include "unjam/core/units.hpp"
#include "unjam/core/vec2.hpp"

namespace unjam {

struct Particles {
  std::vector<double> x, y;    // centre, in [0, Lx) x [0, Ly)
  std::vector<double> radius;  // R_i, in [0.5, 1] for the paper's packings
  std::vector<double> vx, vy;  // peculiar velocity (affine cell motion excluded)
  std::vector<double> omega;   // angular velocity, counter-clockwise positive

  std::size_t size() const { return x.size(); }
  void resize(std::size_t n) {
    for (auto* v : {&x, &y, &radius, &vx, &vy, &omega}) v->resize(n, 0.0);
  }
  // All grains at rest: v = 0, omega = 0.
  void stop() {
    for (auto* v : {&vx, &vy, &omega}) std::fill(v->begin(), v->end(), 0.0);
  }
  // Area covered by the grains, sum pi R^2.
  double area() const {
    double a = 0.0;
    for (const double R : radius) a += disk_area(R);
    return a;
  }
  Vec2 position(std::size_t i) const { return {x[i], y[i]}; }
  Vec2 velocity(std::size_t i) const { return {vx[i], vy[i]}; }
  double mass(std::size_t i) const { return disk_mass(radius[i]); }
  double inertia(std::size_t i) const { return disk_inertia(radius[i]); }
};

}  // namespace unjam
