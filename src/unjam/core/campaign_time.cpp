#include "unjam/core/campaign_time.hpp"

#include <cmath>

namespace unjam {

CampaignTime operator+(const CampaignTime& a, const CampaignTime& b) {
  return {a.runs + b.runs, a.wall_seconds + b.wall_seconds, a.busy_seconds + b.busy_seconds,
          a.untimed + b.untimed};
}

CampaignTime one_run(double wall, const std::vector<RankLoad>& loads) {
  CampaignTime t;
  t.runs = 1;
  t.wall_seconds = wall;
  for (const RankLoad& l : loads) t.busy_seconds += l.busy_seconds;
  return t;
}

double campaign_eta(const CampaignTime& so_far, long long done, long long remaining, int workers) {
  const long long timed = done - so_far.untimed;
  if (timed <= 0 || !(so_far.busy_seconds > 0.0) || workers < 1) return -1.0;
  if (remaining <= 0) return 0.0;
  return static_cast<double>(remaining) * so_far.busy_seconds / static_cast<double>(timed) / workers;
}

nlohmann::json to_json(const CampaignTime& t) {
  return {{"runs", t.runs}, {"wall_seconds", t.wall_seconds}, {"busy_seconds", t.busy_seconds},
          {"untimed", t.untimed}};
}

CampaignTime campaign_time_from_json(const nlohmann::json& record, long long tasks) {
  CampaignTime untimed;
  untimed.untimed = tasks;
  if (!record.is_object()) return untimed;
  const auto number = [&](const char* key, double& to) {
    const auto it = record.find(key);
    if (it == record.end() || !it->is_number()) return false;
    to = it->get<double>();
    return std::isfinite(to) && to >= 0.0;
  };
  double n = 0.0, wall = 0.0, busy = 0.0, u = 0.0;
  if (!number("runs", n) || !number("wall_seconds", wall) || !number("busy_seconds", busy) ||
      !number("untimed", u) || n != std::floor(n) || n > 1e9 || u != std::floor(u) ||
      u > static_cast<double>(tasks))
    return untimed;
  return {static_cast<int>(n), wall, busy, static_cast<long long>(u)};
}

}  // namespace unjam
