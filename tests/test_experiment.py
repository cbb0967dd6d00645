"""Tests of scripts/experiment.py at --scale tiny (about 30 s).

Run from the repository root:  /usr/bin/python3 -m unittest tests/test_experiment.py
The unjam binary: tests/unjam_binary.py.
"""

import csv
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from unjam_binary import REPO, UNJAM, requires_unjam  # noqa: E402

SCRIPT = os.path.join(REPO, "scripts", "experiment.py")

STAGE_LINE = re.compile(r"^\[(\d+)/(\d+)\] (.+?): .* \.\.\. (running|done in [\d.]+ s|"
                        r"skipped \(cached\))  \[")


def run(out, *extra):
    p = subprocess.run([sys.executable, SCRIPT, "--scale", "tiny", "--out", out, "--unjam", UNJAM,
                        *extra], capture_output=True, text=True, cwd=REPO, timeout=300)
    if p.returncode != 0:
        raise AssertionError(f"experiment.py failed ({p.returncode}):\n{p.stdout}\n{p.stderr}")
    return p.stdout


def outcomes(stdout):
    """{stage name: 'ran' | 'cached'} from the progress lines."""
    res = {}
    for line in stdout.splitlines():
        m = STAGE_LINE.match(line)
        if m and m.group(4) != "running":
            res[m.group(3)] = "cached" if m.group(4).startswith("skipped") else "ran"
    return res


@requires_unjam
class ExperimentTiny(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="unjam-experiment-")
        cls.out = os.path.join(cls.tmp, "exp")
        cls.first = run(cls.out)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_1_files(self):
        o = self.out
        expected = ["sweep.csv", "fixed.csv", "report.md", "stage.json",
                    "fig1-field.png", "fig1-packing.png", "fig2-profiles.png",
                    "fig3-friction-sweep.png", "fig4-ensemble.png", "fig-probe-field.png",
                    "fig4/N50-mu0.1-s3/ensemble.json", "fig4/N50-mu0.1-s3/stage.json"]
        for mu in ("0", "0.1", "1"):
            d = f"packings/N100-mu{mu}-s1"
            expected += [f"{d}/meta.json", f"{d}/probe_summary.json", f"{d}/probes.csv",
                         f"{d}/response_profile.csv", f"{d}/stage.json"]
        for mu in ("0.1", "1"):
            expected += [f"fixed/N100-mu{mu}/meta.json", f"fixed/N100-mu{mu}/probe_summary.json",
                         f"packings/N100-mu{mu}-s1/friction_threshold.json"]
        expected.append("friction-threshold.csv")
        for f in expected:
            self.assertTrue(os.path.isfile(os.path.join(o, f)), f"missing {f}")
            self.assertGreater(os.path.getsize(os.path.join(o, f)), 0, f"empty {f}")
        with open(os.path.join(o, "sweep.csv")) as f:
            rows = list(csv.DictReader(f))
        self.assertEqual([r["mu"] for r in rows], ["0", "0.1", "1"])
        with open(os.path.join(o, "fixed.csv")) as f:
            self.assertEqual(len(list(csv.DictReader(f))), 3)
        self.assertEqual(set(outcomes(self.first).values()), {"ran"})
        self.assertEqual(len(outcomes(self.first)), 22)

    def test_1_frictionless_packing_is_isostatic(self):
        # mu = 0 is packed with tighter dynamics (FRICTIONLESS_PACK), so that its network is
        # unique and F_crit = F_cont for every probed contact.
        d = os.path.join(self.out, "packings/N100-mu0-s1")
        with open(os.path.join(d, "meta.json")) as f:
            dynamics = json.load(f)["settings"]["dynamics"]
        self.assertEqual((dynamics["nlgs_tol"], dynamics["nlgs_max_sweeps"]), (1e-6, 2000))
        with open(os.path.join(d, "probes.csv")) as f:
            probes = list(csv.DictReader(f))
        self.assertGreater(len(probes), 100)
        for r in probes:
            self.assertAlmostEqual(float(r["f_crit"]), float(r["f_cont"]),
                                   delta=1e-6 * float(r["f_cont"]), msg=f"contact {r['contact']}")

    def test_2_report_matches_table(self):
        with open(os.path.join(self.out, "sweep.csv")) as f:
            rows = {r["mu"]: r for r in csv.DictReader(f)}
        with open(os.path.join(self.out, "report.md")) as f:
            report = f.read()
        section = report.split("## Measured values per mu")[1].split("\n\n")[2]
        table = [ln for ln in section.splitlines() if ln.startswith("| ")][1:]
        self.assertEqual(len(table), 3)
        cols = ["phi", "z", "F_cont_over_F0", "F_crit_over_F_cont", "alpha"]
        for ln in table:
            cells = [c.strip() for c in ln.strip("|").split("|")]
            mu, n, seeds = cells[:3]
            self.assertEqual((n, seeds), ("100", "1"))
            for c, cell in zip(cols, cells[3:]):
                if rows[mu][c] == "":
                    self.assertEqual(cell, "—", f"mu {mu} {c}")
                    continue
                m = re.fullmatch(r"([-\d.]+) ± ([\d.]+)", cell)
                self.assertIsNotNone(m, f"mu {mu} {c}: {cell!r}")
                self.assertAlmostEqual(float(m.group(1)), float(rows[mu][c]), delta=0.51e-4)
                self.assertEqual(float(m.group(2)), 0.0)
        # the verdict on <F_crit>/<F_cont> names the mu of the measured maximum
        mu_max = max(rows, key=lambda k: float(rows[k]["F_crit_over_F_cont"]))
        self.assertIn(f"maximum of <F_crit>/<F_cont> at mu = {mu_max} ", report)
        # Fig. 4 by the paper's probe, exact: its row is read from the ensemble stage's output
        with open(os.path.join(self.out, "fig4", "N50-mu0.1-s3", "ensemble.json")) as f:
            probe = json.load(f)["probe"]
        self.assertEqual(probe["method"], "cd")
        self.assertEqual(probe["unconverged"], 0)
        ratio = probe["f_crit_over_fn_max"]
        self.assertIn(f"by the cd probe on {probe['contacts_probed']} contacts: F_crit / fn_max "
                      f"median {ratio['median']:.4f}, min {ratio['min']:.4f}", report)
        verdict = "agree" if ratio["median"] >= 0.98 and ratio["min"] >= 0.9 else "disagree"
        self.assertRegex(report, r"\| F_crit = max of the admissible interval \(N = 50, mu = 0\.1\) "
                         r"\|.*\| \*\*" + verdict + r"\*\* \|")

    def test_2b_friction_thresholds_in_table_and_report(self):
        # Every packing with friction has its threshold bracketed to 1e-3 mu below its own mu
        # (its network is admissible at mu), the table holds the json's bracket, and the
        # report's row is the table's.
        with open(os.path.join(self.out, "friction-threshold.csv")) as f:
            rows = {r["mu"]: r for r in csv.DictReader(f)}
        self.assertEqual(set(rows), {"0.1", "1"})
        with open(os.path.join(self.out, "report.md")) as f:
            report = f.read()
        for mu, r in rows.items():
            with open(os.path.join(self.out, f"packings/N100-mu{mu}-s1/friction_threshold.json")) as f:
                t = json.load(f)
            lo, hi, m = float(r["mu_s_low"]), float(r["mu_s_high"]), float(mu)
            self.assertEqual((lo, hi), (t["mu_s_low"], t["mu_s_high"]))
            self.assertLess(lo, hi)
            self.assertLessEqual(hi - lo, 1e-3 * m)
            self.assertLessEqual(hi, m)
            self.assertGreater(lo, 0.0)
            self.assertEqual(float(r["mu_s_over_mu"]), hi / m)
            self.assertEqual(int(r["contacts"]), t["contacts_used"])
            ratio = float(r["mu_s_over_mu"])
            self.assertIn(f"| {mu} | 100 | 1 | {ratio:.4f} ± 0.0000 | {ratio:.4f} | {ratio:.4f} | "
                          f"{t['lps']} |", report)

    def test_3_rerun_skips_everything(self):
        res = outcomes(run(self.out))
        self.assertEqual(len(res), 22)
        self.assertEqual({k for k, v in res.items() if v != "cached"}, set())

    def test_4_changed_parameter_reruns_dependent_stages_only(self):
        res = outcomes(run(self.out, "--probe-g", "2e-9"))
        ran = {k for k, v in res.items() if v == "ran"}
        expected = {"probe N100-mu0-s1", "probe N100-mu0.1-s1", "probe N100-mu1-s1",
                    "probe fixed N100-mu0.1", "probe fixed N100-mu1", "table sweep",
                    "table fixed", "plot fig3", "plot fig2", "plot fig1", "probe one"}
        self.assertEqual(ran, expected)
        self.assertEqual(len(res), 22)     # the packs, thresholds, ensemble and Fig. 4 were cached
        with open(os.path.join(self.out, "packings/N100-mu0.1-s1/probe_summary.json")) as f:
            self.assertIn('"g": 2e-09', f.read())

    def test_5_stopped_pack_stage_resumes(self):
        # An experiment stopped inside `unjam pack` leaves a resumable packing directory and
        # the stage record "running". Made here deterministically: the packing is redone up
        # to --max-steps (unjam saves it, not static, and exits 1) and the record set back to
        # running. The re-run must resume it (unjam pack --resume), reach the same bytes as
        # the uninterrupted run, and recompute only what depends on it. (--probe-g as left by
        # test_4, so the probes of the other packings stay cached.)
        d = os.path.join(self.out, "packings", "N100-mu1-s1")
        with open(os.path.join(d, "particles.csv")) as f:
            before = f.read()
        with open(os.path.join(d, "stage.json")) as f:
            records = json.load(f)
        shutil.rmtree(d)
        p = subprocess.run([UNJAM, "pack", "--n", "100", "--mu", "1", "--seed", "1", "--out", d,
                            "--max-steps", "200", "--quiet"], capture_output=True, text=True)
        self.assertEqual(p.returncode, 1, p.stderr)
        self.assertIn("resume with: unjam pack --resume", p.stderr)
        records["pack N100-mu1-s1"]["status"] = "running"
        with open(os.path.join(d, "stage.json"), "w") as f:
            json.dump(records, f)

        res = outcomes(run(self.out, "--probe-g", "2e-9"))
        ran = {k for k, v in res.items() if v == "ran"}
        self.assertEqual(ran, {"pack N100-mu1-s1", "probe N100-mu1-s1", "threshold N100-mu1-s1",
                               "table sweep", "table threshold", "plot fig3", "plot fig2",
                               "plot fig1", "probe one"})
        with open(os.path.join(self.out, "logs", "pack_N100-mu1-s1.log")) as f:
            self.assertIn("pack --resume", f.read())
        with open(os.path.join(d, "particles.csv")) as f:
            self.assertEqual(f.read(), before, "the resumed packing differs")

    @unittest.skipUnless(os.environ.get("UNJAM_MPI", "1") == "1" and shutil.which("mpirun"),
                         "unjam built without MPI (CMake option UNJAM_MPI off) or no mpirun")
    def test_6_probe_stage_under_mpi_writes_the_same_bytes(self):
        # --mpi K runs the probe stages under mpirun; the outputs are those of one process,
        # so a probe stage recomputed over 2 ranks gives back the same bytes. (CI runs as
        # root: Open MPI needs the two OMPI_ALLOW_RUN_AS_ROOT variables then.)
        d = os.path.join(self.out, "packings", "N100-mu0.1-s1")
        before = {}
        for name in ("probes.csv", "response_profile.csv"):
            with open(os.path.join(d, name)) as f:
                before[name] = f.read()
        os.remove(os.path.join(d, "probe_summary.json"))   # the stage's outputs are incomplete
        env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
        p = subprocess.run([sys.executable, SCRIPT, "--scale", "tiny", "--out", self.out,
                            "--unjam", UNJAM, "--probe-g", "2e-9", "--threads", "1", "--mpi", "2",
                            "--mpirun", "mpirun --oversubscribe"],
                           capture_output=True, text=True, cwd=REPO, timeout=300, env=env)
        self.assertEqual(p.returncode, 0, p.stdout + p.stderr)
        self.assertIn("probe N100-mu0.1-s1", {k for k, v in outcomes(p.stdout).items() if v == "ran"})
        with open(os.path.join(self.out, "logs", "probe_N100-mu0.1-s1.log")) as f:
            self.assertIn("mpirun --oversubscribe -n 2", f.read())
        for name, text in before.items():
            with open(os.path.join(d, name)) as f:
                self.assertEqual(f.read(), text, name)
        with open(os.path.join(d, "probe_summary.json")) as f:
            self.assertEqual(len(json.load(f)["ranks"]), 2)

    def test_7_skip_leaves_out_the_optional_stages_only(self):
        # --skip fixed fig4 probe-one threshold: the sweep's stages stay cached, Fig. 3 is
        # redrawn without the inset, the report has no threshold section; the default run
        # afterwards has every stage again, and only Fig. 3 is redrawn (with the inset).
        # (--probe-g as left by test_4.)
        res = outcomes(run(self.out, "--probe-g", "2e-9", "--skip", "fixed", "fig4", "probe-one",
                           "threshold"))
        self.assertEqual(len(res), 10)
        self.assertFalse(any(k.startswith(("pack fixed", "probe fixed", "pack fig4", "threshold"))
                             or k in ("table fixed", "ensemble fig4", "plot fig4", "probe one",
                                      "table threshold")
                             for k in res), res)
        with open(os.path.join(self.out, "report.md")) as f:
            self.assertNotIn("## How much of its friction", f.read())
        self.assertEqual({k for k, v in res.items() if v == "ran"}, {"plot fig3"})
        with open(os.path.join(self.out, "stage.json")) as f:
            self.assertGreaterEqual(json.load(f)["plot fig3"]["cpu_seconds"], 0)
        res = outcomes(run(self.out, "--probe-g", "2e-9"))
        self.assertEqual(len(res), 22)
        self.assertEqual({k for k, v in res.items() if v == "ran"}, {"plot fig3"})

    def test_8_merge_sweep_rebuilds_the_table_from_the_packings(self):
        # scripts/merge_sweep.py: rows read from the probed packings are the table's own rows
        dirs = [os.path.join(self.out, "packings", f"N100-mu{mu}-s1") for mu in ("1", "0", "0.1")]
        merged = os.path.join(self.tmp, "merged.csv")
        with open(os.path.join(self.out, "sweep.csv")) as f:
            header = f.readline()
        with open(merged, "w", newline="") as f:
            f.write(header)
        p = subprocess.run([sys.executable, os.path.join(REPO, "scripts", "merge_sweep.py"),
                            merged, "--packings", *dirs], capture_output=True, text=True,
                           timeout=60)
        self.assertEqual(p.returncode, 0, p.stderr)
        with open(merged) as f, open(os.path.join(self.out, "sweep.csv")) as g:
            self.assertEqual(f.read(), g.read())

    def run_exact_stages(self, *extra):
        """The experiment again with --cd-sample 3 and `extra`: every exact stage ran, the sweep's
        own stages cached; (stage outcomes, exact-probe.csv's rows by mu)."""
        res = outcomes(run(self.out, "--probe-g", "2e-9", "--cd-sample", "3", *extra))
        self.assertTrue(all(res[k] == "ran" for k in res if k.startswith("exact ")), res)
        self.assertTrue(all(res[k] == "cached" for k in res if k.startswith(("pack ", "probe "))),
                        res)
        with open(os.path.join(self.out, "exact-probe.csv")) as f:
            rows = {r["mu"]: r for r in csv.DictReader(f)}
        self.assertEqual(set(rows), {"0", "0.1", "1"})
        return res, rows

    def test_9_exact_probe_beside_lp(self):
        # --cd-sample 3: the exact probe and lp on the same 3 contacts of every packing, the
        # sweep's own stages cached (--probe-g as left by test_4); exact-probe.csv holds the
        # two summaries' numbers and the report shows them side by side.
        res, rows = self.run_exact_stages()
        exact = {k for k, v in res.items() if k.startswith("exact ")}
        # the sweep's packings, and the fixed series up to --cd-fixed-max-mu (0.1: not mu = 1)
        self.assertEqual(exact, {f"exact N100-mu{mu}-s1" for mu in ("0", "0.1", "1")}
                         | {"exact fixed N100-mu0.1"})
        self.assertEqual(res["table exact"], "ran")
        self.assertEqual(res["table exact fixed"], "ran")
        for mu, r in rows.items():
            d = os.path.join(self.out, "packings", f"N100-mu{mu}-s1")
            for m in ("cd", "lp"):
                with open(os.path.join(d, f"exact-{m}", "probe_summary.json")) as f:
                    s = json.load(f)
                self.assertEqual((s["method"], s["probes"], s["settings"]["g"]), (m, 3, 2e-9))
                if m == "cd":  # the experiment's default start (--cd-start)
                    self.assertEqual(s["settings"]["cd_start"], "interior")
                self.assertEqual(float(r[f"F_crit_over_F_cont_{m}"]), s["F_crit_over_F_cont"])
            self.assertEqual(int(r["not_exact"]), 0, r)
            self.assertEqual(int(r["without_solution"]), 0, r)
        # mu = 0, isostatic: lp gives F_crit = F_cont; the exact step at its quasi-static dt
        # too, up to its inertial term (~1e-3 at g / dt^2 = 1e-5), which is positive
        self.assertAlmostEqual(float(rows["0"]["F_crit_over_F_cont_lp"]), 1.0, places=6)
        self.assertGreater(float(rows["0"]["F_crit_over_F_cont_cd"]), 1.0)
        self.assertLess(float(rows["0"]["F_crit_over_F_cont_cd"]), 1.01)
        with open(os.path.join(self.out, "report.md")) as f:
            report = f.read()
        self.assertIn("## The exact probe beside lp", report)
        self.assertIn("--cd-start interior", report)
        self.assertIn("the path from an interior-point iterate", report)
        self.assertIn("| 1 | 100 | 1 | 3 | 0 | 0 | ", report)
        # Fig. 3 by both probes, drawn from exact-probe.csv and listed in the report
        self.assertEqual(res["plot fig3 exact"], "ran")
        with open(os.path.join(self.out, "fig3-exact-vs-lp.png"), "rb") as f:
            self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")
        self.assertIn("(lp) on the same contacts: [fig3-exact-vs-lp.png](fig3-exact-vs-lp.png)",
                      report)
        # The fixed series (Fig. 3's inset) by both probes: its mu = 0 row is the source
        # packing's own comparison, its mu = 0.1 row the frozen structure's, all exact.
        with open(os.path.join(self.out, "exact-probe-fixed.csv")) as f:
            fixed = {r["mu"]: r for r in csv.DictReader(f)}
        self.assertEqual(set(fixed), {"0", "0.1"})
        self.assertEqual(fixed["0"], rows["0"])
        d = os.path.join(self.out, "fixed", "N100-mu0.1")
        for m in ("cd", "lp"):
            with open(os.path.join(d, f"exact-{m}", "probe_summary.json")) as f:
                s = json.load(f)
            self.assertEqual((s["method"], s["probes"], s["mu"]), (m, 3, 0.1))
            self.assertEqual(float(fixed["0.1"][f"F_crit_over_F_cont_{m}"]), s["F_crit_over_F_cont"])
        self.assertEqual(int(fixed["0.1"]["not_exact"]), 0)
        # the paper's probe does not exceed the LP maximum beyond its inertial term
        self.assertLessEqual(float(fixed["0.1"]["F_crit_over_F_cont_cd"]),
                             1.01 * float(fixed["0.1"]["F_crit_over_F_cont_lp"]))
        self.assertIn("## The exact probe beside lp on the fixed packing", report)
        self.assertIn("`exact-probe-fixed.csv`", report)
        self.assertEqual(res["plot fig3 inset exact"], "ran")
        with open(os.path.join(self.out, "fig3-inset-exact-vs-lp.png"), "rb") as f:
            self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")
        self.assertIn("[fig3-inset-exact-vs-lp.png](fig3-inset-exact-vs-lp.png)", report)
        self.assertIn("--cd-start interior; also on the fixed series up to mu = 0.1", report)

    def test_9b_exact_probe_within_a_budget_of_pieces(self):
        # --cd-max-pieces 2: the exact stages run again with the budget (their command
        # changed); by the interior start the probes at mu = 0.1 take 196-223 pieces and are
        # stopped, at mu = 1 two take none (the iterate's states are the solution's) and one
        # 35 (stopped), at mu = 0 none (the interior-point method solves the frictionless step);
        # the stopped probes are counted in exact-probe.csv and in the report, which names the
        # budget.
        _, rows = self.run_exact_stages("--cd-max-pieces", "2")
        for mu, r in rows.items():
            d = os.path.join(self.out, "packings", f"N100-mu{mu}-s1", "exact-cd")
            with open(os.path.join(d, "probe_summary.json")) as f:
                s = json.load(f)
            self.assertEqual(s["settings"]["cd_max_pieces"], 2)
            self.assertEqual(int(r["over_budget"]), s["over_budget"]["probes"], mu)
            with open(os.path.join(d, "probes.csv")) as f:
                sweeps = [int(p["sweeps"]) for p in csv.DictReader(f)]
            self.assertEqual(s["over_budget"]["probes"], sum(k == 3 for k in sweeps), mu)
            self.assertTrue(all(k <= 3 for k in sweeps), (mu, sweeps))
        self.assertEqual(int(rows["0.1"]["over_budget"]), 3)
        self.assertEqual(int(rows["1"]["over_budget"]), 1)
        self.assertEqual(int(rows["0"]["over_budget"]), 0)
        with open(os.path.join(self.out, "report.md")) as f:
            report = f.read()
        self.assertIn("--cd-max-pieces 2", report)
        self.assertIn("| stopped by the budget |", report)

    def test_9c_exact_probe_options_are_passed_on_where_given(self):
        # --cd-accept-residual, --cd-compliant-start, --cd-settle-compliance, --cd-lost-factor and --cd-restart-floor reach `unjam probe` (recorded in the cd
        # summary's settings), the budget of test_9b is gone from the command (so its stages run
        # again), the accepted probes are counted in exact-probe.csv as in the summary, and the
        # report names both options.
        res, rows = self.run_exact_stages("--cd-accept-residual", "1e-4", "--cd-compliant-start", "1e-3",
                                          "--cd-softer-starts", "0", "--cd-settle-compliance", "1e-5",
                                          "--cd-lost-factor", "1e3", "--cd-restart-floor", "1e-5")
        for mu, r in rows.items():
            d = os.path.join(self.out, "packings", f"N100-mu{mu}-s1", "exact-cd")
            with open(os.path.join(d, "probe_summary.json")) as f:
                s = json.load(f)
            self.assertEqual(s["settings"]["cd_accept_residual"], 1e-4)
            self.assertEqual(s["settings"]["cd_compliant_start"], 1e-3)
            self.assertEqual(s["settings"]["cd_settle_compliance"], 1e-5)
            self.assertEqual(s["settings"]["cd_lost_factor"], 1e3)
            self.assertEqual(s["settings"]["cd_restart_floor"], 1e-5)
            self.assertNotIn("cd_softer_starts", s["settings"])  # 0: one start, recorded where on
            self.assertNotIn("over_budget", s)
            self.assertEqual(int(r["accepted"]), s["accepted"]["probes"], mu)
            with open(os.path.join(d, "probes.csv")) as f:
                probes = list(csv.DictReader(f))
            # an accepted probe is near-exact: not converged, residual within 1e-4 g
            near = [p for p in probes if p["converged"] == "0"]
            self.assertEqual(len(near), int(r["not_exact"]), mu)
            self.assertTrue(all(float(p["residual"]) <= 1e-4 for p in near), (mu, near))
        with open(os.path.join(self.out, "report.md")) as f:
            report = f.read()
        self.assertIn("--cd-accept-residual 0.0001, --cd-compliant-start 0.001, --cd-softer-starts 0, "
                      "--cd-settle-compliance 1e-05, --cd-lost-factor 1000.0, --cd-restart-floor 1e-05", report)
        self.assertIn("| near-exact, accepted |", report)
        self.assertNotIn("--cd-max-pieces 2", report)
        self.assertIn("--cd-start interior --cd-accept-residual 0.0001 --cd-compliant-start 0.001 "
                      "--cd-softer-starts 0 --cd-settle-compliance 1e-05 --cd-lost-factor 1000.0 "
                      "--cd-restart-floor 1e-05 (and lp)", report)  # the stages' own lines in the timings


class ExactProbeTable(unittest.TestCase):
    """exact-probe.csv and its report section, from synthetic probe summaries: the cd probes
    without a solution are counted apart from the near-exact ones, per packing and summed over
    the seeds."""

    def test_probes_without_a_solution_are_counted_apart(self):
        sys.path.insert(0, os.path.join(REPO, "scripts"))
        import experiment_report
        import experiment_stages
        with tempfile.TemporaryDirectory() as tmp:
            rows = []
            for seed, (bad, none) in ((1, (5, 2)), (2, (3, 1))):
                d = os.path.join(tmp, f"N500-mu0.5-s{seed}")
                for m, o in experiment_stages.exact_probe_dirs(d).items():
                    os.makedirs(o)
                    s = {"method": m, "probes": 300, "not_converged": bad if m == "cd" else 0,
                         "without_solution": none if m == "cd" else 0,
                         "F_crit_over_F_cont": 1.5 if m == "cd" else 2.0, "alpha": 0.5,
                         "ranks": [{"busy_seconds": 3000.0}]}
                    if m == "cd" and seed == 2:  # a budget stopped 2 (a summary without one: 0)
                        s["over_budget"] = {"max_pieces": 100, "probes": 2}
                    if m == "cd" and seed == 1:  # 4 accepted near-exact (without the option: 0)
                        s["accepted"] = {"accept_residual": 1e-5, "probes": 4}
                    # the means' standard errors over the contacts: lp 0.02 on both, cd 0.03, 0.04
                    s["F_crit_over_F_cont_err"] = 0.02 if m == "lp" else 0.01 + 0.01 * (seed + 1)
                    with open(os.path.join(o, "probe_summary.json"), "w") as f:
                        json.dump(s, f)
                rows.append(experiment_stages.exact_row(d, 0.5, 500, seed))
            self.assertEqual([(r["not_exact"], r["without_solution"], r["over_budget"],
                               r["accepted"]) for r in rows], [(5, 2, 0, 4), (3, 1, 2, 0)])
            table = os.path.join(tmp, "exact-probe.csv")

            def report_of(rows):
                """The report section of exact-probe.csv written with these rows."""
                with open(table, "w", newline="") as f:
                    w = csv.DictWriter(f, fieldnames=experiment_stages.EXACT_COLUMNS)
                    w.writeheader()
                    w.writerows(rows)
                return "\n".join(experiment_report.exact_probe_section(table, "compliant"))
            report = report_of(rows)
            self.assertIn("| without a solution |", report)
            self.assertEqual([(r["F_crit_over_F_cont_lp_err"], r["F_crit_over_F_cont_cd_err"]) for r in rows],
                             [("0.02", "0.03"), ("0.02", "0.04")])
            # sampling error of the two seeds' mean: sqrt(2 x 0.02^2) / 2 and sqrt(0.03^2 + 0.04^2) / 2
            self.assertIn("| 0.5 | 500 | 2 | 600 | 8 | 3 | 2.0000 ± 0.0000 | 1.5000 ± 0.0000 | "
                          "0.0141 / 0.0250 |", report)
            # a summary without it (made before it was recorded): no sampling error for the group
            rows[1]["F_crit_over_F_cont_cd_err"] = ""
            self.assertIn("| 1.5000 ± 0.0000 | 0.0141 / — |", report_of(rows))
            self.assertTrue(any(line.startswith("| 0.5 | 500 |") and line.endswith("| 2 | 4 |")
                                for line in report.splitlines()), report)


@requires_unjam
class ExperimentArguments(unittest.TestCase):
    """Bad overrides are refused up front (a usage error, exit 2), before any stage runs."""

    def test_bad_overrides_are_refused_before_any_stage(self):
        with tempfile.TemporaryDirectory(prefix="unjam-experiment-args-") as tmp:
            out = os.path.join(tmp, "exp")
            for extra, phrase in [(["--seeds", "-1"], "--seeds"), (["--mus", "0.1", "nan"], "--mus"),
                                  (["--mus", "-1"], "--mus"), (["--ns", "2"], "at least 8"),
                                  (["--samples", "0"], "--samples"), (["--probe-g", "nan"], "--probe-g"),
                                  (["--probe-g", "-1e-9"], "--probe-g"),
                                  (["--cd-max-pieces", "-1"], "--cd-max-pieces"),
                                  (["--cd-accept-residual", "1e-2"], "--cd-accept-residual"),
                                  (["--cd-accept-residual", "nan"], "--cd-accept-residual"),
                                  (["--cd-compliant-start", "0"], "--cd-compliant-start"),
                                  (["--cd-compliant-start", "inf"], "--cd-compliant-start"),
                                  (["--cd-softer-starts", "-1"], "--cd-softer-starts"),
                                  (["--cd-settle-compliance", "-1e-5"], "--cd-settle-compliance"),
                                  (["--cd-settle-compliance", "nan"], "--cd-settle-compliance"),
                                  (["--cd-lost-factor", "-1"], "--cd-lost-factor"),
                                  (["--cd-lost-factor", "inf"], "--cd-lost-factor"),
                                  (["--cd-fixed-max-mu", "-0.1"], "--cd-fixed-max-mu"),
                                  (["--cd-fixed-max-mu", "nan"], "--cd-fixed-max-mu")]:
                p = subprocess.run([sys.executable, SCRIPT, "--scale", "tiny", "--out", out,
                                    "--unjam", UNJAM, *extra],
                                   capture_output=True, text=True, cwd=REPO, timeout=60)
                self.assertEqual(p.returncode, 2, (extra, p.stderr))
                self.assertIn(phrase, p.stderr)
                self.assertNotIn("Traceback", p.stderr)
                self.assertFalse(os.path.exists(out), extra)

    def test_unwritable_out_is_a_message_not_a_traceback(self):
        p = subprocess.run([sys.executable, SCRIPT, "--scale", "tiny", "--out", "/proc/unjam-x",
                            "--unjam", UNJAM],
                           capture_output=True, text=True, cwd=REPO, timeout=60)
        self.assertEqual(p.returncode, 1, p.stderr)
        self.assertIn("cannot create the output directory", p.stderr)
        self.assertNotIn("Traceback", p.stderr)


if __name__ == "__main__":
    unittest.main()
