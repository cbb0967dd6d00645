"""Tests of scripts/probe_solutions.py on the fixture p50-mu1 (about 5 s).

Run from the repository root:  /usr/bin/python3 -m unittest tests/test_probe_solutions.py
The unjam binary: tests/unjam_binary.py.
"""

import csv
import json
import os
import shutil
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from unjam_binary import REPO, UNJAM, requires_unjam, run_script  # noqa: E402

FIXTURES = os.path.join(REPO, "tests", "fixtures")


def reference():
    """{contact: (f_crit from the static state, other solution or None)} of cd-reference.csv."""
    with open(os.path.join(FIXTURES, "p50-mu1", "cd-reference.csv")) as f:
        rows = csv.DictReader(line for line in f if not line.startswith("#"))
        return {int(r["contact"]): (float(r["f_crit_from_static"]),
                                    float(r["f_crit_other_solution"]) if r["f_crit_other_solution"] else None)
                for r in rows}


def run(*args):
    return run_script("probe_solutions.py", *args, timeout=300)


R = {}  # the run shared by the tests: its directory, arguments, rows and summary


def setUpModule():
    if not (os.path.isfile(UNJAM) and os.access(UNJAM, os.X_OK)):
        return
    tmp = R["tmp"] = tempfile.mkdtemp(prefix="unjam-solutions-")
    packing = os.path.join(tmp, "p50-mu1")
    shutil.copytree(os.path.join(FIXTURES, "p50-mu1"), packing)
    out = R["out"] = os.path.join(tmp, "solutions")
    R["packing"] = packing
    # dt = 1e-3: the time step of the reference solutions (cd-reference.csv)
    R["args"] = [packing, "--all", "--starts", "static", "compliant", "lp", "interior",
                 "--threads", "1", "--dt", "1e-3", "--unjam", UNJAM, "--out", out]
    p = run(*R["args"])
    if p.returncode != 0:
        raise AssertionError(f"probe_solutions.py failed ({p.returncode}):\n{p.stdout}\n{p.stderr}")
    with open(os.path.join(out, "solutions.csv"), newline="") as f:
        R["rows"] = {int(r["contact"]): r for r in csv.DictReader(f)}
    with open(os.path.join(out, "solutions.json")) as f:
        R["summary"] = json.load(f)


def tearDownModule():
    if "tmp" in R:
        shutil.rmtree(R["tmp"], ignore_errors=True)


@requires_unjam
class ProbeSolutions(unittest.TestCase):
    """The four starts on every force-carrying contact of p50-mu1 (one run, setUpModule)."""

    def test_1_the_reference_contacts(self):
        # Contacts 5 and 6 have two exact solutions (the independent solver's two): the lp
        # start finds the other one; contacts 1 and 2 have one, which every start finds. The
        # interior start reaches the static start's solution on all four.
        for k, (f_static, f_other) in reference().items():
            r = R['rows'][k]
            self.assertEqual(int(r["exact_starts"]), 4, k)
            self.assertAlmostEqual(float(r["f_crit_static"]) / f_static, 1.0, delta=1e-6)
            self.assertAlmostEqual(float(r["f_crit_interior"]) / f_static, 1.0, delta=1e-6)
            if f_other is None:
                self.assertEqual(int(r["solutions"]), 1, k)
            else:
                self.assertEqual(int(r["solutions"]), 2, k)
                self.assertAlmostEqual(float(r["f_crit_min"]) / f_other, 1.0, delta=1e-6)
                self.assertAlmostEqual(float(r["f_crit_max"]) / f_static, 1.0, delta=1e-6)

    def test_2_counts_agree_with_the_rows(self):
        rows = R['rows'].values()
        s = R['summary']
        self.assertEqual(s["probes"], len(R['rows']))
        self.assertEqual(s["probes"], 56)  # the force-carrying contacts of p50-mu1
        for start in ("static", "compliant", "lp", "interior"):
            self.assertEqual(s["exact"][start],
                             sum(float(r[f"residual_{start}"]) <= 1e-6 for r in rows), start)
        # the interior start is exact on every probe here (measured 56 of 56) and reaches the
        # static start's solution on most (measured 46 of 56; docs/probe.md, "An interior-point
        # start")
        self.assertEqual(s["exact"]["interior"], 56)
        same = sum(abs(float(r["f_crit_interior"]) / float(r["f_crit_static"]) - 1.0) <= 1e-3
                   for r in rows)
        self.assertGreaterEqual(same, 40)
        self.assertLess(same, 56)  # and another exact solution on some
        several = sum(int(r["solutions"]) >= 2 for r in rows)
        self.assertEqual(s["with_two_solutions_or_more"], several)
        self.assertGreaterEqual(several, 2)
        for r in rows:
            self.assertLessEqual(int(r["solutions"]), int(r["exact_starts"]))
            if r["f_crit_min"]:
                self.assertLessEqual(float(r["f_crit_min"]), float(r["f_crit_max"]))

    def test_3_rerun_gives_the_same_bytes(self):
        # The probe runs are complete: unjam resumes them without probing again.
        with open(os.path.join(R['out'], "solutions.csv"), "rb") as f:
            before = f.read()
        p = run(*R['args'])
        self.assertEqual(p.returncode, 0, p.stderr)
        with open(os.path.join(R['out'], "solutions.csv"), "rb") as f:
            self.assertEqual(f.read(), before)

    def test_4_bad_input_is_refused(self):
        a_file = os.path.join(R['tmp'], "a-file")
        with open(a_file, "w") as f:
            f.write("kept")
        for args, message in (([R['tmp'], "--all"], "not a packing directory"),
                              ([R['packing'], "--all", "--out", os.path.join(a_file, "x"), "--unjam", UNJAM],
                               "cannot create the output directory"),
                              ([R['packing'], "--sample", "0", "--unjam", UNJAM], "--sample must be at least 1"),
                              ([R['packing'], "--all", "--starts", "static", "static", "--unjam", UNJAM],
                               "lists a start twice")):
            p = run(*args)
            self.assertEqual(p.returncode, 2, args)
            self.assertIn(message, p.stderr)
        with open(a_file) as f:
            self.assertEqual(f.read(), "kept")


if __name__ == "__main__":
    unittest.main()
