#pragma once
// Static measurements of a packing (docs/analysis.md, "Static
// measurements of a packing") and the checks of a static state:
// packing fraction, coordination, rattlers, mean contact force, overlaps, force and torque
// balance of every grain, P_in against P_ext, Coulomb condition.
//
// Forces are in units of F0 = 2 R_avg P_ext. A contact "carries force" when fn > threshold * F0.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "unjam/core/vec2.hpp"
#include "unjam/packing/packing.hpp"

namespace unjam {

// Net contact force and torque on every grain (simulation units). For each contact the
// force on b is fn n + ft t, on a its negative; the torques are T_a += -R_a ft, T_b += -R_b ft
// (counter-clockwise positive).
struct GrainLoads {
  std::vector<Vec2> force;
  std::vector<double> torque;
};

GrainLoads net_contact_loads(const Packing& packing);

struct PackingStats {
  std::size_t N = 0;                  // grains
  double mu = 0.0;                    // friction coefficient
  double F0 = 0.0;                    // force unit 2 R_avg P_ext (simulation units)
  double phi = 0.0;                   // packing fraction sum(pi R^2) / (Lx Ly)

  std::size_t contacts = 0;           // listed contacts
  std::size_t N_c = 0;                // force-carrying contacts, fn > threshold * F0
  std::size_t rattlers = 0;           // grains without a force-carrying contact
  std::size_t N_prime = 0;            // N' = N - rattlers
  double z = 0.0;                     // 2 N_c / N' (0 if N' = 0)

  double F_cont = 0.0;                // <fn> / F0 over force-carrying contacts (0 if none)
  double F_mean_listed = 0.0;         // <fn> / F0 over all listed contacts (0 if none)

  double max_overlap = 0.0;           // max of max(0, -gap) over listed contacts (length units)
  double mean_overlap = 0.0;          // mean of max(0, -gap) over listed contacts

  double max_force_residual = 0.0;    // max_i |F_i| / F0, F_i the net contact force on grain i
  double mean_force_residual = 0.0;   // mean over all N grains of |F_i| / F0
  double max_torque_residual = 0.0;   // max_i |T_i| / (F0 R_i)

  double P_in = 0.0;                  // (1 / 2V) [sum_k fn_k |l_k| + sum_i m_i |v_i|^2]
  double pressure_ratio = 0.0;        // P_in / P_ext

  double max_coulomb_violation = 0.0; // max_k max(0, |ft| - mu fn) / F0
  double max_tension = 0.0;           // max_k max(0, -fn) / F0

  // mu == 0 only: N_c - (2 N' - 1); zero for an isostatic frictionless packing in a
  // periodic cell under a pressure bath (2 N' - 2 translations + 1 cell degree of freedom).
  std::optional<std::int64_t> isostatic_excess;
};

PackingStats compute_packing_stats(const Packing& packing, double force_threshold_F0 = 1e-9);

// The statistics as `unjam info --json` prints them (and the Python module's stats()): one
// object with the packing's record (source directory, program version, seed, N, cell, P_ext)
// and every field of PackingStats, forces in units of F0, with the geometric check of the
// contact rows (packing/geometry_check.hpp).
nlohmann::ordered_json stats_json(const Packing& packing, const PackingStats& stats,
                                  double force_threshold_F0, const std::string& source);

// Pairs (i, j), i < j, sorted, whose gap |r_j - r_i| - R_i - R_j (minimum image) is below
// -gap_tol but which are not in packing.contacts. Uses a cell list: O(N).
std::vector<std::pair<int, int>> missing_contacts(const Packing& packing, double gap_tol);

}  // namespace unjam
