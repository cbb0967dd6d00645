#!/usr/bin/python3
"""The exact probe step solved by unjam (`--method cd`) and by Siconos numerics' 2D
frictional-contact solvers on the same problems, with CPU times (docs/benchmarks.md).

For each contact K: `unjam probe P --contact K --method cd --export-problem step.dat` solves
the step and writes it in Siconos' file format (W dense, q, mu); Siconos then solves the file
with fc2d Lemke and fc2d NSGS. Printed per contact and solver: F_crit / F0 (the probed
contact's normal force), whether the solver reports success, the solution's Signorini and
Coulomb violations, and CPU seconds (unjam: the child process's user + system time, which
includes reading the packing; Siconos: the solver call alone, the file's parsing apart).

Usage: bench/siconos_compare.py --unjam build/release/unjam --packing P --contacts 0 97 194
                                [--nsgs-iterations 100000] [--solvers cd lemke nsgs]
"""
import argparse
import csv
import json
import os
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np
import siconos.numerics as sn


def child_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def unjam_cd(unjam, packing, k, out):
    dat = os.path.join(out, f"step-{k}.dat")
    t0 = child_cpu()
    subprocess.run([unjam, "probe", packing, "--contact", str(k), "--method", "cd", "--out", out,
                    "--export-problem", dat, "--threads", "1", "--quiet"], check=True, capture_output=True)
    cpu = child_cpu() - t0
    with open(os.path.join(out, f"probe-{k}-forces.csv")) as f:
        rows = [r for r in f if not r.startswith("#")]
    fn = {int(r["contact"]): float(r["fn"]) for r in csv.DictReader(rows)}
    return dat, fn[k], cpu


def violations(r, v, mu):
    """Largest Signorini and Coulomb violations of Siconos' (r, v), relative to max fn."""
    fn, ft, vn = r[0::2], r[1::2], v[0::2]
    scale = max(fn.max(), 1e-300)
    return {"penetration": float(max(0.0, -vn.min()) / max(np.abs(v).max(), 1e-300)),
            "coulomb": float(max(0.0, (np.abs(ft) - mu * fn).max()) / scale),
            "tensile": float(max(0.0, -fn.min()) / scale)}


def siconos_solve(dat, k, solver, nsgs_iterations):
    fc = sn.frictionContact_new_from_filename(dat)
    nc = fc.numberOfContacts
    r, v = np.zeros(2 * nc), np.zeros(2 * nc)
    options = sn.SolverOptions(solver)
    if solver == sn.SICONOS_FRICTION_2D_NSGS:
        options.iparam[sn.SICONOS_IPARAM_MAX_ITER] = nsgs_iterations
        options.dparam[sn.SICONOS_DPARAM_TOL] = 1e-12
    t0 = time.process_time()
    info = sn.fc2d_driver(fc, r, v, options)
    cpu = time.process_time() - t0
    mu = float(fc.mu[0])
    return r[2 * k], info, violations(r, v, mu), cpu


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--unjam", default="build/release/unjam")
    ap.add_argument("--packing", required=True)
    ap.add_argument("--contacts", type=int, nargs="+", required=True)
    ap.add_argument("--solvers", nargs="+", default=["cd", "lemke", "nsgs"], choices=["cd", "lemke", "nsgs"])
    ap.add_argument("--nsgs-iterations", type=int, default=100000)
    args = ap.parse_args()
    solvers = {"lemke": sn.SICONOS_FRICTION_2D_LEMKE, "nsgs": sn.SICONOS_FRICTION_2D_NSGS}
    rows = []
    with tempfile.TemporaryDirectory() as out:
        for k in args.contacts:
            dat, f_cd, cpu = unjam_cd(args.unjam, args.packing, k, out)
            rows.append({"contact": k, "solver": "unjam cd", "F_crit": f_cd, "ok": True, "cpu_s": cpu})
            print(json.dumps(rows[-1]), flush=True)
            for name in args.solvers:
                if name == "cd":
                    continue
                f, info, viol, cpu = siconos_solve(dat, k, solvers[name], args.nsgs_iterations)
                rows.append({"contact": k, "solver": f"siconos {name}", "F_crit": f, "ok": info == 0,
                             "cpu_s": cpu, **viol})
                print(json.dumps(rows[-1]), flush=True)
    print("\n| contact | solver | F_crit / F0 | success | CPU s |")
    print("|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['contact']} | {r['solver']} | {r['F_crit']:.6f} | {'yes' if r['ok'] else 'no'} | {r['cpu_s']:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
