#pragma once
// Compaction settings <-> JSON, as stored in meta.json ("settings"), so that every packing
// records how it was made and a stopped run resumes with the same settings.
#include <nlohmann/json.hpp>

#include "unjam/protocol/compaction.hpp"
#include "unjam/protocol/gas.hpp"

namespace unjam {

nlohmann::json to_json(const CompactionSettings& settings, const GasSettings& gas);

// Reads the settings back; keys that are missing keep the values already in `settings`
// and `gas`. Throws unjam::Error for a value of the wrong type.
void from_json(const nlohmann::json& j, CompactionSettings& settings, GasSettings& gas);

}  // namespace unjam
