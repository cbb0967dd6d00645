#include "unjam/packing/geometry_check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <vector>

namespace unjam {
namespace {

std::string vec(Vec2 v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "(%.17g, %.17g)", v.x(), v.y());
  return buf;
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

}  // namespace

GeometryReport check_geometry(const Packing& p) {
  GeometryReport r;
  const Particles& P = p.particles;
  const double branch_tol = p.state.is_static ? kBranchTolStatic : kBranchTolMoving;
  const auto consider = [&](std::size_t k, double mismatch, double tol, const std::string& what) {
    const double ratio = mismatch / tol;
    if (!(ratio <= r.worst_ratio)) {  // NaN counts as the worst
      r.worst_ratio = std::isnan(ratio) ? INFINITY : ratio;
      r.worst_contact = k;
      r.worst_what = what + " (mismatch " + num(mismatch) + ", tolerance " + num(tol) + ")";
    }
  };
  std::vector<std::pair<std::uint64_t, std::size_t>> pairs;
  pairs.reserve(p.contacts.size());
  for (std::size_t k = 0; k < p.contacts.size(); ++k) {
    const Contact& c = p.contacts[k];
    const double sigma = P.radius[c.a] + P.radius[c.b];  // contact distance R_a + R_b
    const Vec2 l_pos = p.cell.min_image(P.position(c.b) - P.position(c.a));
    const double dl = (c.l - l_pos).norm();
    const double dn = (c.n - c.l / c.l.norm()).norm();
    const double dgap = std::abs(c.gap - (c.l.norm() - sigma));
    r.max_branch_mismatch = std::max(r.max_branch_mismatch, dl);
    r.max_normal_mismatch = std::max(r.max_normal_mismatch, dn);
    r.max_gap_mismatch = std::max(r.max_gap_mismatch, dgap);
    consider(k, dl, branch_tol * sigma, "branch vector (lx, ly) = " + vec(c.l) + " but the positions give " + vec(l_pos));
    consider(k, dn, kNormalTol, "normal (nx, ny) = " + vec(c.n) + " is not l / |l| = " + vec(c.l / c.l.norm()));
    consider(k, dgap, kGapTol * sigma, "gap " + num(c.gap) + " is not |l| - R_a - R_b = " + num(c.l.norm() - sigma));
    if (c.gap > sigma)
      consider(k, c.gap / sigma, 1.0, "grains " + std::to_string(c.a) + " and " + std::to_string(c.b) +
                                          " are not neighbours (gap " + num(c.gap) + " > R_a + R_b)");
    const auto [lo, hi] = std::minmax(c.a, c.b);
    pairs.push_back({(static_cast<std::uint64_t>(lo) << 32) | static_cast<std::uint32_t>(hi), k});
  }
  std::sort(pairs.begin(), pairs.end());
  for (std::size_t i = 1; i < pairs.size(); ++i)
    if (pairs[i].first == pairs[i - 1].first) {
      r.duplicate = std::minmax(pairs[i].second, pairs[i - 1].second);
      break;
    }
  return r;
}

}  // namespace unjam
