#pragma once
// Averages of the probe response over probed contacts (docs/analysis.md, "Mean field" and
// "Profile d(r)"; the paper's Figs. 1 and 2). Every probe contributes its per-grain
// displacement field, mapped into the probed contact's frame (contact_frame.hpp) and divided by
// the probe's gap g:
//
// Mean field (Fig. 1). A square grid over the frame, [-W, W)^2 with W = half_width, n_side =
// 2W/h bins of side h; bin (i, j) covers x in [-W + i h, -W + (i+1) h), y likewise. Per bin:
//   S_u = sum over probes and grains in the bin of (ux, uy)/g,   count = number of such terms,
//   mean field = S_u / count  (the mean displacement of a grain found there; 0 if count = 0).
// (S_u / probes, the field per probe, is mean * count / probes.) Grains outside are skipped.
//
// Profile d(r) (Fig. 2). r = |(x, y)|, the distance from the contact point; K logarithmic bins
//   r_k = r_min (r_max / r_min)^(k / K),  k = 0 .. K,  bin k = [r_k, r_k+1),  r_mid = sqrt(r_k r_k+1).
// Per probe p and bin k: s_pk = sum of |u|/g over its grains in the bin, c_pk their number.
//   d_k = sum_p s_pk / sum_p c_pk    (pooled over probes: every grain weighs the same),
//   sem_k = sqrt(P/(P-1) sum_p (s_pk - d_k c_pk)^2) / sum_p c_pk
//         (the standard error of a ratio estimator with probes as independent samples; P = all
//          probes, including those with no grain in the bin; 0 if P < 2).
// The per-probe rows are kept so that the fit's error can be bootstrapped over probes
// (power_law_fit.hpp).
//
// Determinism. Probes are identified by an id (the probed contact's index), unique within an
// accumulator. The field sums are FixedPointSums (order-independent, exact integer addition);
// the per-probe rows are stored by id and every total over probes is summed in increasing id
// order when it is read. So any split of a set of probes over threads, merged in any order,
// gives bit-identical CSVs, checkpoints and fits.
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "unjam/analysis/contact_frame.hpp"
#include "unjam/analysis/fixed_point_sum.hpp"
#include "unjam/core/cell.hpp"

namespace unjam {

// The bins of the averages (lengths in units of R_max = 1).
struct ResponseGrid {
  double half_width = 20.0;  // W: the field grid covers [-W, W)^2
  double h = 1.0;            // field bin side; 2W/h must be an integer (to 1e-9)
  double r_min = 0.5;        // profile range [r_min, r_max), logarithmic bins
  double r_max = 50.0;
  int r_bins = 30;           // K

  // A grid for a cell: h = half a mean diameter, W = the largest multiple of h <= L_min/2
  // (the minimum-image square), r_min = mean_diameter / 2, r_max = L_min / 2 (beyond it the
  // minimum image truncates the circles of radius r), 10 bins per decade (at least 1).
  static ResponseGrid for_cell(const Cell& cell, double mean_diameter);

  int field_side() const;    // n_side = 2W/h
  double r_edge(int k) const;  // r_k, k = 0 .. K (r_edge(K) == r_max exactly)
  // Throws unjam::Error naming the offending parameter.
  void validate() const;

  bool operator==(const ResponseGrid&) const = default;
};

// The profile table of profile.csv, one entry per bin k.
struct RadialProfile {
  std::vector<double> r_lo, r_hi, r_mid;  // r_k, r_k+1, sqrt(r_k r_k+1)
  std::vector<double> d_mean, d_sem;      // d_k (0 if count = 0), sem_k
  std::vector<std::int64_t> count;        // sum_p c_pk
  std::vector<std::int64_t> probes;       // probes with c_pk > 0

  std::size_t size() const { return r_mid.size(); }
};

// One probe's profile row: s_pk and c_pk for k = 0 .. K-1.
struct ProbeProfile {
  std::vector<double> d_sum;
  std::vector<std::int64_t> count;

  bool operator==(const ProbeProfile&) const = default;
};

class ResponseAverage {
 public:
  // Throws unjam::Error if the grid is invalid.
  explicit ResponseAverage(const ResponseGrid& grid);

  const ResponseGrid& grid() const { return grid_; }
  std::size_t probes() const { return profiles_.size(); }
  bool has_probe(std::int64_t id) const { return profiles_.contains(id); }
  // Per-probe rows in increasing id order (the bootstrap's samples).
  const std::map<std::int64_t, ProbeProfile>& probe_profiles() const { return profiles_; }

  // Adds probe `id` whose grains, in the contact frame, are `field` (displacements in length
  // units); g > 0 is its gap, every displacement is divided by it. Pass g = 1 if the
  // displacements are already u/g. Throws unjam::Error if id was added before, g <= 0, or a
  // value is not finite. The caller chooses which grains enter (e.g. rattlers left out).
  void add_probe(std::int64_t id, const FrameField& field, double g);

  // Adds every probe of `other`; throws unjam::Error if the grids differ or an id is in both.
  void merge(const ResponseAverage& other);

  // Mean field of bin (i, j): (S_ux, S_uy) / count, 0 if empty; and count.
  Vec2 field_mean(int i, int j) const;
  std::int64_t field_count(int i, int j) const { return count_[index(i, j)]; }

  RadialProfile profile() const;

  // response_field.csv: x,y,ux,uy,count; one row per bin, x fastest; (x, y) the bin centre,
  // (ux, uy) the mean field (units of g), NaN in an empty bin (count 0).
  // response_profile.csv: r_lo,r_hi,r_mid,d_mean,d_sem,count,probes; d_mean and d_sem NaN in
  // an empty bin (count 0). Write them with write_file_atomic.
  std::string field_csv() const;
  std::string profile_csv() const;

  // Checkpoint: the grid, the field sums (exact 128-bit integers) and the per-probe rows;
  // from_json(to_json()) reproduces the accumulator exactly. load/save read and write it as a
  // JSON file (save atomically); both throw unjam::Error naming the file on failure.
  nlohmann::json to_json() const;
  static ResponseAverage from_json(const nlohmann::json& j);
  void save(const std::filesystem::path& path) const;
  static ResponseAverage load(const std::filesystem::path& path);

  bool operator==(const ResponseAverage&) const = default;

 private:
  std::size_t index(int i, int j) const { return static_cast<std::size_t>(j) * side_ + i; }
  int profile_bin(double r) const;  // k with r_k <= r < r_k+1, or -1

  ResponseGrid grid_;
  int side_ = 0;                           // n_side
  std::vector<double> r_edges_;            // r_0 .. r_K
  std::vector<FixedPointSum> ux_sum_, uy_sum_;  // S_u per field bin, index(i, j)
  std::vector<std::int64_t> count_;
  std::map<std::int64_t, ProbeProfile> profiles_;
};

}  // namespace unjam
