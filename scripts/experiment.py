"""The paper's experiment from one command: packings over friction and size, probes, Figs. 1-4, report.

Usage:  /usr/bin/python3 scripts/experiment.py --scale demo|tiny|paper [--out runs/experiment]
                                               [--threads N] [--unjam PATH]
                                               [--mpi K [--mpirun LAUNCHER]]
                                               [--mus ...] [--ns ...] [--seeds ...]
                                               [--probe-g G] [--samples S]
                                               [--skip fixed fig4 probe-one threshold]

Stages (each drives the `unjam` binary or one of scripts/plot_*.py through subprocess):

  pack/probe   for every (mu, N, seed) of the scale: `unjam pack` into
               OUT/packings/N{N}-mu{mu}-s{seed}, then `unjam probe DIR --all --method lp`
               (`--sample K` at the paper scale: K seeded contacts per packing);
  fixed        the mu = 0 packing of the first N and seed re-relaxed at every other mu
               (`unjam pack --from`) into OUT/fixed/N{N}-mu{mu}, probed the same way
               (the paper's Fig. 3b inset);
  exact        with --cd-sample K > 0 (300 at the paper scale), on the sweep's packings of at
               most --cd-max-n disks (500): `unjam probe DIR --sample K --seed 1 --method cd
               --cd-start interior` (--cd-start; --cd-max-pieces, --cd-accept-residual,
               --cd-compliant-start, --cd-softer-starts, --cd-settle-compliance,
               --cd-lost-factor and --cd-restart-floor passed on where given)
               (the paper's own probe step, solved exactly; docs/probe.md) and `--method lp` on
               the same contacts, into DIR/exact-cd and DIR/exact-lp; the same on the
               fixed series up to --cd-fixed-max-mu (0.1), into its packings' directories;
  fig4         a 50-disk mu = 0.1 packing, `unjam ensemble --probe cd`, plot_fig4.py;
  probe one    the Fig. 1 packing's contact of largest force probed alone (`unjam probe
               --contact K`) and its displacement field drawn (plot_probe_field.py);
  threshold    every swept packing with friction: `unjam threshold DIR`, its friction
               threshold mu_s (the smallest mu at which its contacts still admit a force
               network) into DIR/friction_threshold.json;
  tables       OUT/sweep.csv and OUT/fixed.csv (one row per packing, from probe_summary.json),
               OUT/exact-probe.csv (lp and cd on the same contacts, one row per packing),
               OUT/exact-probe-fixed.csv (the same over the fixed series),
               OUT/friction-threshold.csv (mu_s per packing with friction);
  figures      fig3-friction-sweep.png, fig3-exact-vs-lp.png (with --cd-sample: Fig. 3 by both
               probes on the same contacts, scripts/plot_exact_sweep.py),
               fig3-inset-exact-vs-lp.png (its inset by both), fig2-profiles.png
               (largest N, one curve per mu),
               fig1-field.png and fig1-packing.png (mu = 0.5, else the largest mu);
  report       OUT/report.md: measured values per mu beside the paper's findings
               (docs/results/README.md), agree / disagree per finding, the packings' friction
               thresholds, parameters, timings, figures.

--skip leaves out the optional stages named: fixed (the fixed-packing series, fixed.csv and the
Fig. 3 inset), fig4 (the 50-disk ensemble and Fig. 4), probe-one (the single probe's field),
threshold (the friction thresholds and their table: ~40 min of one core per packing at 8000
disks, 1-2 min at 2000, seconds at 1000 and below; docs/ensemble.md), e.g.
when a run at new sizes only needs the sweep, Fig. 2 and Fig. 3.  The sweep's pack and probe
stages are the same with or without it, so their cached results stay valid either way.

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

The code, by job: scripts/stage_runner.py (the stage cache, subprocesses, signals),
scripts/experiment_stages.py (the scales and the stage graph), scripts/experiment_report.py
(report.md and its verdicts), scripts/sweep_table.py (the per-packing table and its
aggregation over seeds, shared with plot_friction_sweep.py); this file parses the command line.
"""

import argparse
import math
import os
import shlex
import subprocess
import sys
import time

from experiment_report import START_WORDS, write_report
from experiment_stages import REPO, SCALES, SKIPPABLE, build
from stage_runner import Runner, StageError


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
    p.add_argument("--cd-sample", type=int, help="override the scale's contacts per packing "
                   "probed by the exact probe (--method cd) and by lp on the same contacts, "
                   "side by side in report.md (0 = none; default: 300 at the paper scale, 0 "
                   "otherwise)")
    p.add_argument("--cd-start", choices=list(START_WORDS), help="where the "
                   "exact probe's path starts (`unjam probe --cd-start`; default interior: the "
                   "path from an interior-point iterate, exact on every 500-disk probe measured "
                   "and 1.2-4.7 times faster than compliant there; compliant: the rigid limit of "
                   "stiff contacts followed from the static network; static: the branch from "
                   "the static network; inertial: the step with more inertia followed in dt to the "
                   "quasi-static one; interior-inertial: interior, and where it is not exact the "
                   "inertial start's continuation; docs/probe.md, \"Where the path starts\", \"An "
                   "interior-point start\")")
    p.add_argument("--cd-max-n", type=int, help="the exact probe runs on packings of at most "
                   "this many disks (default 500: its reach with friction, docs/probe.md)")
    p.add_argument("--cd-fixed-max-mu", type=float, metavar="MU", help="the exact probe runs "
                   "on the fixed-packing series up to this mu (default 0.1: about a second per "
                   "probe at 500 disks, ~30 s at 0.2, mostly out of reach above; docs/probe.md, "
                   "\"The fixed packing by the paper's probe\"); its table is "
                   "exact-probe-fixed.csv")
    p.add_argument("--cd-max-pieces", type=int, help="the exact probe's budget of pieces per "
                   "probe (`unjam probe --cd-max-pieces`; stopped probes are counted in "
                   "exact-probe.csv and report.md; default 0: none; docs/probe.md, \"A budget "
                   "of pieces per probe\")")
    p.add_argument("--cd-accept-residual", type=float, metavar="R", help="the exact probe "
                   "stops its search at its first solution within R g, 1e-6 to 1e-3 (`unjam probe "
                   "--cd-accept-residual`; such probes are near-exact and counted in "
                   "exact-probe.csv and report.md; default: only an exact solution stops it; "
                   "docs/probe.md, \"Accepting a near-exact solution\")")
    p.add_argument("--cd-compliant-start", type=float, metavar="C", help="the compliance the "
                   "exact probe's continuation starts from, > 0 (`unjam probe "
                   "--cd-compliant-start`; default: unjam's; docs/probe.md, \"Where the "
                   "continuation starts\")")
    p.add_argument("--cd-softer-starts", type=int, metavar="S", help="the continuation's softer "
                   "starts, >= 0 (`unjam probe --cd-softer-starts`; default: unjam's; which "
                   "settings pay at which friction: docs/probe.md, \"At a glance\")")
    p.add_argument("--cd-settle-compliance", type=float, metavar="C", help="the exact probe "
                   "ends a path at its first exact solution at or below this compliance, >= 0 "
                   "(`unjam probe --cd-settle-compliance`; default 0: never, the rigid limit; it may "
                   "return another of the step's exact solutions at high friction; docs/probe.md, "
                   "\"Settling at an exact solution\")")
    p.add_argument("--cd-lost-factor", type=float, metavar="L", help="the exact probe drops a "
                   "path whose forces at the full opening have a residual above L times its "
                   "compliance (at least 1e-3) in g, >= 0 (`unjam probe --cd-lost-factor`; default "
                   "0: off; docs/probe.md, \"Paths that lose their digits\")")
    p.add_argument("--cd-restart-floor", type=float, metavar="C", help="the exact probe's "
                   "continuation is not restarted below this compliance, its next softer start "
                   "follows instead, >= 0 (`unjam probe --cd-restart-floor`; default 0: every "
                   "restart; docs/probe.md, \"Restarts below a floor\")")
    p.add_argument("--probe-g", type=float, default=1e-9,
                   help="opening gap g of the probes (R_max; default 1e-9)")
    p.add_argument("--mpi", type=int, default=0, metavar="K",
                   help="run the probe stages over K MPI ranks (`mpirun -n K`; each rank uses "
                        "--threads threads); results do not depend on it")
    p.add_argument("--mpirun", default="mpirun",
                   help="the MPI launcher of --mpi, split like a shell word list (default mpirun)")
    p.add_argument("--skip", nargs="+", default=[], choices=SKIPPABLE, metavar="STAGE",
                   help="leave out these optional stages (any of: " + ", ".join(SKIPPABLE)
                        + "): fixed = the fixed-packing series, its table and the Fig. 3 inset; "
                        "fig4 = the ensemble and Fig. 4; probe-one = the single probe's field. "
                        "Default: none (every stage runs); the pack and probe stages of the "
                        "sweep do not depend on it")
    args = p.parse_args(argv)
    # Every override is checked here, before any stage runs (unjam would refuse the same
    # values only when their stage starts, hours into a run).
    if args.mpi < 0:
        p.error("--mpi must be >= 0")
    if args.threads < 0:
        p.error("--threads must be >= 0")
    if args.probe_sample is not None and args.probe_sample < 0:
        p.error("--probe-sample must be >= 0")
    if args.cd_sample is not None and args.cd_sample < 0:
        p.error(f"--cd-sample must be >= 0, got {args.cd_sample}")
    if args.cd_max_n is not None and args.cd_max_n < 0:
        p.error(f"--cd-max-n must be >= 0, got {args.cd_max_n}")
    if args.cd_fixed_max_mu is not None and not (math.isfinite(args.cd_fixed_max_mu)
                                                 and args.cd_fixed_max_mu >= 0):
        p.error(f"--cd-fixed-max-mu must be a finite number >= 0, got {args.cd_fixed_max_mu}")
    if args.cd_max_pieces is not None and args.cd_max_pieces < 0:
        p.error(f"--cd-max-pieces must be >= 0, got {args.cd_max_pieces}")
    if args.cd_accept_residual is not None and not 1e-6 <= args.cd_accept_residual <= 1e-3:
        p.error(f"--cd-accept-residual must be from 1e-6 to 1e-3 g, got {args.cd_accept_residual}")
    if args.cd_compliant_start is not None and not (math.isfinite(args.cd_compliant_start)
                                                    and args.cd_compliant_start > 0):
        p.error(f"--cd-compliant-start must be a finite number > 0, got {args.cd_compliant_start}")
    if args.cd_softer_starts is not None and args.cd_softer_starts < 0:
        p.error(f"--cd-softer-starts must be >= 0, got {args.cd_softer_starts}")
    if args.cd_settle_compliance is not None and not (math.isfinite(args.cd_settle_compliance)
                                                      and args.cd_settle_compliance >= 0):
        p.error(f"--cd-settle-compliance must be a finite number >= 0, got {args.cd_settle_compliance}")
    if args.cd_lost_factor is not None and not (math.isfinite(args.cd_lost_factor)
                                                and args.cd_lost_factor >= 0):
        p.error(f"--cd-lost-factor must be a finite number >= 0, got {args.cd_lost_factor}")
    if args.cd_restart_floor is not None and not (math.isfinite(args.cd_restart_floor)
                                                  and args.cd_restart_floor >= 0):
        p.error(f"--cd-restart-floor must be a finite number >= 0, got {args.cd_restart_floor}")
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


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    args = parse_args(argv)
    cfg = dict(SCALES[args.scale])
    for k in ("mus", "ns", "seeds", "samples", "probe_sample", "cd_sample", "cd_max_n",
              "cd_fixed_max_mu", "cd_start", "cd_max_pieces", "cd_accept_residual", "cd_compliant_start",
              "cd_softer_starts", "cd_settle_compliance", "cd_lost_factor", "cd_restart_floor"):
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
    R = Runner(out, os.path.abspath(args.unjam), args.threads, os.path.join(out, "logs"), launcher,
               cwd=REPO)
    try:
        R.version = subprocess.run([R.unjam, "--version"], capture_output=True, text=True,
                                   check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError) as e:
        print(f"experiment: `{R.unjam} --version` failed: {e}", file=sys.stderr)
        return 1
    stages, figures = build(args, cfg, R)
    print(f"experiment: scale {args.scale}, mu {cfg['mus']}, N {cfg['ns']}, seeds "
          f"{cfg['seeds']}, {len(stages)} stages -> {out}"
          + (f" (skipped: {', '.join(args.skip)})" if args.skip else ""), flush=True)
    try:
        R.execute(stages)
        command = [sys.executable, os.path.relpath(os.path.abspath(__file__), REPO)] + argv
        write_report(os.path.join(out, "report.md"), args, cfg, R, figures, command)
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
    tables = (["sweep.csv"] + ([] if "fixed" in args.skip else ["fixed.csv"])
              + (["exact-probe.csv"] if cfg["cd_sample"] > 0 else []))
    if "threshold" not in args.skip and any(mu > 0 for mu in cfg["mus"]):
        tables.append("friction-threshold.csv")
    print(f"  tables:  {', '.join(os.path.join(out, t) for t in tables)}")
    for _, f in figures:
        print(f"  figure:  {f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
