#include "unjam/campaign/threshold_checkpoint.hpp"

#include <cmath>
#include <utility>

#include "unjam/core/atomic_file.hpp"
#include "unjam/core/checkpoint_settings.hpp"
#include "unjam/core/error.hpp"
#include "unjam/core/json_integer.hpp"
#include "unjam/packing/packing_io.hpp"

namespace unjam {

nlohmann::json threshold_checkpoint_settings(const Packing& packing, double gap_tol, double fn_tol,
                                             int contacts, double mu, double rel_tol) {
  return {{"packing_fingerprint", packing_fingerprint(packing)},
          {"gap_tol", gap_tol},
          {"fn_tol", fn_tol},
          {"contacts", contacts},
          {"mu", mu},
          {"rel_tol", rel_tol}};
}

ThresholdCheckpoint::ThresholdCheckpoint(std::filesystem::path file, nlohmann::json settings)
    : file_(std::move(file)), settings_(std::move(settings)) {
  require_writable(file_);  // before any LP, not at the first save
  const std::optional<nlohmann::json> read = read_checkpoint(file_, settings_, "threshold checkpoint");
  if (!read) return;
  const nlohmann::json& j = *read;
  const std::string name = file_.string();
  ThresholdProgress p;
  FrictionThreshold& t = p.so_far;
  try {
    t.mu = settings_.at("mu").get<double>();
    t.mu_low = j.at("mu_low").get<double>();
    t.mu_high = j.at("mu_high").get<double>();
    t.lps = json_integer<int>(j.at("lps"), "lps");
    t.iterations = json_integer<long long>(j.at("simplex_iterations"), "simplex_iterations");
    t.seconds = j.at("lp_seconds").get<double>();
    p.runs = json_integer<int>(j.at("runs"), "runs");
  } catch (const std::exception& e) {
    throw Error(name + " is damaged (" + e.what() + "); remove it to start over");
  }
  // JSON holds no NaN or infinity, so every number read is finite.
  if (t.lps < 0 || t.iterations < 0 || !(t.seconds >= 0.0) || p.runs < 1)
    throw Error(name + " is damaged (its counts are not lps >= 0, simplex_iterations >= 0, lp_seconds >= 0, " +
                "runs >= 1); remove it to start over");
  if (!(t.mu_low >= 0.0 && t.mu_high > t.mu_low && t.mu_high <= t.mu))
    throw Error(name + " is damaged (its bracket is not 0 <= mu_low < mu_high <= mu); remove it to start over");
  resumed_ = p;
}

void ThresholdCheckpoint::attach(FrictionThresholdOptions& o) const {
  if (resumed_) {
    if (!std::isnan(o.mu_low) || !std::isnan(o.mu_high))
      throw Error(file_.string() + " holds the bracket of a stopped run; start without a bracket to continue it, "
                  "or remove it to start from yours");
    o.mu_low = resumed_->so_far.mu_low;
    o.mu_high = resumed_->so_far.mu_high;
    o.bracket_checked = true;
  }
  o.progress = [this, then = std::move(o.progress)](int total, const FrictionThreshold& so_far) {
    if ((resumed_ || so_far.lps >= 2) && so_far.mu_high > so_far.mu_low)  // both ends checked
      save({with_earlier(so_far), (resumed_ ? resumed_->runs : 0) + 1});
    if (then) then(total, so_far);
  };
}

FrictionThreshold ThresholdCheckpoint::with_earlier(FrictionThreshold r) const {
  if (resumed_) {
    r.lps += resumed_->so_far.lps;
    r.iterations += resumed_->so_far.iterations;
    r.seconds += resumed_->so_far.seconds;
  }
  return r;
}

void ThresholdCheckpoint::save(const ThresholdProgress& p) const {
  const FrictionThreshold& t = p.so_far;
  write_file_atomic(file_, nlohmann::json{{"settings", settings_},
                                          {"mu_low", t.mu_low},
                                          {"mu_high", t.mu_high},
                                          {"lps", t.lps},
                                          {"simplex_iterations", t.iterations},
                                          {"lp_seconds", t.seconds},
                                          {"runs", p.runs}}
                               .dump());
}

void ThresholdCheckpoint::remove() const {
  std::error_code ec;
  std::filesystem::remove(file_, ec);
}

}  // namespace unjam
