// compute_ensemble (campaign/ensemble_run), the library function behind `unjam ensemble`, on
// the fixture p50-mu0.1: the admissible set and LP intervals, the sampler chosen, F_crit of
// the LP probe (= fn_max) on exactly the force-carrying contacts, the same on 1 and 2 threads.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "unjam/campaign/ensemble_run.hpp"
#include "unjam/core/error.hpp"
#include "unjam/packing/packing_io.hpp"
#include "unjam/probe/probe_campaign.hpp"

namespace unjam {
namespace {

const Packing& fixture_p50() {
  static const Packing p = read_packing(std::string(UNJAM_FIXTURES_DIR) + "/p50-mu0.1");
  return p;
}

EnsembleSettings lp_hit_and_run(int threads) {
  EnsembleSettings s;
  s.walk = false;
  s.samples = 100;
  s.probe = "lp";
  s.threads = threads;
  return s;
}

TEST(EnsembleRun, LpProbesOfTheForceCarryingContactsReachFnMax) {
  const Packing& p = fixture_p50();
  const EnsembleReport r = compute_ensemble(p, lp_hit_and_run(2));
  const int Nc = r.system.num_contacts();
  ASSERT_EQ(Nc, 81);
  EXPECT_EQ(r.probe, "lp");
  ASSERT_TRUE(r.hit_and_run && r.hr_columns);
  EXPECT_FALSE(r.walk || r.walk_columns);
  EXPECT_EQ(r.hit_and_run->samples, 100);
  ASSERT_EQ(r.bounds.fn_max.size(), Nc);
  ASSERT_EQ(r.hr_columns->min.size(), Nc);
  ASSERT_EQ(static_cast<int>(r.probes.size()), Nc);
  const double F0 = r.system.F0, tol = 1e-6 * F0;
  int probed = 0;
  for (int k = 0; k < Nc; ++k) {
    const bool carries = p.contacts[r.system.contacts[k]].fn > 1e-9 * F0;
    ASSERT_EQ(r.probes[k].has_value(), carries) << "contact " << k;
    EXPECT_LE(r.bounds.fn_min[k], r.hr_columns->min[k] + tol);
    EXPECT_GE(r.bounds.fn_max[k], r.hr_columns->max[k] - tol);
    if (!carries) continue;
    ++probed;
    EXPECT_EQ(r.probes[k]->contact, r.system.contacts[k]);
    EXPECT_NEAR(r.probes[k]->f_crit, r.bounds.fn_max[k], tol) << "contact " << k;
  }
  ASSERT_EQ(static_cast<int>(r.f_crit_over_fn_max.size()), probed);
  for (const double x : r.f_crit_over_fn_max) EXPECT_NEAR(x, 1.0, 1e-6);
  EXPECT_EQ(r.unconverged, 0);
  EXPECT_GT(r.hr_columns->coverage, 0.0);
  EXPECT_LE(r.hr_columns->coverage, 1.0 + 1e-9);
  EXPECT_NEAR(quantile(r.f_crit_over_fn_max, 0.5), 1.0, 1e-6);

  // One thread: the same intervals, samples and critical forces, bit for bit.
  const EnsembleReport one = compute_ensemble(p, lp_hit_and_run(1));
  EXPECT_EQ(one.bounds.fn_max, r.bounds.fn_max);
  EXPECT_EQ(one.hr_columns->mean, r.hr_columns->mean);
  for (int k = 0; k < Nc; ++k)
    if (r.probes[k]) EXPECT_EQ(one.probes[k]->f_crit, r.probes[k]->f_crit) << "contact " << k;
}

TEST(EnsembleRun, ProbesUseThePackingsOwnContactModel) {
  // The probes of an ensemble take the touch gap and bath mass stored with the packing, as
  // `unjam probe` does (campaign_settings_for), not the library's defaults; g, dt and the
  // NLGS tolerance are the ensemble's own.
  Packing p = read_packing(std::string(UNJAM_FIXTURES_DIR) + "/p50-mu1");
  p.meta.contact.M_lambda = 0.5;
  p.meta.contact.touch_gap = 2e-6;
  EnsembleSettings in;
  in.probe_g = 2e-9;
  in.probe_dt = 2e-3;
  in.probe_velocity_tol = 1e-7;
  const CampaignSettings probe = campaign_settings_for(p);
  for (const char* method : {"nlgs", "lp", "cd"}) {
    const CampaignSettings s = ensemble_probe_settings(p, in, method);
    const std::string m = method;
    EXPECT_EQ(s.method, m == "lp" ? ProbeMethod::kLp : m == "cd" ? ProbeMethod::kCd : ProbeMethod::kNlgs);
    EXPECT_EQ(s.nlgs.model->M_lambda, 0.5);
    EXPECT_EQ(s.kinematic.model->M_lambda, 0.5);
    EXPECT_EQ(s.nlgs.model->touch_gap, 2e-6);
    EXPECT_EQ(s.kinematic.model->touch_gap, 2e-6);
    EXPECT_EQ(s.nlgs.model, probe.nlgs.model);
    EXPECT_EQ(s.kinematic.model, probe.kinematic.model);
    EXPECT_EQ(s.nlgs.g, 2e-9);
    EXPECT_EQ(s.kinematic.g, 2e-9);
    EXPECT_EQ(s.nlgs.dt, 2e-3);
    EXPECT_EQ(s.nlgs.velocity_tol, 1e-7);
  }
  // Without a time step each method takes its own default: nlgs 1e-3, cd the quasi-static one.
  in.probe_dt = 0.0;
  EXPECT_EQ(ensemble_probe_settings(p, in, "nlgs").nlgs.dt, 1e-3);
  EXPECT_EQ(ensemble_probe_settings(p, in, "cd").nlgs.dt, std::sqrt(2e-9 / kQuasiStaticInertia));
}

TEST(EnsembleRun, CdProbesAreThePapersProbeInsideTheirIntervals) {
  // --probe cd, the default up to 200 contacts: the exact step on every force-carrying
  // contact, as `unjam probe --method cd` gives it (the same F_crit bit for bit), inside the
  // contact's LP interval up to the step's inertia at the quasi-static dt, and near its top at
  // 50 disks, mu = 0.1 (measured: F_crit / fn_max median 0.993, min 0.946; t median 0.991, 44
  // of 81 at t >= 0.99; docs/probe.md, "Where F_crit lies in the admissible interval").
  const Packing& p = fixture_p50();
  EnsembleSettings s = lp_hit_and_run(2);
  s.hit_and_run = false;
  s.probe = "";  // the default up to 200 contacts
  const EnsembleReport r = compute_ensemble(p, s);
  EXPECT_EQ(r.probe, "cd");
  EXPECT_EQ(r.probe_dt, default_probe_dt(ProbeMethod::kCd, s.probe_g));
  EXPECT_EQ(r.unconverged, 0);
  const double F0 = r.system.F0;
  const CampaignSettings cd = ensemble_probe_settings(p, s, "cd");
  int probed = 0;
  for (int k = 0; k < r.system.num_contacts(); ++k) {
    if (!r.probes[k]) continue;
    ++probed;
    const double f = r.probes[k]->f_crit;
    EXPECT_GE(f, r.bounds.fn_min[k] - 1e-4 * F0) << "contact " << k;
    EXPECT_LE(f, r.bounds.fn_max[k] + 1e-4 * F0) << "contact " << k;
    if (probed % 20 == 1) EXPECT_EQ(probe_contact(p, cd, r.system.contacts[k]).f_crit, f) << "contact " << k;
  }
  EXPECT_EQ(probed, 81);
  ASSERT_EQ(static_cast<int>(r.f_crit_position.size()), 81);
  EXPECT_GT(quantile(r.f_crit_over_fn_max, 0.5), 0.98);
  EXPECT_LT(quantile(r.f_crit_over_fn_max, 0.5), 1.0);
  EXPECT_GT(quantile(r.f_crit_position, 0.5), 0.98);
  EXPECT_EQ(r.below_f_cont, 0);

  s.probe = "nlgs-fast";
  EXPECT_THROW(compute_ensemble(p, s), Error);
}

TEST(EnsembleRun, NoProbeAndQuantiles) {
  EnsembleSettings s = lp_hit_and_run(2);
  s.probe = "none";
  s.hit_and_run = false;
  s.walk = false;
  const EnsembleReport r = compute_ensemble(fixture_p50(), s);
  EXPECT_EQ(r.probe, "none");
  EXPECT_TRUE(r.probes.empty());
  EXPECT_TRUE(r.f_crit_over_fn_max.empty());
  EXPECT_FALSE(r.hit_and_run || r.walk);
  EXPECT_EQ(r.bounds.fn_max.size(), r.system.num_contacts());
  // Linear interpolation between order statistics.
  EXPECT_EQ(quantile({3.0, 1.0, 2.0}, 0.0), 1.0);
  EXPECT_EQ(quantile({3.0, 1.0, 2.0}, 0.5), 2.0);
  EXPECT_EQ(quantile({3.0, 1.0, 2.0, 4.0}, 0.5), 2.5);
  EXPECT_EQ(quantile({3.0, 1.0, 2.0}, 1.0), 3.0);
  // F_crit / fn_max's summary: quantiles, and the ratios within 1, 2 and 5 % of 1.
  const CriticalForceRatio c = critical_force_ratio({1.0, 0.995, 1.015, 0.96, 0.5});
  EXPECT_EQ(c.min, 0.5);
  EXPECT_EQ(c.median, 0.995);
  EXPECT_EQ(c.max, 1.015);
  EXPECT_EQ(c.within_1_percent, 2);
  EXPECT_EQ(c.within_2_percent, 3);
  EXPECT_EQ(c.within_5_percent, 4);
}

TEST(EnsembleRun, ShouldStopCancelsEachStageAndANeverStoppingPollChangesNothing) {
  // EnsembleSettings::should_stop is polled by the LPs, after every sample of both samplers and
  // by the probes: answering true at its n-th call (n = 1: during the LPs; later: the samplers,
  // then the probes) throws Cancelled; a poll that never stops leaves every number as it was.
  const Packing& p = fixture_p50();
  EnsembleSettings s = lp_hit_and_run(1);
  s.walk = true;
  s.samples = 20;
  const EnsembleReport whole = compute_ensemble(p, s);
  long long polls = 0;
  s.should_stop = [&polls] { return ++polls < 0; };  // never
  const EnsembleReport polled = compute_ensemble(p, s);
  EXPECT_GE(polls, 40) << "polled after each of the 20 + 20 samples at least";
  EXPECT_EQ(polled.bounds.fn_max, whole.bounds.fn_max);
  EXPECT_EQ(polled.hr_columns->mean, whole.hr_columns->mean);
  EXPECT_EQ(polled.walk_columns->mean, whole.walk_columns->mean);
  EXPECT_EQ(polled.f_crit_over_fn_max, whole.f_crit_over_fn_max);
  for (const long long n : {1LL, polls / 2, polls}) {
    long long calls = 0;
    s.should_stop = [&calls, n] { return ++calls >= n; };
    EXPECT_THROW(compute_ensemble(p, s), Cancelled) << "stopped at poll " << n << " of " << polls;
    // Nothing runs after the stop; the LPs' second phase polls once more, handing out nothing.
    EXPECT_LE(calls, n + 1) << "polled on after the stop";
  }
}

}  // namespace
}  // namespace unjam
