"""The report of scripts/experiment.py: measured values per mu, the verdicts against the
paper's findings, parameters, timings and figures (OUT/report.md)."""

import csv
import json
import math
import os
import time

import sweep_table
from experiment_stages import FIG4, cd_options, fmt_mu
from stage_runner import quote


def read_table(path):
    with open(path) as f:
        return list(csv.DictReader(f))


QUANTITIES = [("phi", "phi"), ("z", "z"), ("F_cont_over_F0", "<F_cont>/F0"),
              ("F_crit_over_F_cont", "<F_crit>/<F_cont>"), ("alpha", "alpha")]


def pm(t):
    m, s, n = t
    return "—" if n == 0 else f"{m:.4f} ± {s:.4f}"


def monotonic(vals, sign, tol):
    """vals change monotonically in direction sign (+1 up, -1 down) up to tol."""
    return all(sign * (b - a) >= -tol for a, b in zip(vals, vals[1:]))


def findings(agg, fixed_agg, n_max):
    """[(finding, paper, measured, verdict)] computed from the largest-N numbers."""
    mus = sorted(mu for mu, n in agg if n == n_max)
    col = {c: [agg[(mu, n_max)][c][0] for mu in mus] for c, _ in QUANTITIES}
    out = []
    near = lambda mu: 0.05 <= mu <= 0.2  # noqa: E731  "near mu = 0.1"

    phi = col["phi"]
    ok = (abs(phi[0] - 0.84) <= 0.01 and abs(phi[-1] - 0.80) <= 0.01
          and monotonic(phi, -1, 0.002))
    out.append(("packing fraction", "0.84 at low mu -> 0.80 at high mu, monotonic",
                f"phi = {phi[0]:.4f} at mu = {fmt_mu(mus[0])}, {phi[-1]:.4f} at mu = "
                f"{fmt_mu(mus[-1])}; monotonic: {'yes' if monotonic(phi, -1, 0.002) else 'no'}",
                "agree" if ok else "disagree"))
    for c, label in (("z", "z"), ("F_cont_over_F0", "<F_cont>/F0")):
        v = col[c]
        sign = -1 if v[-1] < v[0] else 1
        mono = monotonic(v, sign, 0.02 * abs(v[0]))
        out.append((f"{label} against mu", "plateaus at low and high mu, smooth monotonic change",
                    f"{label} = {v[0]:.4f} at mu = {fmt_mu(mus[0])} -> {v[-1]:.4f} at mu = "
                    f"{fmt_mu(mus[-1])}; monotonic: {'yes' if mono else 'no'}",
                    "agree" if mono else "disagree"))
    al = [(mu, a) for mu, a in zip(mus, col["alpha"]) if math.isfinite(a)]
    if not al:
        out.append(("alpha", "0.7-1.4, maximum near mu = 0.1",
                    "no power-law fit (the packings are too small for the fit window)",
                    "not measured"))
    else:
        lo, hi = min(a for _, a in al), max(a for _, a in al)
        mu_star = max(al, key=lambda t: t[1])[0]
        ok = lo >= 0.7 and hi <= 1.4 and near(mu_star)
        out.append(("alpha", "0.7-1.4, maximum near mu = 0.1",
                    f"alpha in [{lo:.3f}, {hi:.3f}] over {len(al)} mu; maximum at mu = "
                    f"{fmt_mu(mu_star)}", "agree" if ok else "disagree"))
    fc = col["F_crit_over_F_cont"]
    j = max(range(len(mus)), key=lambda k: fc[k])
    ends = abs(fc[0] - 1) <= 0.1 and abs(fc[-1] - 1) <= 0.1
    out.append(("<F_crit>/<F_cont>", "1 at low and high mu, maximum near mu = 0.1",
                f"maximum of <F_crit>/<F_cont> at mu = {fmt_mu(mus[j])} ({fc[j]:.4f}); "
                f"{fc[0]:.4f} at mu = {fmt_mu(mus[0])}, {fc[-1]:.4f} at mu = {fmt_mu(mus[-1])}",
                "agree" if (ends and near(mus[j])) else "disagree"))
    if fixed_agg:
        fmus = sorted(mu for mu, _ in fixed_agg)
        fv = [fixed_agg[(mu, n)]["F_crit_over_F_cont"][0] for mu, n in sorted(fixed_agg)]
        mono = monotonic(fv, 1, 0.01)
        out.append(("fixed packing, varying mu", "<F_crit>/<F_cont> monotonic (no decrease "
                    "beyond mu ~ 0.1)",
                    f"<F_crit>/<F_cont> = {fv[0]:.4f} at mu = {fmt_mu(fmus[0])} -> {fv[-1]:.4f} "
                    f"at mu = {fmt_mu(fmus[-1])}; monotonic: {'yes' if mono else 'no'}",
                    "agree" if mono else "disagree"))
    return out


def fig4_finding(out):
    """The Fig. 4 finding (F_crit at the top of each admissible interval, 50 disks, mu = 0.1)
    from the ensemble stage's ensemble.json, as a row of findings(); None where the stage did
    not run or did not probe. Agree: the probe is the paper's (nlgs or cd, not the lp stand-in,
    which is fn_max by construction), F_crit / fn_max has a median of at least 0.98 and a
    minimum of at least 0.9."""
    path = os.path.join(out, "fig4", f"N{FIG4['n']}-mu{fmt_mu(FIG4['mu'])}-s{FIG4['seed']}",
                        "ensemble.json")
    try:
        with open(path) as f:
            probe = json.load(f).get("probe", {})
    except (OSError, ValueError):
        return None
    ratio = probe.get("f_crit_over_fn_max")
    if not isinstance(ratio, dict):
        return None
    method, n = probe.get("method"), probe.get("contacts_probed")
    measured = (f"by the {method} probe on {n} contacts: F_crit / fn_max median "
                f"{ratio['median']:.4f}, min {ratio['min']:.4f}; within 2 % of fn_max: "
                f"{ratio['within_2_percent']}")
    t = probe.get("position_in_interval")
    if isinstance(t, dict):
        measured += (f"; place in the interval t median {t['median']:.3f}, "
                     f"{t['at_top']} at t >= 0.99")
    if method == "lp":
        verdict = "not measured (lp is fn_max by construction)"
    else:
        verdict = "agree" if ratio["median"] >= 0.98 and ratio["min"] >= 0.9 else "disagree"
    return (f"F_crit = max of the admissible interval (N = {FIG4['n']}, mu = {FIG4['mu']})",
            "every contact", measured, verdict)


# What each start of the exact probe's path is (`unjam probe --cd-start`; docs/probe.md, "Where
# the path starts", "An interior-point start"), as the report says it; its keys are the
# experiment's --cd-start choices.
START_WORDS = {
    "interior": "the path from an interior-point iterate of the step, lowered to the rigid step, ",
    "compliant": "the rigid limit of stiff contacts followed from the static network, ",
    "static": "the path from the static network, ",
    "inertial": "the step at a tenth of dt followed in dt to the quasi-static one (the limit of vanishing "
                "inertia), ",
    "interior-inertial": "the path from an interior-point iterate of the step, and where it is not exact the "
                         "step at a tenth of dt followed in dt to the quasi-static one, ",
}


def rows_by_mu_and_n(rows):
    """{(mu, N): [rows]} of a per-packing table, in the table's order within each group."""
    groups = {}
    for r in rows:
        key = (round(sweep_table.number(r["mu"]), sweep_table.MU_DIGITS), int(r["N"]))
        groups.setdefault(key, []).append(r)
    return groups


def sampling_error(group, method):
    """sqrt(sum SE_i^2) / n over the packings of a group: the standard error of their mean
    <F_crit>/<F_cont> by `method` from the sampling of the contacts; "—" unless every packing
    has its SE (F_crit_over_F_cont_<method>_err)."""
    errs = [r.get(f"F_crit_over_F_cont_{method}_err") or "" for r in group]
    if not errs or "" in errs:
        return "—"
    return f"{math.sqrt(sum(float(e) ** 2 for e in errs)) / len(errs):.4f}"


def exact_probe_section(path, start, title="The exact probe beside lp", what=""):
    """Report lines comparing the exact probe (cd, from `start`) with lp on the same contacts,
    from OUT/exact-probe.csv or OUT/exact-probe-fixed.csv (none when the table does not exist);
    `what` names the packings before the common explanation."""
    if not os.path.isfile(path):
        return []
    groups = rows_by_mu_and_n(read_table(path))
    mean = lambda g, c: sweep_table.mean_std([sweep_table.number(r[c]) for r in g])  # noqa: E731
    L = ["", "## " + title, "",
         what + "The paper's probe step solved exactly (`--method cd --cd-start " + start + "`: "
         + START_WORDS[start] +
         "docs/probe.md) and the lp stand-in (F_crit = the LP maximum) on the same seeded "
         "contacts of each packing (`" + os.path.basename(path) + "`); mean ± standard deviation "
         "over the seeds. "
         "'sampling error': the standard error of the seeds' mean from the sampling of the "
         "contacts alone, sqrt(sum SE_i^2) / seeds over each packing's own SE_i "
         "(`F_crit_over_F_cont_err` of its summary; docs/probe.md, \"Campaigns\"), lp / cd; the "
         "spread between packings may be larger. "
         "'not exact': residual above 1e-6 g; 'without a solution': above 1e-3 g, left out of "
         "the cd means (the near-exact ones are kept); 'stopped by the budget': cd probes stopped "
         "by `--cd-max-pieces`, which are the hardest ones, so the cd means are those of the "
         "probes solved within it; 'near-exact, accepted': cd probes whose search stopped at their "
         "first solution within `--cd-accept-residual` (counted among the not exact).", "",
         "| mu | N | seeds | probes | not exact | without a solution | <F_crit>/<F_cont> lp | "
         "<F_crit>/<F_cont> cd | sampling error lp / cd | alpha lp | alpha cd | CPU s per cd probe | "
         "stopped by the budget | near-exact, accepted |",
         "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for (mu, n), g in sorted(groups.items()):
        probes = sum(int(r["probes"]) for r in g)
        bad = sum(int(r["not_exact"]) for r in g)
        none = sum(int(r["without_solution"]) for r in g)
        L.append(f"| {fmt_mu(mu)} | {n} | {len(g)} | {probes} | {bad} | {none} | "
                 + " | ".join(pm(mean(g, c)) for c in ("F_crit_over_F_cont_lp",
                                                       "F_crit_over_F_cont_cd"))
                 + f" | {sampling_error(g, 'lp')} / {sampling_error(g, 'cd')} | "
                 + " | ".join(pm(mean(g, c)) for c in ("alpha_lp", "alpha_cd"))
                 + f" | {mean(g, 'cpu_s_per_probe_cd')[0]:.2f} | "
                 + f"{sum(int(r.get('over_budget') or 0) for r in g)} | "
                 + f"{sum(int(r.get('accepted') or 0) for r in g)} |")
    return L


def threshold_section(path):
    """Report lines on the packings' friction thresholds, from OUT/friction-threshold.csv (none
    when the table does not exist: no packing with friction, or --skip threshold)."""
    if not os.path.isfile(path):
        return []
    groups = rows_by_mu_and_n(read_table(path))
    L = ["", "## How much of its friction each packing needs", "",
         "The friction threshold mu_s of each packing (`unjam threshold`; docs/ensemble.md, \"The "
         "friction threshold\"): below mu_s no force network on its contacts balances every grain "
         "and the pressure within the Coulomb cones. With its contacts as they are, the packing "
         "could be held at any friction coefficient from mu_s on, and mu_s / mu is the part of its "
         "own friction it needs: near 1, nearly all of it. Bisection on the LP's feasibility to "
         "1e-3 mu, every verdict checked (a network by its row residuals, an empty set by a "
         "Farkas certificate); mean ± standard deviation over the seeds, and the lowest and "
         "highest packing. From `friction-threshold.csv`.", "",
         "| mu | N | seeds | mu_s / mu | lowest | highest | LPs per packing | LP s per packing |",
         "|---|---|---|---|---|---|---|---|"]
    for (mu, n), g in sorted(groups.items()):
        ratio = [sweep_table.number(r["mu_s_over_mu"]) for r in g]
        lps = sweep_table.mean_std([sweep_table.number(r["lps"]) for r in g])[0]
        secs = sweep_table.mean_std([sweep_table.number(r["lp_seconds"]) for r in g])[0]
        L.append(f"| {fmt_mu(mu)} | {n} | {len(g)} | {pm(sweep_table.mean_std(ratio))} | "
                 f"{min(ratio):.4f} | {max(ratio):.4f} | {lps:.0f} | {secs:.2f} |")
    return L


def pairs(args):
    """[flag, value, flag, value, ...] -> [(flag, value), ...]."""
    return list(zip(args[::2], args[1::2]))


def measured_table(agg):
    """The markdown table of QUANTITIES per (mu, N) of sweep_table.aggregate's AGG, mean ±
    standard deviation over the seeds."""
    L = ["| mu | N | seeds | " + " | ".join(lbl for _, lbl in QUANTITIES) + " |",
         "|---|---|---|" + "---|" * len(QUANTITIES)]
    for (mu, n), a in agg.items():
        L.append(f"| {fmt_mu(mu)} | {n} | {a['seeds']} | "
                 + " | ".join(pm(a[c]) for c, _ in QUANTITIES) + " |")
    return L


def write_report(path, args, cfg, R, figures, command):
    """OUT/report.md from OUT/sweep.csv and OUT/fixed.csv; command: the experiment's command
    line (a list)."""
    out = os.path.dirname(path)
    rows = read_table(os.path.join(out, "sweep.csv"))
    agg = sweep_table.aggregate(rows)
    fixed_path = os.path.join(out, "fixed.csv")
    fixed_agg = sweep_table.aggregate(read_table(fixed_path)) if os.path.isfile(fixed_path) else {}
    n_max = max(cfg["ns"])
    L = ["# unjam experiment report", "",
         f"Scale **{args.scale}**; written {time.strftime('%Y-%m-%d %H:%M:%S')}.", "",
         "## Measured values per mu", "",
         "Mean ± standard deviation over the seeds (0 for one seed); from `sweep.csv`.", ""]
    L += measured_table(agg)
    if fixed_agg:
        L += ["", "Fixed packing (the mu = 0 packing re-relaxed at each mu; `fixed.csv`):", ""]
        L += measured_table(fixed_agg)
    exact_fixed_csv = os.path.join(out, "exact-probe-fixed.csv")
    L += exact_probe_section(os.path.join(out, "exact-probe.csv"), cfg["cd_start"])
    L += exact_probe_section(
        exact_fixed_csv, cfg["cd_start"],
        "The exact probe beside lp on the fixed packing",
        "Fig. 3's inset by both probes: the mu = 0 packing re-relaxed at each mu up to "
        f"{fmt_mu(cfg['cd_fixed_max_mu'])} (`--cd-fixed-max-mu`). ")
    if "threshold" not in (args.skip or []):
        L += threshold_section(os.path.join(out, "friction-threshold.csv"))
    L += ["", f"## Against the paper (findings: docs/results/README.md; measured at N = {n_max})", "",
          "| finding | paper | measured | verdict |", "|---|---|---|---|"]
    fig4 = fig4_finding(out)
    for f, paper, meas, verdict in findings(agg, fixed_agg, n_max) + ([fig4] if fig4 else []):
        L.append(f"| {f} | {paper} | {meas} | **{verdict}** |")
    L += ["", "Criteria: phi within 0.01 of 0.84 / 0.80 and monotonic (tolerance 0.002); z and "
          "<F_cont> monotonic (tolerance 2 %); alpha within [0.7, 1.4] with its maximum at "
          "0.05 <= mu <= 0.2; <F_crit>/<F_cont> within 0.1 of 1 at the ends with its maximum at "
          "0.05 <= mu <= 0.2; fixed packing monotonic (tolerance 0.01); Fig. 4 by the paper's probe "
          "(not the lp stand-in): F_crit / fn_max median >= 0.98 and min >= 0.9.", "",
          "## Figures", ""]
    for title, f in figures:
        rel = os.path.relpath(f, out)
        L.append(f"- {title}: [{rel}]({rel})" if os.path.isfile(f) else f"- {title}: (missing)")
    L += ["", "## Parameters", "",
          f"- scale: {args.scale}",
          f"- mu: {cfg['mus']}", f"- N: {cfg['ns']}", f"- seeds: {cfg['seeds']}",
          f"- probe: lp, g = {args.probe_g:g}, "
          + (f"{cfg['probe_sample']} contacts per packing (seeded subset)" if cfg["probe_sample"]
             else "every force-carrying contact"),
          "- exact probe (cd) beside lp: "
          + (f"{cfg['cd_sample']} contacts per packing of N <= {cfg['cd_max_n']}, "
             f"--cd-start {cfg['cd_start']}"
             + "".join(f", {flag} {value}" for flag, value in pairs(cd_options(cfg)))
             + (f"; also on the fixed series up to mu = {fmt_mu(cfg['cd_fixed_max_mu'])}"
                if os.path.isfile(exact_fixed_csv) else "")
             if cfg["cd_sample"] > 0 else "not run (--cd-sample 0)"),
          f"- Fig. 4: N = {FIG4['n']}, mu = {FIG4['mu']}, seed = {FIG4['seed']}, "
          f"samples = {cfg['samples']}",
          f"- unjam: `{R.unjam}`, version `{R.version}`",
          *([f"- skipped stages (--skip): {', '.join(args.skip)}"] if args.skip else []),
          f"- threads: {args.threads or 'all cores'}"
          + (f" per rank, probe stages over {args.mpi} MPI ranks (`{' '.join(R.launcher)}`)"
             if args.mpi else ""),
          f"- command line: `{quote(command)}`", "",
          "## Timings", "",
          "This run: 'ran' stages were computed now, 'cached' ones were skipped; the last column "
          "is the time the stage took when it was computed (wall, and CPU of its commands; "
          "a stage resumed after a stop counts the resumed part only).", "",
          "| stage | what | this run | s this run | s when computed | CPU s when computed |",
          "|---|---|---|---|---|---|"]
    for name, what, action, dt, dt0, cpu0 in R.timings:
        cpu = "—" if cpu0 is None else f"{cpu0:.1f}"
        L.append(f"| {name} | `{what}` | {action} | {dt:.1f} | {dt0:.1f} | {cpu} |")
    L.append(f"| total | | | {time.time() - R.t0:.1f} | | |")
    with open(path + ".tmp", "w") as f:
        f.write("\n".join(L) + "\n")
    os.replace(path + ".tmp", path)
