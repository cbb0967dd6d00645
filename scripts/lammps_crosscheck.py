"""A packing's static force network against LAMMPS' soft granular DEM (docs/lammps.md).

Usage:  /usr/bin/python3 scripts/lammps_crosscheck.py PACKING [--out OUT]
                     [--strain E [E ...]] [--bounds CSV] [--tol T] [--max-steps N]
                     [--lmp PATH]

An independent code computes a static force network of the same packing. LAMMPS
(Debian's `lammps`, pair style gran/hooke/history: linear normal spring kn, tangential
spring kt = 2/7 kn with Coulomb's cap mu fn, the packing's mu) takes the packing's grains,
compresses the periodic cell and every position affinely by the strain E (so a touching
pair overlaps by ~E |l|), and relaxes by damped dynamics at that fixed cell until every
grain's net force and torque / radius are below T F0 (F0 = 2 R_avg P_ext). Its contact forces
are then scaled by P_ext / P_L, where P_L = sum_c fn_c |l_c| / (2 A) is the soft network's
own pressure (virial; A the cell's area), and compared with the packing's:

  network   the pairs LAMMPS finds loaded against the packing's contact list: `extra`, loaded
            in LAMMPS but not listed by the packing (a pair the packing's detection missed, or
            a gap below E |l| closed by the compression); `missing`, carrying force in the
            packing (fn > 1e-9 F0) but not loaded in LAMMPS
  forces    max |fn_L - fn| / F0 and max |ft_L - ft| / F0 over the union of both networks
            (a pair absent from one has fn = ft = 0 there). At mu = 0 an isostatic packing has
            one force network, so both must agree up to the soft network's distance from the
            rigid limit, O(E); with friction the networks are two of many admissible ones
  bounds    with --bounds (a CSV with a, b, fn_min, fn_max in the packing's force unit, as
            written by `unjam bounds` or the fixtures' bounds-reference.csv): every contact's
            scaled fn_L must lie in [fn_min, fn_max] of the admissible networks; the largest
            excess outside its interval, in F0, and the contacts loaded in LAMMPS that the
            bounds do not list
  balance   the net force and torque / radius of every grain summed from the contact forces
            read back, by `unjam info` on LAMMPS' state (checks the reading of LAMMPS' pair
            output: its signs and its pairs)

Several strains (--strain 1e-4 1e-5 1e-6) run one after the other, each in OUT/strain-E, so
that the approach to the rigid limit can be read off the table.

Outputs (each written atomically), per strain in OUT/strain-E:
  in.lammps, data.lammps  LAMMPS' input, with every value written out (rerun: lmp -in in.lammps)
  log.lammps, pairs.dump, grains.dump  LAMMPS' log and its final pair forces and grains
  forces.csv   a, b, fn, ft (the packing's), fn_lammps, ft_lammps (scaled by P_ext / P_L),
               fn_min, fn_max (from --bounds, empty without), in the packing's force unit
and in OUT:
  crosscheck.json  the command, the packing (its directory, program version and command),
                   LAMMPS' version, the settings and every strain's results
  crosscheck.png   fn by LAMMPS against fn of the packing for every strain; with --bounds,
                   each contact's interval with both networks' fn in it
A table is printed to stdout.

Exit codes: 0 done (the numbers say how well the codes agree; tests/test_lammps_crosscheck.py
holds them to bounds), 1 bad input or command line, 2 LAMMPS failed or did not relax within
--max-steps (its log is kept).
"""

import json
import math
import os
import resource
import shutil
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import unjam_plot as up  # noqa: E402


class LammpsFailed(Exception):
    """LAMMPS exited with an error or did not relax: exit status 2."""


# The soft model, in units of the packing's: kn from the strain so that a touching pair
# compressed by E |l| carries ~F0; damping ratio DAMPING of a pair's normal oscillation, a
# global viscous drag for the floppy grains, and a time step of a tenth of the lightest
# grain's sqrt(m / kn).
DAMPING = 0.5
VISCOUS = 0.1
DT_FACTOR = 0.1
CHECK_EVERY = 100


def parse_args(argv):
    p = up.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("packing", help="packing directory (meta.json, particles.csv, contacts.csv)")
    p.add_argument("--out", help="output directory (default PACKING/lammps-crosscheck)")
    p.add_argument("--strain", type=float, nargs="+", default=[1e-5],
                   help="affine compression of the cell (default 1e-5); several run in turn")
    p.add_argument("--bounds", help="CSV of the admissible intervals (a, b, fn_min, fn_max)")
    p.add_argument("--tol", type=float, default=None,
                   help="relaxed when every grain's net force and torque / radius, and the "
                        "damping force its speed would meet, are below this many F0 "
                        "(default: 1e-9, or 4 times the floor set by the positions' "
                        "round-off where that is higher)")
    p.add_argument("--max-steps", type=int, default=20_000_000,
                   help="give up after this many LAMMPS steps per strain (default 2e7)")
    p.add_argument("--lmp", default="lmp", help="the LAMMPS executable (default lmp, Debian's)")
    p.add_argument("--no-own-bounds", action="store_true",
                   help="skip `unjam bounds` of LAMMPS' state (2 LPs per contact: minutes "
                        "from ~1000 disks on)")
    p.add_argument("--unjam", default=None,
                   help="the unjam tool (default: $UNJAM, else build/release/unjam of this "
                        "checkout, else unjam on PATH)")
    a = p.parse_args(argv)
    for e in a.strain:
        if not (math.isfinite(e) and 0 < e < 0.01):
            raise up.UserError(f"--strain must be in (0, 0.01), got {e}")
    if a.tol is not None and not (math.isfinite(a.tol) and a.tol > 0):
        raise up.UserError(f"--tol must be a finite number > 0, got {a.tol}")
    if a.max_steps < CHECK_EVERY:
        raise up.UserError(f"--max-steps must be at least {CHECK_EVERY}, got {a.max_steps}")
    return a


def read_packing(directory):
    up.require_dir(directory)
    meta = up.read_meta(directory)
    particles = up.read_particles(directory)
    contacts = up.read_contacts(directory, len(particles["radius"]))
    return meta, particles, contacts


def read_bounds(path, n):
    t = up.read_intervals(path)
    out = {}
    for a, b, lo, hi in zip(t["a"], t["b"], t["fn_min"], t["fn_max"]):
        if a != round(a) or b != round(b) or not (0 <= a < n and 0 <= b < n):
            raise up.UserError(f"{path}: a contact joins grains outside 0..{n - 1}")
        out[pair_key(int(a), int(b))] = (float(lo), float(hi))
    return out


def pair_key(a, b):
    return (a, b) if a < b else (b, a)


def lammps_executable(lmp):
    """The LAMMPS executable's path and its version line."""
    exe = shutil.which(lmp)
    if exe is None:
        raise up.UserError(f"'{lmp}' not found: install Debian's lammps (scripts/setup.sh) "
                           "or pass --lmp PATH")
    r = subprocess.run([exe, "-h"], capture_output=True, text=True)
    for line in r.stdout.splitlines():
        if line.startswith("Large-scale Atomic/Molecular"):
            return exe, "LAMMPS" + line.split("Simulator", 1)[1].replace(" - ", " ", 1)
    return exe, "unknown"


def model(particles, F0, strain):
    """kn, kt, gamman, gammat, viscous drag and dt of the soft model at this strain."""
    R = particles["radius"]
    m = math.pi * R ** 2  # mass of a disk of unit area density (LAMMPS' density/disc)
    kn = F0 / (strain * 2.0 * float(np.mean(R)))
    gamman = 2.0 * DAMPING * math.sqrt(kn / (0.5 * float(np.mean(m))))
    return {"kn": kn, "kt": 2.0 / 7.0 * kn, "gamman": gamman, "gammat": 0.5 * gamman,
            "viscous": VISCOUS * math.sqrt(kn * float(np.mean(m))),
            "dt": DT_FACTOR * math.sqrt(float(np.min(m)) / kn)}


def relaxation_floor(meta, p, m_max, F0):
    """The smallest damping force, in F0, that the relaxation can tell from rest: a grain
    slower than half a unit in the last place of a coordinate (up to L) per time step does
    not move in floating point, and its drag and contact damping at that speed stay. Below
    it a creeping grain passes for static while its contacts are out of balance."""
    ulp = math.ulp(max(meta["Lx"], meta["Ly"]))
    return (p["viscous"] + p["gamman"] * m_max) * 0.5 * ulp / p["dt"] / F0


def data_file(meta, particles, strain):
    s = 1.0 - strain
    Lx, Ly = meta["Lx"], meta["Ly"]
    x = np.mod(particles["x"], Lx) * s
    y = np.mod(particles["y"], Ly) * s
    lines = [f"unjam packing compressed by {strain!r}", "",
             f"{len(x)} atoms", "1 atom types", "",
             f"0 {Lx * s!r} xlo xhi", f"0 {Ly * s!r} ylo yhi", "-0.5 0.5 zlo zhi", "",
             "Atoms # sphere", ""]
    for i, (xi, yi, ri) in enumerate(zip(x, y, particles["radius"])):
        lines.append(f"{i + 1} 1 {2.0 * float(ri)!r} 1.0 {float(xi)!r} {float(yi)!r} 0.0")
    return "\n".join(lines) + "\n"


def input_file(mu, p, tol_F, max_steps, m_max):
    """LAMMPS input: damped dynamics at the fixed compressed cell until every grain's net
    force and torque / radius are below tol_F and no grain moves fast enough for a damping
    force (the drag, a contact's normal damping) above tol_F, then one pass writing the pairs
    and grains. The second condition keeps a grain that creeps against the drag, with
    contacts out of balance, from passing for static."""
    v_tol = tol_F / (p["viscous"] + p["gamman"] * m_max)
    return f"""# unjam's packing relaxed by soft granular DEM (scripts/lammps_crosscheck.py)
dimension 2
units lj
atom_style sphere
boundary p p p
comm_modify vel yes
read_data data.lammps
set group all density/disc 1.0
pair_style gran/hooke/history {p['kn']!r} {p['kt']!r} {p['gamman']!r} {p['gammat']!r} {mu!r} 1
pair_coeff * *
neighbor {0.1!r} bin
neigh_modify delay 0 every 1 check yes
fix move all nve/sphere disc
fix plane all enforce2d
fix drag all viscous {p['viscous']!r}
timestep {p['dt']!r}
variable f atom sqrt(fx*fx+fy*fy)
compute tq all property/atom tqz radius
variable t atom abs(c_tq[1])/c_tq[2]
compute fmax all reduce max v_f v_t
variable fmax equal (c_fmax[1]>=c_fmax[2])*c_fmax[1]+(c_fmax[1]<c_fmax[2])*c_fmax[2]
variable v atom sqrt(vx*vx+vy*vy)
compute vmax all reduce max v_v
variable relaxed equal (v_fmax<{tol_F!r})*(c_vmax<{v_tol!r})
fix halt all halt {CHECK_EVERY} v_relaxed > 0.5 error continue
thermo_style custom step ke v_fmax c_vmax
thermo 10000
thermo_modify format float %.6g
run {max_steps}
print "relaxed ${{relaxed}} steps $(step) fmax ${{fmax}}"
compute pair all pair/local force p1 p2
compute ids all property/local patom1 patom2
dump pairs all local 1 pairs.dump c_ids[1] c_ids[2] c_pair[1] c_pair[2] c_pair[3]
dump_modify pairs format float %.17g
dump grains all custom 1 grains.dump id x y radius fx fy tqz
dump_modify grains format float %.17g sort id
run 0
"""


def run_lammps(exe, workdir, stdin_files):
    for name, text in stdin_files.items():
        up.write_file_atomic(os.path.join(workdir, name), lambda f, t=text: f.write(t))
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    wall = time.monotonic()
    r = subprocess.run([exe, "-in", "in.lammps", "-log", "log.lammps", "-screen", "none",
                        "-nocite"], cwd=workdir, capture_output=True, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    log = os.path.join(workdir, "log.lammps")
    if r.returncode != 0:
        tail = ""
        if os.path.exists(log):
            with open(log) as f:
                tail = "".join(f.readlines()[-5:])
        raise LammpsFailed(f"LAMMPS failed in {workdir} (exit {r.returncode}):\n"
                           f"{tail or r.stderr or r.stdout}")
    relaxed, steps, fmax = None, None, None
    with open(log) as f:
        for line in f:
            if line.startswith("relaxed "):
                w = line.split()
                relaxed, steps, fmax = w[1] == "1", int(w[3]), float(w[5])
    if relaxed is None:
        raise LammpsFailed(f"{log}: no 'relaxed' line: the run did not finish")
    return {"relaxed": relaxed, "steps": steps, "fmax": fmax, "cpu_s": cpu,
            "wall_s": time.monotonic() - wall}


def read_dump_rows(path, ncols):
    with open(path) as f:
        lines = f.read().splitlines()
    try:
        start = next(i for i, ln in enumerate(lines) if ln.startswith("ITEM: ENTRIES")
                     or ln.startswith("ITEM: ATOMS")) + 1
    except StopIteration:
        raise LammpsFailed(f"{path}: no entries") from None
    rows = [ln.split() for ln in lines[start:] if ln.strip()]
    if any(len(r) != ncols for r in rows):
        raise LammpsFailed(f"{path}: expected {ncols} columns")
    return np.array(rows, dtype=float).reshape(-1, ncols)


def lammps_network(workdir, Lx, Ly):
    """Pairs loaded in LAMMPS' final state: {(a, b): (fn, ft, |l|, nx, ny)} with a < b
    (0-based), n the unit vector from a to b and ft the tangential force on b along
    t = (-ny, nx) (docs/packing-format.md); and the grains, one row per grain in the order of
    their ids (id, x, y, radius, fx, fy, tqz)."""
    g = read_dump_rows(os.path.join(workdir, "grains.dump"), 7)
    x, y = g[:, 1], g[:, 2]
    pairs = read_dump_rows(os.path.join(workdir, "pairs.dump"), 5)
    net = {}
    for i1, j1, fn, fs1, fs2 in pairs:
        if not fn > 0:
            continue  # within the neighbour cut-off, not touching
        i, j = int(i1) - 1, int(j1) - 1
        a, b = pair_key(i, j)
        dx = up.min_image(x[b] - x[a], Lx)
        dy = up.min_image(y[b] - y[a], Ly)
        dist = math.hypot(dx, dy)
        nx, ny = dx / dist, dy / dist
        # LAMMPS: the force on atom i is (x_i - x_j) fn / |l| + fs, fs = (p1, p2) tangential.
        sign = -1.0 if b == j else 1.0
        ft = sign * (-ny * fs1 + nx * fs2)
        if (a, b) in net:
            raise LammpsFailed(f"pair {a}-{b} appears twice in pairs.dump (two images)")
        net[(a, b)] = (float(fn), float(ft), dist, nx, ny)
    return net, g


def interval_excess(fn, bounds, F0):
    """How far the forces fn ({pair: fn}) lie outside the intervals bounds ({pair: (fn_min,
    fn_max)}), in F0, and the pairs of fn that bounds does not list. A pair of bounds absent
    from fn carries no force, which its interval must allow (fn_min <= 0)."""
    excess, unlisted = 0.0, []
    for k, f in fn.items():
        if k not in bounds:
            unlisted.append(list(k))
            continue
        lo, hi = bounds[k]
        excess = max(excess, (lo - f) / F0, (f - hi) / F0)
    for k, (lo, _) in bounds.items():
        if k not in fn:
            excess = max(excess, lo / F0)
    return excess, unlisted


def compare(meta, contacts, bounds, net, cell, F0, strain, run):
    """LAMMPS' network, scaled to P_ext, against the packing's and its intervals."""
    area = cell[0] * cell[1]
    P_L = sum(fn * dist for fn, _, dist, _, _ in net.values()) / (2.0 * area)
    scale = meta["P_ext"] / P_L
    carrying = up.force_carrying(contacts["fn"], F0)
    ours = {}
    listed = set()
    for a, b, fn, ft, c in zip(contacts["a"], contacts["b"], contacts["fn"], contacts["ft"],
                               carrying):
        key = pair_key(int(a), int(b))
        listed.add(key)
        if c:  # ft is the same for (b, a): both the force and t change sign
            ours[key] = (float(fn), float(ft))
    theirs = {k: (v[0] * scale, v[1] * scale) for k, v in net.items()}
    extra = sorted(k for k in theirs if k not in listed)
    missing = sorted(k for k in ours if k not in theirs)
    keys = sorted(set(ours) | set(theirs))
    dfn = max(abs(theirs.get(k, (0, 0))[0] - ours.get(k, (0, 0))[0]) for k in keys) / F0
    dft = max(abs(theirs.get(k, (0, 0))[1] - ours.get(k, (0, 0))[1]) for k in keys) / F0
    rows = []
    for k in keys:
        lo, hi = bounds.get(k, (math.nan, math.nan)) if bounds else (math.nan, math.nan)
        fn, ft = ours.get(k, (0.0, 0.0))
        fl, tl = theirs.get(k, (0.0, 0.0))
        rows.append({"a": k[0], "b": k[1], "fn": fn, "ft": ft, "fn_lammps": fl,
                     "ft_lammps": tl, "fn_min": lo, "fn_max": hi})
    result = {"strain": strain, **run, "contacts_lammps": len(theirs),
              "contacts_packing": len(ours), "extra": [list(k) for k in extra],
              "missing": [list(k) for k in missing], "P_lammps": P_L,
              "max_dfn_F0": dfn, "max_dft_F0": dft,
              "coulomb_excess_F0": max(
                  [(abs(t) - meta["mu"] * f) / F0 for f, t in theirs.values()] + [0.0])}
    if bounds is not None:
        result["bounds_excess_F0"], result["bounds_unlisted"] = interval_excess(
            {k: v[0] for k, v in theirs.items()}, bounds, F0)
    return result, rows


def unjam_tool(given):
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    for cand in (given, os.environ.get("UNJAM"), os.path.join(root, "build", "release", "unjam"),
                 shutil.which("unjam")):
        if cand and os.path.isfile(cand) and os.access(cand, os.X_OK):
            return cand
        if given:
            raise up.UserError(f"--unjam {given}: not an executable file")
    raise up.UserError("the unjam tool was not found: build it (scripts/build.sh), or pass "
                       "--unjam PATH or set UNJAM")


def write_lammps_packing(directory, meta, cell, g, net, scale):
    """LAMMPS' relaxed state as a packing (docs/packing-format.md, "Reading packings written
    by other programs"): its cell, grains and loaded contacts, forces scaled to P_ext."""
    os.makedirs(directory, exist_ok=True)
    record = {"Lx": cell[0], "Ly": cell[1], "P_ext": meta["P_ext"], "mu": meta["mu"],
              "state": {"time": 0.0, "step": 0, "lambda": 0.0, "static": True},
              "command": "scripts/lammps_crosscheck.py (LAMMPS' relaxed state)"}
    up.write_file_atomic(os.path.join(directory, "meta.json"),
                         lambda f: json.dump(record, f, indent=1))
    grains = [{"id": i, "x": float(r[1]), "y": float(r[2]), "radius": float(r[3])}
              for i, r in enumerate(g)]
    up.write_file_atomic(os.path.join(directory, "particles.csv"), lambda f: f.write(
        up.csv_text(grains, ["id", "x", "y", "radius"])))
    rows = [{"a": a, "b": b, "nx": nx, "ny": ny, "lx": dist * nx, "ly": dist * ny,
             "fn": fn * scale, "ft": ft * scale}
            for (a, b), (fn, ft, dist, nx, ny) in sorted(net.items())]
    up.write_file_atomic(os.path.join(directory, "contacts.csv"), lambda f: f.write(
        up.csv_text(rows, ["a", "b", "nx", "ny", "lx", "ly", "fn", "ft"])))
    return {pair_key(r["a"], r["b"]): r["fn"] for r in rows}


def unjam_checks(tool, directory, fn_lammps, F0, own_bounds):
    """unjam's static checks (`unjam info`) and LP intervals (`unjam bounds`) of LAMMPS'
    relaxed state: its network is admissible there, so each fn must lie in its interval."""
    def run(args):
        r = subprocess.run([tool] + args, capture_output=True, text=True)
        if r.returncode != 0:
            raise LammpsFailed(f"{' '.join([tool] + args)} failed (exit {r.returncode}): "
                               f"{r.stderr.strip()}")
        return r.stdout
    info = json.loads(run(["info", "--json", directory]))
    checks = {"balance_force_F0": info["max_force_residual_over_F0"],
              "balance_torque_F0": info["max_torque_residual_over_F0R"],
              "unjam_info": {k: info[k] for k in (
        "max_force_residual_over_F0", "max_torque_residual_over_F0R", "P_in_over_P_ext",
        "max_coulomb_violation_over_F0", "max_tension_over_F0",
        "geometry_worst_over_tolerance", "contacts_force_carrying")}}
    if not own_bounds:
        return {}, checks
    bounds_csv = os.path.join(directory, "bounds.csv")
    run(["bounds", directory, "--out", bounds_csv, "--threads", "1"])
    own = read_bounds(bounds_csv, info["N"])
    excess, unlisted = interval_excess(fn_lammps, own, F0)
    checks.update({"own_bounds_excess_F0": excess, "own_bounds_unlisted": unlisted,
                   "own_bounds_contacts": len(own)})
    return own, checks


def intervals(ax, lo, hi, points, F0):
    """Each contact's interval [lo, hi] as a vertical bar, sorted by hi, with the fn of
    every network in points ({label: (fn array, style)})."""
    order = np.argsort(np.where(np.isfinite(hi), hi, -1.0), kind="stable")
    xs = np.arange(len(order))
    ax.vlines(xs, lo[order] / F0, hi[order] / F0, color="0.7", lw=1.5)
    for label, (fn, style) in points.items():
        ax.plot(xs, fn[order] / F0, style, ms=3, label=label)
    ax.set_xlabel("contact (by fn_max)")
    ax.set_ylabel("fn (F0)")
    ax.legend(fontsize=7)


def plot(out, results, rows_by_strain, own, bounds, F0):
    import matplotlib.pyplot as plt
    bounds_own, fn_lammps = own
    panels = [None, "own" if bounds_own else None, "bounds" if bounds is not None else None]
    panels = [p for p in panels if p]
    n = 1 + len(panels)
    fig, axes = plt.subplots(1, n, figsize=(5.2 * n, 4.6), squeeze=False)
    ax = axes[0][0]
    for res, rows in zip(results, rows_by_strain):
        fn = np.array([r["fn"] for r in rows]) / F0
        fl = np.array([r["fn_lammps"] for r in rows]) / F0
        ax.plot(fn, fl, ".", ms=4, label=f"strain {res['strain']:g}: max |diff| "
                f"{res['max_dfn_F0']:.1e} F0")
    top = max(1e-12, max(max(r["fn"], r["fn_lammps"]) for rows in rows_by_strain
                         for r in rows) / F0)
    ax.plot([0, top], [0, top], "k-", lw=0.6)
    ax.set_xlabel("fn, the packing's static network (F0)")
    ax.set_ylabel("fn, LAMMPS soft DEM at P_ext (F0)")
    ax.set_title("the two networks", fontsize=9)
    ax.legend(fontsize=7)
    strain = results[-1]["strain"]
    if "own" in panels:
        keys = sorted(fn_lammps)
        lo = np.array([bounds_own.get(k, (math.nan, math.nan))[0] for k in keys])
        hi = np.array([bounds_own.get(k, (math.nan, math.nan))[1] for k in keys])
        ax = axes[0][1 + panels.index("own")]
        intervals(ax, lo, hi, {f"LAMMPS fn (strain {strain:g})": (
            np.array([fn_lammps[k] for k in keys]), "r.")}, F0)
        ax.set_title(f"LAMMPS' network in unjam's LP intervals of its state: "
                     f"outside by {results[-1]['own_bounds_excess_F0']:.1e} F0", fontsize=9)
    if "bounds" in panels:
        rows = rows_by_strain[-1]
        ax = axes[0][1 + panels.index("bounds")]
        intervals(ax, np.array([r["fn_min"] for r in rows]),
                  np.array([r["fn_max"] for r in rows]),
                  {"the packing's fn": (np.array([r["fn"] for r in rows]), "k."),
                   f"LAMMPS fn (strain {strain:g})": (
                       np.array([r["fn_lammps"] for r in rows]), "r.")}, F0)
        ax.set_title("both networks in the packing's intervals (--bounds)", fontsize=9)
    fig.tight_layout()
    up.save_figure(fig, os.path.join(out, "crosscheck.png"))
    plt.close(fig)


def main():
    args = parse_args(sys.argv[1:])
    meta, particles, contacts = read_packing(args.packing)
    n = len(particles["radius"])
    bounds = read_bounds(args.bounds, n) if args.bounds else None
    exe, version = lammps_executable(args.lmp)
    tool = unjam_tool(args.unjam)
    out = args.out or os.path.join(args.packing, "lammps-crosscheck")
    os.makedirs(out, exist_ok=True)
    F0 = up.force_unit(meta, particles["radius"])
    m_max = math.pi * float(np.max(particles["radius"])) ** 2
    results, rows_by_strain, owns = [], [], []
    for e in args.strain:
        p = model(particles, F0, e)
        cell = (meta["Lx"] * (1.0 - e), meta["Ly"] * (1.0 - e))
        floor = relaxation_floor(meta, p, m_max, F0)
        tol = args.tol if args.tol is not None else max(1e-9, 4.0 * floor)
        if tol < floor:
            up.warn(f"strain {e:g}: --tol {tol:g} F0 is below the floor set by the positions' "
                    f"round-off (~{floor:.1e} F0): the relaxation may not reach it")
        work = os.path.join(out, f"strain-{e:g}")
        os.makedirs(work, exist_ok=True)
        run = run_lammps(exe, work, {
            "data.lammps": data_file(meta, particles, e),
            "in.lammps": input_file(meta["mu"], p, tol * F0, args.max_steps, m_max)})
        if not run["relaxed"]:
            raise LammpsFailed(f"strain {e:g}: not relaxed after {run['steps']} steps "
                               f"(largest force {run['fmax'] / F0:.3g} F0; "
                               f"{os.path.join(work, 'log.lammps')})")
        net, g = lammps_network(work, *cell)
        res, rows = compare(meta, contacts, bounds, net, cell, F0, e, run)
        res["model"] = p
        res["tol_F0"], res["round_off_floor_F0"] = tol, floor
        fn_lammps = write_lammps_packing(os.path.join(work, "packing"), meta, cell, g, net,
                                         meta["P_ext"] / res["P_lammps"])
        own, checks = unjam_checks(tool, os.path.join(work, "packing"), fn_lammps, F0,
                                   not args.no_own_bounds)
        res.update(checks)
        owns.append((own, fn_lammps))
        cols = ["a", "b", "fn", "ft", "fn_lammps", "ft_lammps", "fn_min", "fn_max"]
        up.write_file_atomic(os.path.join(work, "forces.csv"),
                             lambda f, r=rows: f.write(up.csv_text(r, cols)))
        results.append(res)
        rows_by_strain.append(rows)
        print(f"strain {e:g}: relaxed in {run['steps']} steps, {run['cpu_s']:.2f} s of CPU; "
              f"{res['contacts_lammps']} contacts loaded (packing: {res['contacts_packing']}), "
              f"{len(res['extra'])} extra, {len(res['missing'])} missing; "
              f"max |fn_L - fn| {res['max_dfn_F0']:.2e} F0, |ft_L - ft| "
              f"{res['max_dft_F0']:.2e} F0"
              + (f"; outside the bounds by at most {res['bounds_excess_F0']:.2e} F0"
                 f" ({len(res['bounds_unlisted'])} contacts not in them)"
                 if bounds is not None else "")
              + (f"; in unjam's bounds of its own state within "
                 f"{res['own_bounds_excess_F0']:.2e} F0" if own else "")
              + f"; unjam's residual of it {res['unjam_info']['max_force_residual_over_F0']:.1e}"
              " F0")
    record = {"command": " ".join([os.path.basename(sys.argv[0])] + sys.argv[1:]),
              "packing": {"directory": os.path.abspath(args.packing),
                          "program_version": meta.get("program_version"),
                          "command": meta.get("command"), "N": n, "mu": meta["mu"],
                          "P_ext": meta["P_ext"], "F0": F0},
              "lammps": {"executable": exe, "version": version,
                         "pair_style": "gran/hooke/history"},
              "settings": {"strains": args.strain, "tol_F0": args.tol,
                           "max_steps": args.max_steps, "bounds": args.bounds,
                           "own_bounds": not args.no_own_bounds,
                           "damping_ratio": DAMPING, "viscous": VISCOUS,
                           "dt_factor": DT_FACTOR},
              "results": results}
    up.write_file_atomic(os.path.join(out, "crosscheck.json"),
                         lambda f: json.dump(up.json_value(record), f, indent=1))
    plot(out, results, rows_by_strain, owns[-1], bounds, F0)


if __name__ == "__main__":
    try:
        up.run_main(main)
    except LammpsFailed as e:
        print(f"lammps_crosscheck.py: {e}", file=sys.stderr)
        sys.exit(2)
