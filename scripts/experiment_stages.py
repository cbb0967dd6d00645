"""The experiment's definition: its scales, and its stage graph built as data.

build(args, cfg, R) returns the stages of scripts/experiment.py in the order they run (see
its docstring for what each does) and the list of figures for the report.  The packings are
described first as plain records (directory, pack and probe stage names, unjam arguments);
the stages and their dependencies are then read off these records.
"""

import csv
import os
import shutil
import sys

import sweep_table
from campaign_time import cpu_per_probe
from stage_runner import Stage, StageError, nonempty, read_json

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCRIPTS = os.path.join(REPO, "scripts")
PY = sys.executable or "/usr/bin/python3"

# The scales, as data.  samples: ensemble networks for Fig. 4; probe_sample: contacts probed
# per packing (a seeded subset; 0 = every force-carrying contact).
# cd_sample: contacts per packing probed by the exact probe (`--method cd --cd-start
# cd_start`) and, for the comparison, by lp on the same contacts (0: none), on the packings of
# N <= cd_max_n. cd_start: interior (the path from an interior-point iterate, exact on every
# probe of the 500-disk samples at mu = 0.01-1; at its default, quasi-static dt it costs 0.6,
# 3.7, 27, 7 and 2.3 s of CPU per probe at mu = 0.01, 0.1, 0.2, 0.5 and 1 at 500 disks, 2.2 s
# at 1000 and 11 s at 2000 disks at mu = 0.01, and ~100 s or more at 1000 disks with mu >= 0.1;
# docs/probe.md, "An interior-point start", "What limits it"; docs/benchmarks.md, section 10),
# compliant (the rigid limit of stiff contacts followed from the static network: exact on 1789
# of 1800 probes at 500 disks, "300 probes per packing", 1.2-4.7 times slower than interior
# except at mu = 0.2), or static (the branch from the static network; without friction the
# fastest, with the same F_crit). cd_max_pieces: the exact probe's budget of pieces per probe
# (`unjam probe --cd-max-pieces`; 0: none), which bounds its cost at N >= 1000 (docs/probe.md,
# "A budget of pieces per probe"). cd_accept_residual: stop a probe's search at its first solution
# within this residual, in g (`unjam probe --cd-accept-residual`; 0: unjam's default, only an
# exact solution stops it; docs/probe.md, "Accepting a near-exact solution").
# cd_compliant_start: the compliance the continuation starts from (`unjam probe
# --cd-compliant-start`; 0: unjam's default; docs/probe.md, "Where the continuation starts");
# cd_softer_starts: its softer starts (`unjam probe --cd-softer-starts`; -1: unjam's default).
# cd_settle_compliance: end a path at its first exact solution at or below this compliance
# (`unjam probe --cd-settle-compliance`; 0: unjam's default, never; docs/probe.md, "Settling at
# an exact solution"). cd_lost_factor: drop the paths whose forces lost their digits (`unjam
# probe --cd-lost-factor`; 0: unjam's default, off; docs/probe.md, "Paths that lose their digits").
# cd_restart_floor: no restart of the continuation below this compliance (`unjam probe
# --cd-restart-floor`; 0: unjam's default, every restart; docs/probe.md, "Restarts below a floor").
# They are passed to unjam only where set, so stages cached without them stay valid.
CD_DEFAULTS = {"cd_max_pieces": 0, "cd_accept_residual": 0, "cd_compliant_start": 0,
               "cd_softer_starts": -1, "cd_settle_compliance": 0, "cd_lost_factor": 0,
               "cd_restart_floor": 0}
SCALES = {
    "tiny": {"mus": [0, 0.1, 1], "ns": [100], "seeds": [1], "samples": 2000, "probe_sample": 0,
             "cd_sample": 0, "cd_max_n": 500, "cd_fixed_max_mu": 0.1,
             "cd_start": "interior", **CD_DEFAULTS},
    "demo": {"mus": [0, 0.02, 0.1, 0.5, 1], "ns": [400], "seeds": [1, 2], "samples": 2000,
             "probe_sample": 0, "cd_sample": 0, "cd_max_n": 500, "cd_fixed_max_mu": 0.1,
             "cd_start": "interior", **CD_DEFAULTS},
    "paper": {"mus": [0, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1],
              "ns": [500, 1000, 2000, 4000, 8000], "seeds": [1, 2, 3], "samples": 20000,
              "probe_sample": 1000, "cd_sample": 300, "cd_max_n": 500, "cd_fixed_max_mu": 0.1,
              "cd_start": "interior", **CD_DEFAULTS},
}
# The exact probe's comparison table (OUT/exact-probe.csv), one row per packing. not_exact:
# cd probes whose step was not solved exactly (residual above 1e-6 g); without_solution: those
# of them without a solution (residual above 1e-3 g), left out of the cd means (the near-exact
# ones are kept); alpha empty where the fit failed; over_budget: cd probes stopped by the
# budget of pieces (cd_max_pieces; 0 without one), with or without a solution; accepted: cd
# probes whose search stopped at a near-exact solution within cd_accept_residual (0 without
# one; they are among not_exact). F_crit_over_F_cont_{lp,cd}_err: the means' standard errors
# over the sampled contacts (probe_summary.json's F_crit_over_F_cont_err; empty in a summary
# without it).
EXACT_COLUMNS = ["mu", "N", "seed", "probes", "not_exact", "without_solution",
                 "F_crit_over_F_cont_lp",
                 "F_crit_over_F_cont_cd", "alpha_lp", "alpha_cd", "cpu_s_per_probe_cd",
                 "over_budget", "accepted", "F_crit_over_F_cont_lp_err", "F_crit_over_F_cont_cd_err"]
FIG4 = {"n": 50, "mu": 0.1, "seed": 3}
# mu = 0 packings get tighter dynamics: their network must be unique (isostatic) for
# F_crit = F_cont. The default (NLGS tolerance 1e-4, 200 sweeps a step) leaves overlaps of
# ~1e-4 R_max that count as 2-15 redundant contacts at N = 500-2000 (docs/method.md).
FRICTIONLESS_PACK = ["--tol", "1e-6", "--max-sweeps", "2000"]
FIG1_MU = 0.5
# The friction-threshold table (OUT/friction-threshold.csv), one row per swept packing with
# mu > 0: `unjam threshold` brackets mu_s, the smallest friction coefficient at which the
# packing's contacts still admit a force network, in (mu_s_low, mu_s_high] (docs/ensemble.md,
# "The friction threshold"); mu_s_over_mu = mu_s_high / mu; lps and simplex_iterations its cost.
THRESHOLD_COLUMNS = ["mu", "N", "seed", "contacts", "mu_s_low", "mu_s_high", "mu_s_over_mu",
                     "lps", "simplex_iterations", "lp_seconds"]
# The optional stages that `--skip` can leave out (scripts/experiment.py).
SKIPPABLE = ["fixed", "fig4", "probe-one", "threshold"]
PROBE_OUTPUTS = ["probes.csv", "response_field.csv", "response_profile.csv",
                 "probe_summary.json", "probe_checkpoint.json"]


def fmt_mu(mu):
    return f"{mu:g}"


def packing_static(d):
    meta = read_json(os.path.join(d, "meta.json"))
    return bool(meta and meta.get("state", {}).get("static") is True)


def probe_done(d):
    s = read_json(os.path.join(d, "probe_summary.json"))
    return bool(s and "F_crit_over_F_cont" in s and "probes" in s)


# ---------------------------------------------------------------- the stage builders

def pack_stage(R, name, d, pack_args, deps=()):
    """`unjam pack ARGS --out d`, resumed with --resume when a stopped run left d behind."""
    params = {"command": ["unjam", "pack"] + [str(a) for a in pack_args] + ["--out", d],
              "version": R.version}

    def run(st):
        if st.resume and os.path.isfile(os.path.join(d, "meta.json")) and not packing_static(d):
            R.call(st, R.unjam_cmd("pack", "--resume", d, "--quiet"))
            return
        if os.path.exists(d):
            shutil.rmtree(d)
        os.makedirs(os.path.dirname(d), exist_ok=True)
        R.call(st, R.unjam_cmd("pack", *pack_args, "--out", d, "--quiet"))
    return Stage(name, f"unjam pack {' '.join(map(str, pack_args))}",
                 os.path.join(d, "stage.json"), params, run, lambda: packing_static(d), deps)


def remove_probe_outputs(d):
    """Deletes a probe run's outputs and checkpoint in d (a stage whose parameters changed)."""
    for f in PROBE_OUTPUTS:
        p = os.path.join(d, f)
        if os.path.exists(p):
            os.remove(p)


def read_summary(d):
    """d/probe_summary.json, or StageError."""
    s = read_json(os.path.join(d, "probe_summary.json"))
    if s is None:
        raise StageError(f"{d}/probe_summary.json does not read")
    return s


def alpha_text(s):
    """alpha of a probe summary as a table field: empty where the fit failed."""
    return "" if "fit_error" in s or s.get("alpha") is None else repr(float(s["alpha"]))


def probe_stage(R, name, d, g, sample, dep):
    """`unjam probe --all`, or `--sample K` (seeded, K per packing) when sample > 0."""
    select = ["--sample", str(sample)] if sample else ["--all"]
    args = select + ["--method", "lp", "--g", repr(g)]
    params = {"command": ["unjam", "probe", d] + args, "version": R.version}

    def run(st):
        if not st.resume:     # other parameters: no stale checkpoint or outputs
            remove_probe_outputs(d)
        R.call(st, R.unjam_cmd("probe", d, *args, "--quiet", mpi=True))
    return Stage(name, f"unjam probe {os.path.relpath(d, R.out)} {' '.join(select)}",
                 os.path.join(d, "stage.json"), params, run, lambda: probe_done(d), [dep])


def threshold_file(d):
    return os.path.join(d, "friction_threshold.json")


def threshold_checkpoint_file(d):
    return os.path.join(d, "friction_threshold_checkpoint.json")


def threshold_done(d):
    t = read_json(threshold_file(d))
    return bool(t and "mu_s_over_mu" in t and "mu_s_low" in t)


def threshold_stage(R, name, d, dep):
    """`unjam threshold d`: the packing's friction threshold into d/friction_threshold.json."""
    params = {"command": ["unjam", "threshold", d], "version": R.version}

    def run(st):
        # A stopped run's checkpoint (friction_threshold_checkpoint.json) is resumed by unjam
        # itself; other parameters start over.
        stale = [threshold_file(d)] + ([] if st.resume else [threshold_checkpoint_file(d)])
        for f in stale:
            if os.path.exists(f):
                os.remove(f)
        R.call(st, R.unjam_cmd("threshold", d, "--quiet", threads_flag=False))
    return Stage(name, f"unjam threshold {os.path.relpath(d, R.out)}",
                 os.path.join(d, "stage.json"), params, run, lambda: threshold_done(d), [dep])


def threshold_row(d, mu, n, seed):
    """One row of THRESHOLD_COLUMNS from d/friction_threshold.json."""
    t = read_json(threshold_file(d))
    if t is None:
        raise StageError(f"{threshold_file(d)} does not read")
    return {"mu": fmt_mu(mu), "N": n, "seed": seed, "contacts": t["contacts_used"],
            "mu_s_low": repr(float(t["mu_s_low"])), "mu_s_high": repr(float(t["mu_s_high"])),
            "mu_s_over_mu": repr(float(t["mu_s_over_mu"])), "lps": t["lps"],
            "simplex_iterations": t.get("simplex_iterations", ""),
            "lp_seconds": repr(float(t["timings_s"]["lp"]))}


def exact_probe_dirs(d):
    """{method: output directory} of the exact-probe comparison of packing directory d."""
    return {"cd": os.path.join(d, "exact-cd"), "lp": os.path.join(d, "exact-lp")}


def cd_options(cfg):
    """The exact probe's options of cfg as `unjam probe` arguments, each only where set
    (CD_DEFAULTS: unset), so that a stage's command is the same as before they existed."""
    args = []
    for key, flag in (("cd_max_pieces", "--cd-max-pieces"),
                      ("cd_accept_residual", "--cd-accept-residual"),
                      ("cd_compliant_start", "--cd-compliant-start"),
                      ("cd_softer_starts", "--cd-softer-starts"),
                      ("cd_settle_compliance", "--cd-settle-compliance"),
                      ("cd_lost_factor", "--cd-lost-factor"),
                      ("cd_restart_floor", "--cd-restart-floor")):
        value = cfg.get(key, CD_DEFAULTS[key])
        if value != CD_DEFAULTS[key]:
            args += [flag, str(value) if isinstance(value, int) else repr(value)]
    return args


def exact_probe_stage(R, name, d, g, sample, start, dep, cd_args):
    """The exact probe (`unjam probe --sample K --method cd --cd-start START` and cd_args, from
    cd_options) and the lp probe of the same seeded contacts, into d/exact-cd and d/exact-lp:
    the paper's probe beside the stand-in."""
    outs = exact_probe_dirs(d)
    args = {m: ["--sample", str(sample), "--seed", "1", "--method", m, "--g", repr(g)]
            for m in outs}
    args["cd"] += ["--cd-start", start] + list(cd_args)
    params = {"commands": [["unjam", "probe", d] + args[m] for m in sorted(outs)],
              "version": R.version}

    def run(st):
        for m in ("lp", "cd"):
            if not st.resume:
                remove_probe_outputs(outs[m])
            if not probe_done(outs[m]):
                R.call(st, R.unjam_cmd("probe", d, *args[m], "--out", outs[m], "--quiet", mpi=True))
    what = " ".join([f"unjam probe {os.path.relpath(d, R.out)} --sample {sample} --method cd "
                     f"--cd-start {start}", *cd_args, "(and lp)"])
    return Stage(name, what, os.path.join(d, "stage.json"), params, run,
                 lambda: all(probe_done(o) for o in outs.values()), [dep])


def exact_row(d, mu, n, seed):
    """One row of EXACT_COLUMNS from d/exact-{cd,lp}/probe_summary.json."""
    s = {m: read_summary(o) for m, o in exact_probe_dirs(d).items()}
    return {"mu": fmt_mu(mu), "N": n, "seed": seed, "probes": s["cd"]["probes"],
            "not_exact": s["cd"]["not_converged"],
            "without_solution": s["cd"]["without_solution"],
            "F_crit_over_F_cont_lp": repr(float(s["lp"]["F_crit_over_F_cont"])),
            "F_crit_over_F_cont_cd": repr(float(s["cd"]["F_crit_over_F_cont"])),
            "alpha_lp": alpha_text(s["lp"]), "alpha_cd": alpha_text(s["cd"]),
            "cpu_s_per_probe_cd": repr(cpu_per_probe(s["cd"], max(1, s["cd"]["probes"]))),
            "over_budget": s["cd"].get("over_budget", {}).get("probes", 0),
            "accepted": s["cd"].get("accepted", {}).get("probes", 0),
            **{f"F_crit_over_F_cont_{m}_err": repr(float(s[m]["F_crit_over_F_cont_err"]))
               if "F_crit_over_F_cont_err" in s[m] else "" for m in ("lp", "cd")}}


def plot_stage(R, name, outputs, cmds, deps):
    """A stage of python scripts; outputs are files under OUT."""
    params = {"commands": [[os.path.relpath(c, REPO) if isinstance(c, str) and c.startswith(
        SCRIPTS) else c for c in cmd[1:]] for cmd in cmds]}

    def run(st):
        for o in outputs:
            if os.path.exists(o):
                os.remove(o)
        for cmd in cmds:
            R.call(st, cmd)
    return Stage(name, ", ".join(os.path.relpath(o, R.out) for o in outputs),
                 os.path.join(R.out, "stage.json"), params, run,
                 lambda: all(nonempty(o) for o in outputs), deps)


def summary_row(d, mu, n, seed):
    s = read_summary(d)
    alpha = alpha_text(s)
    aerr = "" if alpha == "" or s.get("alpha_err") is None else repr(float(s["alpha_err"]))
    return {"mu": fmt_mu(mu), "N": n, "seed": seed, "phi": repr(float(s["phi"])),
            "z": repr(float(s["z"])), "F_cont_over_F0": repr(float(s["F_cont_over_F0"])),
            "F_crit_over_F_cont": repr(float(s["F_crit_over_F_cont"])), "alpha": alpha,
            "alpha_err": aerr}


def largest_force_contact(d):
    """Row index in d/contacts.csv of the contact with the largest normal force fn."""
    with open(os.path.join(d, "contacts.csv")) as f:
        fn = [float(r["fn"]) for r in csv.DictReader(f)]
    if not fn:
        raise StageError(f"{d}/contacts.csv has no contact")
    return max(range(len(fn)), key=lambda k: fn[k])


def write_table(path, rows, columns=sweep_table.COLUMNS):
    tmp = path + ".tmp"
    with open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=columns)
        w.writeheader()
        w.writerows(rows)
    os.replace(tmp, path)


def table_stage(R, name, path, entries, deps, columns=sweep_table.COLUMNS, row=summary_row):
    """entries: [(dir, mu, N, seed)] -> one row each, row(dir, mu, N, seed) (by default from
    dir/probe_summary.json), in the given columns."""
    params = {"table": os.path.relpath(path, R.out),
              "rows": [[os.path.relpath(d, R.out), mu, n, s] for d, mu, n, s in entries]}

    def run(st):
        st.record["commands"].append(f"(python) write {path} from {len(entries)} summaries")
        write_table(path, [row(d, mu, n, s) for d, mu, n, s in entries], columns)

    def check():  # every row, in today's columns (a table of an older version is rewritten)
        try:
            with open(path) as f:
                r = csv.DictReader(f)
                return len(list(r)) == len(entries) and r.fieldnames == list(columns)
        except OSError:
            return False
    return Stage(name, os.path.relpath(path, R.out), os.path.join(R.out, "stage.json"),
                 params, run, check, deps)


# ---------------------------------------------------------------- the stage graph

def sweep_packings(cfg, out):
    """One record per (N, mu, seed) of the scale, in stage order: its directory, the names of
    its pack, probe and exact-probe stages, the `unjam pack` arguments and the stages its pack depends on."""
    packings = []
    for n in cfg["ns"]:
        for mu in cfg["mus"]:
            for seed in cfg["seeds"]:
                tag = f"N{n}-mu{fmt_mu(mu)}-s{seed}"
                packings.append({
                    "mu": mu, "n": n, "seed": seed, "dir": os.path.join(out, "packings", tag),
                    "pack": f"pack {tag}", "probe": f"probe {tag}", "exact": f"exact {tag}",
                    "deps": [],
                    "args": ["--n", n, "--mu", fmt_mu(mu), "--seed", seed]
                    + (FRICTIONLESS_PACK if mu == 0 else [])})
    return packings


def fixed_packings(cfg, out, source):
    """The fixed-packing series: `source` (the mu = 0 packing of the first N and seed)
    re-relaxed at every other mu of the scale (`unjam pack --from`)."""
    n0 = source["n"]
    packings = []
    for mu in cfg["mus"]:
        if mu == 0:
            continue
        tag = f"fixed N{n0}-mu{fmt_mu(mu)}"
        packings.append({
            "mu": mu, "n": n0, "seed": source["seed"],
            "dir": os.path.join(out, "fixed", f"N{n0}-mu{fmt_mu(mu)}"),
            "pack": f"pack {tag}", "probe": f"probe {tag}", "exact": f"exact {tag}",
            "deps": [source["pack"]],
            "args": ["--from", source["dir"], "--mu", fmt_mu(mu)]})
    return packings


def packing_stages(R, packings, g, sample):
    """The pack and the probe stage of every packing record."""
    stages = []
    for p in packings:
        stages.append(pack_stage(R, p["pack"], p["dir"], p["args"], deps=p["deps"]))
        stages.append(probe_stage(R, p["probe"], p["dir"], g, sample, p["pack"]))
    return stages


def table_entry(p):
    return (p["dir"], p["mu"], p["n"], p["seed"])


def ensemble_stage(R, d, samples):
    """`unjam ensemble d --samples S --probe cd` (Fig. 4): the paper's probe, exact (the lp
    stand-in would put F_crit at the top of every interval by construction)."""
    ens_args = ["--samples", samples, "--probe", "cd"]
    params = {"command": ["unjam", "ensemble", d] + [str(a) for a in ens_args],
              "version": R.version}

    def run(st):
        for f in ("ensemble.csv", "ensemble.json"):
            if os.path.exists(os.path.join(d, f)):
                os.remove(os.path.join(d, f))
        R.call(st, R.unjam_cmd("ensemble", d, *ens_args))
    return Stage("ensemble fig4", f"unjam ensemble {os.path.relpath(d, R.out)} "
                 f"--samples {samples} --probe cd", os.path.join(d, "stage.json"), params, run,
                 lambda: read_json(os.path.join(d, "ensemble.json")) is not None, ["pack fig4"])


def probe_one_stage(R, p, g, one_dir, fig):
    """The contact of largest normal force of packing record p probed alone, and its field
    drawn (plot_probe_field.py)."""
    d = p["dir"]
    params = {"command": ["unjam", "probe", os.path.relpath(d, R.out), "--contact",
                          "(largest fn)", "--method", "lp", "--g", repr(g)],
              "plot": "plot_probe_field.py", "version": R.version}

    def run(st):
        k = largest_force_contact(d)
        if os.path.exists(fig):
            os.remove(fig)
        R.call(st, R.unjam_cmd("probe", d, "--contact", k, "--method", "lp",
                               "--g", repr(g), "--out", one_dir, "--quiet"))
        R.call(st, [PY, os.path.join(SCRIPTS, "plot_probe_field.py"), one_dir, "--contact", k,
                    "--packing", d, "--out", fig])
    return Stage("probe one", f"unjam probe {os.path.relpath(d, R.out)} --contact K, "
                 f"{os.path.relpath(fig, R.out)}", os.path.join(R.out, "stage.json"),
                 params, run, lambda: nonempty(fig), [p["pack"]])


def build(args, cfg, R):
    """(stages in run order, [(figure title, path)]) of the experiment at configuration cfg."""
    out = R.out
    sweep = sweep_packings(cfg, out)
    of = {(p["mu"], p["n"], p["seed"]): p for p in sweep}
    skip = set(getattr(args, "skip", None) or [])
    n0, s0 = cfg["ns"][0], cfg["seeds"][0]
    # the fixed series exists when mu = 0 is swept and it is not skipped
    source = None if "fixed" in skip else of.get((0, n0, s0))
    fixed = fixed_packings(cfg, out, source) if source else []
    stages = packing_stages(R, sweep, args.probe_g, cfg["probe_sample"])
    stages += packing_stages(R, fixed, args.probe_g, cfg["probe_sample"])
    # The exact probe beside lp, where it is affordable.
    exact = [p for p in sweep if cfg["cd_sample"] > 0 and p["n"] <= cfg["cd_max_n"]]
    # and on the fixed series up to cd_fixed_max_mu (the frozen mu = 0 structure is solved in
    # about a second per probe up to mu = 0.1 at 500 disks, ~30 s at 0.2; docs/probe.md, "The
    # fixed packing by the paper's probe"); its mu = 0 point is the source's own comparison.
    exact_fixed = [p for p in fixed if cfg["cd_sample"] > 0 and p["n"] <= cfg["cd_max_n"]
                   and p["mu"] <= cfg["cd_fixed_max_mu"]]
    exact_fixed_rows = ([source] if source in exact else []) + exact_fixed
    for p in exact + exact_fixed:
        stages.append(exact_probe_stage(R, p["exact"], p["dir"],
                                        args.probe_g, cfg["cd_sample"], cfg["cd_start"],
                                        p["pack"], cd_options(cfg)))

    # How far each packing is from losing its network: its friction threshold mu_s.
    frictional = [p for p in sweep if p["mu"] > 0] if "threshold" not in skip else []
    for p in frictional:
        stages.append(threshold_stage(R, "threshold " + p["pack"][len("pack "):], p["dir"],
                                      p["pack"]))

    # Fig. 4
    fig4 = os.path.join(out, "fig4-ensemble.png")
    if "fig4" not in skip:
        d4 = os.path.join(out, "fig4", f"N{FIG4['n']}-mu{fmt_mu(FIG4['mu'])}-s{FIG4['seed']}")
        stages.append(pack_stage(R, "pack fig4", d4, ["--n", FIG4["n"], "--mu",
                                                      fmt_mu(FIG4["mu"]), "--seed", FIG4["seed"]]))
        stages.append(ensemble_stage(R, d4, cfg["samples"]))
        stages.append(plot_stage(R, "plot fig4", [fig4],
                                 [[PY, os.path.join(SCRIPTS, "plot_fig4.py"), d4, "--out", fig4]],
                                 ["ensemble fig4"]))
    # Tables
    sweep_csv = os.path.join(out, "sweep.csv")
    fixed_csv = os.path.join(out, "fixed.csv")
    stages.append(table_stage(R, "table sweep", sweep_csv, [table_entry(p) for p in sweep],
                              [p["probe"] for p in of.values()]))
    if exact:
        stages.append(table_stage(
            R, "table exact", os.path.join(out, "exact-probe.csv"),
            [table_entry(p) for p in exact],
            [p["exact"] for p in exact], EXACT_COLUMNS, exact_row))
    exact_fixed_csv = os.path.join(out, "exact-probe-fixed.csv")
    if exact_fixed:
        stages.append(table_stage(
            R, "table exact fixed", exact_fixed_csv, [table_entry(p) for p in exact_fixed_rows],
            [p["exact"] for p in exact_fixed_rows], EXACT_COLUMNS,
            exact_row))
    if frictional:
        stages.append(table_stage(
            R, "table threshold", os.path.join(out, "friction-threshold.csv"),
            [table_entry(p) for p in frictional],
            ["threshold " + p["pack"][len("pack "):] for p in frictional], THRESHOLD_COLUMNS,
            threshold_row))
    if source:
        series = [source] + fixed
        stages.append(table_stage(R, "table fixed", fixed_csv,
                                  [(source["dir"], 0.0, n0, s0)] + [table_entry(p) for p in fixed],
                                  [p["probe"] for p in series]))
    # Figures
    fig3 = os.path.join(out, "fig3-friction-sweep.png")
    cmd3 = [PY, os.path.join(SCRIPTS, "plot_friction_sweep.py"), sweep_csv]
    cmd3 += (["--fixed", fixed_csv] if source else []) + ["--out", fig3]
    stages.append(plot_stage(R, "plot fig3", [fig3], [cmd3],
                             ["table sweep"] + (["table fixed"] if source else [])))
    # Fig. 3 by the paper's probe beside the stand-in, from the exact-probe table.
    fig3x = os.path.join(out, "fig3-exact-vs-lp.png")
    if exact:
        stages.append(plot_stage(R, "plot fig3 exact", [fig3x],
                                 [[PY, os.path.join(SCRIPTS, "plot_exact_sweep.py"),
                                   os.path.join(out, "exact-probe.csv"), "--out", fig3x]],
                                 ["table exact"]))
    # The inset by both probes, from the fixed series' exact-probe table.
    fig3ix = os.path.join(out, "fig3-inset-exact-vs-lp.png")
    if exact_fixed:
        stages.append(plot_stage(R, "plot fig3 inset exact", [fig3ix],
                                 [[PY, os.path.join(SCRIPTS, "plot_exact_sweep.py"), exact_fixed_csv,
                                   "--out", fig3ix, "--title",
                                   "the fixed packing (Fig. 3 inset): cd filled, lp open"]],
                                 ["table exact fixed"]))
    nmax = max(cfg["ns"])
    # Fig. 2 per size: d(r) of every mu (first seed); fig2-profiles.png is the largest N.
    fig2_of = {}
    for n in cfg["ns"]:
        fig2_of[n] = os.path.join(out, "fig2-profiles.png" if n == nmax
                                  else f"fig2-profiles-N{n}.png")
        curves = [of[(mu, n, s0)] for mu in cfg["mus"]]
        stages.append(plot_stage(
            R, "plot fig2" if n == nmax else f"plot fig2 N{n}", [fig2_of[n]],
            [[PY, os.path.join(SCRIPTS, "plot_profile.py"), *[p["dir"] for p in curves],
              "--labels", *[f"mu = {fmt_mu(mu)}" for mu in cfg["mus"]], "--out", fig2_of[n]]],
            [p["probe"] for p in curves]))
    fig2 = fig2_of[nmax]
    mu1 = FIG1_MU if FIG1_MU in cfg["mus"] else max(cfg["mus"])
    p1 = of[(mu1, nmax, s0)]
    fig1f = os.path.join(out, "fig1-field.png")
    fig1p = os.path.join(out, "fig1-packing.png")
    stages.append(plot_stage(
        R, "plot fig1", [fig1f, fig1p],
        [[PY, os.path.join(SCRIPTS, "plot_response_field.py"), p1["dir"], "--out", fig1f],
         [PY, os.path.join(SCRIPTS, "plot_packing.py"), p1["dir"], "--out", fig1p]],
        [p1["probe"]]))
    # One probe's own displacement field: the contact of largest normal force of that packing.
    fig_one = os.path.join(out, "fig-probe-field.png")
    if "probe-one" not in skip:
        stages.append(probe_one_stage(R, p1, args.probe_g, os.path.join(out, "probe-one"),
                                      fig_one))
    figures = [(f"Fig. 1: mean displacement field, N = {nmax}, mu = {fmt_mu(mu1)}", fig1f),
               (f"Fig. 1: the packing and its force chains, N = {nmax}, mu = {fmt_mu(mu1)}",
                fig1p),
               *([(f"One probe's displacement field (the contact of largest force), N = {nmax}, "
                   f"mu = {fmt_mu(mu1)}", fig_one)] if "probe-one" not in skip else []),
               (f"Fig. 2: d(r) per mu, N = {nmax}", fig2),
               *[(f"Fig. 2: d(r) per mu, N = {n}", fig2_of[n]) for n in cfg["ns"] if n != nmax],
               ("Fig. 3: friction sweep" + (" (with the fixed-packing inset)" if source else ""),
                fig3),
               *([(f"Fig. 3 by the paper's probe (cd, {cfg['cd_sample']} contacts per packing of "
                   f"N <= {cfg['cd_max_n']}) beside the stand-in (lp) on the same contacts", fig3x)]
                 if exact else []),
               *([(f"Fig. 3's inset by the paper's probe (cd, {cfg['cd_sample']} contacts per "
                   f"packing, mu <= {fmt_mu(cfg['cd_fixed_max_mu'])}) beside the stand-in (lp)",
                   fig3ix)] if exact_fixed else []),
               *([(f"Fig. 4: force-network ensemble, N = {FIG4['n']}, mu = {FIG4['mu']}", fig4)]
                 if "fig4" not in skip else [])]
    return stages, figures
