#include "unjam/analysis/packing_stats.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_set>

#include "unjam/core/units.hpp"
#include "unjam/packing/geometry_check.hpp"

namespace unjam {

GrainLoads net_contact_loads(const Packing& packing) {
  const std::size_t N = packing.size();
  const std::vector<double>& R = packing.particles.radius;
  GrainLoads loads{std::vector<Vec2>(N, Vec2::Zero()), std::vector<double>(N, 0.0)};
  for (const Contact& c : packing.contacts) {
    const Vec2 f = c.force_on_b();
    loads.force[c.b] += f;
    loads.force[c.a] -= f;
    loads.torque[c.a] += -R[c.a] * c.ft;
    loads.torque[c.b] += -R[c.b] * c.ft;
  }
  return loads;
}

PackingStats compute_packing_stats(const Packing& packing, double force_threshold_F0) {
  const Particles& P = packing.particles;
  const double V = packing.cell.area();
  PackingStats s;
  s.N = packing.size();
  s.mu = packing.meta.contact.mu;
  s.F0 = packing.force_unit();
  s.contacts = packing.contacts.size();

  double kinetic = 0.0;  // sum m |v|^2
  for (std::size_t i = 0; i < s.N; ++i) kinetic += P.mass(i) * P.velocity(i).squaredNorm();
  s.phi = packing.packing_fraction();

  // Contacts: force-carrying ones, overlaps, virial, Coulomb and sign checks.
  const double F0 = s.F0;
  const std::vector<char> carries = packing.loaded_grains(force_threshold_F0 * F0);
  double sum_fn_carrying = 0.0, sum_fn = 0.0, sum_overlap = 0.0, virial = 0.0;
  for (const Contact& c : packing.contacts) {
    sum_fn += c.fn;
    const double overlap = std::max(0.0, -c.gap);
    sum_overlap += overlap;
    s.max_overlap = std::max(s.max_overlap, overlap);
    virial += c.fn * c.l.norm();
    s.max_coulomb_violation = std::max(s.max_coulomb_violation, (std::abs(c.ft) - s.mu * c.fn) / F0);
    s.max_tension = std::max(s.max_tension, -c.fn / F0);
    if (c.fn > force_threshold_F0 * F0) {
      ++s.N_c;
      sum_fn_carrying += c.fn;
    }
  }
  s.rattlers = static_cast<std::size_t>(std::count(carries.begin(), carries.end(), 0));
  s.N_prime = s.N - s.rattlers;
  s.z = s.N_prime > 0 ? 2.0 * static_cast<double>(s.N_c) / static_cast<double>(s.N_prime) : 0.0;
  if (s.N_c > 0) s.F_cont = sum_fn_carrying / static_cast<double>(s.N_c) / F0;
  if (s.contacts > 0) {
    s.F_mean_listed = sum_fn / static_cast<double>(s.contacts) / F0;
    s.mean_overlap = sum_overlap / static_cast<double>(s.contacts);
  }

  // Balance of every grain.
  const GrainLoads loads = net_contact_loads(packing);
  double sum_residual = 0.0;
  for (std::size_t i = 0; i < s.N; ++i) {
    const double residual = loads.force[i].norm() / F0;
    sum_residual += residual;
    s.max_force_residual = std::max(s.max_force_residual, residual);
    s.max_torque_residual = std::max(s.max_torque_residual, std::abs(loads.torque[i]) / (F0 * P.radius[i]));
  }
  if (s.N > 0) s.mean_force_residual = sum_residual / static_cast<double>(s.N);

  s.P_in = (virial + kinetic) / (2.0 * V);
  s.pressure_ratio = s.P_in / packing.meta.contact.P_ext;

  if (s.mu == 0.0)
    s.isostatic_excess = static_cast<std::int64_t>(s.N_c) - (2 * static_cast<std::int64_t>(s.N_prime) - 1);
  return s;
}

std::vector<std::pair<int, int>> missing_contacts(const Packing& packing, double gap_tol) {
  const Particles& P = packing.particles;
  const Cell& cell = packing.cell;
  const int N = static_cast<int>(packing.size());
  if (N == 0) return {};

  // Two grains can overlap only closer than R_a + R_b <= 2 R_max: bins at least that wide
  // need only the 3 x 3 neighbouring bins (fewer when the cell holds fewer than 3 bins).
  const double R_max = *std::max_element(P.radius.begin(), P.radius.end());
  const double reach = 2.0 * R_max + std::max(0.0, -gap_tol);
  const int nx = std::max(1, static_cast<int>(cell.Lx / reach));
  const int ny = std::max(1, static_cast<int>(cell.Ly / reach));
  auto bin_of = [&](int i) {
    const Vec2 r = cell.wrap(P.position(i));
    const int bx = std::min(nx - 1, static_cast<int>(r.x() / cell.Lx * nx));
    const int by = std::min(ny - 1, static_cast<int>(r.y() / cell.Ly * ny));
    return by * nx + bx;
  };
  // Grains sorted by bin: start[b] .. start[b + 1] index into `order`.
  std::vector<int> bin(N), start(nx * ny + 1, 0), order(N);
  for (int i = 0; i < N; ++i) ++start[(bin[i] = bin_of(i)) + 1];
  for (int b = 0; b < nx * ny; ++b) start[b + 1] += start[b];
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (int i = 0; i < N; ++i) order[fill[bin[i]]++] = i;

  auto key = [N](int i, int j) {
    return static_cast<std::uint64_t>(std::min(i, j)) * static_cast<std::uint64_t>(N) +
           static_cast<std::uint64_t>(std::max(i, j));
  };
  std::unordered_set<std::uint64_t> listed;
  listed.reserve(packing.contacts.size() * 2);
  for (const Contact& c : packing.contacts) listed.insert(key(c.a, c.b));

  // The distinct neighbouring bin indices of k among 0..n-1 (periodic).
  auto neighbours = [](int k, int n) {
    std::vector<int> out;
    for (int d = -1; d <= 1; ++d) {
      const int m = ((k + d) % n + n) % n;
      if (std::find(out.begin(), out.end(), m) == out.end()) out.push_back(m);
    }
    return out;
  };

  std::vector<std::pair<int, int>> missing;
  for (int by = 0; by < ny; ++by) {
    for (int bx = 0; bx < nx; ++bx) {
      const int b = by * nx + bx;
      for (const int my : neighbours(by, ny)) {
        for (const int mx : neighbours(bx, nx)) {
          const int m = my * nx + mx;
          for (int p = start[b]; p < start[b + 1]; ++p) {
            const int i = order[p];
            for (int q = start[m]; q < start[m + 1]; ++q) {
              const int j = order[q];
              if (j <= i) continue;
              const Vec2 l = cell.min_image(P.position(j) - P.position(i));
              const double gap = l.norm() - P.radius[i] - P.radius[j];
              if (gap < -gap_tol && !listed.count(key(i, j))) missing.emplace_back(i, j);
            }
          }
        }
      }
    }
  }
  std::sort(missing.begin(), missing.end());
  return missing;
}

nlohmann::ordered_json stats_json(const Packing& p, const PackingStats& s, double threshold,
                                  const std::string& source) {
  const GeometryReport g = check_geometry(p);
  nlohmann::ordered_json j = {
      {"packing", source},
      {"program_version", p.meta.program_version},
      {"seed", p.meta.seed},
      {"N", s.N},
      {"Lx", p.cell.Lx},
      {"Ly", p.cell.Ly},
      {"P_ext", p.meta.contact.P_ext},
      {"mu", s.mu},
      {"F0", s.F0},
      {"phi", s.phi},
      {"z", s.z},
      {"rattlers", s.rattlers},
      {"N_prime", s.N_prime},
      {"force_threshold_F0", threshold},
      {"contacts_force_carrying", s.N_c},
      {"contacts_listed", s.contacts},
      {"F_cont_over_F0", s.F_cont},
      {"F_mean_listed_over_F0", s.F_mean_listed},
      {"max_overlap", s.max_overlap},
      {"mean_overlap", s.mean_overlap},
      {"max_force_residual_over_F0", s.max_force_residual},
      {"mean_force_residual_over_F0", s.mean_force_residual},
      {"max_torque_residual_over_F0R", s.max_torque_residual},
      {"P_in", s.P_in},
      {"P_in_over_P_ext", s.pressure_ratio},
      {"max_coulomb_violation_over_F0", s.max_coulomb_violation},
      {"max_tension_over_F0", s.max_tension},
      {"geometry_max_branch_mismatch", g.max_branch_mismatch},
      {"geometry_max_normal_mismatch", g.max_normal_mismatch},
      {"geometry_max_gap_mismatch", g.max_gap_mismatch},
      {"geometry_worst_over_tolerance", g.worst_ratio},
  };
  if (s.isostatic_excess) j["isostatic_excess"] = *s.isostatic_excess;
  return j;
}

}  // namespace unjam
