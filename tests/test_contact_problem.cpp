// The one contact problem (contact/contact_problem.hpp; docs/method.md, "Which contacts
// count"): every solver of the probe step, and every static solver's networks (the unshifted
// step), are checked by the same residual, step_residual, and every consumer classifies the
// same contacts as touching from the same ContactProblem.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "unjam/campaign/ensemble_run.hpp"
#include "unjam/contact/contact_problem.hpp"
#include "unjam/contact/equilibrium_matrix.hpp"
#include "unjam/core/error.hpp"
#include "unjam/ensemble/hit_and_run.hpp"
#include "unjam/ensemble/random_walk.hpp"
#include "unjam/lp/force_lp.hpp"
#include "unjam/packing/packing_io.hpp"
#include "unjam/probe/cd_path.hpp"
#include "unjam/probe/cd_step.hpp"
#include "unjam/probe/kinematic_probe.hpp"
#include "unjam/probe/nlgs_probe.hpp"
#include "unjam/probe/probe_campaign.hpp"
#include "unjam/solver/force_polish.hpp"
#include "unjam/solver/step_problem.hpp"

namespace unjam {
namespace {

Packing fixture(const std::string& name) {
  return read_packing(std::string(UNJAM_FIXTURES_DIR) + "/" + name);
}

// The packing's own contact problem, as `unjam probe` builds it (campaign_settings_for).
ContactProblem own_problem(const Packing& p) {
  const ProbeSettings s = campaign_settings_for(p).nlgs;
  return build_contact_problem(p, contact_model_of(p, s.model), s.dt);
}

// An NLGS solution, converged on velocity changes of 1e-6 g / dt, leaves a residual of this
// (units of g and F0) in the step (measured on p50-mu0.1, contact 1: 1.2e-6, against 1e-12 for the
// exact path).
constexpr double kNlgsStepResidual = 1e-5;

TEST(StepResidual, NlgsAndTheExactPathSolveTheSameProbeStep) {
  const Packing p = fixture("p50-mu0.1");
  const ProbeSettings set = campaign_settings_for(p).nlgs;
  const int contact = 1;
  const CdStepProblem step = build_cd_step(p, contact, set);
  const CdStepSolution exact = probe_cd_path(p, contact, set);
  Eigen::VectorXd f_nlgs;
  const ProbeResult nlgs = probe_nlgs(p, contact, set, f_nlgs);
  ASSERT_TRUE(exact.result.converged);
  ASSERT_TRUE(nlgs.converged);
  ASSERT_EQ(f_nlgs.size(), 2 * step.num_contacts());
  EXPECT_EQ(f_nlgs[2 * contact], nlgs.f_crit);

  const StepResidual r_exact = step_residual(step, exact.f, set.g);
  const StepResidual r_nlgs = step_residual(step, f_nlgs, set.g);
  EXPECT_LE(r_exact.max(), kExactStepTolerance);
  EXPECT_LE(r_nlgs.max(), kNlgsStepResidual);
  EXPECT_EQ(cd_step_residual(step, exact.f).max(), r_exact.max()) << "cd_step_residual is step_residual in units of g";
  EXPECT_NEAR(nlgs.f_crit / exact.result.f_crit, 1.0, 1e-5);

  // A 1e-3 F0 change of the probed contact's normal force moves grains by ~1e-3 dt^2 / m,
  // far above the solutions' residuals; a loaded contact's force outside the cone breaks
  // Coulomb's law.
  const double F0 = p.force_unit();
  for (const Eigen::VectorXd* f : std::initializer_list<const Eigen::VectorXd*>{&exact.f, &f_nlgs}) {
    Eigen::VectorXd bad = *f;
    bad[2 * contact] += 1e-3 * F0;
    EXPECT_GT(step_residual(step, bad, set.g).max(), 100.0 * kNlgsStepResidual);
    bad = *f;
    int loaded = -1;
    for (int k = 0; k < step.num_contacts() && loaded < 0; ++k)
      if (k != contact && bad[2 * k] > 0.1 * F0) loaded = k;
    ASSERT_GE(loaded, 0);
    bad[2 * loaded + 1] = p.meta.contact.mu * bad[2 * loaded] + 0.1 * F0;  // 0.1 F0 outside the cone
    EXPECT_GT(step_residual(step, bad, set.g).coulomb, 0.05);
  }
}

TEST(ContactProblem, EveryConsumerSeesTheSameTouchingContacts) {
  // The fixture's contacts, with one pushed just beyond the touch gap, one exactly at it (the
  // rule is gap < touch_gap: not touching) and one just inside, so that the classification has
  // both answers near its boundary. Their forces stay, so the network stays admissible.
  Packing p = fixture("p50-mu0.1");
  const CampaignSettings cs = campaign_settings_for(p);
  const double touch_gap = cs.nlgs.model->touch_gap;
  ASSERT_GT(p.contacts.size(), 10u);
  const int probed = 1;
  p.contacts[3].gap = 2.0 * touch_gap;
  p.contacts[5].gap = touch_gap;
  p.contacts[7].gap = 0.5 * touch_gap;

  const ContactProblem cp = own_problem(p);
  ASSERT_EQ(cp.num_contacts(), static_cast<int>(p.contacts.size()));
  std::vector<int> touching, admissible;
  const double fn_tol_F0 = 1e-9;
  for (int k = 0; k < cp.num_contacts(); ++k) {
    EXPECT_EQ(cp.state[k].touching, p.contacts[k].gap < touch_gap) << "contact " << k;
    EXPECT_EQ(cp.g_eff[k], cp.state[k].touching ? 0.0 : p.contacts[k].gap) << "contact " << k;
    if (cp.state[k].touching) touching.push_back(k);
    if (cp.state[k].touching || p.contacts[k].fn > fn_tol_F0 * cp.system.F0) admissible.push_back(k);
  }
  EXPECT_FALSE(cp.state[3].touching);
  EXPECT_FALSE(cp.state[5].touching);
  EXPECT_TRUE(cp.state[7].touching);

  // The static solve's step (solver/static_solve) and the NLGS probe's step.
  EXPECT_EQ(touching_gaps(p.contacts, touch_gap), std::vector<double>(cp.g_eff.data(), cp.g_eff.data() + cp.g_eff.size()));
  const StepProblem nlgs = step_problem(cp);
  ASSERT_EQ(nlgs.g_eff.size(), p.contacts.size());
  for (int k = 0; k < cp.num_contacts(); ++k) EXPECT_EQ(nlgs.g_eff[k], cp.g_eff[k]) << "contact " << k;
  EXPECT_EQ(nlgs.mu, cp.model.mu);
  EXPECT_EQ(nlgs.bath.P_ext, cp.model.P_ext);
  EXPECT_EQ(nlgs.bath.M_lambda, cp.model.M_lambda);

  // The exact step (cd path, Lemke): the same problem, the probed contact shifted to -g.
  const CdStepProblem cd = build_cd_step(p, probed, cs.nlgs);
  for (int k = 0; k < cp.num_contacts(); ++k)
    EXPECT_EQ(cd.g_eff[k], k == probed ? -cs.nlgs.g : cp.g_eff[k]) << "contact " << k;
  EXPECT_EQ(cd.system.contacts, cp.system.contacts);
  EXPECT_EQ(cd.inverse_mass, cp.inverse_mass);
  EXPECT_EQ(cd.system.rhs, cp.system.rhs);

  // The kinematic probe and the LP bounds: the admissible set is every touching or loaded
  // contact, by the same rule (select_contacts); without the loaded ones, the touching set.
  const KinematicProbe kinematic(p, cs.kinematic);
  EXPECT_EQ(kinematic.system().contacts, admissible);
  EXPECT_EQ(select_contacts(p, touch_gap, fn_tol_F0), admissible);
  EXPECT_EQ(select_contacts(p, touch_gap, std::numeric_limits<double>::infinity()), touching);
}

TEST(ContactProblem, ThePolishAndTheKinematicProbeShareOneContactState) {
  // The one state of a contact in a network, contact_state (packing/contact.hpp): the polish's
  // active set (solver/force_polish) and the kinematic probe's held displacements
  // (probe/kinematic_probe) both come from it, and the polish's contacts are the ones the
  // ContactProblem marks touching and loaded.
  int slid = 0;  // sliding contacts of the polished networks (p500-mu0.1's: 96, the others' none)
  for (const char* name : {"p50-mu0.1", "p50-mu1", "p200-mu1", "p500-mu0.1"}) {
    SCOPED_TRACE(name);
    const Packing p = fixture(name);
    const double mu = p.meta.contact.mu;
    const ContactProblem cp = own_problem(p);

    // The polish of the packing's static network, under the packing's own model.
    Packing polished = p;
    const PolishResult pol = polish_forces(polished, 1e-9, p.meta.contact);
    ASSERT_TRUE(pol.success);
    ASSERT_EQ(pol.states.size(), p.contacts.size());
    ForceNetwork net{Eigen::VectorXd(cp.num_contacts()), Eigen::VectorXd(cp.num_contacts())};
    for (int k = 0; k < cp.num_contacts(); ++k) {
      net.fn[k] = polished.contacts[k].fn;
      net.ft[k] = polished.contacts[k].ft;
    }
    const std::vector<ContactState> of_network = contact_states(net, mu, 0.0);
    int closed = 0, sliding = 0;
    for (int k = 0; k < cp.num_contacts(); ++k) {
      // The same state, but for a closed contact on the boundary (the polish keeps it closed).
      const bool boundary = pol.states[k] == ContactState::closed &&
                            (net.fn[k] == 0.0 || std::abs(net.ft[k]) == mu * net.fn[k]);
      if (!boundary) EXPECT_EQ(pol.states[k], of_network[k]) << "contact " << k;
      if (pol.states[k] == ContactState::open) {
        EXPECT_EQ(net.fn[k], 0.0);
        EXPECT_EQ(net.ft[k], 0.0);
      }
      if (pol.states[k] != ContactState::open) {
        EXPECT_TRUE(cp.state[k].touching && cp.state[k].loaded) << "contact " << k;
      }
      closed += pol.states[k] == ContactState::closed;
      sliding += pol.states[k] == ContactState::sliding;
    }
    EXPECT_GT(closed, 0);
    slid += sliding;
    EXPECT_EQ(pol.active, closed + sliding);

    // The kinematic probe's field holds what contact_state says of the LP optimum: U_n = 0
    // for closed and sliding contacts, U_t = 0 for closed ones, U_n = g for the probed one,
    // and, converged, no open contact closes and no sliding one slips along its force.
    const CampaignSettings cs = campaign_settings_for(p);
    KinematicProbe kinematic(p, cs.kinematic);
    const EquilibriumSystem& sys = kinematic.system();
    const double g = cs.kinematic.g, slack = 1e-6 * g;
    int probes = 0;
    for (int kc = 0; kc < sys.num_contacts() && probes < 6; kc += 7, ++probes) {
      const ProbeResult r = kinematic.probe(sys.contacts[kc]);
      ASSERT_TRUE(r.converged) << "contact " << sys.contacts[kc];
      // Held rows hold to the field's equality residual (r.residual, units of g); a contact
      // held after breaking its condition (an open one closing, a sliding one slipping along
      // its force) then meets it to the same tolerance.
      const double held = std::max(slack, 1.01 * r.residual * g);
      Eigen::VectorXd q(sys.A.rows());
      for (std::size_t i = 0; i < sys.grains.size(); ++i) {
        const int grain = sys.grains[i];
        q[3 * i] = r.u[grain].x();
        q[3 * i + 1] = r.u[grain].y();
        q[3 * i + 2] = r.u_rot[grain] * p.particles.radius[grain];
      }
      q[sys.pressure_row()] = r.lambda_dt;
      const Eigen::VectorXd U = sys.A.transpose() * q;
      const ForceNetwork opt = kinematic.network();
      const auto state = contact_states(opt, sys.mu, cs.kinematic.state_tol * sys.F0);
      for (int k = 0; k < sys.num_contacts(); ++k) {
        const double un = U[2 * k], ut = U[2 * k + 1];
        if (k == kc) {
          EXPECT_NEAR(un, g, held) << "probed contact " << sys.contacts[k];
        } else if (state[k] == ContactState::open) {
          EXPECT_GE(un, -held) << "open contact " << sys.contacts[k] << " closes";
        } else {
          EXPECT_NEAR(un, 0.0, held) << "contact " << sys.contacts[k] << " not held";
        }
        if (k != kc && state[k] == ContactState::closed && mu > 0.0) {
          EXPECT_NEAR(ut, 0.0, held) << "closed contact " << sys.contacts[k] << " slips";
        }
        if (k != kc && state[k] == ContactState::sliding) {
          EXPECT_LE(ut * opt.ft[k], held * std::abs(opt.ft[k])) << "contact " << sys.contacts[k];
        }
      }
    }
    EXPECT_GT(probes, 0);
  }
  EXPECT_GT(slid, 0) << "both answers of contact_state are compared";
}

TEST(ContactProblem, ProbeSettingsCarryThePackingsContactModel) {
  // Every field of meta.contact away from its default (mu = 1 is the fixture's), so that a
  // field taken from anywhere else shows.
  Packing p = fixture("p50-mu1");
  p.meta.contact = {1.0, 1.5, 0.25, 3e-6};
  const CampaignSettings cs = campaign_settings_for(p);
  ASSERT_TRUE(cs.nlgs.model && cs.kinematic.model);
  EXPECT_EQ(*cs.nlgs.model, p.meta.contact);
  EXPECT_EQ(*cs.kinematic.model, p.meta.contact);
  EXPECT_EQ(contact_model_of(p, std::nullopt), p.meta.contact);

  // The summary records the method's model; settings without one are refused.
  for (const ProbeMethod method : {ProbeMethod::kLp, ProbeMethod::kCd, ProbeMethod::kNlgs}) {
    CampaignSettings s = cs;
    s.method = method;
    const nlohmann::json j = to_json(s);
    EXPECT_EQ(j.at("touch_gap").get<double>(), 3e-6);
    EXPECT_EQ(j.at("M_lambda").get<double>(), 0.25);
    s.nlgs.model.reset();
    s.kinematic.model.reset();
    EXPECT_THROW(to_json(s), Error);
  }

  // The exact step and the fast probe are built from that model: its mu, F0 = 2 R_avg P_ext,
  // pressure row 2 V P_ext and cell mass 2 V M_lambda.
  const CdStepProblem step = build_cd_step(p, 1, cs.nlgs);
  EXPECT_EQ(step.model, p.meta.contact);
  const KinematicProbe kinematic(p, cs.kinematic);
  const EquilibriumSystem& sys = kinematic.system();
  const double V = p.cell.area();
  EXPECT_EQ(sys.mu, 1.0);
  EXPECT_EQ(sys.F0, 2.0 * p.mean_radius() * 1.5);
  EXPECT_EQ(sys.rhs[sys.pressure_row()], 2.0 * V * 1.5);
  EXPECT_EQ(step.inverse_mass[step.system.pressure_row()], 1.0 / (2.0 * V * 0.25));
  EXPECT_EQ(inverse_masses(p, sys, p.meta.contact)[sys.pressure_row()], 1.0 / (2.0 * V * 0.25));
}

TEST(StepResidual, StaticNetworksSolveTheUnshiftedStep) {
  // A static network f0 balances every grain and the pressure (A f0 = b), so q = 0 and
  // u = g_eff: it solves the packing's own step without a probe (docs/probe.md, "The exact
  // step"). The same residual checks every static solver's networks: the packing's own (NLGS
  // and the polish), the LP's optima, hit-and-run's and the random walk's samples (set on the
  // contacts of the admissible set, zero elsewhere); lengths in units of the probe's opening
  // g, forces in F0.
  const Packing p = fixture("p50-mu0.1");
  const ContactProblem pb = own_problem(p);
  const double g = campaign_settings_for(p).nlgs.g;
  const EquilibriumSystem sys = admissible_system(p, ensemble_contact_model(p, {}));
  const auto on_problem = [&](const ForceNetwork& net) {
    Eigen::VectorXd f = Eigen::VectorXd::Zero(2 * pb.num_contacts());
    for (int k = 0; k < sys.num_contacts(); ++k) {
      f[2 * sys.contacts[k]] = net.fn[k];
      f[2 * sys.contacts[k] + 1] = net.ft[k];
    }
    return step_residual(pb, f, g).max();
  };
  // Bounds in units of g (measured: the packing's own 4.5e-9, LP 4.1e-7 over every tenth
  // contact's max, hit-and-run 1.2e-11, walk 1.8e-12): polished networks balance to
  // round-off, the barrier's optima to CLP's feasibility tolerance (1e-9, ForceLP).
  constexpr double kStatic = 1e-8, kLp = 1e-6;
  const double own = step_residual(pb, packing_forces(p, pb.system), g).max();
  EXPECT_LE(own, kStatic);

  ForceLP lp(sys);
  double worst_lp = 0.0;
  for (int k = 0; k < sys.num_contacts(); k += 10) {
    lp.max_fn(k);
    worst_lp = std::max(worst_lp, on_problem(lp.network()));
  }
  const ForceBounds bounds = compute_force_bounds(sys, {});
  double worst_hr = 0.0, worst_walk = 0.0;
  HitAndRunOptions hr;
  hr.samples = 50;
  hr.on_sample = [&](const ForceNetwork& net) { worst_hr = std::max(worst_hr, on_problem(net)); };
  sample_hit_and_run(sys, bounds, hr);
  RandomWalkOptions walk;
  walk.samples = 20;
  walk.model = ensemble_contact_model(p, {});
  walk.on_sample = [&](const ForceNetwork& net) { worst_walk = std::max(worst_walk, on_problem(net)); };
  sample_random_walk(p, sys, walk);
  std::printf("[ step ] p50-mu0.1, static networks' step residual: own %.3g, LP %.3g, "
              "hit-and-run %.3g, walk %.3g\n", own, worst_lp, worst_hr, worst_walk);
  EXPECT_LE(worst_lp, kLp);
  EXPECT_LE(worst_hr, kStatic);
  EXPECT_LE(worst_walk, kStatic);

  // A network off balance by 1e-3 F0 on one contact moves grains: it fails the residual.
  Eigen::VectorXd bad = packing_forces(p, pb.system);
  bad[2 * sys.contacts[0]] += 1e-3 * p.force_unit();
  EXPECT_GT(step_residual(pb, bad, g).max(), 1e3 * kLp);
}

TEST(ContactProblem, TheLpProbesAdmissibleSetIsTheModelsTouchingContacts) {
  // p50-mu1 (80 contacts, counted from contacts.csv): 56 have gap < 1e-6 (its touch gap), all
  // of them loaded; the other 24 carry no force, 15 of them with gap < 1e-3.
  const Packing p = fixture("p50-mu1");
  ASSERT_EQ(p.contacts.size(), 80u);
  const ContactModel own = campaign_settings_for(p).kinematic.model.value();
  for (const auto& [touch_gap, expected] : {std::pair{own.touch_gap, 56}, std::pair{1e-3, 71}}) {
    const ContactModel model = with_touch_gap(own, touch_gap);
    std::vector<int> touching;
    for (int k = 0; k < static_cast<int>(p.contacts.size()); ++k)
      if (classify_contact(p.contacts[k], model.touch_gap, 0.0).touching) touching.push_back(k);
    KinematicProbeSettings ks;
    ks.model = model;
    const KinematicProbe kinematic(p, ks);
    EXPECT_EQ(kinematic.system().num_contacts(), expected) << "touch_gap " << touch_gap;
    EXPECT_EQ(kinematic.system().contacts, touching) << "touch_gap " << touch_gap;
    EXPECT_EQ(admissible_system(p, model).contacts, touching) << "touch_gap " << touch_gap;
  }
  // Without a model the probe takes the packing's own.
  EXPECT_EQ(KinematicProbe(p, {}).system().num_contacts(), 56);
}

TEST(ContactProblem, EnsembleAndProbeGiveTheSameNlgsCriticalForce) {
  // `ensemble --probe nlgs` and `probe --method nlgs` probe with the packing's own contact
  // model: the same F_crit, bit for bit, on every contact both probe. A loose velocity
  // tolerance (both the same; each probe stops after its minimum of 100 sweeps) keeps the
  // ensemble's 81 probes short: the bits still differ for any other touch gap, bath or P_ext.
  const Packing p = fixture("p50-mu0.1");
  EnsembleSettings in;
  in.probe = "nlgs";
  in.hit_and_run = in.walk = false;
  in.threads = 2;
  in.probe_velocity_tol = 1.0;
  const EnsembleReport r = compute_ensemble(p, in);
  CampaignSettings probe = campaign_settings_for(p);
  probe.method = ProbeMethod::kNlgs;
  probe.nlgs.velocity_tol = in.probe_velocity_tol;
  int compared = 0;
  for (int k = 0; k < r.system.num_contacts(); k += 10) {
    if (!r.probes[k]) continue;
    const int contact = r.system.contacts[k];
    const ProbeResult one = probe_contact(p, probe, contact);
    EXPECT_EQ(one.f_crit, r.probes[k]->f_crit) << "contact " << contact;
    EXPECT_EQ(one.sweeps, r.probes[k]->sweeps) << "contact " << contact;
    ++compared;
  }
  EXPECT_GE(compared, 5);
}

}  // namespace
}  // namespace unjam
