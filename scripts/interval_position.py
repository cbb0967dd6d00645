"""Where the paper's probe (cd) puts F_crit in each contact's admissible interval.

Usage:  /usr/bin/python3 scripts/interval_position.py CD_DIR BOUNDS [CD_DIR BOUNDS ...]
                     [--out OUT] [--label NAME ...] [--tol REL]

Each pair is a campaign of `unjam probe P --method cd` and the admissible intervals of the
same packing, `unjam bounds P --out BOUNDS` (BOUNDS: the bounds.csv it writes, with
bounds.json beside it). In the quasi-static limit the step's end forces are an admissible
network, so fn_min <= F_crit <= fn_max (docs/probe.md, "The probe"; docs/ensemble.md for the
interval); the paper finds F_crit = fn_max. Forces in units of F0 = 2 R_avg P_ext.

Rules (per probed contact, from the cd run's `residual`, in units of g):
  solved   residual <= 1e-3 (a probe without a solution has 1.8e308); only solved probes
           enter the numbers below
  exact    residual <= 1e-6
  t        (F_crit - fn_min) / (fn_max - fn_min): 0 at the bottom of the interval, 1 at the
           top (the paper's finding); t_cont the same of f_cont. Only where the interval is
           wider than 1e-6 F0 (a contact with a unique force has no t)
  below_f_cont
           F_crit < f_cont: the step opens the contact under less than the force it carries
  zero_force
           F_crit < 1e-3 f_cont: the step opens it with (next to) no force on it
  outside  F_crit below fn_min or above fn_max by more than REL (--tol, default 1e-2) of
           fn_max: not an admissible end state. The inertia of the step m g / dt^2, summed
           over the grains that move, lifts F_crit a little (at the quasi-static dt up to a
           few 1e-3 of it at mu = 0, docs/probe.md, "The quasi-static limit"); the largest
           excess above fn_max and shortfall below fn_min are given whatever the tolerance
The contacts are joined by their grains (a, b) and their force (f_cont = bounds' fn to 1e-9
relative); every probed contact must be in BOUNDS (both made from one packing).

Outputs, each written atomically, in OUT (default interval-position):
  OUT/interval.csv   one row per pair: packing (the last component of the campaign's
                     packing directory; interval.json has the whole commands), mu, N,
                     seed, label, probes (all), then over the solved probes only:
                     solved, exact, below_f_cont, zero_force, outside, t_median, t_q1,
                     t_q3, t_min, t_cont_median, at_top (t >= 0.99), can_open (their
                     contact has fn_min = 0), excess_max (max (F_crit - fn_max) / fn_max),
                     shortfall_max (max (fn_min - F_crit) / fn_max), crit_over_max_median
                     (the median of F_crit / fn_max, as compare_probes.py's ratio_median)
  OUT/positions.csv  one row per probed contact: packing, mu, N, seed, contact, f_cont,
                     fn_min, fn_max, f_crit (all in F0), t, t_cont, residual, solved, exact
  OUT/interval.md    the table in Markdown, with the command
  OUT/interval.json  the command, the inputs (directories, commands, versions), the rules
                     and the per-pair numbers (NaN as null)
  OUT/interval-position.png
                     the empirical cumulative distributions of t (left) and of
                     F_crit / f_cont (right), one curve per pair
Exit codes: 0 done, 1 bad input or command line (the message is printed, no traceback).
"""

import json
import math
import os
import shlex
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from compare_probes import EXACT_RESIDUAL, SOLVED_RESIDUAL, read_campaign  # noqa: E402
from unjam_plot import (ArgumentParser, UserError, csv_text, format_mu,  # noqa: E402
                        json_number, json_value, read_intervals, read_json, run_main, save_figure,
                        warn, write_file_atomic)

F_REL_TOL = 1e-9          # f_cont against bounds' fn of one contact: one packing
MIN_WIDTH_F0 = 1e-6       # narrower intervals have no t
ZERO_FORCE = 1e-3         # F_crit below this fraction of f_cont opens with no force
AT_TOP = 0.99

PAIR_COLUMNS = ["packing", "mu", "N", "seed", "label", "probes", "solved", "exact",
                "below_f_cont", "zero_force", "outside", "t_median", "t_q1", "t_q3", "t_min",
                "t_cont_median", "at_top", "can_open", "excess_max", "shortfall_max",
                "crit_over_max_median"]
POSITION_COLUMNS = ["packing", "mu", "N", "seed", "contact", "f_cont", "fn_min", "fn_max",
                    "f_crit", "t", "t_cont", "residual", "solved", "exact"]


def parse(argv):
    ap = ArgumentParser(prog="interval_position.py", description=__doc__.split("\n")[0])
    ap.add_argument("inputs", nargs="+", metavar="CD_DIR BOUNDS",
                    help="pairs: a cd probe campaign and the packing's bounds.csv")
    ap.add_argument("--out", default="interval-position", help="output directory")
    ap.add_argument("--label", nargs="+", action="extend", default=[],
                    help="a name per pair (default: mu, N, seed)")
    ap.add_argument("--tol", type=float, default=1e-2,
                    help="relative tolerance (of fn_max) of the interval's ends (default 1e-2)")
    a = ap.parse_args(argv)
    if len(a.inputs) % 2 != 0:
        raise UserError(f"{len(a.inputs)} inputs: expected pairs CD_DIR BOUNDS")
    if a.label and len(a.label) != len(a.inputs) // 2:
        raise UserError(f"{len(a.label)} labels for {len(a.inputs) // 2} pairs")
    if not (a.tol >= 0 and math.isfinite(a.tol)):
        raise UserError(f"--tol {a.tol}: must be a number >= 0")
    return a


def read_cd(directory):
    """A cd campaign (compare_probes.read_campaign) and its force unit F0."""
    cd = read_campaign(directory, "cd", pairs="CD_DIR BOUNDS")
    cd["F0"] = json_number(cd["summary"], "F0", cd["summary_path"], positive=True)
    return cd


def read_bounds(path):
    t = read_intervals(path, ["a", "b", "fn", "fn_min", "fn_max"], min_rows=1)
    by_pair = {}
    for i in range(len(t["a"])):
        lo, hi = float(t["fn_min"][i]), float(t["fn_max"][i])
        by_pair.setdefault((int(t["a"][i]), int(t["b"][i])), []).append(
            {"fn": float(t["fn"][i]), "fn_min": lo, "fn_max": hi})
    jpath = os.path.splitext(path)[0] + ".json"
    meta = read_json(jpath) if os.path.exists(jpath) else {}
    return {"path": path, "by_pair": by_pair, "meta": meta}


def join(cd, bounds):
    """The interval of every probed contact (UserError where one has none, or two)."""
    s = cd["summary"]
    for key in ("N", "mu"):
        if key in s and key in bounds["meta"] and not math.isclose(
                float(s[key]), float(bounds["meta"][key]), rel_tol=1e-12):
            raise UserError(f"{cd['dir']} and {bounds['path']} come from different packings: "
                            f"{key} {s[key]} and {bounds['meta'][key]}")
    out = []
    for k, r in sorted(cd["rows"].items()):
        cands = [b for b in bounds["by_pair"].get((int(r["a"]), int(r["b"])), [])
                 if abs(b["fn"] - r["f_cont"]) <= F_REL_TOL * max(abs(r["f_cont"]), 1.0)]
        if not cands:
            raise UserError(f"{bounds['path']}: no interval for contact {k} (grains "
                            f"{int(r['a'])}-{int(r['b'])}, f_cont {r['f_cont']!r}) of "
                            f"{cd['dir']}: not the same packing, or not a contact of its "
                            f"admissible set")
        if len(cands) > 1:
            raise UserError(f"{bounds['path']}: two intervals match contact {k} (grains "
                            f"{int(r['a'])}-{int(r['b'])}) of {cd['dir']}")
        out.append((k, r, cands[0]))
    return out


def quartiles(v):
    if not v:
        return math.nan, math.nan, math.nan
    if len(v) == 1:
        return v[0], v[0], v[0]
    q1, q2, q3 = statistics.quantiles(v, n=4)
    return q1, statistics.median(v), q3


def position(cd, bounds, label, tol):
    s, F0 = cd["summary"], cd["F0"]
    packing = {"packing": os.path.basename(os.path.normpath(str(s.get("packing", "")))),
               "mu": s.get("mu", math.nan), "N": s.get("N"),
               "seed": s.get("seed")}
    rows, ts, t_conts, crit_over_cont, crit_over_max = [], [], [], [], []
    n = {"solved": 0, "exact": 0, "below_f_cont": 0, "zero_force": 0, "outside": 0,
         "at_top": 0, "can_open": 0}
    excess = shortfall = -math.inf
    outside = []
    for k, r, b in join(cd, bounds):
        solved = r["residual"] <= SOLVED_RESIDUAL
        exact = r["residual"] <= EXACT_RESIDUAL
        width = b["fn_max"] - b["fn_min"]
        t = t_cont = math.nan
        if width > MIN_WIDTH_F0 * F0:
            t_cont = (r["f_cont"] - b["fn_min"]) / width
            if solved:
                t = (r["f_crit"] - b["fn_min"]) / width
        if solved:
            if not math.isfinite(r["f_crit"]):
                raise UserError(f"{cd['dir']}/probes.csv: contact {k} is "
                                f"solved but its f_crit is not a number")
            n["solved"] += 1
            n["exact"] += exact
            n["below_f_cont"] += r["f_crit"] < r["f_cont"]
            n["zero_force"] += r["f_crit"] < ZERO_FORCE * r["f_cont"]
            n["can_open"] += b["fn_min"] == 0.0
            scale = max(b["fn_max"], MIN_WIDTH_F0 * F0)
            e, d = (r["f_crit"] - b["fn_max"]) / scale, (b["fn_min"] - r["f_crit"]) / scale
            excess, shortfall = max(excess, e), max(shortfall, d)
            if e > tol or d > tol:
                n["outside"] += 1
                outside.append(k)
            if math.isfinite(t):
                ts.append(t)
                n["at_top"] += t >= AT_TOP
            if math.isfinite(t_cont):
                t_conts.append(t_cont)
            if r["f_cont"] > 0:
                crit_over_cont.append(r["f_crit"] / r["f_cont"])
            if b["fn_max"] > 0:
                crit_over_max.append(r["f_crit"] / b["fn_max"])
        rows.append({**packing, "contact": k, "f_cont": r["f_cont"] / F0,
                     "fn_min": b["fn_min"] / F0, "fn_max": b["fn_max"] / F0,
                     "f_crit": r["f_crit"] / F0, "t": t, "t_cont": t_cont,
                     "residual": r["residual"], "solved": int(solved), "exact": int(exact)})
    name = label or f"{cd['dir']}"
    if outside:
        warn(f"{name}: {len(outside)} solved probe(s) outside their interval by more than "
             f"{tol:g} of fn_max: contacts {', '.join(str(k) for k in outside[:10])}")
    if n["solved"] == 0:
        warn(f"{name}: no probe is solved (residual <= {SOLVED_RESIDUAL:g} g)")
    q1, med, q3 = quartiles(ts)
    pair = {**packing, "label": label or "", "probes": len(rows), **n, "t_median": med,
            "t_q1": q1, "t_q3": q3, "t_min": min(ts) if ts else math.nan,
            "t_cont_median": statistics.median(t_conts) if t_conts else math.nan,
            "excess_max": excess if n["solved"] else math.nan,
            "shortfall_max": shortfall if n["solved"] else math.nan,
            "crit_over_max_median": statistics.median(crit_over_max) if crit_over_max
            else math.nan}
    return pair, rows, ts, crit_over_cont


def pair_name(p):
    if p["label"]:
        return p["label"]
    mu = p["mu"]
    return (f"mu {format_mu(mu) if isinstance(mu, (int, float)) else mu}, N {p['N']}, "
            f"seed {p['seed']}")


def markdown(pairs, command):
    def f3(v):
        return "–" if isinstance(v, float) and math.isnan(v) else f"{v:.3f}"
    lines = [f"Command: `{command}`", "",
             "| packing | solved (exact) | t median [q1, q3] | lowest t | t of f_cont | "
             "at the top (t >= 0.99) | F_crit < f_cont | with no force | outside | "
             "F_crit / fn_max, median |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for p in pairs:
        lines.append(f"| {pair_name(p)} | {p['solved']} ({p['exact']}) | {f3(p['t_median'])} "
                     f"[{f3(p['t_q1'])}, {f3(p['t_q3'])}] | {f3(p['t_min'])} | "
                     f"{f3(p['t_cont_median'])} | {p['at_top']} | {p['below_f_cont']} | "
                     f"{p['zero_force']} | {p['outside']} | {f3(p['crit_over_max_median'])} |")
    return "\n".join(lines) + "\n"


def figure(pairs, ts, ratios):
    import matplotlib.pyplot as plt
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(10, 4))
    colours = plt.get_cmap("tab10" if len(pairs) <= 10 else "tab20")  # one colour per packing
    for n, (p, t, q) in enumerate(zip(pairs, ts, ratios)):
        for axis, v in ((ax, t), (bx, [max(x, ZERO_FORCE) for x in q])):
            if v:
                v = sorted(v)
                axis.step(v, [(i + 1) / len(v) for i in range(len(v))], where="post",
                          label=pair_name(p), color=colours(n % colours.N))
    ax.set_xlabel("t = (F_crit - fn_min) / (fn_max - fn_min)")
    ax.set_ylabel("fraction of the solved probes")
    ax.set_xlim(-0.02, 1.02)
    ax.set_title("F_crit in the admissible interval (1: its top)")
    bx.axvline(1.0, color="grey", lw=0.8)
    bx.set_xscale("log")
    bx.set_xlabel(f"F_crit / f_cont (below {ZERO_FORCE:g} drawn at {ZERO_FORCE:g})")
    bx.set_title("F_crit against the force the contact carries")
    bx.legend(fontsize=7)
    fig.tight_layout()
    return fig


def main():
    a = parse(sys.argv[1:])
    command = shlex.join([os.path.basename(sys.executable), *sys.argv])
    pairs, rows, ts, ratios, inputs = [], [], [], [], []
    for i in range(0, len(a.inputs), 2):
        cd = read_cd(a.inputs[i])
        bounds = read_bounds(a.inputs[i + 1])
        label = a.label[i // 2] if a.label else None
        pair, pair_rows, t, q = position(cd, bounds, label, a.tol)
        pairs.append(pair)
        rows += pair_rows
        ts.append(t)
        ratios.append(q)
        s = cd["summary"]
        inputs.append({"cd": {"dir": os.path.abspath(cd["dir"]), "command": s.get("command"),
                              "program_version": s.get("program_version")},
                       "bounds": {"path": os.path.abspath(bounds["path"]),
                                  "command": bounds["meta"].get("command"),
                                  "program_version": bounds["meta"].get("program_version")}})
    if os.path.exists(a.out) and not os.path.isdir(a.out):
        raise UserError(f"{a.out}: exists and is not a directory")
    fig = figure(pairs, ts, ratios)
    try:
        os.makedirs(a.out, exist_ok=True)
    except OSError as e:
        raise UserError(f"{a.out}: cannot create the directory: {e.strerror or e}") from None
    record = json_value({
        "command": command, "inputs": inputs, "pairs": pairs,
        "rules": {"solved_residual_g": SOLVED_RESIDUAL, "exact_residual_g": EXACT_RESIDUAL,
                  "t": "(F_crit - fn_min) / (fn_max - fn_min), intervals wider than 1e-6 F0",
                  "zero_force": f"F_crit < {ZERO_FORCE:g} f_cont", "at_top": f"t >= {AT_TOP}",
                  "outside_tol_of_fn_max": a.tol, "quartiles": "statistics.quantiles(n=4)"}})

    def write(name, text):
        write_file_atomic(os.path.join(a.out, name), lambda f: f.write(text))
        print(os.path.join(a.out, name))

    write("interval.csv", csv_text(pairs, PAIR_COLUMNS))
    write("positions.csv", csv_text(rows, POSITION_COLUMNS))
    write("interval.md", markdown(pairs, command))
    write("interval.json", json.dumps(record, indent=1, sort_keys=True, allow_nan=False) + "\n")
    save_figure(fig, os.path.join(a.out, "interval-position.png"))
    for p in pairs:
        print(f"{pair_name(p)}: {p['solved']} solved, t median {p['t_median']:.3f}, "
              f"{p['below_f_cont']} below f_cont, {p['outside']} outside")


if __name__ == "__main__":
    run_main(main)
