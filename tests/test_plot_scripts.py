"""Tests of the plotting scripts in scripts/ (plain unittest, no pytest).

Run from the repository root:
    /usr/bin/python3 -m unittest tests/test_plot_scripts.py

Each test writes small synthetic unjam outputs into a temporary directory, runs a script as a
subprocess and checks its exit status and the PNG it writes (PNG signature, size > 5 kB), and
the error path (missing or corrupt input: exit status 1, a message naming the file, no
traceback).  Set UNJAM_PLOT_KEEP=DIR to keep the inputs and figures in DIR for inspection.
"""

import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import numpy as np

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCRIPTS = os.path.join(REPO, "scripts")
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


# ------------------------------------------------------------------------------------------
# Synthetic inputs


def write_csv(path, header, rows):
    with open(path, "w") as f:
        f.write(",".join(header) + "\n")
        for r in rows:
            f.write(",".join(repr(v) if isinstance(v, float) else str(v) for v in r) + "\n")


def make_packing(d, n_cols=5, n_rows=6, mu=0.1, rattler=7, seed=1):
    """A 30-disk triangular lattice (diameter 1) in a periodic cell, with its contacts.

    Grain `rattler` is shrunk and loses its contacts; a few contacts carry no force.
    Returns (particles, contacts, meta) as written.
    """
    os.makedirs(d, exist_ok=True)
    rng = np.random.default_rng(seed)
    h = math.sqrt(3.0) / 2.0
    Lx, Ly = float(n_cols), n_rows * h
    x, y = [], []
    for j in range(n_rows):
        for i in range(n_cols):
            x.append((i + 0.5 * (j % 2) + 0.3) % Lx)
            y.append((j * h + 0.2) % Ly)
    x, y = np.array(x), np.array(y)
    N = len(x)
    R = np.full(N, 0.5)
    R[rattler] = 0.4
    P_ext = 1.0
    F0 = 2.0 * float(R.mean()) * P_ext
    contacts = []
    for a in range(N):
        for b in range(a + 1, N):
            lx = (x[b] - x[a]) - Lx * round((x[b] - x[a]) / Lx)
            ly = (y[b] - y[a]) - Ly * round((y[b] - y[a]) / Ly)
            l = math.hypot(lx, ly)
            if l < 1.0 + 1e-9 and rattler not in (a, b):
                fn = float(rng.uniform(0.2, 2.5)) * F0 if rng.random() > 0.1 else 0.0
                ft = float(rng.uniform(-mu, mu)) * fn
                contacts.append((a, b, lx / l, ly / l, lx, ly, l - R[a] - R[b], fn, ft))
    write_csv(os.path.join(d, "particles.csv"), ["id", "x", "y", "radius", "vx", "vy", "omega"],
              [(i, float(x[i]), float(y[i]), float(R[i]), 0, 0, 0) for i in range(N)])
    write_csv(os.path.join(d, "contacts.csv"), ["a", "b", "nx", "ny", "lx", "ly", "gap", "fn", "ft"],
              [tuple(float(v) if k >= 2 else v for k, v in enumerate(c)) for c in contacts])
    meta = {"format_version": 1, "N": N, "Lx": Lx, "Ly": Ly, "P_ext": P_ext, "mu": mu,
            "seed": seed, "F0": F0}
    with open(os.path.join(d, "meta.json"), "w") as f:
        json.dump(meta, f, indent=1)
    return {"x": x, "y": y, "R": R}, contacts, meta


def make_probe(d, particles, contacts, meta):
    """probe-K.csv (quadrupolar displacements around contact K) and probes.csv.

    K is the force-carrying contact nearest the centre of the cell; returns K.
    """
    x, y, R = particles["x"], particles["y"], particles["R"]
    Lx, Ly = meta["Lx"], meta["Ly"]

    def centre_distance(k):
        a, _, nx, ny = contacts[k][:4]
        return math.hypot(x[a] + R[a] * nx - Lx / 2, y[a] + R[a] * ny - Ly / 2)

    K = min((k for k in range(len(contacts)) if contacts[k][7] > 0), key=centre_distance)
    a, b, nx, ny, lx, ly = contacts[K][:6]
    n = np.array([nx, ny])
    t = np.array([-ny, nx])
    rc = np.array([x[a], y[a]]) + R[a] * n
    dx = x - rc[0]
    dy = y - rc[1]
    dx -= Lx * np.round(dx / Lx)
    dy -= Ly * np.round(dy / Ly)
    r = np.hypot(dx, dy)
    cos_t = (dx * n[0] + dy * n[1]) / r
    sin_t = (dx * t[0] + dy * t[1]) / r
    amp = (cos_t ** 2 - sin_t ** 2 + 0.2) / np.maximum(r, 0.5)
    ux_g, uy_g = amp * dx / r, amp * dy / r
    g = 1e-9
    rows = [(i, float(x[i]), float(y[i]), float(R[i]), float(ux_g[i] * g), float(uy_g[i] * g), 0.0,
             float(ux_g[i]), float(uy_g[i])) for i in range(len(x))]
    write_csv(os.path.join(d, f"probe-{K}.csv"),
              ["id", "x", "y", "radius", "ux", "uy", "rot", "ux_g", "uy_g"], rows)
    fn = contacts[K][7]
    write_csv(os.path.join(d, "probes.csv"),
              ["contact", "a", "b", "f_cont", "f_crit", "method", "converged", "sweeps", "residual",
               "violations", "lambda_dt"],
              [(K, a, b, float(fn), float(1.5 * fn), "kinematic", 1, 1200, 1e-10, 0, 0.0)])
    return K


def make_field(d, W=10.0, h=0.5, seed=2):
    """response_field.csv: a quadrupolar mean field, empty bins outside |r| > W and a few more."""
    os.makedirs(d, exist_ok=True)
    rng = np.random.default_rng(seed)
    n_side = int(round(2 * W / h))
    c = -W + (np.arange(n_side) + 0.5) * h
    rows = []
    for yv in c:
        for xv in c:
            r = math.hypot(xv, yv)
            th = math.atan2(yv, xv)
            ur = math.cos(2 * th) / max(r, 0.3)          # out along x, in along y
            ut = -0.5 * math.sin(2 * th) / max(r, 0.3)
            ux = ur * math.cos(th) - ut * math.sin(th)
            uy = ur * math.sin(th) + ut * math.cos(th)
            count = 0 if (r > W or rng.random() < 0.02) else int(rng.integers(5, 60))
            if count == 0:
                ux = uy = math.nan                        # as unjam writes an empty bin
            rows.append((float(xv), float(yv), ux, uy, count))
    write_csv(os.path.join(d, "response_field.csv"), ["x", "y", "ux", "uy", "count"], rows)


def make_profile(d, alpha=0.9, mu=0.1, N=300, seed=3, r_min=0.75, r_max=12.0, K=12):
    """response_profile.csv (d = A r^-alpha with noise) and probe_summary.json with its fit."""
    os.makedirs(d, exist_ok=True)
    rng = np.random.default_rng(seed)
    edges = r_min * (r_max / r_min) ** (np.arange(K + 1) / K)
    r_mid = np.sqrt(edges[:-1] * edges[1:])
    dm = 2.0 * r_mid ** -alpha * np.exp(rng.normal(0, 0.05, K))
    sem = 0.08 * dm
    count = rng.integers(50, 500, K)
    dm[-1], sem[-1], count[-1] = math.nan, math.nan, 0  # an empty bin, as unjam writes it
    rows = [(float(edges[k]), float(edges[k + 1]), float(r_mid[k]), float(dm[k]), float(sem[k]),
             int(count[k]), 40) for k in range(K)]
    write_csv(os.path.join(d, "response_profile.csv"),
              ["r_lo", "r_hi", "r_mid", "d_mean", "d_sem", "count", "probes"], rows)
    win = (edges[:-1] >= 1.5) & (edges[1:] <= 6.0) & (count > 0)
    slope, icpt = np.polyfit(np.log(r_mid[win]), np.log(dm[win]), 1)
    summary = {"alpha": float(-slope), "alpha_err": 0.04,
               "fit": {"r_lo": float(edges[:-1][win][0]), "r_hi": float(edges[1:][win][-1]),
                       "bins": int(win.sum()), "R2": 0.99, "log_A": float(icpt)},
               "F_crit_over_F_cont": 1.4, "F_cont_over_F0": 1.1, "z": 3.6, "phi": 0.82,
               "mu": mu, "N": N, "probes": 40, "method": "kinematic", "g": 1e-9}
    with open(os.path.join(d, "probe_summary.json"), "w") as f:
        json.dump(summary, f, indent=1)


SWEEP_COLUMNS = ["mu", "N", "seed", "phi", "z", "F_cont_over_F0", "F_crit_over_F_cont", "alpha",
                 "alpha_err"]


def make_sweep(path, fixed_path, seed=4):
    """A friction-sweep table (2 sizes x 3 seeds x 7 mu) and a fixed-packing table."""
    rng = np.random.default_rng(seed)
    mus = [0.0, 0.01, 0.03, 0.1, 0.3, 0.6, 1.0]
    rows = []
    for N in (100, 300):
        for s in (1, 2, 3):
            for mu in mus:
                step = 1.0 / (1.0 + (0.1 / mu) ** 2) if mu > 0 else 0.0   # 0 -> 1 around mu = 0.1
                peak = math.exp(-(math.log10(max(mu, 1e-3)) + 1.0) ** 2 / 0.3) if mu > 0 else 0.0
                z = 4.0 - 1.0 * step + rng.normal(0, 0.02)
                phi = 0.842 - 0.04 * step + rng.normal(0, 0.002)
                fc = 1.0 + 0.15 * step + rng.normal(0, 0.01)
                fr = 1.0 + 0.6 * peak + rng.normal(0, 0.03)
                al = "nan" if (mu == 1.0 and s == 3) else 0.8 + 0.5 * peak + rng.normal(0, 0.05)
                rows.append((mu, N, s, phi, z, fc, fr, al, 0.05))
    write_csv(path, SWEEP_COLUMNS, rows)
    rows = []
    for mu in mus:
        step = 1.0 / (1.0 + (0.1 / mu) ** 2) if mu > 0 else 0.0
        rows.append((mu, 100, 1, 0.84, 4.0, 1.0, 1.0 + 0.7 * step, 0.9 + 0.3 * step, 0.05))
    write_csv(fixed_path, SWEEP_COLUMNS, rows)


# ------------------------------------------------------------------------------------------
# Tests


class PlotScriptsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        keep = os.environ.get("UNJAM_PLOT_KEEP")
        if keep:
            os.makedirs(keep, exist_ok=True)
            cls.tmp = keep
            cls._cleanup = False
        else:
            cls.tmp = tempfile.mkdtemp(prefix="unjam-plot-test-")
            cls._cleanup = True
        cls.pack = os.path.join(cls.tmp, "packing")
        particles, contacts, meta = make_packing(cls.pack)
        cls.K = make_probe(cls.pack, particles, contacts, meta)
        cls.contacts = contacts
        make_field(cls.pack)
        make_profile(cls.pack, alpha=0.9, mu=0.1, N=300)
        cls.prof2 = os.path.join(cls.tmp, "profile-mu1")
        make_profile(cls.prof2, alpha=1.3, mu=1.0, N=300, seed=5)
        cls.sweep = os.path.join(cls.tmp, "sweep.csv")
        cls.fixed = os.path.join(cls.tmp, "fixed.csv")
        make_sweep(cls.sweep, cls.fixed)

    @classmethod
    def tearDownClass(cls):
        if cls._cleanup:
            shutil.rmtree(cls.tmp, ignore_errors=True)

    def run_script(self, name, *args):
        cmd = [sys.executable, os.path.join(SCRIPTS, name), *args]
        env = dict(os.environ, MPLBACKEND="Agg")
        return subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=300)

    def assert_ok(self, proc):
        self.assertEqual(proc.returncode, 0, f"exit {proc.returncode}\nstdout:\n{proc.stdout}\n"
                                             f"stderr:\n{proc.stderr}")
        self.assertNotIn("Traceback", proc.stderr)

    def assert_png(self, path):
        self.assertTrue(os.path.isfile(path), f"{path} not written")
        with open(path, "rb") as f:
            head = f.read(8)
        self.assertEqual(head, PNG_MAGIC, f"{path} is not a PNG")
        self.assertGreater(os.path.getsize(path), 5000, f"{path} is suspiciously small")
        leftovers = [n for n in os.listdir(os.path.dirname(path)) if n.endswith(".tmp")]
        self.assertEqual(leftovers, [], "temporary files left behind")

    def assert_user_error(self, proc, *fragments):
        self.assertEqual(proc.returncode, 1, f"exit {proc.returncode}\nstderr:\n{proc.stderr}")
        self.assertNotIn("Traceback", proc.stderr)
        self.assertIn("error", proc.stderr)
        for frag in fragments:
            self.assertIn(frag, proc.stderr)

    def scratch(self, name, files=()):
        """A fresh directory holding copies of some of the packing directory's files."""
        d = os.path.join(self.tmp, name)
        shutil.rmtree(d, ignore_errors=True)
        os.makedirs(d)
        for f in files:
            shutil.copy(os.path.join(self.pack, f), d)
        return d

    # --- plot_packing.py

    def test_packing(self):
        proc = self.run_script("plot_packing.py", self.pack)
        self.assert_ok(proc)
        self.assert_png(os.path.join(self.pack, "packing.png"))
        # Title statistics: 29 grains carry force, one rattler.
        out = os.path.join(self.tmp, "packing-out.png")
        self.assert_ok(self.run_script("plot_packing.py", self.pack, "--out", out))
        self.assert_png(out)

    def test_packing_errors(self):
        d = self.scratch("pk-missing", ["meta.json", "particles.csv"])
        self.assert_user_error(self.run_script("plot_packing.py", d),
                               os.path.join(d, "contacts.csv"), "not found")
        self.assert_user_error(self.run_script("plot_packing.py", os.path.join(self.tmp, "nope")),
                               "nope")
        d = self.scratch("pk-corrupt", ["meta.json", "particles.csv", "contacts.csv"])
        path = os.path.join(d, "contacts.csv")
        with open(path) as f:
            lines = f.read().splitlines()
        with open(path, "w") as f:
            f.write("\n".join([lines[0].replace(",fn,", ",f_n,")] + lines[1:]) + "\n")
        self.assert_user_error(self.run_script("plot_packing.py", d), path, "'fn'")
        with open(path, "w") as f:
            f.write("\n".join(lines[:3] + [lines[3].replace(lines[3].split(",")[7], "abc")] + lines[4:]))
        self.assert_user_error(self.run_script("plot_packing.py", d), path, "line 4", "abc")
        with open(os.path.join(d, "meta.json"), "w") as f:
            f.write("{not json")
        self.assert_user_error(self.run_script("plot_packing.py", d), "meta.json", "JSON")

    # --- plot_fig4.py

    def test_fig4_without_ensemble_csv(self):
        d = self.scratch("fig4-missing", ["meta.json"])
        self.assert_user_error(self.run_script("plot_fig4.py", d), "no ensemble.csv in", "unjam ensemble")

    # --- plot_probe_field.py

    def test_probe_field(self):
        K = str(self.K)
        proc = self.run_script("plot_probe_field.py", self.pack, "--contact", K)
        self.assert_ok(proc)
        self.assertNotIn("warning", proc.stderr)  # the probed contact was found
        self.assert_png(os.path.join(self.pack, f"probe-{K}.png"))

    def test_probe_field_without_probes_csv(self):
        # Pair from contacts.csv of the packing given by --packing.
        K = str(self.K)
        d = self.scratch("pf-noprobes", [f"probe-{K}.csv"])
        proc = self.run_script("plot_probe_field.py", d, "--contact", K, "--packing", self.pack,
                               "--exponent", "1")
        self.assert_ok(proc)
        self.assertNotIn("warning", proc.stderr)
        self.assert_png(os.path.join(d, f"probe-{K}.png"))

    def test_probe_field_errors(self):
        self.assert_user_error(self.run_script("plot_probe_field.py", self.pack, "--contact", "99"),
                               os.path.join(self.pack, "probe-99.csv"), "not found")
        K = str(self.K)
        d = self.scratch("pf-nometa", [f"probe-{K}.csv"])
        self.assert_user_error(self.run_script("plot_probe_field.py", d, "--contact", K),
                               os.path.join(d, "meta.json"))

    # --- plot_response_field.py

    def test_response_field(self):
        proc = self.run_script("plot_response_field.py", self.pack)
        self.assert_ok(proc)
        self.assert_png(os.path.join(self.pack, "fig1-field.png"))
        out = os.path.join(self.tmp, "fig1-arrows.png")
        self.assert_ok(self.run_script("plot_response_field.py", self.pack, "--style", "arrows",
                                       "--linear", "--extent", "4", "--out", out))
        self.assert_png(out)

    def test_response_field_errors(self):
        d = self.scratch("rf-missing")
        self.assert_user_error(self.run_script("plot_response_field.py", d),
                               os.path.join(d, "response_field.csv"), "not found")
        d = self.scratch("rf-holes", ["response_field.csv", "particles.csv"])
        path = os.path.join(d, "response_field.csv")
        with open(path) as f:
            lines = f.read().splitlines()
        with open(path, "w") as f:
            f.write("\n".join(lines[:-5]) + "\n")  # rows missing: not a full grid
        self.assert_user_error(self.run_script("plot_response_field.py", d), path, "grid")
        with open(path, "w") as f:
            f.write("")
        self.assert_user_error(self.run_script("plot_response_field.py", d), path, "empty")

    # --- plot_profile.py

    def test_profile(self):
        proc = self.run_script("plot_profile.py", self.pack)
        self.assert_ok(proc)
        self.assert_png(os.path.join(self.pack, "fig2-profile.png"))
        out = os.path.join(self.tmp, "fig2-two.png")
        proc = self.run_script("plot_profile.py", self.pack, self.prof2, "--labels", "mu = 0.1",
                               "mu = 1", "--out", out)
        self.assert_ok(proc)
        self.assert_png(out)

    def test_profile_errors(self):
        d = self.scratch("pr-nosummary")
        shutil.copy(os.path.join(self.pack, "response_profile.csv"), d)
        self.assert_user_error(self.run_script("plot_profile.py", d),
                               os.path.join(d, "probe_summary.json"), "not found")
        # Without the fit, the summary is not needed.
        self.assert_ok(self.run_script("plot_profile.py", d, "--no-fit"))
        self.assert_png(os.path.join(d, "fig2-profile.png"))
        with open(os.path.join(d, "probe_summary.json"), "w") as f:
            json.dump({"alpha": 1.0, "fit": {"r_lo": 1.0}}, f)
        self.assert_user_error(self.run_script("plot_profile.py", d), "fit.r_hi")
        proc = self.run_script("plot_profile.py", self.pack, self.prof2, "--labels", "only-one")
        self.assertNotEqual(proc.returncode, 0)
        self.assertNotIn("Traceback", proc.stderr)
        self.assertIn("--labels", proc.stderr)

    # --- plot_friction_sweep.py

    def test_friction_sweep(self):
        out = os.path.join(self.tmp, "fig3.png")
        proc = self.run_script("plot_friction_sweep.py", self.sweep, "--out", out)
        self.assert_ok(proc)
        self.assert_png(out)
        out = os.path.join(self.tmp, "fig3-fixed.png")
        proc = self.run_script("plot_friction_sweep.py", self.sweep, "--fixed", self.fixed, "--out", out)
        self.assert_ok(proc)
        self.assert_png(out)

    def test_friction_sweep_errors(self):
        missing = os.path.join(self.tmp, "no-such-table.csv")
        self.assert_user_error(self.run_script("plot_friction_sweep.py", missing), missing, "not found")
        self.assert_user_error(self.run_script("plot_friction_sweep.py", self.sweep, "--fixed", missing,
                                               "--out", os.path.join(self.tmp, "x.png")), missing)
        bad = os.path.join(self.tmp, "bad-sweep.csv")
        with open(bad, "w") as f:
            f.write("mu,N,seed,phi,z,F_cont_over_F0,alpha,alpha_err\n0.1,100,1,0.8,3.6,1.1,0.9,0.1\n")
        self.assert_user_error(self.run_script("plot_friction_sweep.py", bad), bad,
                               "F_crit_over_F_cont")
        with open(bad, "w") as f:
            f.write(",".join(SWEEP_COLUMNS) + "\n0.1,100,1,0.8,3.6,1.1\n")
        self.assert_user_error(self.run_script("plot_friction_sweep.py", bad), bad, "line 2",
                               "fields")

    # --- plot_exact_sweep.py

    def exact_table(self):
        """Two seeds at N = 500 and one at N = 1000 (its alpha by lp: a failed fit, empty)."""
        path = os.path.join(self.tmp, "exact-probe.csv")
        write_csv(path, ["mu", "N", "seed", "probes", "F_crit_over_F_cont_lp", "F_crit_over_F_cont_cd",
                         "alpha_lp", "alpha_cd"],
                  [(0, 500, 1, 300, 1.0, 1.02, 0.3, 0.3), (0, 500, 2, 300, 1.0, 1.0, 0.2, 0.24),
                   (0.1, 500, 1, 300, 2.1, 2.0, 1.1, 0.9), (0.1, 500, 2, 300, 2.1, 1.9, 1.1, 0.8),
                   (0.1, 1000, 1, 300, 2.3, 2.1, "", 0.9)])
        return path

    def test_exact_sweep(self):
        table = self.exact_table()
        out = os.path.join(self.tmp, "exact-sweep.png")
        self.assert_ok(self.run_script("plot_exact_sweep.py", table, "--out", out))
        self.assert_png(out)
        # what is drawn: the lines through the means over the seeds, per N and method
        sys.path.insert(0, SCRIPTS)
        import plot_exact_sweep
        fig = plot_exact_sweep.friction_figure(plot_exact_sweep.read_table(table))
        lines = {(i, ln.get_label()): (list(ln.get_xdata()), list(ln.get_ydata()))
                 for i, ax in enumerate(fig.axes) for ln in ax.get_lines()}
        self.assertEqual(lines[(0, "cd, N = 500")], ([0.0, 0.1], [1.01, 1.95]))
        self.assertEqual(lines[(0, "lp, N = 500")], ([0.0, 0.1], [1.0, 2.1]))
        self.assertEqual(lines[(1, "cd, N = 500")], ([0.0, 0.1], [0.27, 0.8500000000000001]))
        self.assertEqual(lines[(0, "cd, N = 1000")], ([0.1], [2.1]))
        self.assertNotIn((1, "lp, N = 1000"), lines)  # no alpha by lp at N = 1000: not drawn

    def test_exact_sweep_draws_the_means_standard_errors(self):
        """F_crit_over_F_cont_{lp,cd}_err, where given, are the error bars of panel (a)."""
        path = os.path.join(self.tmp, "exact-probe-err.csv")
        write_csv(path, ["mu", "N", "seed", "F_crit_over_F_cont_lp", "F_crit_over_F_cont_cd",
                         "F_crit_over_F_cont_lp_err", "F_crit_over_F_cont_cd_err"],
                  [(0, 500, 1, 1.0, 1.02, 0.01, 0.02), (0.1, 500, 1, 2.1, 2.0, "", 0.05)])
        sys.path.insert(0, SCRIPTS)
        import plot_exact_sweep
        fig = plot_exact_sweep.friction_figure(plot_exact_sweep.read_table(path))
        bars = [c for c in fig.axes[0].containers if c.has_yerr]
        halves = sorted(tuple(round((seg[1][1] - seg[0][1]) / 2, 12) for seg in c[2][0].get_segments())
                        for c in bars)
        self.assertEqual(halves, [(0.01, 0.0), (0.02, 0.05)])  # lp (none at mu = 0.1), cd

    def test_exact_sweep_errors(self):
        missing = os.path.join(self.tmp, "no-such-exact.csv")
        self.assert_user_error(self.run_script("plot_exact_sweep.py", missing), missing, "not found")
        bad = os.path.join(self.tmp, "bad-exact.csv")
        write_csv(bad, ["mu", "N", "seed", "F_crit_over_F_cont_lp"], [(0.1, 500, 1, 2.0)])
        self.assert_user_error(self.run_script("plot_exact_sweep.py", bad), bad, "F_crit_over_F_cont_cd")
        write_csv(bad, ["mu", "N", "seed", "F_crit_over_F_cont_lp", "F_crit_over_F_cont_cd"],
                  [(0.1, 0, 1, 2.0, 1.9)])
        self.assert_user_error(self.run_script("plot_exact_sweep.py", bad), bad, "N must be a positive integer")


if __name__ == "__main__":
    unittest.main()
