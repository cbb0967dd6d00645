#pragma once
// The checkpoint of a run of the force bounds (ensemble/force_bounds; `unjam bounds` and
// unjam.bounds): a JSON file with what identifies the run ("settings"), the interval ends known
// so far (null: not known yet), the counts of ForceBounds and the time of the runs that made
// them ("runs", core/campaign_time). A run stopped (Ctrl-C, SIGTERM, a budget of LPs) saves it
// and the same run resumes from it, solving only the LPs whose values it does not hold; the
// values do not depend on the thread count, so the resumed run's are those of one uninterrupted
// run (docs/ensemble.md, "The LP", its last paragraphs).
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "unjam/core/campaign_time.hpp"
#include "unjam/ensemble/force_bounds.hpp"
#include "unjam/packing/packing.hpp"

namespace unjam {

// What identifies a run of the bounds: the packing (as named by the run, "packing", and by its
// contents, "packing_fingerprint"), the admissible set (gap_tol in R_max, fn_tol in F0), the LP
// of `lp`: its method ("barrier" or "simplex") and, where they are not the defaults, its
// tolerances ("lp_tolerance", "open_tol_F0"); the shard ("i/K" or empty) and the number of
// contacts of the system. The thread count and the hooks of `lp` are not part of it.
nlohmann::json bounds_checkpoint_settings(const std::string& packing_name, const Packing& packing, double gap_tol,
                                          double fn_tol, const ForceBoundsOptions& lp, const std::string& shard,
                                          int contacts);

// The LP's tolerances of `lp`, written into the object j as "lp_tolerance" and "open_tol_F0"
// where they are not ForceBoundsOptions' defaults (so that a file written before they could be
// set reads as the default run's): as the checkpoint's settings and the shards' options
// store them.
void put_lp_tolerances(nlohmann::json& j, const ForceBoundsOptions& lp);
// The same read back from j into lp, the defaults where absent. Throws nlohmann's exception for
// a value that is not a number; the ranges are check_force_bounds_options'.
void get_lp_tolerances(const nlohmann::json& j, ForceBoundsOptions& lp);

// The values known in a partial result: the finite entries of fn_min and fn_max.
long long known_values(const ForceBounds& b);

// The counts of ForceBounds (min_lps_skipped, iterations, loosened_solves, simplex_finishes,
// unscaled_solves), written into the object j under those names: as the checkpoint and the
// shards of `unjam bounds --shard` store them.
void put_bounds_counts(nlohmann::json& j, const ForceBounds& b);
// The counts read back from j into b: integers >= 0 (json_integer), simplex_finishes and
// unscaled_solves 0 where absent (files written before they were kept). Throws unjam::Error
// naming the count, or nlohmann's exception for a count missing.
void get_bounds_counts(const nlohmann::json& j, ForceBounds& b);

// The partial result saved in `file` by a run with `settings` (bounds_checkpoint_settings), and
// in `runs` (if not null) the time of the runs that made it; nullopt if there is no such file.
// Reads only. Throws unjam::Error, naming the file, for a checkpoint of other settings (naming
// the settings that differ), one that is not valid JSON, or one whose values do not fit the
// settings' number of contacts.
std::optional<ForceBounds> read_bounds_checkpoint(const std::filesystem::path& file, const nlohmann::json& settings,
                                                  CampaignTime* runs = nullptr);

// A checkpoint file and the run it belongs to. Constructing it checks that the file can be
// written (unjam::Error if not, before any LP is solved) and reads the file if there is one
// (read_bounds_checkpoint, with its refusals).
class BoundsCheckpoint {
 public:
  BoundsCheckpoint(std::filesystem::path file, nlohmann::json settings);

  const std::filesystem::path& file() const { return file_; }
  // The partial result read from the file, or null where there was none.
  const ForceBounds* resumed() const { return resumed_ ? resumed_.get() : nullptr; }
  // The time of the runs that made the resumed values (zero without a checkpoint; its untimed:
  // the values of a checkpoint that did not record it).
  const CampaignTime& earlier() const { return earlier_; }

  // Hooks `lp` to the checkpoint: resumes from the values read (lp.resume, pointing into this
  // object, which must outlive the computation), saves the values known every `every_s`
  // seconds with the runs' time `time_so_far()`, and stops handing out LPs once `stop()` is
  // true or `stop_after` (> 0) LPs have been solved in this run. After an incomplete result
  // call save(); after a complete one, remove().
  void attach(ForceBoundsOptions& lp, double every_s, int stop_after, std::function<bool()> stop,
              std::function<CampaignTime()> time_so_far) const;

  // Writes the file (atomically) with the values of `b` and the runs' time `runs`.
  void save(const ForceBounds& b, const CampaignTime& runs) const;
  // Removes the file, if there is one.
  void remove() const;

 private:
  std::filesystem::path file_;
  nlohmann::json settings_;
  std::shared_ptr<const ForceBounds> resumed_;
  CampaignTime earlier_;
};

}  // namespace unjam
