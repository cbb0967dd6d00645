#include "unjam/campaign/bounds_checkpoint.hpp"

#include <chrono>
#include <cmath>
#include <utility>

#include "unjam/core/atomic_file.hpp"
#include "unjam/core/checkpoint_settings.hpp"
#include "unjam/core/error.hpp"
#include "unjam/core/json_integer.hpp"
#include "unjam/packing/packing_io.hpp"

namespace unjam {

namespace {

// A vector with NaN (not known yet) as JSON null, and back.
nlohmann::json values_json(const Eigen::VectorXd& v) {
  nlohmann::json j = nlohmann::json::array();
  for (const double x : v) j.push_back(std::isnan(x) ? nlohmann::json() : nlohmann::json(x));
  return j;
}

Eigen::VectorXd values_of(const nlohmann::json& j) {
  if (!j.is_array()) throw Error("not an array");
  Eigen::VectorXd v(static_cast<Eigen::Index>(j.size()));
  for (std::size_t i = 0; i < j.size(); ++i) {
    if (!j[i].is_null() && !j[i].is_number()) throw Error("not a number or null");
    v[static_cast<Eigen::Index>(i)] = j[i].is_null() ? std::nan("") : j[i].get<double>();
  }
  return v;
}

}  // namespace

nlohmann::json bounds_checkpoint_settings(const std::string& packing_name, const Packing& packing, double gap_tol,
                                          double fn_tol, const std::string& method, const std::string& shard,
                                          int contacts) {
  return {{"packing", packing_name}, {"packing_fingerprint", packing_fingerprint(packing)}, {"gap_tol", gap_tol},
          {"fn_tol", fn_tol},        {"method", method},
          {"shard", shard},          {"contacts", contacts}};
}

long long known_values(const ForceBounds& b) {
  return static_cast<long long>((b.fn_min.array() == b.fn_min.array()).count() +
                                (b.fn_max.array() == b.fn_max.array()).count());
}

BoundsCheckpoint::BoundsCheckpoint(std::filesystem::path file, nlohmann::json settings)
    : file_(std::move(file)), settings_(std::move(settings)) {
  require_writable(file_);  // before any LP, not at the first save
  const std::optional<nlohmann::json> read = read_checkpoint(file_, settings_, "bounds checkpoint");
  if (!read) return;
  const nlohmann::json& j = *read;
  const std::string name = file_.string();
  auto b = std::make_shared<ForceBounds>();
  try {
    b->fn_min = values_of(j.at("fn_min"));
    b->fn_max = values_of(j.at("fn_max"));
    b->min_lps_skipped = json_integer<int>(j.at("min_lps_skipped"), "min_lps_skipped");
    b->iterations = json_integer<long long>(j.at("iterations"), "iterations");
    b->loosened_solves = json_integer<long long>(j.at("loosened_solves"), "loosened_solves");
    // Checkpoints written before these counts were kept: 0.
    const auto count_or_zero = [&j](const char* key) {
      return j.contains(key) ? json_integer<long long>(j.at(key), key) : 0LL;
    };
    b->simplex_finishes = count_or_zero("simplex_finishes");
    b->unscaled_solves = count_or_zero("unscaled_solves");
  } catch (const std::exception& e) {
    throw Error(name + " is damaged (" + e.what() + "); remove it to start over");
  }
  const auto contacts = settings_.value("contacts", -1);
  if (b->fn_min.size() != contacts || b->fn_max.size() != contacts)
    throw Error(name + " is damaged (" + std::to_string(b->fn_max.size()) + " values for " +
                std::to_string(contacts) + " contacts); remove it to start over");
  if (b->min_lps_skipped < 0 || b->min_lps_skipped > contacts || b->iterations < 0 || b->loosened_solves < 0 ||
      b->simplex_finishes < 0 || b->unscaled_solves < 0)
    throw Error(name + " is damaged (its counts are not 0 <= min_lps_skipped <= contacts and >= 0 otherwise); " +
                "remove it to start over");
  // A minimum known is 0 (opened) or positive (ensemble/force_bounds); NaN: not known yet.
  if ((b->fn_min.array() < 0.0).any())
    throw Error(name + " is damaged (a negative fn_min); remove it to start over");
  b->complete = false;
  earlier_ = campaign_time_from_json(j.value("runs", nlohmann::json()), known_values(*b));
  resumed_ = std::move(b);
}

void BoundsCheckpoint::attach(ForceBoundsOptions& lp, double every_s, int stop_after, std::function<bool()> stop,
                              std::function<CampaignTime()> time_so_far) const {
  lp.resume = resumed();
  auto solved = std::make_shared<int>(0);
  lp.should_stop = [stop, stop_after, solved] {
    return (stop && stop()) || (stop_after > 0 && *solved >= stop_after);
  };
  // Called after every LP, one call at a time (ForceBoundsOptions::checkpoint).
  lp.checkpoint = [this, every_s, stop, solved, time_so_far = std::move(time_so_far),
                   last = std::chrono::steady_clock::now()](const ForceBounds& b) mutable {
    ++*solved;
    const bool stopping = stop && stop();
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - last).count() < every_s && !stopping) return;
    last = std::chrono::steady_clock::now();
    save(b, time_so_far ? time_so_far() : CampaignTime{});
  };
}

void BoundsCheckpoint::save(const ForceBounds& b, const CampaignTime& runs) const {
  write_file_atomic(file_, nlohmann::json{{"settings", settings_},
                                          {"fn_min", values_json(b.fn_min)},
                                          {"fn_max", values_json(b.fn_max)},
                                          {"min_lps_skipped", b.min_lps_skipped},
                                          {"iterations", b.iterations},
                                          {"loosened_solves", b.loosened_solves},
                                          {"simplex_finishes", b.simplex_finishes},
                                          {"unscaled_solves", b.unscaled_solves},
                                          {"runs", to_json(runs)}}
                               .dump());
}

void BoundsCheckpoint::remove() const {
  std::error_code ec;
  std::filesystem::remove(file_, ec);
}

}  // namespace unjam
