#pragma once
// The loads of a campaign's ranks as its outputs record them ("ranks" of probe_summary.json
// and bounds.json).
#include <vector>

#include <nlohmann/json.hpp>

#include "unjam/core/work_source.hpp"

namespace unjam {

// One object per MPI rank or process: rank, threads, the tasks it computed under `tasks_key`
// ("probes", "lps") and busy_seconds (s, summed over its threads). Json is nlohmann::json
// (keys sorted) or nlohmann::ordered_json (keys in this order).
template <class Json>
Json rank_loads_json(const std::vector<RankLoad>& loads, const char* tasks_key) {
  Json j = Json::array();
  for (const RankLoad& l : loads)
    j.push_back({{"rank", l.rank}, {"threads", l.threads}, {tasks_key, l.tasks}, {"busy_seconds", l.busy_seconds}});
  return j;
}

}  // namespace unjam
