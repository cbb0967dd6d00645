#pragma once
// The checkpoint of a run of the friction threshold's bisection (ensemble/friction_threshold;
// `unjam threshold`): a JSON file with what identifies the run ("settings"), the bracket
// (mu_low, mu_high] reached, both ends checked, and the LPs, simplex iterations and LP time
// spent on it. A run stopped (Ctrl-C, SIGTERM, --stop-after) keeps it, and the same run
// resumes from it without solving the ends again; the bracket it then reaches is that of one
// uninterrupted run (docs/ensemble.md, "The friction threshold").
#include <filesystem>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "unjam/ensemble/friction_threshold.hpp"
#include "unjam/packing/packing.hpp"

namespace unjam {

// What identifies a run of the bisection: the packing's contents ("packing_fingerprint"), the
// admissible set (gap_tol in R_max, fn_tol in F0, its number of contacts), the packing's own
// mu and rel_tol.
nlohmann::json threshold_checkpoint_settings(const Packing& packing, double gap_tol, double fn_tol,
                                             int contacts, double mu, double rel_tol);

// A bracket with both ends checked (so_far.mu_low, so_far.mu_high), what it cost (so_far's LPs,
// iterations and LP seconds), and the runs that made it.
struct ThresholdProgress {
  FrictionThreshold so_far;
  int runs = 0;
};

// A checkpoint file and the run it belongs to. Constructing it checks that the file can be
// written (unjam::Error if not) and reads it if it is there: one of other settings is refused
// (unjam::Error naming the settings that differ, core/checkpoint_settings), as is one that is
// not a checkpoint or whose bracket is not 0 <= mu_low < mu_high; the file is then kept.
class ThresholdCheckpoint {
 public:
  ThresholdCheckpoint(std::filesystem::path file, nlohmann::json settings);

  const std::filesystem::path& file() const { return file_; }
  // The progress read from the file, if there was one.
  const std::optional<ThresholdProgress>& resumed() const { return resumed_; }
  // Hooks a run of the bisection to the checkpoint (`unjam threshold`, unjam.friction_threshold):
  // with a bracket read, the run starts from it without solving its ends again
  // (o.bracket_checked); once both ends are checked (after the run's second LP, or from the
  // start when resumed) the bracket and the counts of every run so far are saved after every
  // LP, before the progress hook o had (still called); the hook points into this object, which
  // must outlive the run. Throws unjam::Error where a bracket was read and o already starts
  // from one (o.mu_low or o.mu_high set): the file is kept.
  void attach(FrictionThresholdOptions& o) const;
  // A run's result r with the LPs, iterations and LP seconds of the runs read from the file
  // added: the counts of every run that made the bracket.
  FrictionThreshold with_earlier(FrictionThreshold r) const;
  // Writes the file (atomically).
  void save(const ThresholdProgress& p) const;
  // Removes the file, if there is one.
  void remove() const;

 private:
  std::filesystem::path file_;
  nlohmann::json settings_;
  std::optional<ThresholdProgress> resumed_;
};

}  // namespace unjam
