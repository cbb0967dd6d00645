"""The paper's experiment from one command: packings over friction and size, probes, Figs. 1-4, report.

Usage:  /usr/bin/python3 scripts/experiment.py --scale demo|tiny|paper [--out runs/experiment]
                                               [--threads N] [--unjam PATH]
                                               [--mpi K [--mpirun LAUNCHER]]
                                               [--mus ...] [--ns ...] [--seeds ...]
                                               [--probe-g G] [--samples S]

Stages (each drives the `unjam` binary or one of scripts/plot_*.py through subprocess):

  pack/probe   for every (mu, N, seed) of the scale: `unjam pack` into
               OUT/packings/N{N}-mu{mu}-s{seed}, then `unjam probe DIR --all --method lp`
               (`--sample K` at the paper scale: K seeded contacts per packing);
  fixed        the mu = 0 packing of the first N and seed re-relaxed at every other mu
               (`unjam pack --from`) into OUT/fixed/N{N}-mu{mu}, probed the same way
               (the paper's Fig. 3b inset);
  fig4         a 50-disk mu = 0.1 packing, `unjam ensemble --probe lp`, plot_fig4.py;
  probe one    the Fig. 1 packing's contact of largest force probed alone (`unjam probe
               --contact K`) and its displacement field drawn (plot_probe_field.py);
  tables       OUT/sweep.csv and OUT/fixed.csv (one row per packing, from probe_summary.json);
  figures      fig3-friction-sweep.png, fig2-profiles.png (largest N, one curve per mu),
               fig1-field.png and fig1-packing.png (mu = 0.5, else the largest mu);
  report       OUT/report.md: measured values per mu beside the paper's findings (PHYSICS.md
               section 9), agree / disagree per finding, parameters, timings, figures.

Caching and resume: every stage records its command and parameters in a stage.json next to its
output (a packing directory holds the records of its pack and probe stages; OUT/stage.json those
of the tables and figures).  A re-run skips a stage whose record matches, whose inputs were not
recomputed since, and whose outputs exist and read; it prints "skipped (cached)".  A stage whose
parameters changed is recomputed, and so is every stage that depends on it.  A stopped
`unjam pack` resumes with `unjam pack --resume DIR`; a stopped `unjam probe --all` resumes from
its own checkpoint when run again with the same parameters.  The report is rewritten every run.

MPI: with --mpi K the probe stages run as `mpirun -n K unjam probe ...` (--mpirun names another
launcher, e.g. "srun" or "mpirun --oversubscribe"); their outputs are the same bytes as in one
process, so the stage records do not depend on K and cached stages stay valid.

Exit status 0 on success; 1 with a message naming the failed stage and its command.
"""

import argparse
import csv
import json
import math
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import time
import uuid

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCRIPTS = os.path.join(REPO, "scripts")
PY = sys.executable or "/usr/bin/python3"

# The scales, as data.  samples: ensemble networks for Fig. 4; probe_sample: contacts probed
# per packing (a seeded subset; 0 = every force-carrying contact).
SCALES = {
    "tiny": {"mus": [0, 0.1, 1], "ns": [100], "seeds": [1], "samples": 2000, "probe_sample": 0},
    "demo": {"mus": [0, 0.02, 0.1, 0.5, 1], "ns": [400], "seeds": [1, 2], "samples": 2000,
             "probe_sample": 0},
    "paper": {"mus": [0, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1],
              "ns": [500, 1000, 2000, 4000, 8000], "seeds": [1, 2, 3], "samples": 20000,
              "probe_sample": 1000},
}
FIG4 = {"n": 50, "mu": 0.1, "seed": 3}
# mu = 0 packings get tighter dynamics: their network must be unique (isostatic) for
# F_crit = F_cont. The default (NLGS tolerance 1e-4, 200 sweeps a step) leaves overlaps of
# ~1e-4 R_max that count as 2-15 redundant contacts at N = 500-2000 (docs/method.md).
FRICTIONLESS_PACK = ["--tol", "1e-6", "--max-sweeps", "2000"]
FIG1_MU = 0.5
COLUMNS = ["mu", "N", "seed", "phi", "z", "F_cont_over_F0", "F_crit_over_F_cont", "alpha",
           "alpha_err"]
PROBE_OUTPUTS = ["probes.csv", "response_field.csv", "response_profile.csv",
                 "probe_summary.json", "probe_checkpoint.json"]


class StageError(Exception):
    pass


# ---------------------------------------------------------------- small helpers

def fmt_mu(mu):
    return f"{mu:g}"


def read_json(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def write_json(path, obj):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(obj, f, indent=1, sort_keys=True)
        f.write("\n")
    os.replace(tmp, path)


def nonempty(path):
    return os.path.isfile(path) and os.path.getsize(path) > 0


def packing_static(d):
    meta = read_json(os.path.join(d, "meta.json"))
    return bool(meta and meta.get("state", {}).get("static") is True)


def probe_done(d):
    s = read_json(os.path.join(d, "probe_summary.json"))
    return bool(s and "F_crit_over_F_cont" in s and "probes" in s)


def quote(cmd):
    return " ".join(shlex.quote(str(c)) for c in cmd)


# ---------------------------------------------------------------- stages

class Stage:
    """One step: name, parameters (compared for caching), inputs, outputs check, action."""

    def __init__(self, name, what, record_file, params, run, check, deps=(), commands=()):
        self.name = name
        self.what = what
        self.record_file = record_file   # stage.json holding this stage's record under `name`
        self.params = params
        self.run = run                   # run(stage, record) -> None
        self.check = check               # check() -> bool: outputs exist and read
        self.deps = list(deps)
        self.commands = list(commands)   # filled as run() goes, for the record / errors


class Runner:
    def __init__(self, out, unjam, threads, log_dir, launcher=()):
        self.out = out
        self.launcher = list(launcher)   # e.g. ["mpirun", "-n", "4"]: for the probe campaigns
        self.unjam = unjam
        self.threads = threads
        self.log_dir = log_dir
        self.stamps = {}      # stage name -> stamp of its current outputs
        self.timings = []     # (name, what, action, seconds this run, seconds when computed)
        self.t0 = time.time()

    def records(self, path):
        return read_json(path) or {}

    def save_record(self, stage, rec):
        recs = self.records(stage.record_file)
        recs[stage.name] = rec
        os.makedirs(os.path.dirname(stage.record_file), exist_ok=True)
        write_json(stage.record_file, recs)

    def execute(self, stages):
        n = len(stages)
        for i, st in enumerate(stages, 1):
            inputs = {d: self.stamps[d] for d in st.deps}
            old = self.records(st.record_file).get(st.name)
            prefix = f"[{i}/{n}] {st.name}: {st.what}"
            if (old and old.get("status") == "done" and old.get("params") == st.params
                    and old.get("inputs") == inputs and st.check()):
                self.stamps[st.name] = old["stamp"]
                self.timings.append((st.name, st.what, "cached", 0.0, old.get("seconds", 0.0)))
                print(f"{prefix} ... skipped (cached)  [{self.elapsed()}]", flush=True)
                continue
            print(f"{prefix} ... running  [{self.elapsed()}]", flush=True)
            resume = bool(old and old.get("status") == "running"
                          and old.get("params") == st.params and old.get("inputs") == inputs)
            rec = {"status": "running", "params": st.params, "inputs": inputs,
                   "commands": [], "started": time.strftime("%Y-%m-%dT%H:%M:%S")}
            t = time.time()
            st.resume = resume
            st.record = rec
            self.save_record(st, rec)
            st.run(st)
            if not st.check():
                raise StageError(f"stage {st.name}: the outputs are missing or unreadable after "
                                 f"the commands\n  " + "\n  ".join(rec["commands"]))
            dt = time.time() - t
            rec.update(status="done", seconds=round(dt, 3), stamp=uuid.uuid4().hex)
            self.save_record(st, rec)
            self.stamps[st.name] = rec["stamp"]
            self.timings.append((st.name, st.what, "ran", dt, dt))
            print(f"{prefix} ... done in {dt:.1f} s  [{self.elapsed()}]", flush=True)

    def elapsed(self):
        return f"{time.time() - self.t0:.1f} s elapsed"

    def call(self, stage, cmd):
        """Run one command of `stage`; its output goes to OUT/logs/<stage>.log."""
        cmd = [str(c) for c in cmd]
        stage.record["commands"].append(quote(cmd))
        self.save_record(stage, stage.record)
        os.makedirs(self.log_dir, exist_ok=True)
        log = os.path.join(self.log_dir, re.sub(r"[^A-Za-z0-9.=-]+", "_", stage.name) + ".log")
        with open(log, "a") as f:
            f.write(f"$ {quote(cmd)}\n")
            f.flush()
            proc = subprocess.Popen(cmd, stdout=f, stderr=subprocess.STDOUT, cwd=REPO)
            try:
                rc = proc.wait()
            except KeyboardInterrupt:
                # let unjam save its state (pack: --resume; probe: its checkpoint)
                proc.send_signal(signal.SIGINT)
                try:
                    proc.wait(timeout=60)
                except subprocess.TimeoutExpired:
                    proc.kill()
                raise
        if rc != 0:
            with open(log) as f:
                tail = "".join(f.readlines()[-15:])
            raise StageError(f"stage {stage.name} failed (exit status {rc}) in the command\n"
                             f"  {quote(cmd)}\nlast lines of {log}:\n{tail}")

    def unjam_cmd(self, *args, threads_flag=True, mpi=False):
        cmd = (self.launcher if mpi else []) + [self.unjam] + [str(a) for a in args]
        if threads_flag and self.threads:
            cmd += ["--threads", str(self.threads)]
        return cmd


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


def probe_stage(R, name, d, g, sample, dep):
    """`unjam probe --all`, or `--sample K` (seeded, K per packing) when sample > 0."""
    select = ["--sample", str(sample)] if sample else ["--all"]
    args = select + ["--method", "lp", "--g", repr(g)]
    params = {"command": ["unjam", "probe", d] + args, "version": R.version}

    def run(st):
        if not st.resume:     # other parameters: no stale checkpoint or outputs
            for f in PROBE_OUTPUTS:
                p = os.path.join(d, f)
                if os.path.exists(p):
                    os.remove(p)
        R.call(st, R.unjam_cmd("probe", d, *args, "--quiet", mpi=True))
    return Stage(name, f"unjam probe {os.path.relpath(d, R.out)} {' '.join(select)}",
                 os.path.join(d, "stage.json"), params, run, lambda: probe_done(d), [dep])


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
    s = read_json(os.path.join(d, "probe_summary.json"))
    if s is None:
        raise StageError(f"{d}/probe_summary.json does not read")
    alpha = "" if "fit_error" in s or s.get("alpha") is None else repr(float(s["alpha"]))
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


def write_table(path, rows):
    tmp = path + ".tmp"
    with open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        w.writerows(rows)
    os.replace(tmp, path)


def table_stage(R, name, path, entries, deps):
    """entries: [(dir, mu, N, seed)] -> one row each, from probe_summary.json."""
    params = {"table": os.path.relpath(path, R.out),
              "rows": [[os.path.relpath(d, R.out), mu, n, s] for d, mu, n, s in entries]}

    def run(st):
        st.record["commands"].append(f"(python) write {path} from {len(entries)} summaries")
        write_table(path, [summary_row(d, mu, n, s) for d, mu, n, s in entries])

    def check():
        try:
            with open(path) as f:
                return len(list(csv.DictReader(f))) == len(entries)
        except OSError:
            return False
    return Stage(name, os.path.relpath(path, R.out), os.path.join(R.out, "stage.json"),
                 params, run, check, deps)


# ---------------------------------------------------------------- the report

def read_table(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def fnum(v):
    try:
        x = float(v)
    except (TypeError, ValueError):
        return math.nan
    return x


def mean_std(vals):
    v = [x for x in vals if math.isfinite(x)]
    if not v:
        return math.nan, math.nan, 0
    m = sum(v) / len(v)
    s = math.sqrt(sum((x - m) ** 2 for x in v) / (len(v) - 1)) if len(v) > 1 else 0.0
    return m, s, len(v)


QUANTITIES = [("phi", "phi"), ("z", "z"), ("F_cont_over_F0", "<F_cont>/F0"),
              ("F_crit_over_F_cont", "<F_crit>/<F_cont>"), ("alpha", "alpha")]


def aggregate(rows):
    """{(mu, N): {col: (mean, std, n)}} over seeds."""
    groups = {}
    for r in rows:
        groups.setdefault((float(r["mu"]), int(r["N"])), []).append(r)
    return {k: {c: mean_std([fnum(r[c]) for r in g]) for c, _ in QUANTITIES} | {"seeds": len(g)}
            for k, g in sorted(groups.items())}


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


def write_report(path, args, cfg, R, figures, argv):
    out = os.path.dirname(path)
    rows = read_table(os.path.join(out, "sweep.csv"))
    agg = aggregate(rows)
    fixed_path = os.path.join(out, "fixed.csv")
    fixed_agg = aggregate(read_table(fixed_path)) if os.path.isfile(fixed_path) else {}
    n_max = max(cfg["ns"])
    L = ["# unjam experiment report", "",
         f"Scale **{args.scale}**; written {time.strftime('%Y-%m-%d %H:%M:%S')}.", "",
         "## Measured values per mu", "",
         "Mean ± standard deviation over the seeds (0 for one seed); from `sweep.csv`.", "",
         "| mu | N | seeds | " + " | ".join(lbl for _, lbl in QUANTITIES) + " |",
         "|---|---|---|" + "---|" * len(QUANTITIES)]
    for (mu, n), a in agg.items():
        L.append(f"| {fmt_mu(mu)} | {n} | {a['seeds']} | "
                 + " | ".join(pm(a[c]) for c, _ in QUANTITIES) + " |")
    if fixed_agg:
        L += ["", f"Fixed packing (the mu = 0 packing re-relaxed at each mu; `fixed.csv`):", "",
              "| mu | N | seeds | " + " | ".join(lbl for _, lbl in QUANTITIES) + " |",
              "|---|---|---|" + "---|" * len(QUANTITIES)]
        for (mu, n), a in fixed_agg.items():
            L.append(f"| {fmt_mu(mu)} | {n} | {a['seeds']} | "
                     + " | ".join(pm(a[c]) for c, _ in QUANTITIES) + " |")
    L += ["", f"## Against the paper (PHYSICS.md section 9; measured at N = {n_max})", "",
          "| finding | paper | measured | verdict |", "|---|---|---|---|"]
    for f, paper, meas, verdict in findings(agg, fixed_agg, n_max):
        L.append(f"| {f} | {paper} | {meas} | **{verdict}** |")
    L += ["", "Criteria: phi within 0.01 of 0.84 / 0.80 and monotonic (tolerance 0.002); z and "
          "<F_cont> monotonic (tolerance 2 %); alpha within [0.7, 1.4] with its maximum at "
          "0.05 <= mu <= 0.2; <F_crit>/<F_cont> within 0.1 of 1 at the ends with its maximum at "
          "0.05 <= mu <= 0.2; fixed packing monotonic (tolerance 0.01).", "",
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
          f"- Fig. 4: N = {FIG4['n']}, mu = {FIG4['mu']}, seed = {FIG4['seed']}, "
          f"samples = {cfg['samples']}",
          f"- unjam: `{R.unjam}`, version `{R.version}`",
          f"- threads: {args.threads or 'all cores'}"
          + (f" per rank, probe stages over {args.mpi} MPI ranks (`{' '.join(R.launcher)}`)"
             if args.mpi else ""),
          f"- command line: `{quote([sys.executable, os.path.relpath(os.path.abspath(__file__), REPO)] + argv)}`", "",
          "## Timings", "",
          "This run: 'ran' stages were computed now, 'cached' ones were skipped; the last column "
          "is the time the stage took when it was computed.", "",
          "| stage | what | this run | s this run | s when computed |", "|---|---|---|---|---|"]
    for name, what, action, dt, dt0 in R.timings:
        L.append(f"| {name} | `{what}` | {action} | {dt:.1f} | {dt0:.1f} |")
    L.append(f"| total | | | {time.time() - R.t0:.1f} | |")
    with open(path + ".tmp", "w") as f:
        f.write("\n".join(L) + "\n")
    os.replace(path + ".tmp", path)


# ---------------------------------------------------------------- main

def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=__doc__.split("\n\n", 2)[2])
    p.add_argument("--scale", required=True, choices=sorted(SCALES))
    p.add_argument("--out", default="runs/experiment", help="output directory (default "
                   "runs/experiment, relative to the current directory)")
    p.add_argument("--threads", type=int, default=0,
                   help="threads for unjam (default: all cores); results do not depend on it")
    p.add_argument("--unjam", default=os.path.join(REPO, "build", "release", "unjam"),
                   help="the unjam binary (default build/release/unjam of the repository)")
    p.add_argument("--mus", type=float, nargs="+", help="override the scale's mu list")
    p.add_argument("--ns", type=int, nargs="+", help="override the scale's N list")
    p.add_argument("--seeds", type=int, nargs="+", help="override the scale's seed list")
    p.add_argument("--samples", type=int, help="override the scale's ensemble samples (Fig. 4)")
    p.add_argument("--probe-sample", type=int, help="override the scale's contacts probed per "
                   "packing (a seeded subset; 0 = all)")
    p.add_argument("--probe-g", type=float, default=1e-9,
                   help="opening gap g of the probes (R_max; default 1e-9)")
    p.add_argument("--mpi", type=int, default=0, metavar="K",
                   help="run the probe stages over K MPI ranks (`mpirun -n K`; each rank uses "
                        "--threads threads); results do not depend on it")
    p.add_argument("--mpirun", default="mpirun",
                   help="the MPI launcher of --mpi, split like a shell word list (default mpirun)")
    args = p.parse_args(argv)
    # Every override is checked here, before any stage runs (unjam would refuse the same
    # values only when their stage starts, hours into a run).
    if args.mpi < 0:
        p.error("--mpi must be >= 0")
    if args.threads < 0:
        p.error("--threads must be >= 0")
    if args.probe_sample is not None and args.probe_sample < 0:
        p.error("--probe-sample must be >= 0")
    if args.mus is not None and not all(math.isfinite(m) and m >= 0 for m in args.mus):
        p.error(f"--mus: every friction coefficient must be a finite number >= 0, got {args.mus}")
    if args.ns is not None and not all(n >= 8 for n in args.ns):
        p.error(f"--ns: every N must be at least 8 (fewer disks cannot jam), got {args.ns}")
    if args.seeds is not None and not all(0 <= s < 2**64 for s in args.seeds):
        p.error(f"--seeds: every seed must be an integer from 0 to 2^64 - 1, got {args.seeds}")
    if args.samples is not None and args.samples <= 0:
        p.error(f"--samples must be > 0, got {args.samples}")
    if not (math.isfinite(args.probe_g) and args.probe_g > 0):
        p.error(f"--probe-g must be a finite number > 0, got {args.probe_g}")
    if os.path.exists(args.out) and not os.path.isdir(args.out):
        p.error(f"--out {args.out} is a file, not a directory")
    if not (os.path.isfile(args.unjam) and os.access(args.unjam, os.X_OK)):
        p.error(f"no unjam binary at {args.unjam} (build it: cmake --build build/release -j2)")
    return args


def build(args, cfg, R):
    out = R.out
    stages = []
    sweep_entries, fixed_entries = [], []
    probe_of = {}                       # (mu, N, seed) -> (probe stage name, dir)
    for n in cfg["ns"]:
        for mu in cfg["mus"]:
            for seed in cfg["seeds"]:
                d = os.path.join(out, "packings", f"N{n}-mu{fmt_mu(mu)}-s{seed}")
                tag = f"N{n}-mu{fmt_mu(mu)}-s{seed}"
                stages.append(pack_stage(R, f"pack {tag}", d,
                                         ["--n", n, "--mu", fmt_mu(mu), "--seed", seed]
                                         + (FRICTIONLESS_PACK if mu == 0 else [])))
                stages.append(probe_stage(R, f"probe {tag}", d, args.probe_g,
                                          cfg["probe_sample"], f"pack {tag}"))
                probe_of[(mu, n, seed)] = (f"probe {tag}", d)
                sweep_entries.append((d, mu, n, seed))
    # The fixed-packing series: the mu = 0 packing of the first N and seed at every other mu.
    n0, s0 = cfg["ns"][0], cfg["seeds"][0]
    if 0 in cfg["mus"]:
        src = probe_of[(0, n0, s0)][1]
        fixed_entries.append((src, 0.0, n0, s0))
        for mu in cfg["mus"]:
            if mu == 0:
                continue
            d = os.path.join(out, "fixed", f"N{n0}-mu{fmt_mu(mu)}")
            tag = f"fixed N{n0}-mu{fmt_mu(mu)}"
            stages.append(pack_stage(R, f"pack {tag}", d, ["--from", src, "--mu", fmt_mu(mu)],
                                     deps=[f"pack N{n0}-mu0-s{s0}"]))
            stages.append(probe_stage(R, f"probe {tag}", d, args.probe_g, cfg["probe_sample"],
                                      f"pack {tag}"))
            fixed_entries.append((d, mu, n0, s0))
    # Fig. 4
    d4 = os.path.join(out, "fig4", f"N{FIG4['n']}-mu{fmt_mu(FIG4['mu'])}-s{FIG4['seed']}")
    stages.append(pack_stage(R, "pack fig4", d4, ["--n", FIG4["n"], "--mu", fmt_mu(FIG4["mu"]),
                                                  "--seed", FIG4["seed"]]))
    ens_args = ["--samples", cfg["samples"], "--probe", "lp"]
    ens_params = {"command": ["unjam", "ensemble", d4] + [str(a) for a in ens_args],
                  "version": R.version}

    def run_ens(st):
        for f in ("ensemble.csv", "ensemble.json"):
            if os.path.exists(os.path.join(d4, f)):
                os.remove(os.path.join(d4, f))
        R.call(st, R.unjam_cmd("ensemble", d4, *ens_args))
    stages.append(Stage("ensemble fig4", f"unjam ensemble {os.path.relpath(d4, out)} "
                        f"--samples {cfg['samples']} --probe lp", os.path.join(d4, "stage.json"),
                        ens_params, run_ens,
                        lambda: read_json(os.path.join(d4, "ensemble.json")) is not None,
                        ["pack fig4"]))
    fig4 = os.path.join(out, "fig4-ensemble.png")
    stages.append(plot_stage(R, "plot fig4", [fig4],
                             [[PY, os.path.join(SCRIPTS, "plot_fig4.py"), d4, "--out", fig4]],
                             ["ensemble fig4"]))
    # Tables
    sweep_csv = os.path.join(out, "sweep.csv")
    fixed_csv = os.path.join(out, "fixed.csv")
    sweep_deps = [probe_of[k][0] for k in probe_of]
    stages.append(table_stage(R, "table sweep", sweep_csv, sweep_entries, sweep_deps))
    fixed_deps = []
    if fixed_entries:
        fixed_deps = [probe_of[(0, n0, s0)][0]] + [
            f"probe fixed N{n0}-mu{fmt_mu(mu)}" for mu in cfg["mus"] if mu != 0]
        stages.append(table_stage(R, "table fixed", fixed_csv, fixed_entries, fixed_deps))
    # Figures
    fig3 = os.path.join(out, "fig3-friction-sweep.png")
    cmd3 = [PY, os.path.join(SCRIPTS, "plot_friction_sweep.py"), sweep_csv]
    if fixed_entries:
        cmd3 += ["--fixed", fixed_csv]
    cmd3 += ["--out", fig3]
    stages.append(plot_stage(R, "plot fig3", [fig3], [cmd3],
                             ["table sweep"] + (["table fixed"] if fixed_entries else [])))
    nmax, s0 = max(cfg["ns"]), cfg["seeds"][0]
    # Fig. 2 per size: d(r) of every mu (first seed); fig2-profiles.png is the largest N.
    fig2_of = {}
    for n in cfg["ns"]:
        fig2_of[n] = os.path.join(out, "fig2-profiles.png" if n == nmax
                                  else f"fig2-profiles-N{n}.png")
        prof_dirs = [probe_of[(mu, n, s0)][1] for mu in cfg["mus"]]
        stages.append(plot_stage(
            R, "plot fig2" if n == nmax else f"plot fig2 N{n}", [fig2_of[n]],
            [[PY, os.path.join(SCRIPTS, "plot_profile.py"), *prof_dirs, "--labels",
              *[f"mu = {fmt_mu(mu)}" for mu in cfg["mus"]], "--out", fig2_of[n]]],
            [probe_of[(mu, n, s0)][0] for mu in cfg["mus"]]))
    fig2 = fig2_of[nmax]
    mu1 = FIG1_MU if FIG1_MU in cfg["mus"] else max(cfg["mus"])
    name1, d1 = probe_of[(mu1, nmax, s0)]
    fig1f = os.path.join(out, "fig1-field.png")
    fig1p = os.path.join(out, "fig1-packing.png")
    stages.append(plot_stage(
        R, "plot fig1", [fig1f, fig1p],
        [[PY, os.path.join(SCRIPTS, "plot_response_field.py"), d1, "--out", fig1f],
         [PY, os.path.join(SCRIPTS, "plot_packing.py"), d1, "--out", fig1p]], [name1]))
    # One probe's own displacement field: the contact of largest normal force of that packing.
    one_dir = os.path.join(out, "probe-one")
    fig_one = os.path.join(out, "fig-probe-field.png")
    one_params = {"command": ["unjam", "probe", os.path.relpath(d1, out), "--contact",
                              "(largest fn)", "--method", "lp", "--g", repr(args.probe_g)],
                  "plot": "plot_probe_field.py", "version": R.version}

    def run_one(st):
        k = largest_force_contact(d1)
        if os.path.exists(fig_one):
            os.remove(fig_one)
        R.call(st, R.unjam_cmd("probe", d1, "--contact", k, "--method", "lp",
                               "--g", repr(args.probe_g), "--out", one_dir, "--quiet"))
        R.call(st, [PY, os.path.join(SCRIPTS, "plot_probe_field.py"), one_dir, "--contact", k,
                    "--packing", d1, "--out", fig_one])
    stages.append(Stage("probe one", f"unjam probe {os.path.relpath(d1, out)} --contact K, "
                        f"{os.path.relpath(fig_one, out)}", os.path.join(out, "stage.json"),
                        one_params, run_one, lambda: nonempty(fig_one),
                        [name1.replace("probe ", "pack ", 1)]))
    figures = [(f"Fig. 1: mean displacement field, N = {nmax}, mu = {fmt_mu(mu1)}", fig1f),
               (f"Fig. 1: the packing and its force chains, N = {nmax}, mu = {fmt_mu(mu1)}",
                fig1p),
               (f"One probe's displacement field (the contact of largest force), N = {nmax}, "
                f"mu = {fmt_mu(mu1)}", fig_one),
               (f"Fig. 2: d(r) per mu, N = {nmax}", fig2),
               *[(f"Fig. 2: d(r) per mu, N = {n}", fig2_of[n]) for n in cfg["ns"] if n != nmax],
               ("Fig. 3: friction sweep (with the fixed-packing inset)", fig3),
               (f"Fig. 4: force-network ensemble, N = {FIG4['n']}, mu = {FIG4['mu']}", fig4)]
    return stages, figures


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    args = parse_args(argv)
    cfg = dict(SCALES[args.scale])
    for k in ("mus", "ns", "seeds", "samples", "probe_sample"):
        if getattr(args, k) is not None:
            cfg[k] = getattr(args, k)
    cfg["mus"] = sorted(set(float(m) for m in cfg["mus"]))
    out = os.path.abspath(args.out)
    try:
        os.makedirs(out, exist_ok=True)
        os.makedirs(os.path.join(out, "logs"), exist_ok=True)
    except OSError as e:
        print(f"experiment: cannot create the output directory {out}: {e.strerror}", file=sys.stderr)
        return 1
    launcher = shlex.split(args.mpirun) + ["-n", str(args.mpi)] if args.mpi > 0 else []
    R = Runner(out, os.path.abspath(args.unjam), args.threads, os.path.join(out, "logs"), launcher)
    try:
        R.version = subprocess.run([R.unjam, "--version"], capture_output=True, text=True,
                                   check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError) as e:
        print(f"experiment: `{R.unjam} --version` failed: {e}", file=sys.stderr)
        return 1
    stages, figures = build(args, cfg, R)
    print(f"experiment: scale {args.scale}, mu {cfg['mus']}, N {cfg['ns']}, seeds "
          f"{cfg['seeds']}, {len(stages)} stages -> {out}", flush=True)
    try:
        R.execute(stages)
        write_report(os.path.join(out, "report.md"), args, cfg, R, figures, argv)
    except StageError as e:
        print(f"experiment: FAILED: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("experiment: interrupted; run the same command again to resume", file=sys.stderr)
        return 130
    ran = sum(1 for t in R.timings if t[2] == "ran")
    print(f"experiment: done in {time.time() - R.t0:.1f} s: {ran} stage(s) ran, "
          f"{len(R.timings) - ran} skipped (cached)")
    print(f"  report:  {os.path.join(out, 'report.md')}")
    print(f"  tables:  {os.path.join(out, 'sweep.csv')}, {os.path.join(out, 'fixed.csv')}")
    for _, f in figures:
        print(f"  figure:  {f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
