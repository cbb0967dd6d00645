#pragma once
// Compaction settings <-> JSON, as stored in meta.json ("settings"), so that every packing
// records how it was made and a stopped run resumes with the same settings.
#include <string>

#include <nlohmann/json.hpp>

#include "unjam/protocol/compaction.hpp"
#include "unjam/protocol/gas.hpp"

namespace unjam {

nlohmann::json to_json(const CompactionSettings& settings, const GasSettings& gas);

// Reads the settings back; keys that are missing keep the values already in `settings`
// and `gas`. Throws unjam::Error for a value of the wrong type.
void from_json(const nlohmann::json& j, CompactionSettings& settings, GasSettings& gas);

// The bath mass and the static solve's touch gap of a packing's contact model
// (PackingMeta::contact) into settings.
void apply_contact_model(const ContactModel& model, CompactionSettings& settings);

// Readies a packing for compact(), as `unjam pack` and the Python module do: the bath takes
// packing.meta.contact.P_ext, the settings are validated with packing.meta.contact.mu (throws unjam::Error)
// and recorded in meta.settings (and the contact model, meta.contact) with the command, so that a
// stopped run resumes with them.
void prepare_compaction(Packing& packing, CompactionSettings& settings, const GasSettings& gas,
                        const std::string& command);

// A packing to re-relax at friction mu and pressure P_ext (`unjam pack --from`): `settings`
// and `gas` become those it was made with (its meta.settings), meta.contact.mu and meta.contact.P_ext the new
// values. Then prepare_compaction and compact() as for a gas.
void prepare_relaxation(Packing& packing, double mu, double P_ext, CompactionSettings& settings,
                        GasSettings& gas);

}  // namespace unjam
