// libFuzzer target of the probe checkpoint reader (read_campaign_checkpoint, as `unjam probe
// --all` resumes) on the fixture lattice16. An input is a checkpoint's text; it is read as a
// whole (fingerprint, settings, hash) and its "state" also on its own (an edit that recomputed
// the hash). Every input must end in unjam::Error, in "another packing" (nullopt), or in a
// state run_campaign could have made on the packing that saves and reloads unchanged; a
// crash, a sanitizer report, a timeout or another exception fails. Its record of the runs'
// time (campaign_time_from_json of its "runs") is read from any JSON object without throwing, and is
// either a valid one or none (every probe untimed).
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "fuzz_common.hpp"
#include "unjam/core/error.hpp"
#include "unjam/packing/packing_io.hpp"
#include "unjam/probe/campaign_run.hpp"
#include "unjam/probe/probe_campaign.hpp"

namespace {

using unjam::fuzz::accepted_invalid;

const unjam::Packing& packing() {
  static const unjam::Packing p = unjam::read_packing(std::filesystem::path(UNJAM_FIXTURES_DIR) / "lattice16");
  return p;
}

const nlohmann::json& settings() {
  static const nlohmann::json s = unjam::to_json(unjam::campaign_settings_for(packing()));
  return s;
}

std::vector<std::string> seeds() {
  const unjam::Packing& p = packing();
  const unjam::ResponseGrid grid = unjam::ResponseGrid::for_cell(p.cell, 2.0 * p.mean_radius());
  const std::string fingerprint = unjam::packing_fingerprint(p);
  std::vector<std::string> out;
  unjam::CampaignState state(grid);
  out.push_back(unjam::campaign_checkpoint_text(fingerprint, settings(), state));
  // Two probes, contacts 3 and 17, with a few grains each (displacements / g in the contact frame).
  for (const int k : {3, 17}) {
    const unjam::Contact& c = p.contacts[k];
    unjam::FrameField field;
    field.x = {0.5, -1.5, 2.25};
    field.y = {1.0, 0.5, -2.5};
    field.ux = {0.1 * k, -0.2, 0.3};
    field.uy = {-0.4, 0.5, 0.01 * k};
    state.average.add_probe(k, field, 1.0);
    state.rows.push_back({k, c.a, c.b, c.fn, 1.5 * c.fn, true, 12, 1e-12, 0, 1e-9});
  }
  state.rows.push_back({30, p.contacts[30].a, p.contacts[30].b, 1.0, 0.0, false, 0, 1e300, 2, 0.0});
  out.push_back(unjam::campaign_checkpoint_text(fingerprint, settings(), state));
  unjam::CampaignTime time;
  time.runs = 2;
  time.wall_seconds = 12.5;
  time.busy_seconds = 11.0;
  time.untimed = 1;
  out.push_back(unjam::campaign_checkpoint_text(fingerprint, settings(), state, &time));
  return out;
}

// What a state run_campaign could have made on the packing satisfies, checked independently
// of the reader's code; then it must save and reload unchanged, and summarize.
void check_accepted(const unjam::CampaignState& state) {
  const unjam::Packing& p = packing();
  if (!(state.average.grid() == unjam::ResponseGrid::for_cell(p.cell, 2.0 * p.mean_radius())))
    accepted_invalid("averages on another grid than the packing's");
  const auto contacts = static_cast<int>(p.contacts.size());
  for (std::size_t k = 0; k < state.rows.size(); ++k) {
    const unjam::ProbeRow& r = state.rows[k];
    if (r.contact < 0 || r.contact >= contacts) accepted_invalid("row of a contact out of range");
    if (k > 0 && !(state.rows[k - 1].contact < r.contact)) accepted_invalid("rows not in increasing contact order");
    if (r.a != p.contacts[r.contact].a || r.b != p.contacts[r.contact].b) accepted_invalid("row with other grains");
  }
  for (const auto& [id, profile] : state.average.probe_profiles()) {
    bool listed = false;
    for (const unjam::ProbeRow& r : state.rows) listed = listed || r.contact == id;
    if (!listed) accepted_invalid("averaged probe without a row");
  }
  const unjam::CampaignState again = unjam::campaign_state_from_json(unjam::to_json(state), p);
  if (!(again.average == state.average) || unjam::to_json(again) != unjam::to_json(state))
    accepted_invalid("the state does not reload as saved");
  (void)state.average.field_csv();
  (void)state.average.profile_csv();
  try {
    (void)unjam::summarize(p, state, std::nullopt, 5, 1);
  } catch (const unjam::Error&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  unjam::fuzz::write_seeds_if_asked(*argc, *argv, seeds);
  (void)packing();
  (void)settings();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    if (const auto state = unjam::read_campaign_checkpoint(text, "fuzz", packing(), settings()))
      check_accepted(*state);
  } catch (const unjam::Error&) {
  }
  const auto j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_object()) {
    const long long probes = 3;
    const unjam::CampaignTime t = unjam::campaign_time_from_json(j.value("runs", nlohmann::json()), probes);
    const bool valid = t.runs >= 0 && std::isfinite(t.wall_seconds) && t.wall_seconds >= 0.0 &&
                       std::isfinite(t.busy_seconds) && t.busy_seconds >= 0.0 && t.untimed >= 0 &&
                       t.untimed <= probes;
    if (!valid) accepted_invalid("a record of the runs' time out of range");
  }
  if (!j.is_object() || !j.contains("state")) return 0;
  try {
    check_accepted(unjam::campaign_state_from_json(j["state"], packing()));
  } catch (const unjam::Error&) {
  }
  return 0;
}
