#pragma once
// A packing: grains, cell, contacts and the record of how it was made.
// On disk it is a directory (meta.json, particles.csv, contacts.csv), see docs/packing-format.md.
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "unjam/core/cell.hpp"
#include "unjam/packing/contact.hpp"
#include "unjam/packing/contact_model.hpp"
#include "unjam/packing/particles.hpp"

namespace unjam {

// State of the pressure bath and the clock, enough to resume a run exactly.
struct RunState {
  double time = 0.0;            // simulated time (units of t0)
  std::int64_t step = 0;        // time steps taken
  double lambda = 0.0;          // strain rate of the cell, Ldot / L (1/t0)
  bool is_static = false;       // true once the compaction reached a static packing
};

struct PackingMeta {
  // The contact model every contact problem of the packing is built with: mu and P_ext
  // (meta.json "mu", "P_ext"), the bath mass and the touch gap (meta.json
  // settings.dynamics.M_lambda and settings.static.touch_gap; docs/packing-format.md).
  ContactModel contact;
  std::uint64_t seed = 0;       // seed of the gas the packing was compacted from
  // Solver and protocol settings (protocol/settings_json); its M_lambda and touch_gap are
  // written from `contact`.
  nlohmann::json settings = nlohmann::json::object();
  std::string command;          // the command line that made it
  std::string program_version;  // unjam version that wrote it
};

struct Packing {
  Cell cell;
  Particles particles;
  Contacts contacts;
  PackingMeta meta;
  RunState state;

  std::size_t size() const { return particles.size(); }
  double mean_radius() const;
  double force_unit() const;  // F0 = 2 R_avg P_ext
  double packing_fraction() const { return particles.area() / cell.area(); }
  // The narrowest cell side at which no pair touches through two periodic images at once
  // (the contacts follow the minimum image): 2 (R_1 + R_2), R_1 and R_2 the two largest radii.
  double min_cell_side() const;
  // Grains with a contact carrying fn > fn_min (simulation units); the others are rattlers.
  std::vector<char> loaded_grains(double fn_min) const;
};

}  // namespace unjam
