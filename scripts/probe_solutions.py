"""How many exact solutions has each probe step? The exact probe from several starts, per contact.

Usage:  /usr/bin/python3 scripts/probe_solutions.py PACKING (--all | --sample M [--seed S])
                     [--starts static compliant lp interior] [--rel-tol 1e-3] [--out DIR]
                     [--unjam PATH] [--threads T] [--g G] [--dt DT]

With friction the probe step's complementarity problem is not a P-matrix problem, and one
probe can have several exact solutions (docs/probe.md, "Where the path starts"). This runs
`unjam probe PACKING --method cd --cd-start START` for every start on the same contacts (into
DIR/START; an interrupted run resumes there), and writes per contact:

  DIR/solutions.csv   contact, f_cont, then f_crit_START and residual_START for every start,
                      exact_starts (starts whose probe is exact: `converged` in probes.csv,
                      residual at most 1e-6 g, docs/probe.md), solutions (the number of
                      distinct exact F_crit: two differ when their relative difference
                      exceeds --rel-tol), f_crit_min, f_crit_max (over the exact ones; empty
                      where no start is exact)
  DIR/solutions.json  the counts (probes, exact per start, probes with two solutions or more),
                      the packing, the starts, the command and the program's version

Starts: static (the path from the static network, the default of --method cd), compliant
(the rigid limit of stiff contacts), lp (from the lp probe's optimum; small packings only:
it fails at 500 disks), interior (from an interior-point iterate of the step). The solutions
found are a lower bound of the step's solutions.
Exit codes: 0 done, 1 bad input or a failed unjam run (its message is printed), 3 interrupted
(run the same command again to resume).
"""

import argparse
import csv
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from experiment_stages import write_table  # noqa: E402
from stage_runner import read_json, write_json  # noqa: E402

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
STARTS = ("static", "compliant", "lp", "interior")


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("packing")
    sel = ap.add_mutually_exclusive_group(required=True)
    sel.add_argument("--all", action="store_true", help="every force-carrying contact")
    sel.add_argument("--sample", type=int, help="M seeded force-carrying contacts")
    ap.add_argument("--seed", type=int, default=1, help="seed of --sample (default 1)")
    ap.add_argument("--starts", nargs="+", choices=STARTS, default=["static", "compliant"],
                    help="starts of the exact path (default: static compliant)")
    ap.add_argument("--rel-tol", type=float, default=1e-3,
                    help="exact F_crit closer than this (relative) are one solution (default 1e-3)")
    ap.add_argument("--out", help="output directory (default: PACKING-solutions)")
    ap.add_argument("--unjam", default=os.path.join(REPO, "build", "release", "unjam"))
    ap.add_argument("--threads", type=int, default=0, help="threads of each unjam run (0: all)")
    ap.add_argument("--g", type=float, help="the probe's opening (unjam probe --g; default 1e-9)")
    ap.add_argument("--dt", type=float, help="the probe step's time step (unjam probe --dt; "
                    "default the quasi-static sqrt(g / 1e-5))")
    a = ap.parse_args(argv)
    if not os.path.isfile(os.path.join(a.packing, "meta.json")):
        ap.error(f"{a.packing} is not a packing directory (no meta.json)")
    if a.sample is not None and a.sample < 1:
        ap.error("--sample must be at least 1")
    if not a.rel_tol > 0:
        ap.error("--rel-tol must be positive")
    for name in ("g", "dt"):
        v = getattr(a, name)
        if v is not None and not (v > 0 and v < float("inf")):
            ap.error(f"--{name} must be a finite number > 0, got {v}")
    if len(set(a.starts)) != len(a.starts):
        ap.error("--starts lists a start twice")
    if not (os.path.isfile(a.unjam) and os.access(a.unjam, os.X_OK)):
        ap.error(f"{a.unjam} is not an executable (build it: cmake --build build/release -j2)")
    a.out = a.out or a.packing.rstrip("/") + "-solutions"
    try:
        os.makedirs(a.out, exist_ok=True)
    except OSError as e:
        ap.error(f"cannot create the output directory {a.out}: {e.strerror or e}")
    return a


def run_start(a, start):
    out = os.path.join(a.out, start)
    os.makedirs(out, exist_ok=True)
    sel = ["--all"] if a.all else ["--sample", str(a.sample), "--seed", str(a.seed)]
    cmd = [a.unjam, "probe", a.packing, *sel, "--method", "cd", "--cd-start", start,
           "--threads", str(a.threads), "--out", out]
    cmd += [arg for name in ("g", "dt") if getattr(a, name) is not None
            for arg in (f"--{name}", repr(getattr(a, name)))]
    print(f"[{start}] {' '.join(cmd)}", flush=True)
    p = subprocess.run(cmd)
    if p.returncode != 0:
        sys.exit(p.returncode if p.returncode == 3 else 1)
    with open(os.path.join(out, "probes.csv"), newline="") as f:
        return {int(r["contact"]): r for r in csv.DictReader(f)}


def distinct(values, rel_tol):
    """The number of clusters of sorted values, a new one where a value exceeds the last by rel_tol."""
    n, last = 0, None
    for v in sorted(values):
        if last is None or abs(v - last) > rel_tol * max(abs(last), abs(v)):
            n += 1
        last = v
    return n


def main(argv):
    a = parse(argv)
    runs = {s: run_start(a, s) for s in a.starts}
    contacts = sorted(runs[a.starts[0]])
    for s in a.starts[1:]:
        if sorted(runs[s]) != contacts:
            sys.exit(f"probe_solutions: the starts probed different contacts ({a.starts[0]}, {s})")
    cols = ["contact", "f_cont"]
    for s in a.starts:
        cols += [f"f_crit_{s}", f"residual_{s}"]
    cols += ["exact_starts", "solutions", "f_crit_min", "f_crit_max"]
    rows, several = [], 0
    exact_per_start = {s: 0 for s in a.starts}
    for k in contacts:
        row = {"contact": k, "f_cont": runs[a.starts[0]][k]["f_cont"]}
        exact = []
        for s in a.starts:
            r = runs[s][k]
            row[f"f_crit_{s}"], row[f"residual_{s}"] = r["f_crit"], r["residual"]
            if r["converged"] == "1":  # the step solved exactly (unjam's own verdict)
                exact.append(float(r["f_crit"]))
                exact_per_start[s] += 1
        n = distinct(exact, a.rel_tol)
        several += n >= 2
        row.update(exact_starts=len(exact), solutions=n,
                   f_crit_min=repr(min(exact)) if exact else "",
                   f_crit_max=repr(max(exact)) if exact else "")
        rows.append(row)

    write_table(os.path.join(a.out, "solutions.csv"), rows, cols)
    first = read_json(os.path.join(a.out, a.starts[0], "probe_summary.json")) or {}
    summary = {
        "packing": os.path.abspath(a.packing), "N": first.get("N"), "mu": first.get("mu"),
        "starts": a.starts, "rel_tol": a.rel_tol,
        "probes": len(rows), "exact": exact_per_start,
        "with_two_solutions_or_more": several,
        "program_version": first.get("program_version"),
        "command": " ".join([os.path.basename(sys.executable), *sys.argv]),
    }
    write_json(os.path.join(a.out, "solutions.json"), summary)
    print(f"{len(rows)} probes of {a.packing} from {', '.join(a.starts)}: exact "
          + ", ".join(f"{s} {exact_per_start[s]}" for s in a.starts)
          + f"; {several} with two exact solutions or more -> {a.out}/solutions.csv")


if __name__ == "__main__":
    main(sys.argv[1:])
