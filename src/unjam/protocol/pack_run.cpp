#include "unjam/protocol/pack_run.hpp"

#include <algorithm>
#include <cstdint>

#include "unjam/packing/packing_io.hpp"
#include "unjam/protocol/settings_json.hpp"

namespace unjam {

Packing gas_packing(const GasSettings& gas, double mu, double P_ext) {
  Packing p = make_gas(gas);
  p.meta.contact.mu = mu;
  p.meta.contact.P_ext = P_ext;
  return p;
}

Packing stopped_packing(const std::filesystem::path& dir, CompactionSettings& settings,
                        GasSettings& gas) {
  Packing p = read_packing(dir);
  from_json(p.meta.settings, settings, gas);
  apply_contact_model(p.meta.contact, settings);
  return p;
}

PackReport pack_report(const Packing& packing, const CompactionResult& result) {
  PackReport r;
  r.stats = compute_packing_stats(packing);
  r.sweeps_per_step =
      static_cast<double>(result.sweeps) / std::max<std::int64_t>(1, result.steps);
  r.updates_per_s = result.contact_updates / std::max(result.wall_s, 1e-9);
  return r;
}

}  // namespace unjam
