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
                                          double fn_tol, const ForceBoundsOptions& lp, const std::string& shard,
                                          int contacts) {
  nlohmann::json j = {{"packing", packing_name}, {"packing_fingerprint", packing_fingerprint(packing)},
                      {"gap_tol", gap_tol},      {"fn_tol", fn_tol},
                      {"method", lp.method == LpMethod::simplex ? "simplex" : "barrier"},
                      {"shard", shard},          {"contacts", contacts}};
  put_lp_tolerances(j, lp);
  return j;
}

void put_lp_tolerances(nlohmann::json& j, const ForceBoundsOptions& lp) {
  const ForceBoundsOptions defaults;
  if (lp.tolerance != defaults.tolerance) j["lp_tolerance"] = lp.tolerance;
  if (lp.open_tol_F0 != defaults.open_tol_F0) j["open_tol_F0"] = lp.open_tol_F0;
}

void get_lp_tolerances(const nlohmann::json& j, ForceBoundsOptions& lp) {
  const ForceBoundsOptions defaults;
  lp.tolerance = j.value("lp_tolerance", defaults.tolerance);
  lp.open_tol_F0 = j.value("open_tol_F0", defaults.open_tol_F0);
}

long long known_values(const ForceBounds& b) {
  return static_cast<long long>((b.fn_min.array() == b.fn_min.array()).count() +
                                (b.fn_max.array() == b.fn_max.array()).count());
}

void put_bounds_counts(nlohmann::json& j, const ForceBounds& b) {
  j["min_lps_skipped"] = b.min_lps_skipped;
  j["iterations"] = b.iterations;
  j["loosened_solves"] = b.loosened_solves;
  j["simplex_finishes"] = b.simplex_finishes;
  j["unscaled_solves"] = b.unscaled_solves;
}

void get_bounds_counts(const nlohmann::json& j, ForceBounds& b) {
  const auto count = [&j](const char* key, bool required) {
    const long long n = required || j.contains(key) ? json_integer<long long>(j.at(key), key) : 0;
    if (n < 0) throw Error(std::string(key) + " is negative");
    return n;
  };
  b.min_lps_skipped = json_integer<int>(j.at("min_lps_skipped"), "min_lps_skipped");
  if (b.min_lps_skipped < 0) throw Error("min_lps_skipped is negative");
  b.iterations = count("iterations", true);
  b.loosened_solves = count("loosened_solves", true);
  b.simplex_finishes = count("simplex_finishes", false);
  b.unscaled_solves = count("unscaled_solves", false);
}

std::optional<ForceBounds> read_bounds_checkpoint(const std::filesystem::path& file, const nlohmann::json& settings,
                                                  CampaignTime* runs) {
  const std::optional<nlohmann::json> read = read_checkpoint(file, settings, "bounds checkpoint");
  if (!read) return std::nullopt;
  const nlohmann::json& j = *read;
  const std::string name = file.string();
  ForceBounds b;
  try {
    b.fn_min = values_of(j.at("fn_min"));
    b.fn_max = values_of(j.at("fn_max"));
    get_bounds_counts(j, b);
  } catch (const std::exception& e) {
    throw Error(name + " is damaged (" + e.what() + "); remove it to start over");
  }
  const auto contacts = settings.value("contacts", -1);
  if (b.fn_min.size() != contacts || b.fn_max.size() != contacts)
    throw Error(name + " is damaged (" + std::to_string(b.fn_max.size()) + " values for " +
                std::to_string(contacts) + " contacts); remove it to start over");
  if (b.min_lps_skipped > contacts)
    throw Error(name + " is damaged (min_lps_skipped is more than its " + std::to_string(contacts) +
                " contacts); remove it to start over");
  // A minimum known is 0 (opened) or positive (ensemble/force_bounds); NaN: not known yet.
  if ((b.fn_min.array() < 0.0).any())
    throw Error(name + " is damaged (a negative fn_min); remove it to start over");
  b.complete = false;
  if (runs) *runs = campaign_time_from_json(j.value("runs", nlohmann::json()), known_values(b));
  return b;
}

BoundsCheckpoint::BoundsCheckpoint(std::filesystem::path file, nlohmann::json settings)
    : file_(std::move(file)), settings_(std::move(settings)) {
  require_writable(file_);  // before any LP, not at the first save
  std::optional<ForceBounds> b = read_bounds_checkpoint(file_, settings_, &earlier_);
  if (b) resumed_ = std::make_shared<ForceBounds>(std::move(*b));
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
  nlohmann::json j = {{"settings", settings_},
                      {"fn_min", values_json(b.fn_min)},
                      {"fn_max", values_json(b.fn_max)},
                      {"runs", to_json(runs)}};
  put_bounds_counts(j, b);
  write_file_atomic(file_, j.dump());
}

void BoundsCheckpoint::remove() const {
  std::error_code ec;
  std::filesystem::remove(file_, ec);
}

}  // namespace unjam
