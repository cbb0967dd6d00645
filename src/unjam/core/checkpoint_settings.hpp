#pragma once
// A checkpoint is resumed only by the run it belongs to: the settings it saved must equal the
// present run's (probe, bounds and threshold checkpoints). Where they do not, the error names every
// setting that differs, so that the run can be repeated with the checkpoint's settings
// instead of started over.
#include <filesystem>
#include <optional>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include "unjam/core/atomic_file.hpp"
#include "unjam/core/error.hpp"

namespace unjam {

// The keys whose values differ between the settings objects a and b, in key order:
//   "<key>: <a's value> <a_word>, <b's value> <b_word>, ..."
// (a key missing on one side reads "none"); empty where either is not an object.
inline std::string settings_differences(const nlohmann::json& a, const nlohmann::json& b, const std::string& a_word,
                                        const std::string& b_word) {
  std::string diff;
  if (!a.is_object() || !b.is_object()) return diff;
  std::set<std::string> keys;
  for (const auto& [k, v] : a.items()) keys.insert(k);
  for (const auto& [k, v] : b.items()) keys.insert(k);
  for (const std::string& k : keys) {
    const auto x = a.find(k), y = b.find(k);
    const std::string in_a = x == a.end() ? "none" : x->dump(), in_b = y == b.end() ? "none" : y->dump();
    if (in_a != in_b) diff += (diff.empty() ? "" : ", ") + k + ": " + in_a + " " + a_word + ", " + in_b + " " + b_word;
  }
  return diff;
}

// Throws unjam::Error unless `saved` (the checkpoint's settings) equals `now` (this run's):
//   "<name> belongs to a run with other settings (<key>: <saved> there, <now> here, ...);
//    give its settings to resume it, or remove it to start over"
// (settings_differences; no list where `saved` is not an object).
inline void require_same_settings(const nlohmann::json& saved, const nlohmann::json& now, const std::string& name) {
  if (saved == now) return;
  const std::string diff = settings_differences(saved, now, "there", "here");
  throw Error(name + " belongs to a run with other settings" + (diff.empty() ? "" : " (" + diff + ")") +
              "; give its settings to resume it, or remove it to start over");
}

// The checkpoint in `file`, if there is one: its JSON object, once its "settings" passed
// require_same_settings against `settings`. Throws unjam::Error where the file is not a JSON
// object ("<file> is not a <what> (not a JSON object); remove it to start over").
inline std::optional<nlohmann::json> read_checkpoint(const std::filesystem::path& file, const nlohmann::json& settings,
                                                     const std::string& what) {
  if (!std::filesystem::exists(file)) return std::nullopt;
  auto j = nlohmann::json::parse(read_file(file), nullptr, false);
  if (j.is_discarded() || !j.is_object())
    throw Error(file.string() + " is not a " + what + " (not a JSON object); remove it to start over");
  require_same_settings(j.value("settings", nlohmann::json{}), settings, file.string());
  return j;
}

}  // namespace unjam
