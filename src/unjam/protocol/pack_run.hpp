#pragma once
// The start and the report of one compaction run, as `unjam pack` and the Python module's
// pack and relax make it (docs/method.md, "Compaction"): a gas, a stopped run continued in
// place, or a packing re-relaxed (prepare_relaxation, settings_json.hpp); then
// prepare_compaction and compact().
#include <filesystem>

#include "unjam/analysis/packing_stats.hpp"
#include "unjam/packing/packing.hpp"
#include "unjam/protocol/compaction.hpp"
#include "unjam/protocol/gas.hpp"

namespace unjam {

// A gas of `gas` (make_gas) at friction mu and pressure P_ext (pressure units): `unjam pack
// --n N`.
Packing gas_packing(const GasSettings& gas, double mu, double P_ext);

// The packing of a stopped compaction in `dir` (`unjam pack --resume DIR`): `settings` and
// `gas` become those it was started with (its meta.settings). Throws unjam::Error as
// read_packing and from_json do.
Packing stopped_packing(const std::filesystem::path& dir, CompactionSettings& settings,
                        GasSettings& gas);

// What `unjam pack` reports of a finished compaction.
struct PackReport {
  PackingStats stats;              // of the static packing (compute_packing_stats)
  double sweeps_per_step = 0.0;    // NLGS sweeps of the dynamics / max(1, steps)
  double updates_per_s = 0.0;      // contact updates per wall second
};

PackReport pack_report(const Packing& packing, const CompactionResult& result);

}  // namespace unjam
