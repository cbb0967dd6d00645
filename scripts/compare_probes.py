"""The paper's probe (cd) against the LP maximum fn_max (lp) on the same contacts.

Usage:  /usr/bin/python3 scripts/compare_probes.py CD_DIR LP_DIR [CD_DIR LP_DIR ...]
                     [--out OUT] [--label NAME ...]

Each pair is two campaign directories of `unjam probe` on one packing: the first made with
--method cd (the probe step solved exactly), the second with --method lp (f_crit is fn_max,
the maximum of the admissible interval), normally with the same --sample M --seed S. The
contacts are matched by their index in the packing (column `contact` of probes.csv); forces
are in units of F0 = 2 R_avg P_ext, residuals in units of the probe's opening g.

Rules (per contact of a pair, from the cd run's `residual`):
  solved   the cd step has a solution: residual <= 1e-3 g (a probe without one has residual
           1.8e308); only solved contacts enter the means and the ratios, and of them
           only those that are not inertial (below)
  exact    the cd step solved exactly: residual <= 1e-6 g (`converged` in probes.csv)
  ratio    f_crit(cd) / fn_max(lp), over the solved contacts with fn_max > 0 (a contact with
           fn_max <= 0 has no ratio: a warning says how many)
  inertial a solved contact whose cd step's f_inertia (the largest net force on a grain,
           docs/probe.md, "The inertia of the step") is above the cd campaign's --max-inertia
           (settings.max_inertia_F0 of its summary, in F0): left out of the means and the
           ratios, as the campaign leaves it out of its own; none where it was not set
  error    the standard error of a mean R = sum(x) / sum(f_cont) over the n contacts it
           takes, from the sampling of the contacts (the delta method for a ratio of
           means): SE = sqrt(sum(e^2) / (n (n - 1))) / mean(f_cont), e = x - R f_cont; for
           lp minus cd, x = f_crit(lp) - f_crit(cd) on each contact. It says how far another
           sample of contacts of the same packing would move the mean, not how far another
           packing would (compare the seeds for that).
Contacts probed by only one run of a pair are ignored (a warning gives how many and which).

Outputs, each written atomically (a temporary file, then os.replace), in OUT (default
compare-probes):
  OUT/compare.csv   one row per pair: packing, mu, N, seed (the packing's, from the
                    summaries), label, probes (contacts probed by both), exact, solved,
                    F_crit_over_F_cont_lp and F_crit_over_F_cont_cd (sum of f_crit over the
                    solved contacts / sum of their f_cont, both methods on the same contacts),
                    F_crit_over_F_cont_lp_all (the lp mean over every shared contact, solved
                    or not: with the one over the solved, how much leaving the unsolved out
                    moves the stand-in's mean), F_crit_over_F_cont_lp_exact and
                    F_crit_over_F_cont_cd_exact (both means over the exact contacts only:
                    with the ones over the solved, how much the near-exact probes move them),
                    ratio_median, ratio_q1, ratio_q3 (quartiles: statistics.quantiles, n=4),
                    ratio_min, ratio_max, alpha_lp, alpha_lp_err, alpha_cd, alpha_cd_err (the
                    power-law fits of each probe_summary.json; empty where a fit failed),
                    pieces_median (median over the shared contacts of cd's `sweeps`, the
                    pieces of all its paths; of the returned path only in campaigns run
                    before 2026-11-27), cpu_s_per_probe_cd (the mean CPU of the cd
                    campaign's probes, each on its own thread: cpu_per_probe; for a summary
                    written before that was recorded, its busy seconds over all its runs /
                    its timed probes, from all_runs; without all_runs, its ranks'
                    busy_seconds / its probes: scripts/campaign_time.py),
                    inertial (solved contacts
                    left out by --max-inertia), f_inertia_median_F0, f_inertia_max_F0 and
                    f_inertia_max_contact (cd's f_inertia / F0 over the solved contacts
                    that record it; empty for campaigns made before it was recorded),
                    F_crit_over_F_cont_lp_err and F_crit_over_F_cont_cd_err (the standard
                    errors of the two means over the sampled contacts, see below),
                    F_crit_over_F_cont_lp_minus_cd (lp's mean minus cd's) and its standard
                    error F_crit_over_F_cont_lp_minus_cd_err (paired: the same contacts)
  OUT/ratios.csv    one row per shared contact and pair: packing, mu, N, seed, contact,
                    f_cont, f_crit_lp (fn_max), f_crit_cd, ratio (empty where there is none),
                    residual_cd, exact (0/1), solved (0/1), f_inertia_cd (in F0; empty
                    where it is not recorded), inertial (0/1)
  OUT/compare.md    the per-pair table in Markdown, with the command that made it and the
                    program version of the campaigns, and a second table of both means over
                    every probe, the solved ones and the exact ones
  OUT/compare.json  the command, the campaigns (directories, commands, program versions),
                    the rules and the per-pair numbers (NaN as null)
  OUT/ratio-distribution.png
                    the empirical cumulative distribution of f_crit(cd) / fn_max, one curve
                    per pair (labelled by mu, N and seed, or by --label), a line at 1
  OUT/friction.png  <F_crit>/<F_cont> and alpha by both methods against mu (the paper's
                    Fig. 3 by both probes), one colour per N, a marker per packing, lines
                    through the means over the seeds
A short table is printed to stdout.

Nothing is written unless every pair is read and checked: each directory must hold a
readable probes.csv and probe_summary.json; the first of a pair must be a cd campaign and
the second an lp one; both must come from the same packing (`packing`, and N, mu and seed
where both summaries have them; a shared contact must join the same grains with the same
f_cont); a pair must share at least one contact.
Exit codes: 0 done, 1 bad input or command line (the message is printed, no traceback).
"""

import json
import math
import os
import shlex
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from campaign_time import cpu_per_probe  # noqa: E402
from plot_exact_sweep import friction_figure  # noqa: E402
from unjam_plot import (ArgumentParser, UserError, csv_text, json_number, json_value, read_csv,  # noqa: E402
                        read_json, require_dir, run_main, save_figure, warn,
                        write_file_atomic)

# Residual of the cd step (units of g) up to which it has a solution, and is exact.
SOLVED_RESIDUAL = 1e-3
EXACT_RESIDUAL = 1e-6
# f_cont of one contact in the two runs of a pair (units of F0): the same packing gives the
# same bits; a relative difference above this means two different packings.
F_CONT_REL_TOL = 1e-9

COMPARE_COLUMNS = ["packing", "mu", "N", "seed", "label", "probes", "exact", "solved",
                   "F_crit_over_F_cont_lp", "F_crit_over_F_cont_cd", "ratio_median", "ratio_q1",
                   "ratio_q3", "ratio_min", "ratio_max", "alpha_lp", "alpha_lp_err", "alpha_cd",
                   "alpha_cd_err", "pieces_median", "cpu_s_per_probe_cd", "inertial",
                   "f_inertia_median_F0", "f_inertia_max_F0", "f_inertia_max_contact",
                   "F_crit_over_F_cont_lp_all", "F_crit_over_F_cont_lp_exact",
                   "F_crit_over_F_cont_cd_exact", "F_crit_over_F_cont_lp_err",
                   "F_crit_over_F_cont_cd_err", "F_crit_over_F_cont_lp_minus_cd",
                   "F_crit_over_F_cont_lp_minus_cd_err"]
RATIO_COLUMNS = ["packing", "mu", "N", "seed", "contact", "f_cont", "f_crit_lp", "f_crit_cd",
                 "ratio", "residual_cd", "exact", "solved", "f_inertia_cd", "inertial"]


def parse(argv):
    ap = ArgumentParser(prog="compare_probes.py", description=__doc__.split("\n")[0])
    ap.add_argument("dirs", nargs="+", metavar="CD_DIR LP_DIR",
                    help="pairs of probe campaign directories: cd first, lp second")
    ap.add_argument("--out", default="compare-probes",
                    help="output directory (default: compare-probes)")
    ap.add_argument("--label", nargs="+", action="extend", default=[],
                    help="a name per pair for the table and the figure (default: mu, N, seed)")
    a = ap.parse_args(argv)
    if len(a.dirs) % 2 != 0:
        raise UserError(f"{len(a.dirs)} directories: expected pairs CD_DIR LP_DIR (an even "
                        f"number)")
    if a.label and len(a.label) != len(a.dirs) // 2:
        raise UserError(f"{len(a.label)} labels for {len(a.dirs) // 2} pairs: give one "
                        f"--label per pair or none")
    return a


# ---------------------------------------------------------------------------------------
# Reading


def _optional_number(campaign, key):
    """The campaign summary's number `key`, NaN where it is missing or null (a failed fit)."""
    return json_number(campaign["summary"], key, campaign["summary_path"], required=False,
                       default=math.nan)


def _integer_column(t, name, path):
    v = t[name]
    if any(x != round(x) for x in v):
        raise UserError(f"{path}: column '{name}' holds a value that is not an integer")
    return [int(x) for x in v]


def read_campaign(directory, method, pairs="CD_DIR LP_DIR: cd first, lp second"):
    """A probe campaign: {dir, summary, rows: {contact: row dict}} checked to be of method;
    `pairs` says in its error what the command line pairs."""
    require_dir(directory)
    spath = os.path.join(directory, "probe_summary.json")
    summary = read_json(spath)
    got = summary.get("method")
    if got != method:
        raise UserError(f"{directory}: a campaign of method {got!r}, expected {method!r} "
                        f"(each pair is {pairs})")
    if not isinstance(summary.get("packing"), str) or not summary["packing"]:
        raise UserError(f"{spath}: missing 'packing'")
    ppath = os.path.join(directory, "probes.csv")
    t = read_csv(ppath, ["contact", "a", "b", "f_cont", "f_crit", "sweeps", "residual"],
                 optional=["f_inertia"], text=["method"], allow_nan=["f_crit", "f_inertia"],
                 min_rows=1)
    if "method" not in t:
        raise UserError(f"{ppath}: missing column 'method'")
    if any(m != method for m in t["method"]):
        bad = sorted(set(m for m in t["method"] if m != method))
        raise UserError(f"{ppath}: rows of method {', '.join(repr(m) for m in bad)} in a "
                        f"campaign of method {method!r}")
    partial = partial_count(summary)
    if partial:
        warn(f"{directory}: a partial campaign ({partial}, written by `unjam probe --partial` "
             f"from its checkpoint)")
    contact = _integer_column(t, "contact", ppath)
    a = _integer_column(t, "a", ppath)
    b = _integer_column(t, "b", ppath)
    sweeps = _integer_column(t, "sweeps", ppath)
    f_inertia = t["f_inertia"] if "f_inertia" in t else [math.nan] * len(contact)
    rows = {}
    for i, k in enumerate(contact):
        if k in rows:
            raise UserError(f"{ppath}: contact {k} appears twice")
        if t["residual"][i] < 0:
            raise UserError(f"{ppath}: contact {k} has a negative residual")
        rows[k] = {"a": a[i], "b": b[i], "f_cont": float(t["f_cont"][i]),
                   "f_crit": float(t["f_crit"][i]), "sweeps": sweeps[i],
                   "residual": float(t["residual"][i]), "f_inertia": float(f_inertia[i])}
    return {"dir": directory, "summary": summary, "summary_path": spath, "rows": rows}


def partial_count(summary):
    """'N of M probes' of a campaign written by `unjam probe --partial`, None for a finished one."""
    partial = summary.get("partial")
    if not isinstance(partial, dict):
        return None
    return f"{partial.get('probes_done')} of {partial.get('probes_planned')} probes"


def max_inertia_F0(campaign):
    """The campaign's --max-inertia in F0 (settings.max_inertia_F0), 0 where it was not set."""
    settings = campaign["summary"].get("settings")
    v = settings.get("max_inertia_F0", 0.0) if isinstance(settings, dict) else 0.0
    if not isinstance(v, (int, float)) or isinstance(v, bool) or not v >= 0:
        raise UserError(f"{campaign['summary_path']}: settings.max_inertia_F0 is not a "
                        f"number >= 0: {v!r}")
    return float(v)


def _same_value(x, y):
    if isinstance(x, (int, float)) and isinstance(y, (int, float)) \
            and not isinstance(x, bool) and not isinstance(y, bool):
        return x == y or abs(x - y) <= 1e-12 * max(abs(x), abs(y))
    return x == y


def check_same_packing(cd, lp):
    """Both runs of a pair made from one packing (UserError naming the difference)."""
    s_cd, s_lp = cd["summary"], lp["summary"]
    where = f"{cd['dir']} and {lp['dir']} come from different packings"
    # The packing as given on each run's command line: a relative path is relative to a
    # directory the summary does not record, so it is compared by its last component only
    # (the packing's numbers and contacts below still have to agree).
    p_cd, p_lp = os.path.normpath(s_cd["packing"]), os.path.normpath(s_lp["packing"])
    both_absolute = os.path.isabs(p_cd) and os.path.isabs(p_lp)
    if (p_cd != p_lp if both_absolute else os.path.basename(p_cd) != os.path.basename(p_lp)):
        raise UserError(f"{where}: packing {s_cd['packing']} and {s_lp['packing']}")
    for key in ("N", "mu", "seed"):
        if key in s_cd and key in s_lp and not _same_value(s_cd[key], s_lp[key]):
            raise UserError(f"{where}: {key} {s_cd[key]} and {s_lp[key]}")
    for k in sorted(set(cd["rows"]) & set(lp["rows"])):
        r, q = cd["rows"][k], lp["rows"][k]
        if (r["a"], r["b"]) != (q["a"], q["b"]):
            raise UserError(f"{where}: contact {k} joins grains {r['a']}-{r['b']} in the cd "
                            f"run and {q['a']}-{q['b']} in the lp run")
        if abs(r["f_cont"] - q["f_cont"]) > F_CONT_REL_TOL * max(abs(r["f_cont"]),
                                                                 abs(q["f_cont"]), 1.0):
            raise UserError(f"{where}: contact {k} carries f_cont {r['f_cont']!r} in the cd "
                            f"run and {q['f_cont']!r} in the lp run")


def _list(contacts, most=10):
    shown = ", ".join(str(k) for k in contacts[:most])
    return shown + (f", ... ({len(contacts) - most} more)" if len(contacts) > most else "")


# ---------------------------------------------------------------------------------------
# The comparison of one pair


def ratio_of_means_err(x, y):
    """The standard error of sum(x) / sum(y) over n paired samples (x_i, y_i), by the delta
    method: sqrt(sum(e^2) / (n (n - 1))) / mean(y), e_i = x_i - R y_i; NaN below 2 samples
    or where sum(y) <= 0."""
    n = len(x)
    if n < 2 or sum(y) <= 0:
        return math.nan
    r = sum(x) / sum(y)
    return math.sqrt(sum((a - r * b) ** 2 for a, b in zip(x, y)) / (n * (n - 1))) / (sum(y) / n)


def compare_pair(cd, lp, label):
    """(the pair's numbers, its ratios.csv rows, the ratios of its solved contacts)."""
    s_cd = cd["summary"]
    name = label or f"pair {cd['dir']} {lp['dir']}"
    shared = sorted(set(cd["rows"]) & set(lp["rows"]))
    if not shared:
        raise UserError(f"{cd['dir']} and {lp['dir']} have no probed contact in common "
                        f"(probe both with the same --sample M --seed S, or --all)")
    for run, other in ((cd, lp), (lp, cd)):
        only = sorted(set(run["rows"]) - set(other["rows"]))
        if only:
            method = run["summary"]["method"]
            warn(f"{name}: {len(only)} contact{'s' if len(only) > 1 else ''} probed only by "
                 f"{method} ({run['dir']}) ignored: {_list(only)}")

    packing = {"packing": s_cd["packing"], "mu": _optional_number(cd, "mu"),
               "N": s_cd.get("N"), "seed": s_cd.get("seed")}
    rows, ratios, no_lp, inertia = [], [], [], []
    cont, crit_cd, crit_lp = [], [], []  # f_cont and both F_crit of the contacts the means take
    # The same sums over every shared contact (lp only) and over the exact ones.
    all_cont = all_lp = exact_cont = exact_cd = exact_lp = 0.0
    n_exact = n_solved = n_inertial = 0
    line = max_inertia_F0(cd)
    F0 = _optional_number(cd, "F0")
    for k in shared:
        r, q = cd["rows"][k], lp["rows"][k]
        solved = r["residual"] <= SOLVED_RESIDUAL
        exact = r["residual"] <= EXACT_RESIDUAL
        f_inertia = r["f_inertia"] / F0 if F0 > 0 else math.nan
        # The campaign's own rule (enters_averages, probe/probe_campaign): NaN stays in.
        inertial = solved and line > 0 and f_inertia > line
        if solved and math.isfinite(f_inertia):
            inertia.append((f_inertia, k))
        ratio = math.nan
        if solved:
            if not math.isfinite(r["f_crit"]):
                raise UserError(f"{cd['dir']}/probes.csv: contact {k} is solved (residual "
                                f"{r['residual']:g} g) but its f_crit is not a number")
            if not math.isfinite(q["f_crit"]):
                raise UserError(f"{lp['dir']}/probes.csv: contact {k}: f_crit is not a number")
            n_solved += 1
            n_exact += exact
            if q["f_crit"] > 0:
                ratio = r["f_crit"] / q["f_crit"]
        if inertial:
            n_inertial += 1
        elif solved:
            cont.append(r["f_cont"])
            crit_cd.append(r["f_crit"])
            crit_lp.append(q["f_crit"])
            if q["f_crit"] > 0:
                ratios.append(ratio)
            else:
                no_lp.append(k)
        if math.isfinite(q["f_crit"]):
            all_cont += r["f_cont"]
            all_lp += q["f_crit"]
        if exact and not inertial:
            exact_cont += r["f_cont"]
            exact_cd += r["f_crit"]
            exact_lp += q["f_crit"]
        rows.append({**packing, "contact": k, "f_cont": r["f_cont"], "f_crit_lp": q["f_crit"],
                     "f_crit_cd": r["f_crit"], "ratio": ratio, "residual_cd": r["residual"],
                     "exact": int(exact), "solved": int(solved), "f_inertia_cd": f_inertia,
                     "inertial": int(inertial)})
    if no_lp:
        warn(f"{name}: {len(no_lp)} solved contact{'s' if len(no_lp) > 1 else ''} with "
             f"fn_max <= 0 left out of the ratios: {_list(no_lp)}")
    if n_solved == 0:
        warn(f"{name}: no shared contact is solved by cd (residual <= {SOLVED_RESIDUAL:g} g): "
             f"no means and no ratios")
    elif n_inertial == n_solved:
        warn(f"{name}: every solved contact is above --max-inertia {line:g} F0: no means and "
             f"no ratios")

    if len(ratios) >= 2:
        q1, _, q3 = statistics.quantiles(ratios, n=4)
    else:
        q1 = q3 = ratios[0] if ratios else math.nan
    sum_cont, sum_cd, sum_lp = sum(cont), sum(crit_cd), sum(crit_lp)
    largest = max(inertia) if inertia else (math.nan, None)  # (f_inertia / F0, contact)
    probes_cd = s_cd.get("probes")
    if not isinstance(probes_cd, int) or isinstance(probes_cd, bool) or probes_cd <= 0:
        probes_cd = len(cd["rows"])
    numbers = {
        **packing, "label": label or "", "probes": len(shared), "exact": n_exact,
        "solved": n_solved,
        "F_crit_over_F_cont_lp": sum_lp / sum_cont if sum_cont > 0 else math.nan,
        "F_crit_over_F_cont_cd": sum_cd / sum_cont if sum_cont > 0 else math.nan,
        "ratio_median": statistics.median(ratios) if ratios else math.nan,
        "ratio_q1": q1, "ratio_q3": q3,
        "ratio_min": min(ratios) if ratios else math.nan,
        "ratio_max": max(ratios) if ratios else math.nan,
        "alpha_lp": _optional_number(lp, "alpha"),
        "alpha_lp_err": _optional_number(lp, "alpha_err"),
        "alpha_cd": _optional_number(cd, "alpha"),
        "alpha_cd_err": _optional_number(cd, "alpha_err"),
        "pieces_median": float(statistics.median(cd["rows"][k]["sweeps"] for k in shared)),
        "cpu_s_per_probe_cd": cpu_per_probe(s_cd, probes_cd),
        "inertial": n_inertial,
        "f_inertia_median_F0": statistics.median(v for v, _ in inertia) if inertia else math.nan,
        "f_inertia_max_F0": largest[0],
        "f_inertia_max_contact": largest[1],
        "F_crit_over_F_cont_lp_all": all_lp / all_cont if all_cont > 0 else math.nan,
        "F_crit_over_F_cont_lp_exact": exact_lp / exact_cont if exact_cont > 0 else math.nan,
        "F_crit_over_F_cont_cd_exact": exact_cd / exact_cont if exact_cont > 0 else math.nan,
        "F_crit_over_F_cont_lp_err": ratio_of_means_err(crit_lp, cont),
        "F_crit_over_F_cont_cd_err": ratio_of_means_err(crit_cd, cont),
        "F_crit_over_F_cont_lp_minus_cd": (sum_lp - sum_cd) / sum_cont if sum_cont > 0 else math.nan,
        "F_crit_over_F_cont_lp_minus_cd_err": ratio_of_means_err([a - b for a, b in zip(crit_lp, crit_cd)], cont),
    }
    return numbers, rows, ratios


# ---------------------------------------------------------------------------------------
# Writing


def write_atomic(path, text):
    """text to path: a temporary file beside it, then os.replace (UserError if it fails)."""
    write_file_atomic(path, lambda f: f.write(text))


def _fixed(v, digits):
    return "–" if v is None or (isinstance(v, float) and not math.isfinite(v)) \
        else f"{v:.{digits}f}"


def _alpha(v, err):
    if not math.isfinite(v):
        return "–"
    return f"{v:.2f} ± {err:.2f}" if math.isfinite(err) else f"{v:.2f}"


def _mean(v, err):
    """A mean with its standard error, "1.234 ± 0.012" (the error left out where there is none)."""
    if not math.isfinite(v):
        return "–"
    return f"{v:.3f} ± {err:.3f}" if math.isfinite(err) else f"{v:.3f}"


def pair_name(p):
    if p["label"]:
        return p["label"]
    mu = f"{p['mu']:g}" if math.isfinite(p["mu"]) else "?"
    parts = [f"mu = {mu}"]
    if p["N"] is not None:
        parts.append(f"N = {p['N']}")
    if p["seed"] is not None:
        parts.append(f"seed {p['seed']}")
    return ", ".join(parts)


TABLE_HEAD = ["pair", "probes", "exact", "solved", "<F_crit>/<F_cont> lp",
              "<F_crit>/<F_cont> cd", "lp - cd", "ratio median [q1, q3]", "ratio min–max",
              "alpha lp", "alpha cd", "pieces", "CPU s/probe cd", "f_inertia/F0 median (max)"]


def table_cells(p):
    solved = str(p["solved"]) + (f" ({p['inertial']} inertial)" if p["inertial"] else "")
    return [pair_name(p), str(p["probes"]), str(p["exact"]), solved,
            _mean(p["F_crit_over_F_cont_lp"], p["F_crit_over_F_cont_lp_err"]),
            _mean(p["F_crit_over_F_cont_cd"], p["F_crit_over_F_cont_cd_err"]),
            _mean(p["F_crit_over_F_cont_lp_minus_cd"], p["F_crit_over_F_cont_lp_minus_cd_err"]),
            f"{_fixed(p['ratio_median'], 3)} [{_fixed(p['ratio_q1'], 3)}, "
            f"{_fixed(p['ratio_q3'], 3)}]",
            f"{_fixed(p['ratio_min'], 3)}–{_fixed(p['ratio_max'], 3)}",
            _alpha(p["alpha_lp"], p["alpha_lp_err"]), _alpha(p["alpha_cd"], p["alpha_cd_err"]),
            f"{p['pieces_median']:g}",
            f"{p['cpu_s_per_probe_cd']:.3g}" if math.isfinite(p["cpu_s_per_probe_cd"]) else "–",
            f"{p['f_inertia_median_F0']:.1e} ({p['f_inertia_max_F0']:.1e})"
            if math.isfinite(p["f_inertia_median_F0"]) else "–"]


SELECTION_HEAD = ["pair", "lp, every probe", "lp, solved", "lp, exact", "cd, solved", "cd, exact"]


def selection_cells(p):
    """<F_crit>/<F_cont> of each method over the probes each mean takes."""
    return [pair_name(p)] + [_fixed(p[k], 3) for k in (
        "F_crit_over_F_cont_lp_all", "F_crit_over_F_cont_lp", "F_crit_over_F_cont_lp_exact",
        "F_crit_over_F_cont_cd", "F_crit_over_F_cont_cd_exact")]


def markdown(pairs, campaigns, command):
    versions = sorted({str(c["summary"].get("program_version", "unknown")) for c in campaigns})
    out = [f"Made by `{command}` from campaigns of unjam {', '.join(versions)}.", "",
           "| " + " | ".join(TABLE_HEAD) + " |",
           "|" + "|".join("---" if i == 0 else "---:" for i in range(len(TABLE_HEAD))) + "|"]
    for p in pairs:
        out.append("| " + " | ".join(table_cells(p)) + " |")
    out += ["",
            f"Contacts probed by both methods; solved: the cd step's residual <= "
            f"{SOLVED_RESIDUAL:g} g, exact: <= {EXACT_RESIDUAL:g} g. <F_crit>/<F_cont>: sums "
            f"over the contacts solved by cd, both methods on the same contacts, ± the standard "
            f"error from the sampling of the contacts (delta method; lp - cd paired on the same "
            f"contacts). ratio: "
            f"F_crit(cd) / fn_max(lp) per solved contact (quartiles: statistics.quantiles, "
            f"n=4). alpha: the power-law fit of each campaign (± its error). pieces: median "
            f"pieces of the cd path. CPU: the cd campaign's busy seconds per probe, over all its "
            f"runs. "
            f"f_inertia: the largest net force on a grain in the cd step, over the solved "
            f"contacts; inertial: solved contacts above the cd campaign's --max-inertia, left "
            f"out of the means and ratios as the campaign leaves them out.", ""]
    out += ["Which probes the means take (the near-exact and unsolved probes' weight in them):", "",
            "| " + " | ".join(SELECTION_HEAD) + " |",
            "|" + "|".join("---" if i == 0 else "---:" for i in range(len(SELECTION_HEAD))) + "|"]
    out += ["| " + " | ".join(selection_cells(p)) + " |" for p in pairs]
    out.append("")
    for i, (p, (cd, lp)) in enumerate(zip(pairs, zip(campaigns[::2], campaigns[1::2])), 1):
        part = [f"{partial_count(c['summary'])} of the {m} campaign so far"
                for m, c in (("cd", cd), ("lp", lp)) if partial_count(c["summary"])]
        out.append(f"{i}. {pair_name(p)}: packing `{p['packing']}`, cd `{cd['dir']}`, "
                   f"lp `{lp['dir']}`" + (f" (partial: {'; '.join(part)})" if part else ""))
    return "\n".join(out) + "\n"


def text_table(pairs):
    rows = [TABLE_HEAD] + [table_cells(p) for p in pairs]
    widths = [max(len(r[i]) for r in rows) for i in range(len(TABLE_HEAD))]
    return "\n".join("  ".join(c.ljust(w) if i == 0 else c.rjust(w)
                               for i, (c, w) in enumerate(zip(r, widths)))
                     for r in rows)


X_MAX = 2.0  # the figure's largest ratio F_crit(cd) / fn_max


def figure(pairs, ratios):
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for p, r in zip(pairs, ratios):
        if not r:
            continue
        x = sorted(r)
        y = [(i + 1) / len(x) for i in range(len(x))]
        ax.step([x[0]] + x, [0.0] + y, where="post",
                label=f"{pair_name(p)} ({len(x)} contacts)")
    ax.axvline(1.0, color="0.4", linestyle="--", linewidth=0.9, label="F_crit(cd) = fn_max")
    ax.set_xlabel("F_crit(cd) / fn_max(lp), per contact (both in units of F0)")
    ax.set_ylabel("fraction of contacts solved by cd with ratio ≤ x")
    ax.set_title("The paper's probe (cd) against the LP maximum fn_max", fontsize=10)
    ax.set_ylim(0.0, 1.02)
    # The axis ends at X_MAX: the few larger ratios (mu = 0: the inertial term on a contact
    # of small F_cont) would squeeze the bulk of the curves; their count is given.
    beyond = sum(1 for r in ratios for v in r if v > X_MAX)
    if beyond:
        ax.set_xlim(0.0, X_MAX)
        ax.text(0.98, 0.03, f"{beyond} ratio(s) above {X_MAX:g} off the axis",
                transform=ax.transAxes, ha="right", va="bottom", fontsize=8)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    return fig


def main():
    a = parse(sys.argv[1:])
    command = shlex.join([os.path.basename(sys.executable), *sys.argv])
    campaigns, pairs, rows, ratios = [], [], [], []
    for i in range(0, len(a.dirs), 2):
        cd = read_campaign(a.dirs[i], "cd")
        lp = read_campaign(a.dirs[i + 1], "lp")
        check_same_packing(cd, lp)
        label = a.label[i // 2] if a.label else None
        numbers, pair_rows, pair_ratios = compare_pair(cd, lp, label)
        campaigns += [cd, lp]
        pairs.append(numbers)
        rows += pair_rows
        ratios.append(pair_ratios)

    if os.path.exists(a.out) and not os.path.isdir(a.out):
        raise UserError(f"{a.out}: exists and is not a directory")
    fig = figure(pairs, ratios)
    fig_mu = friction_figure(pairs)
    try:
        os.makedirs(a.out, exist_ok=True)
    except OSError as e:
        raise UserError(f"{a.out}: cannot create the directory: {e.strerror or e}") from None

    record = {
        "command": command,
        "rules": {"solved_residual_g": SOLVED_RESIDUAL, "exact_residual_g": EXACT_RESIDUAL,
                  "ratio": "f_crit(cd) / f_crit(lp) over solved contacts with f_crit(lp) > 0",
                  "quartiles": "statistics.quantiles(n=4)"},
        "pairs": [],
    }
    for p, cd, lp in zip(pairs, campaigns[::2], campaigns[1::2]):
        entry = {k: json_value(p[k]) for k in COMPARE_COLUMNS}
        for role, c in (("cd", cd), ("lp", lp)):
            s = c["summary"]
            entry[role] = {"dir": os.path.abspath(c["dir"]), "command": s.get("command"),
                           "program_version": s.get("program_version"),
                           "settings": s.get("settings"), "probes": s.get("probes")}
        record["pairs"].append(entry)
    record = json_value(record)
    record["program_versions"] = sorted({str(c["summary"].get("program_version", "unknown"))
                                         for c in campaigns})

    write_atomic(os.path.join(a.out, "compare.csv"), csv_text(pairs, COMPARE_COLUMNS))
    write_atomic(os.path.join(a.out, "ratios.csv"), csv_text(rows, RATIO_COLUMNS))
    write_atomic(os.path.join(a.out, "compare.md"), markdown(pairs, campaigns, command))
    write_atomic(os.path.join(a.out, "compare.json"),
                 json.dumps(record, indent=1, sort_keys=True, allow_nan=False) + "\n")
    print(text_table(pairs))
    for name in ("compare.csv", "ratios.csv", "compare.md", "compare.json"):
        print(os.path.join(a.out, name))
    save_figure(fig, os.path.join(a.out, "ratio-distribution.png"))
    save_figure(fig_mu, os.path.join(a.out, "friction.png"))


if __name__ == "__main__":
    run_main(main)
