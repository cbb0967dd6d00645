"""Siconos numerics solves the probe step exported by `unjam probe --export-problem` to the
same F_crit as unjam's exact Lemke probe and the independent reference
(tests/fixtures/p50-mu1/cd-reference.csv; docs/probe.md, "Against Siconos")."""
import csv
import os
import subprocess
import tempfile
import unittest

import numpy as np
import siconos.numerics as sn

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
UNJAM = os.environ.get("UNJAM", os.path.join(ROOT, "build", "release", "unjam"))
FIXTURE = os.path.join(ROOT, "tests", "fixtures", "p50-mu1")


def reference():
    with open(os.path.join(FIXTURE, "cd-reference.csv")) as f:
        rows = [r for r in f if not r.startswith("#")]
    return {int(r["contact"]): float(r["f_crit_from_static"]) for r in csv.DictReader(rows)}


class SiconosCrossCheck(unittest.TestCase):
    def test_lemke_of_siconos_solves_the_exported_step(self):
        with tempfile.TemporaryDirectory() as out:
            for k, f_ref in reference().items():
                dat = os.path.join(out, f"step-{k}.dat")
                # dt = 1e-3: the time step of the reference (cd-reference.csv)
                subprocess.run([UNJAM, "probe", FIXTURE, "--contact", str(k), "--method", "lemke",
                                "--dt", "1e-3", "--out", out, "--export-problem", dat,
                                "--threads", "1"],
                               check=True, capture_output=True)
                with open(os.path.join(out, f"probe-{k}-forces.csv")) as f:
                    ours = {int(r["contact"]): float(r["fn"]) for r in csv.DictReader(f)}
                self.assertAlmostEqual(ours[k] / f_ref, 1.0, delta=1e-9)
                fc = sn.frictionContact_new_from_filename(dat)
                nc = fc.numberOfContacts
                r, v = np.zeros(2 * nc), np.zeros(2 * nc)
                info = sn.fc2d_driver(fc, r, v, sn.SolverOptions(sn.SICONOS_FRICTION_2D_LEMKE))
                self.assertEqual(info, 0, f"contact {k}")
                # Siconos' solution is exact: Signorini and Coulomb hold on its velocities.
                self.assertGreater(v[0::2].min(), -1e-9)
                self.assertLess((np.abs(r[1::2]) - r[0::2]).max(), 1e-9)  # mu = 1
                if k in (1, 2):  # one solution: the same F_crit
                    self.assertAlmostEqual(r[2 * k] / f_ref, 1.0, delta=1e-9)


if __name__ == "__main__":
    unittest.main()
