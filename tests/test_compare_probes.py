"""Tests of scripts/compare_probes.py on the fixtures p50-mu1 and p50-mu0.1 (a few seconds).

Run from the repository root:  /usr/bin/python3 -m unittest tests/test_compare_probes.py
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

from unjam_binary import REPO, UNJAM, read_rows, requires_unjam, run_script  # noqa: E402
from unjam_binary import edit_rows as edit_csv  # noqa: E402

FIXTURES = os.path.join(REPO, "tests", "fixtures")
PACKINGS = ("p50-mu1", "p50-mu0.1")
# The residual of a probe without a solution (unjam writes the largest double).
NO_SOLUTION = "1.7976931348623157e+308"


def run(*args):
    return run_script("compare_probes.py", *args)


def probes(directory):
    """{contact: row} of a campaign's probes.csv."""
    return {int(r["contact"]): r for r in read_rows(os.path.join(directory, "probes.csv"))}


def summary(directory):
    """A campaign's probe_summary.json."""
    with open(os.path.join(directory, "probe_summary.json")) as f:
        return json.load(f)


def contents(directory):
    """{name: bytes} of the files in directory."""
    out = {}
    for name in os.listdir(directory):
        with open(os.path.join(directory, name), "rb") as f:
            out[name] = f.read()
    return out


def copy_campaign(src, name, edit_rows=None, edit_summary=None):
    """A copy of campaign src in the test's directory; edit_rows(list of rows) and
    edit_summary(dict) change its probes.csv and probe_summary.json in place."""
    dst = os.path.join(R["tmp"], name)
    shutil.copytree(src, dst)
    if edit_rows:
        edit_csv(os.path.join(dst, "probes.csv"), edit_rows)
    if edit_summary:
        path = os.path.join(dst, "probe_summary.json")
        with open(path) as f:
            s = json.load(f)
        edit_summary(s)
        with open(path, "w") as f:
            json.dump(s, f)
    return dst


R = {}  # the runs shared by the tests: directories, outputs


def setUpModule():
    if not (os.path.isfile(UNJAM) and os.access(UNJAM, os.X_OK)):
        return
    tmp = R["tmp"] = tempfile.mkdtemp(prefix="unjam-compare-")
    R["cd"], R["lp"] = {}, {}
    for name in PACKINGS:
        packing = os.path.join(tmp, name)
        shutil.copytree(os.path.join(FIXTURES, name), packing)
        for method in ("cd", "lp"):
            out = R[method][name] = os.path.join(tmp, f"{name}-{method}")
            p = subprocess.run([UNJAM, "probe", packing, "--sample", "12", "--seed", "1",
                                "--method", method, "--threads", "1", "--out", out],
                               capture_output=True, text=True, timeout=120)
            if p.returncode != 0:
                raise AssertionError(f"unjam probe {name} {method} failed ({p.returncode}):\n"
                                     f"{p.stdout}\n{p.stderr}")
    out = R["out"] = os.path.join(tmp, "compare")
    R["args"] = [R["cd"]["p50-mu1"], R["lp"]["p50-mu1"], R["cd"]["p50-mu0.1"],
                 R["lp"]["p50-mu0.1"], "--out", out]
    p = R["run"] = run(*R["args"])
    if p.returncode != 0:
        raise AssertionError(f"compare_probes.py failed ({p.returncode}):\n{p.stdout}\n{p.stderr}")
    R["compare"] = read_rows(os.path.join(out, "compare.csv"))
    R["ratios"] = read_rows(os.path.join(out, "ratios.csv"))


def tearDownModule():
    if "tmp" in R:
        shutil.rmtree(R["tmp"], ignore_errors=True)


def inertia_F0(cd_dir):
    """{contact: f_inertia / F0} of a cd campaign (NaN where the cell is empty or absent)."""
    F0 = summary(cd_dir)["F0"]
    return {k: float(r.get("f_inertia") or "nan") / F0 for k, r in probes(cd_dir).items()}


def expected(cd_dir, lp_dir):
    """The pair's numbers recomputed from its two probes.csv (the rules of the script)."""
    cd, lp = probes(cd_dir), probes(lp_dir)
    shared = sorted(set(cd) & set(lp))
    line = summary(cd_dir)["settings"].get("max_inertia_F0", 0.0)
    fi = inertia_F0(cd_dir)
    sol = [k for k in shared if float(cd[k]["residual"]) <= 1e-3
           and not (line > 0 and fi[k] > line)]
    exact = [k for k in sol if float(cd[k]["residual"]) <= 1e-6]
    f_cont = sum(float(cd[k]["f_cont"]) for k in sol)
    f_cont_exact = sum(float(cd[k]["f_cont"]) for k in exact)
    ratios = [float(cd[k]["f_crit"]) / float(lp[k]["f_crit"]) for k in sol
              if float(lp[k]["f_crit"]) > 0]
    q1, _, q3 = statistics.quantiles(ratios, n=4)

    def err(x):
        """The standard error of sum(x) / f_cont over the solved contacts: that of the mean
        of x_k - R f_cont_k (which is 0), divided by the mean f_cont."""
        r = sum(x.values()) / f_cont
        e = [x[k] - r * float(cd[k]["f_cont"]) for k in sol]
        return statistics.stdev(e) / math.sqrt(len(sol)) / (f_cont / len(sol))

    x_cd = {k: float(cd[k]["f_crit"]) for k in sol}
    x_lp = {k: float(lp[k]["f_crit"]) for k in sol}
    return {"probes": len(shared), "solved": len(sol),
            "F_crit_over_F_cont_cd_err": err(x_cd), "F_crit_over_F_cont_lp_err": err(x_lp),
            "F_crit_over_F_cont_lp_minus_cd": (sum(x_lp.values()) - sum(x_cd.values())) / f_cont,
            "F_crit_over_F_cont_lp_minus_cd_err": err({k: x_lp[k] - x_cd[k] for k in sol}),
            "exact": sum(float(cd[k]["residual"]) <= 1e-6 for k in shared),
            "F_crit_over_F_cont_cd": sum(float(cd[k]["f_crit"]) for k in sol) / f_cont,
            "F_crit_over_F_cont_lp": sum(float(lp[k]["f_crit"]) for k in sol) / f_cont,
            "ratio_median": statistics.median(ratios), "ratio_q1": q1, "ratio_q3": q3,
            "ratio_min": min(ratios), "ratio_max": max(ratios),
            "pieces_median": statistics.median(int(cd[k]["sweeps"]) for k in shared),
            "F_crit_over_F_cont_lp_all": sum(float(lp[k]["f_crit"]) for k in shared)
            / sum(float(cd[k]["f_cont"]) for k in shared),
            "F_crit_over_F_cont_lp_exact": sum(float(lp[k]["f_crit"]) for k in exact) / f_cont_exact,
            "F_crit_over_F_cont_cd_exact": sum(float(cd[k]["f_crit"]) for k in exact) / f_cont_exact}


@requires_unjam
class ComparePairs(unittest.TestCase):
    """The two fixtures, 12 contacts each by cd and lp (one run, setUpModule)."""

    def assertClose(self, a, b, msg=None):
        self.assertTrue(math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-300), f"{a} != {b} {msg}")

    def test_1_ratios_are_the_two_f_crit_per_contact(self):
        for name in PACKINGS:
            cd, lp = probes(R["cd"][name]), probes(R["lp"][name])
            rows = [r for r in R["ratios"] if r["packing"].endswith(name)]
            self.assertEqual(sorted(int(r["contact"]) for r in rows), sorted(set(cd) & set(lp)))
            for r in rows:
                k = int(r["contact"])
                self.assertEqual(float(r["f_crit_cd"]), float(cd[k]["f_crit"]))
                self.assertEqual(float(r["f_crit_lp"]), float(lp[k]["f_crit"]))
                self.assertEqual(float(r["f_cont"]), float(cd[k]["f_cont"]))
                self.assertClose(float(r["ratio"]),
                                 float(cd[k]["f_crit"]) / float(lp[k]["f_crit"]), k)
                self.assertEqual(int(r["exact"]), int(float(cd[k]["residual"]) <= 1e-6))

    def test_2_means_and_counts_are_recomputed(self):
        self.assertEqual(len(R["compare"]), 2)
        for row, name in zip(R["compare"], PACKINGS):
            e = expected(R["cd"][name], R["lp"][name])
            cd = probes(R["cd"][name])
            for key in ("probes", "solved", "exact"):
                self.assertEqual(int(row[key]), e[key], (name, key))
            # Every probe of the fixtures is exact: unjam's own verdict agrees.
            self.assertEqual(int(row["exact"]), sum(r["converged"] == "1" for r in cd.values()))
            self.assertEqual(int(row["probes"]), 12)
            for key, value in e.items():
                self.assertClose(float(row[key]), float(value), (name, key))
            with open(os.path.join(R["cd"][name], "probe_summary.json")) as f:
                s_cd = json.load(f)
            with open(os.path.join(R["lp"][name], "probe_summary.json")) as f:
                s_lp = json.load(f)
            # All 12 probes solved: the cd mean is unjam's own <F_crit>/<F_cont>.
            self.assertAlmostEqual(float(row["F_crit_over_F_cont_cd"]),
                                   s_cd["F_crit_over_F_cont"], delta=1e-9)
            self.assertAlmostEqual(float(row["F_crit_over_F_cont_lp"]),
                                   s_lp["F_crit_over_F_cont"], delta=1e-9)
            # Every probe exact: the means over all, solved and exact probes are one.
            for key in ("F_crit_over_F_cont_lp_all", "F_crit_over_F_cont_lp_exact"):
                self.assertClose(float(row[key]), float(row["F_crit_over_F_cont_lp"]), key)
            self.assertClose(float(row["F_crit_over_F_cont_cd_exact"]),
                             float(row["F_crit_over_F_cont_cd"]))
            self.assertEqual(float(row["alpha_cd"]), s_cd["alpha"])
            self.assertEqual(float(row["alpha_lp_err"]), s_lp["alpha_err"])
            self.assertClose(float(row["cpu_s_per_probe_cd"]),
                             s_cd["cpu_per_probe"]["total_seconds"] / s_cd["cpu_per_probe"]["probes"])
            self.assertEqual(float(row["mu"]), s_cd["mu"])
            self.assertEqual((int(row["N"]), int(row["seed"])), (s_cd["N"], s_cd["seed"]))

    def test_3_figure_markdown_and_record(self):
        for name in ("ratio-distribution.png", "friction.png"):
            png = os.path.join(R["out"], name)
            self.assertGreater(os.path.getsize(png), 1000)
            with open(png, "rb") as f:
                self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")
        with open(os.path.join(R["out"], "compare.md")) as f:
            md = f.read()
        self.assertIn("scripts/compare_probes.py", md.splitlines()[0])
        version = summary(R["cd"]["p50-mu1"])["program_version"]  # the campaigns' own
        self.assertIn(version, md.splitlines()[0])
        # One row per pair in each of the two tables.
        self.assertEqual(sum(line.startswith("| mu = ") for line in md.splitlines()), 4)
        self.assertIn("| pair | lp, every probe | lp, solved | lp, exact | cd, solved | cd, exact |", md)
        with open(os.path.join(R["out"], "compare.json")) as f:
            record = json.load(f)
        self.assertIn("compare_probes.py", record["command"])
        for entry, row in zip(record["pairs"], R["compare"]):
            self.assertEqual(entry["ratio_median"], float(row["ratio_median"]))
            self.assertEqual(entry["cd"]["program_version"], version)
        self.assertEqual(len(R["run"].stdout.splitlines()), 3 + 6)  # table, then 6 paths
        self.assertEqual(R["run"].stderr, "")
        # No temporary file is left behind.
        self.assertEqual(sorted(os.listdir(R["out"])),
                         ["compare.csv", "compare.json", "compare.md", "friction.png",
                          "ratio-distribution.png", "ratios.csv"])

    def test_4_unsolved_and_inexact_probes(self):
        # One probe without a solution and one solved but not exact (made by editing a copy).
        cd_src = R["cd"]["p50-mu1"]
        contacts = sorted(probes(cd_src))
        k_none, k_inexact = contacts[2], contacts[5]

        def edit(rows):
            for r in rows:
                if int(r["contact"]) == k_none:
                    r["residual"], r["converged"] = NO_SOLUTION, "0"
                elif int(r["contact"]) == k_inexact:
                    r["residual"], r["converged"] = "1e-05", "0"
        cd = copy_campaign(cd_src, "cd-unsolved", edit)
        out = os.path.join(R["tmp"], "compare-unsolved")
        p = run(cd, R["lp"]["p50-mu1"], "--out", out, "--label", "edited")
        self.assertEqual(p.returncode, 0, p.stderr)
        row = read_rows(os.path.join(out, "compare.csv"))[0]
        e = expected(cd, R["lp"]["p50-mu1"])
        self.assertEqual((int(row["probes"]), int(row["solved"]), int(row["exact"])), (12, 11, 10))
        self.assertEqual(row["label"], "edited")
        for key, value in e.items():
            self.assertClose(float(row[key]), float(value), key)
        # The three selections differ: 12 probes, 11 solved, 10 exact.
        lp_means = {row[k] for k in ("F_crit_over_F_cont_lp_all", "F_crit_over_F_cont_lp",
                                     "F_crit_over_F_cont_lp_exact")}
        self.assertEqual(len(lp_means), 3)
        self.assertNotEqual(row["F_crit_over_F_cont_cd_exact"], row["F_crit_over_F_cont_cd"])
        with open(os.path.join(out, "compare.md")) as f:
            self.assertIn(f"| edited | {float(row['F_crit_over_F_cont_lp_all']):.3f} | ", f.read())
        ratios = {int(r["contact"]): r for r in read_rows(os.path.join(out, "ratios.csv"))}
        self.assertEqual(ratios[k_none]["ratio"], "")
        self.assertEqual(ratios[k_none]["solved"], "0")
        self.assertNotEqual(ratios[k_inexact]["ratio"], "")
        self.assertEqual((ratios[k_inexact]["exact"], ratios[k_inexact]["solved"]), ("0", "1"))

    def test_5_contact_missing_from_lp_is_skipped(self):
        lp_src = R["lp"]["p50-mu1"]
        k = sorted(probes(lp_src))[3]
        lp = copy_campaign(lp_src, "lp-missing",
                           lambda rows: rows.remove(next(r for r in rows if int(r["contact"]) == k)))
        out = os.path.join(R["tmp"], "compare-missing")
        p = run(R["cd"]["p50-mu1"], lp, "--out", out)
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertIn("warning: ", p.stderr)
        self.assertIn(f"1 contact probed only by cd ({R['cd']['p50-mu1']}) ignored: {k}", p.stderr)
        row = read_rows(os.path.join(out, "compare.csv"))[0]
        self.assertEqual(int(row["probes"]), 11)
        contacts = [int(r["contact"]) for r in read_rows(os.path.join(out, "ratios.csv"))]
        self.assertNotIn(k, contacts)
        self.assertEqual(len(contacts), 11)
        e = expected(R["cd"]["p50-mu1"], lp)
        self.assertClose(float(row["F_crit_over_F_cont_lp"]), e["F_crit_over_F_cont_lp"])

    def test_6_zero_fn_max_has_no_ratio(self):
        lp_src = R["lp"]["p50-mu0.1"]
        k = sorted(probes(lp_src))[0]

        def edit(rows):
            for r in rows:
                if int(r["contact"]) == k:
                    r["f_crit"] = "0"
        lp = copy_campaign(lp_src, "lp-zero", edit)
        out = os.path.join(R["tmp"], "compare-zero")
        p = run(R["cd"]["p50-mu0.1"], lp, "--out", out)
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertIn("fn_max <= 0 left out of the ratios", p.stderr)
        ratios = {int(r["contact"]): r for r in read_rows(os.path.join(out, "ratios.csv"))}
        self.assertEqual(ratios[k]["ratio"], "")
        row = read_rows(os.path.join(out, "compare.csv"))[0]
        e = expected(R["cd"]["p50-mu0.1"], lp)
        self.assertClose(float(row["ratio_median"]), e["ratio_median"])

    def test_8_probes_above_the_campaigns_max_inertia_stay_out_of_the_means(self):
        # The campaign's --max-inertia (settings.max_inertia_F0) drawn between the probes'
        # f_inertia: those above it leave the means and ratios, and are counted.
        cd_src = R["cd"]["p50-mu1"]
        fi = inertia_F0(cd_src)
        values = sorted(fi.values())
        self.assertTrue(all(math.isfinite(v) and v > 0 for v in values), values)
        line = 0.5 * (values[7] + values[8])  # 4 of the 12 above it
        cd = copy_campaign(cd_src, "cd-inertial",
                           edit_summary=lambda s: s["settings"].update(max_inertia_F0=line))
        out = os.path.join(R["tmp"], "compare-inertial")
        p = run(cd, R["lp"]["p50-mu1"], "--out", out)
        self.assertEqual(p.returncode, 0, p.stderr)
        row = read_rows(os.path.join(out, "compare.csv"))[0]
        e = expected(cd, R["lp"]["p50-mu1"])
        self.assertEqual((int(row["probes"]), int(row["solved"]), int(row["inertial"])), (12, 12, 4))
        for key in ("F_crit_over_F_cont_cd", "F_crit_over_F_cont_lp", "ratio_median", "ratio_max"):
            self.assertClose(float(row[key]), e[key], key)
        # Not the means over all 12: the line changed them.
        full = read_rows(os.path.join(R["out"], "compare.csv"))[0]
        self.assertNotEqual(row["F_crit_over_F_cont_cd"], full["F_crit_over_F_cont_cd"])
        self.assertClose(float(row["f_inertia_median_F0"]), statistics.median(values))
        self.assertClose(float(row["f_inertia_max_F0"]), values[-1])
        self.assertEqual(int(row["f_inertia_max_contact"]), max(fi, key=fi.get))
        ratios = {int(r["contact"]): r for r in read_rows(os.path.join(out, "ratios.csv"))}
        for k, v in fi.items():
            self.assertEqual(ratios[k]["inertial"], str(int(v > line)), k)
            self.assertClose(float(ratios[k]["f_inertia_cd"]), v, k)
        with open(os.path.join(out, "compare.md")) as f:
            self.assertIn("| 12 (4 inertial) |", f.read())
        # Without the line nobody is left out, and the f_inertia columns are the same.
        self.assertEqual(int(full["inertial"]), 0)
        self.assertEqual(full["f_inertia_max_F0"], row["f_inertia_max_F0"])

    def test_9_campaigns_without_the_f_inertia_column(self):
        # probes.csv of an unjam before f_inertia: the comparison still runs, the inertia
        # columns are empty and no probe is left out, even under a max_inertia_F0.
        def drop(rows):
            for r in rows:
                del r["f_inertia"]
        cd_src = R["cd"]["p50-mu0.1"]
        path = copy_campaign(cd_src, "cd-old", edit_summary=lambda s: s["settings"].update(
            max_inertia_F0=1e-30))
        edit_csv(os.path.join(path, "probes.csv"), drop)
        out = os.path.join(R["tmp"], "compare-old")
        p = run(path, R["lp"]["p50-mu0.1"], "--out", out)
        self.assertEqual(p.returncode, 0, p.stderr)
        row = read_rows(os.path.join(out, "compare.csv"))[0]
        self.assertEqual((row["inertial"], row["f_inertia_median_F0"], row["f_inertia_max_F0"],
                          row["f_inertia_max_contact"]), ("0", "", "", ""))
        full = read_rows(os.path.join(R["out"], "compare.csv"))[1]
        self.assertEqual(row["F_crit_over_F_cont_cd"], full["F_crit_over_F_cont_cd"])

    def test_10_a_partial_campaign_is_named(self):
        # Outputs of `unjam probe --partial` (probe_summary.json's `partial`): compared as any
        # campaign, with a warning and a note in compare.md.
        cd = copy_campaign(R["cd"]["p50-mu1"], "cd-partial", edit_summary=lambda s: s.update(
            partial={"probes_done": 12, "probes_planned": 40}))
        out = os.path.join(R["tmp"], "compare-partial")
        p = run(cd, R["lp"]["p50-mu1"], "--out", out)
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertIn(f"{cd}: a partial campaign (12 of 40 probes", p.stderr)
        with open(os.path.join(out, "compare.md")) as f:
            self.assertIn("(partial: 12 of 40 probes of the cd campaign so far)", f.read())
        self.assertEqual(read_rows(os.path.join(out, "compare.csv"))[0]["F_crit_over_F_cont_cd"],
                         R["compare"][0]["F_crit_over_F_cont_cd"])

    def test_11_cpu_per_probe_counts_every_run(self):
        # A resumed campaign: all_runs (every run's busy seconds) gives the CPU column, over the
        # probes whose runs recorded their time; a summary without it falls back to its last
        # run's ranks over all its probes.
        # Each probe's own CPU (cpu_per_probe), where the summary records it, comes first.
        def measured(s):
            s["cpu_per_probe"] = {"probes": 8, "total_seconds": 4.0}
            s["all_runs"] = {"runs": 3, "wall_seconds": 100.0, "busy_seconds": 90.0,
                             "untimed": 2}

        def resumed(s):
            del s["cpu_per_probe"]
            s["all_runs"] = {"runs": 3, "wall_seconds": 100.0, "busy_seconds": 90.0,
                             "untimed": 2}
            s["ranks"] = [{"rank": 0, "threads": 1, "probes": 4, "busy_seconds": 7.0}]

        def older(s):
            del s["cpu_per_probe"]
            del s["all_runs"]
            s["ranks"] = [{"rank": 0, "threads": 1, "probes": 12, "busy_seconds": 6.0}]

        for name, edit, cpu in (("cd-measured", measured, 4.0 / 8), ("cd-resumed", resumed, 90.0 / 10),
                                ("cd-older", older, 6.0 / 12)):
            cd = copy_campaign(R["cd"]["p50-mu1"], name, edit_summary=edit)
            out = os.path.join(R["tmp"], "compare-" + name)
            p = run(cd, R["lp"]["p50-mu1"], "--out", out)
            self.assertEqual(p.returncode, 0, p.stderr)
            self.assertClose(float(read_rows(os.path.join(out, "compare.csv"))[0]["cpu_s_per_probe_cd"]),
                             cpu, name)

    def test_12_a_relative_packing_path_names_the_same_packing(self):
        # A campaign run from the packing's parent directory records `p50-mu1`, another run
        # elsewhere the absolute path: the same packing (its numbers and contacts agree);
        # the results are those of the pair as it was.
        lp = copy_campaign(R["lp"]["p50-mu1"], "lp-relative-path",
                           edit_summary=lambda s: s.update(packing="p50-mu1"))
        out = os.path.join(R["tmp"], "compare-relative")
        p = run(R["cd"]["p50-mu1"], lp, "--out", out)
        self.assertEqual(p.returncode, 0, p.stderr)
        row = read_rows(os.path.join(out, "compare.csv"))[0]
        first = R["compare"][0]  # the pair p50-mu1 of setUpModule
        self.assertTrue(first["packing"].endswith("p50-mu1"), first)
        for key in ("probes", "solved", "F_crit_over_F_cont_cd", "F_crit_over_F_cont_lp", "ratio_median"):
            self.assertEqual(row[key], first[key], key)
        other = copy_campaign(R["lp"]["p50-mu1"], "lp-relative-other",
                              edit_summary=lambda s: s.update(packing="p50-mu0.1"))
        p = run(R["cd"]["p50-mu1"], other, "--out", out)
        self.assertEqual(p.returncode, 1, p.stderr)
        self.assertIn("come from different packings: packing ", p.stderr)

    def test_7_errors_write_nothing(self):
        cd1, lp1 = R["cd"]["p50-mu1"], R["lp"]["p50-mu1"]
        cd01, lp01 = R["cd"]["p50-mu0.1"], R["lp"]["p50-mu0.1"]
        corrupt = copy_campaign(cd1, "cd-corrupt")
        with open(os.path.join(corrupt, "probes.csv"), "a") as f:
            f.write("7,1,2,not-a-number\n")
        no_summary = copy_campaign(cd1, "cd-no-summary")
        os.unlink(os.path.join(no_summary, "probe_summary.json"))
        bad_json = copy_campaign(lp1, "lp-bad-json")
        with open(os.path.join(bad_json, "probe_summary.json"), "w") as f:
            f.write('{"method": "lp", ')
        other_mu = copy_campaign(lp1, "lp-other-mu", edit_summary=lambda s: s.update(mu=0.5))
        bad_line = copy_campaign(cd1, "cd-bad-line", edit_summary=lambda s: s["settings"].update(
            max_inertia_F0=-1))

        def renumber(rows):
            for r in rows:
                r["contact"] = str(int(r["contact"]) + 10000)
        disjoint = copy_campaign(lp1, "lp-disjoint", renumber)
        other_path = copy_campaign(lp1, "lp-other-path",
                                   edit_summary=lambda s: s.update(packing="/elsewhere/p50-mu1"))

        def regrain(rows):
            rows[4]["b"] = str(int(rows[4]["b"]) + 1)
        other_grains = copy_campaign(lp1, "lp-other-grains", regrain)

        def relabel(rows):
            rows[0]["method"] = "lp"
        mixed = copy_campaign(cd1, "cd-mixed", relabel)
        cases = [
            ([cd1, lp1, cd01], "3 directories: expected pairs"),
            ([lp1, cd1], "a campaign of method 'lp', expected 'cd'"),
            ([cd1, cd1], "a campaign of method 'cd', expected 'lp'"),
            ([cd1, lp01], "come from different packings"),
            ([cd1, lp1, cd1, other_mu], "come from different packings: mu 1.0 and 0.5"),
            ([bad_line, lp1], "settings.max_inertia_F0 is not a number >= 0: -1"),
            ([cd1, other_path], "come from different packings: packing "),
            ([cd1, other_grains], "come from different packings: contact "),
            ([mixed, lp1], "rows of method 'lp' in a campaign of method 'cd'"),
            ([cd1, lp1, corrupt, lp1], "probes.csv line 14"),
            ([no_summary, lp1], "probe_summary.json: file not found"),
            ([cd1, bad_json], "probe_summary.json: not valid JSON"),
            ([cd1, disjoint], "no probed contact in common"),
            ([cd1, lp1, os.path.join(R["tmp"], "nowhere"), lp1], "directory not found"),
            ([cd1, lp1, "--label", "a", "b"], "2 labels for 1 pairs"),
        ]
        for args, message in cases:
            out = os.path.join(R["tmp"], "compare-error")
            p = run(*args, "--out", out)
            self.assertEqual(p.returncode, 1, (args, p.stderr))
            self.assertTrue(p.stderr.startswith("compare_probes.py: error: "), p.stderr)
            self.assertIn(message, p.stderr)
            self.assertNotIn("Traceback", p.stderr)
            self.assertFalse(os.path.exists(out), args)
        # A failed run leaves earlier outputs as they were.
        before = contents(R["out"])
        p = run(lp1, cd1, "--out", R["out"])
        self.assertEqual(p.returncode, 1)
        self.assertEqual(contents(R["out"]), before)


class RatioOfMeansError(unittest.TestCase):
    """compare_probes.ratio_of_means_err by hand."""

    @classmethod
    def setUpClass(cls):
        sys.path.insert(0, os.path.join(REPO, "scripts"))
        import compare_probes
        cls.f = staticmethod(compare_probes.ratio_of_means_err)

    def test_with_equal_weights_it_is_the_standard_error_of_the_mean(self):
        # x = 1, 2, 3 over y = 1: R = 2, e = -1, 0, 1, SE = sqrt(2 / 6) = 1 / sqrt(3).
        self.assertAlmostEqual(self.f([1.0, 2.0, 3.0], [1.0, 1.0, 1.0]), 1.0 / math.sqrt(3.0), places=15)

    def test_it_scales_with_x_and_is_zero_for_proportional_samples(self):
        x, y = [1.0, 4.0, 2.5, 0.5], [2.0, 1.0, 3.0, 0.5]
        self.assertAlmostEqual(self.f([3.0 * v for v in x], y), 3.0 * self.f(x, y), places=14)
        self.assertAlmostEqual(self.f([1.7 * v for v in y], y), 0.0, places=15)
        # y = 2, 1, 3, 0.5 (mean 1.625), R = 8 / 6.5: e = x - R y by hand.
        r = 8.0 / 6.5
        e = [1.0 - 2.0 * r, 4.0 - r, 2.5 - 3.0 * r, 0.5 - 0.5 * r]
        self.assertAlmostEqual(self.f(x, y), math.sqrt(sum(v * v for v in e) / 12.0) / 1.625, places=15)

    def test_below_two_samples_or_without_weight_there_is_none(self):
        self.assertTrue(math.isnan(self.f([1.0], [1.0])))
        self.assertTrue(math.isnan(self.f([1.0, 2.0], [0.0, 0.0])))


if __name__ == "__main__":
    unittest.main()


if __name__ == "__main__":
    unittest.main()
