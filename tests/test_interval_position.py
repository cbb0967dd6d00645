"""Tests of scripts/interval_position.py on the fixtures p50-mu1 and p50-mu0.1 (a few seconds).

Run from the repository root:  /usr/bin/python3 -m unittest tests/test_interval_position.py
The unjam binary: tests/unjam_binary.py.
"""

import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from unjam_binary import REPO, UNJAM, edit_rows, read_rows, requires_unjam, run_script  # noqa: E402

FIXTURES = os.path.join(REPO, "tests", "fixtures")
PACKINGS = ("p50-mu1", "p50-mu0.1")


def run(*args):
    return run_script("interval_position.py", *args)


def unjam(*args):
    p = subprocess.run([UNJAM, *args], capture_output=True, text=True, timeout=120)
    if p.returncode != 0:
        raise AssertionError(f"unjam {' '.join(args)} failed ({p.returncode}):\n{p.stdout}\n"
                             f"{p.stderr}")


R = {}


def setUpModule():
    if not (os.path.isfile(UNJAM) and os.access(UNJAM, os.X_OK)):
        return
    tmp = R["tmp"] = tempfile.mkdtemp(prefix="unjam-interval-")
    R["cd"], R["lp"], R["bounds"] = {}, {}, {}
    for name in PACKINGS:
        packing = os.path.join(tmp, name)
        shutil.copytree(os.path.join(FIXTURES, name), packing)
        for method in ("cd", "lp"):
            out = R[method][name] = os.path.join(tmp, f"{name}-{method}")
            unjam("probe", packing, "--sample", "20", "--seed", "1", "--method", method,
                  "--threads", "1", "--out", out)
        bounds = R["bounds"][name] = os.path.join(tmp, f"{name}-bounds.csv")
        unjam("bounds", packing, "--threads", "1", "--out", bounds)
    out = R["out"] = os.path.join(tmp, "interval")
    p = R["run"] = run(R["cd"]["p50-mu1"], R["bounds"]["p50-mu1"], R["cd"]["p50-mu0.1"],
                       R["bounds"]["p50-mu0.1"], "--out", out)
    if p.returncode != 0:
        raise AssertionError(f"interval_position.py failed ({p.returncode}):\n{p.stdout}\n"
                             f"{p.stderr}")
    R["pairs"] = read_rows(os.path.join(out, "interval.csv"))
    R["positions"] = read_rows(os.path.join(out, "positions.csv"))


def tearDownModule():
    if "tmp" in R:
        shutil.rmtree(R["tmp"], ignore_errors=True)


def edited_copy(src, name, edit):
    """A copy of campaign src whose probes.csv rows edit(rows) changes in place."""
    dst = os.path.join(R["tmp"], name)
    shutil.rmtree(dst, ignore_errors=True)
    shutil.copytree(src, dst)
    edit_rows(os.path.join(dst, "probes.csv"), edit)
    return dst


@requires_unjam
class IntervalPosition(unittest.TestCase):
    def test_1_positions_are_the_probe_and_the_bounds_joined(self):
        # Every probed contact gets its own interval: the joined fn_max is the lp probe's
        # F_crit (the same LP maximum by another route), and t is recomputed from the columns.
        for name in PACKINGS:
            with open(os.path.join(R["cd"][name], "probe_summary.json")) as f:
                F0 = json.load(f)["F0"]
            lp = {int(r["contact"]): float(r["f_crit"])
                  for r in read_rows(os.path.join(R["lp"][name], "probes.csv"))}
            cd = {int(r["contact"]): r for r in read_rows(os.path.join(R["cd"][name],
                                                                       "probes.csv"))}
            rows = [r for r in R["positions"] if r["packing"].endswith(name)]
            self.assertEqual(sorted(int(r["contact"]) for r in rows), sorted(cd))
            self.assertEqual(len(rows), 20)
            for r in rows:
                k = int(r["contact"])
                lo, hi = float(r["fn_min"]), float(r["fn_max"])
                self.assertAlmostEqual(hi * F0, lp[k], delta=1e-6 * F0)
                self.assertTrue(math.isclose(float(r["f_crit"]) * F0, float(cd[k]["f_crit"]),
                                             rel_tol=1e-14), k)
                self.assertLessEqual(lo, float(r["f_cont"]) + 1e-9)
                self.assertGreaterEqual(hi, float(r["f_cont"]) - 1e-9)
                t = (float(r["f_crit"]) - lo) / (hi - lo)
                self.assertTrue(math.isclose(float(r["t"]), t, rel_tol=1e-12), k)

    def test_2_the_step_lies_in_its_interval_and_the_numbers_are_recomputed(self):
        # The exact step at the quasi-static dt: every probe inside [fn_min, fn_max] up to
        # the inertial term (measured: at most 7e-5 of fn_max above it on p50-mu1).
        self.assertEqual(len(R["pairs"]), 2)
        for pair, name in zip(R["pairs"], PACKINGS):
            rows = [r for r in R["positions"] if r["packing"].endswith(name)]
            t = [float(r["t"]) for r in rows if r["t"]]
            self.assertEqual(int(pair["outside"]), 0)
            self.assertLess(float(pair["excess_max"]), 1e-4)
            self.assertLess(float(pair["shortfall_max"]), 0.0)
            self.assertEqual(int(pair["solved"]), 20)
            self.assertEqual(int(pair["exact"]), 20)
            self.assertTrue(math.isclose(float(pair["t_median"]), statistics.median(t),
                                         rel_tol=1e-12))
            self.assertEqual(float(pair["t_min"]), min(t))
            self.assertTrue(math.isclose(
                float(pair["crit_over_max_median"]),
                statistics.median(float(r["f_crit"]) / float(r["fn_max"]) for r in rows),
                rel_tol=1e-12))
            self.assertEqual(int(pair["at_top"]), sum(x >= 0.99 for x in t))
            self.assertEqual(int(pair["below_f_cont"]),
                             sum(float(r["f_crit"]) < float(r["f_cont"]) for r in rows))
        # At mu = 0.1 the paper's probe sits at the top of the interval, at mu = 1 below it.
        self.assertGreater(float(R["pairs"][1]["t_median"]), 0.98)
        self.assertLess(float(R["pairs"][0]["t_median"]), 0.98)
        with open(os.path.join(R["out"], "interval.json")) as f:
            record = json.load(f)
        self.assertIn("interval_position.py", record["command"])
        self.assertEqual(len(record["inputs"]), 2)
        for name in ("interval.md", "interval-position.png"):
            self.assertGreater(os.path.getsize(os.path.join(R["out"], name)), 100)

    def test_3_a_force_outside_its_interval_is_counted_and_named(self):
        def raise_one(rows):
            rows[0]["f_crit"] = repr(float(rows[0]["f_crit"]) * 1.5 + 10.0)
        bad = edited_copy(R["cd"]["p50-mu1"], "raised", raise_one)
        out = os.path.join(R["tmp"], "raised-out")
        p = run(bad, R["bounds"]["p50-mu1"], "--out", out)
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertIn("outside their interval", p.stderr)
        pair = read_rows(os.path.join(out, "interval.csv"))[0]
        self.assertEqual(int(pair["outside"]), 1)
        self.assertGreater(float(pair["excess_max"]), 0.5)

    def test_5_ends_crossed_by_round_off_are_one_point_and_a_wider_crossing_is_refused(self):
        # unjam_plot.read_intervals, the reader every script shares: an interval whose fn_min
        # lies above its fn_max by round-off (two LPs reaching one optimum from either side)
        # is the point fn_max; by 1e-3 it is no interval.
        src = R["bounds"]["p50-mu1"]
        probes = read_rows(os.path.join(R["cd"]["p50-mu1"], "probes.csv"))
        contact_of = {(int(r["a"]), int(r["b"])): r["contact"] for r in probes}

        def crossed(name, by):
            """A copy of the bounds with the first probed contact's ends crossed by `by`
            relative; its contact."""
            dst = os.path.join(R["tmp"], name + ".csv")
            shutil.copy(os.path.splitext(src)[0] + ".json", os.path.splitext(dst)[0] + ".json")
            shutil.copy(src, dst)
            edited = []

            def cross(rows):
                for r in rows:
                    pair = (int(r["a"]), int(r["b"]))
                    if pair in contact_of and float(r["fn_max"]) > 0.0 and not edited:
                        r["fn_min"] = repr(float(r["fn_max"]) * (1.0 + by))
                        edited.append(contact_of[pair])
            edit_rows(dst, cross)
            self.assertEqual(len(edited), 1)
            return dst, edited[0]

        ok, k = crossed("roundoff-bounds", 1e-13)
        out = os.path.join(R["tmp"], "roundoff-out")
        p = run(R["cd"]["p50-mu1"], ok, "--out", out)
        self.assertEqual(p.returncode, 0, p.stderr)
        before = {r["contact"]: r for r in R["positions"] if r["packing"].endswith("p50-mu1")}
        after = {r["contact"]: r for r in read_rows(os.path.join(out, "positions.csv"))}
        self.assertEqual(before.keys(), after.keys())
        self.assertEqual(after[k]["fn_min"], after[k]["fn_max"])  # the point fn_max
        self.assertEqual(after[k]["fn_max"], before[k]["fn_max"])
        self.assertNotEqual(before[k]["fn_min"], before[k]["fn_max"])

        bad, _ = crossed("crossed-bounds", 1e-3)
        out = os.path.join(R["tmp"], "crossed-out")
        p = run(R["cd"]["p50-mu1"], bad, "--out", out)
        self.assertEqual(p.returncode, 1, p.stderr)
        self.assertIn("not an interval", p.stderr)
        self.assertNotIn("Traceback", p.stderr)
        self.assertFalse(os.path.exists(out))

    def test_4_bad_input_is_refused_and_writes_nothing(self):
        out = os.path.join(R["tmp"], "refused")
        no_json = os.path.join(R["tmp"], "no-json.csv")
        shutil.copy(R["bounds"]["p50-mu0.1"], no_json)
        cases = [
            ([R["cd"]["p50-mu1"]], "expected pairs"),
            ([R["lp"]["p50-mu1"], R["bounds"]["p50-mu1"]], "expected 'cd'"),
            ([R["cd"]["p50-mu1"], R["bounds"]["p50-mu0.1"]], "different packings"),
            ([R["cd"]["p50-mu1"], no_json], "no interval for contact"),
            ([R["cd"]["p50-mu1"], os.path.join(R["tmp"], "missing.csv")], "not found"),
            ([R["cd"]["p50-mu1"], R["bounds"]["p50-mu1"], "--tol", "-1"], "--tol"),
        ]
        for args, message in cases:
            p = run(*args, "--out", out)
            self.assertEqual(p.returncode, 1, (args, p.stdout, p.stderr))
            self.assertIn(message, p.stderr, args)
            self.assertNotIn("Traceback", p.stderr)
            self.assertFalse(os.path.exists(out), args)


if __name__ == "__main__":
    unittest.main()
