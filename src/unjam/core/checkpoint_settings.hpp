#pragma once
// A checkpoint is resumed only by the run it belongs to: the settings it saved must equal the
// present run's (probe and bounds checkpoints). Where they do not, the error names every
// setting that differs, so that the run can be repeated with the checkpoint's settings
// instead of started over.
#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include "unjam/core/error.hpp"

namespace unjam {

// Throws unjam::Error unless `saved` (the checkpoint's settings) equals `now` (this run's):
//   "<name> belongs to a run with other settings (<key>: <saved> there, <now> here, ...);
//    give its settings to resume it, or remove it to start over"
// (a key missing on one side reads "none"; no list where `saved` is not an object).
inline void require_same_settings(const nlohmann::json& saved, const nlohmann::json& now, const std::string& name) {
  if (saved == now) return;
  std::string diff;
  if (saved.is_object() && now.is_object()) {
    std::set<std::string> keys;
    for (const auto& [k, v] : saved.items()) keys.insert(k);
    for (const auto& [k, v] : now.items()) keys.insert(k);
    for (const std::string& k : keys) {
      const auto a = saved.find(k), b = now.find(k);
      const std::string was = a == saved.end() ? "none" : a->dump(), is = b == now.end() ? "none" : b->dump();
      if (was != is) diff += (diff.empty() ? " (" : ", ") + k + ": " + was + " there, " + is + " here";
    }
    if (!diff.empty()) diff += ")";
  }
  throw Error(name + " belongs to a run with other settings" + diff +
              "; give its settings to resume it, or remove it to start over");
}

}  // namespace unjam
