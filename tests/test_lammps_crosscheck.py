"""unjam's static networks and LP intervals against LAMMPS' soft granular DEM
(scripts/lammps_crosscheck.py; docs/lammps.md)."""
import json
import os
import shutil
import subprocess
import tempfile
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
UNJAM = os.environ.get("UNJAM", os.path.join(ROOT, "build", "release", "unjam"))
SCRIPT = os.path.join(ROOT, "scripts", "lammps_crosscheck.py")
FIXTURES = os.path.join(ROOT, "tests", "fixtures")


def crosscheck(packing, out, *args):
    r = subprocess.run(["/usr/bin/python3", SCRIPT, packing, "--out", out, "--unjam", UNJAM,
                        *args], capture_output=True, text=True)
    return r


def results(out):
    with open(os.path.join(out, "crosscheck.json")) as f:
        return json.load(f)["results"]


class LammpsCrossCheck(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        if shutil.which("lmp") is None:
            raise RuntimeError("LAMMPS (Debian's lammps, `lmp`) is not installed: "
                               "run scripts/setup.sh")
        cls.tmp = tempfile.TemporaryDirectory()
        # p50-mu0.1 at a strain of 1e-6 against HiGHS' reference intervals: shared by the
        # tests of the frictional network and of a narrowed interval
        cls.p50 = os.path.join(FIXTURES, "p50-mu0.1")
        cls.p50_out = os.path.join(cls.tmp.name, "mu0.1")
        cls.p50_run = crosscheck(cls.p50, cls.p50_out, "--strain", "1e-6", "--bounds",
                                 os.path.join(cls.p50, "bounds-reference.csv"))

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def assert_ran(self, r, out):
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertTrue(os.path.getsize(os.path.join(out, "crosscheck.png")) > 0)
        return results(out)

    def run_ok(self, packing, name, *args):
        out = os.path.join(self.tmp.name, name)
        return self.assert_ran(crosscheck(packing, out, *args), out)

    def test_frictionless_isostatic_network_is_the_rigid_limit_of_the_soft_one(self):
        # One force network at mu = 0 (isostatic): LAMMPS' approaches the packing's as the
        # compression goes to 0, until the packing's own overlaps (~1e-5) limit it.
        packing = os.path.join(self.tmp.name, "p100-mu0")
        subprocess.run([UNJAM, "pack", "--n", "100", "--mu", "0", "--seed", "1", "--tol",
                        "1e-6", "--max-sweeps", "2000", "--threads", "1", "--quiet",
                        "--out", packing], check=True, capture_output=True)
        coarse, fine = self.run_ok(packing, "mu0", "--strain", "1e-4", "1e-5")
        for res in (coarse, fine):
            self.assertTrue(res["relaxed"])
            self.assertEqual(res["extra"], [])
            self.assertEqual(res["missing"], [])
            self.assertEqual(res["contacts_lammps"], res["contacts_packing"])
            self.assertEqual(res["max_dft_F0"], 0.0)
            self.assertLess(res["own_bounds_excess_F0"], 1e-6)
        self.assertLess(fine["max_dfn_F0"], 5e-3)
        self.assertGreater(coarse["max_dfn_F0"], 5 * fine["max_dfn_F0"])

    def test_frictional_network_lies_in_both_lps_intervals(self):
        # p50-mu0.1: at a strain of 1e-6 LAMMPS loads exactly the packing's contacts, so its
        # network is one of the packing's admissible networks: inside the intervals of an
        # independent LP (HiGHS, bounds-reference.csv) and of unjam's LP of its own state.
        (res,) = self.assert_ran(self.p50_run, self.p50_out)
        self.assertEqual(res["extra"], [])
        self.assertEqual(res["bounds_unlisted"], [])
        self.assertLess(res["bounds_excess_F0"], 1e-6)
        self.assertLess(res["own_bounds_excess_F0"], 1e-6)
        # LAMMPS stops with every grain's net force (contacts and drag) and its drag below
        # tol_F0: the contact forces read back balance to twice that
        self.assertLess(res["tol_F0"], 1e-7)
        self.assertLess(res["balance_force_F0"], 2 * res["tol_F0"])
        self.assertLess(res["balance_torque_F0"], 2 * res["tol_F0"])
        self.assertLessEqual(res["coulomb_excess_F0"], 1e-12)
        # another admissible network than the packing's, with sliding contacts of its own
        self.assertGreater(res["max_dfn_F0"], 0.1)

    def test_lammps_state_passes_unjams_checks_and_lies_in_its_intervals_at_mu_1(self):
        (res,) = self.run_ok(os.path.join(FIXTURES, "p200-mu1"), "mu1", "--strain", "1e-5")
        info = res["unjam_info"]
        self.assertLess(info["max_force_residual_over_F0"], 1e-7)
        self.assertLess(info["max_torque_residual_over_F0R"], 1e-7)
        self.assertAlmostEqual(info["P_in_over_P_ext"], 1.0, delta=1e-8)
        self.assertLessEqual(info["max_coulomb_violation_over_F0"], 1e-12)
        self.assertLess(info["geometry_worst_over_tolerance"], 1.0)
        self.assertEqual(res["own_bounds_unlisted"], [])
        self.assertEqual(res["own_bounds_contacts"], res["contacts_lammps"])
        self.assertLess(res["own_bounds_excess_F0"], 1e-6)

    def test_an_interval_that_excludes_the_network_is_reported(self):
        # The check can fail: an interval narrowed below LAMMPS' force is found outside.
        self.assert_ran(self.p50_run, self.p50_out)
        with open(os.path.join(self.p50_out, "strain-1e-06", "forces.csv")) as f:
            lines = f.read().splitlines()
        head = lines[0].split(",")
        rows = [dict(zip(head, ln.split(","))) for ln in lines[1:]]
        top = max(rows, key=lambda r: float(r["fn_lammps"]))
        narrowed = os.path.join(self.tmp.name, "narrowed.csv")
        with open(narrowed, "w") as f:
            f.write("a,b,fn_min,fn_max\n")
            for r in rows:
                if r["fn_max"] == "":
                    continue  # not in the reference's intervals
                hi = float(r["fn_max"])
                if r is top:
                    hi = 0.5 * float(r["fn_lammps"])
                f.write(f"{r['a']},{r['b']},{min(float(r['fn_min']), hi)!r},{hi!r}\n")
        (bad,) = self.run_ok(self.p50, "narrow", "--strain", "1e-6", "--bounds", narrowed)
        with open(os.path.join(self.tmp.name, "narrow", "crosscheck.json")) as f:
            F0 = json.load(f)["packing"]["F0"]
        self.assertAlmostEqual(bad["bounds_excess_F0"], 0.5 * float(top["fn_lammps"]) / F0,
                               delta=1e-9)
        self.assertLess(bad["own_bounds_excess_F0"], 1e-6)

    def test_bad_input_is_refused_with_a_message(self):
        fixture = os.path.join(FIXTURES, "p50-mu0.1")
        cases = [
            ([os.path.join(self.tmp.name, "nowhere")], "nowhere"),
            ([fixture, "--strain", "0"], "--strain"),
            ([fixture, "--lmp", "no-such-lammps"], "not found"),
            ([fixture, "--bounds", os.path.join(fixture, "meta.json")], "meta.json"),
        ]
        for args, words in cases:
            out = os.path.join(self.tmp.name, "refused")
            r = subprocess.run(["/usr/bin/python3", SCRIPT, *args, "--out", out,
                                "--unjam", UNJAM], capture_output=True, text=True)
            self.assertEqual(r.returncode, 1, args)
            self.assertIn(words, r.stderr)
            self.assertNotIn("Traceback", r.stderr)
            self.assertFalse(os.path.exists(os.path.join(out, "crosscheck.json")))


if __name__ == "__main__":
    unittest.main()
