"""Tests of scripts/field_cosines.py (the lp probe's field against the exact probe's).

Run by ctest (field_cosines) with PYTHONPATH=build/<preset>/python and UNJAM set to the tool;
by hand: PYTHONPATH=build/release/python UNJAM=build/release/unjam \
/usr/bin/python3 -m pytest tests/test_field_cosines.py
"""
import csv
import json
import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import unjam

REPO = Path(__file__).resolve().parent.parent
SCRIPT = str(REPO / "scripts" / "field_cosines.py")
UNJAM = os.environ.get("UNJAM", str(REPO / "build" / "release" / "unjam"))
P50 = str(REPO / "tests" / "fixtures" / "p50-mu0.1")


def run(*args, ok=True):
    r = subprocess.run([sys.executable, SCRIPT, *map(str, args)], capture_output=True, text=True,
                       timeout=600)
    if ok:
        assert r.returncode == 0, r.stderr
    return r


def probe_campaign(packing, out, *options):
    """`unjam probe PACKING OPTIONS --threads 1 --out OUT --quiet`: a campaign to probe again."""
    subprocess.run([UNJAM, "probe", str(packing), *map(str, options), "--threads", "1", "--out", str(out),
                    "--quiet"], check=True, capture_output=True)


def rows(out):
    with open(out / "fields.csv", newline="") as f:
        return list(csv.DictReader(f))


def write_rows(out, table):
    """fields.csv of out rewritten with these rows (their own columns)."""
    with open(out / "fields.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(table[0]))
        w.writeheader()
        w.writerows(table)


def test_each_row_is_the_two_probes_and_their_fields_cosine(tmp_path):
    ks = [0, 1, 2, 3, 5, 8]
    run(P50, "--contacts", *ks, "--threads", 1, "--near", 1.5, "--out", tmp_path)
    p = unjam.read_packing(P50)
    lp = unjam.probe(p, contacts=ks, method="lp")
    cd = unjam.probe(p, contacts=ks, method="cd", cd_start="compliant")
    table = rows(tmp_path)
    assert [int(r["contact"]) for r in table] == ks
    for r, a, b in zip(table, lp, cd):
        assert float(r["f_crit_lp"]) == a.f_crit and float(r["f_crit_cd"]) == b.f_crit
        assert r["exact"] == ("1" if b.residual <= 1e-6 else "0")
        u, v = a.u.ravel(), b.u.ravel()
        assert float(r["cosine"]) == pytest.approx(u @ v / np.sqrt((u @ u) * (v @ v)), abs=1e-14)
        assert float(r["norm_ratio"]) == pytest.approx(np.linalg.norm(v) / np.linalg.norm(u), rel=1e-14)
        assert float(r["f_inertia_cd"]) == b.f_inertia and b.f_inertia > 0
        # The near field: grains within 1.5 mean diameters of the pair's midpoint (periodic).
        L = np.asarray(p.cell)[:2]
        xy = np.column_stack([p.x, p.y])
        k = int(r["contact"])
        xa, xb = xy[p.contacts.a[k]], xy[p.contacts.b[k]]
        mid = xa + 0.5 * (xb - xa - L * np.round((xb - xa) / L))
        d = xy - mid
        d -= L * np.round(d / L)
        near = np.linalg.norm(d, axis=1) <= 1.5 * 2 * np.mean(p.radii)
        assert 2 <= near.sum() < p.N
        un, vn = a.u[near].ravel(), b.u[near].ravel()
        assert float(r["cosine_near"]) == pytest.approx(un @ vn / np.sqrt((un @ un) * (vn @ vn)), abs=1e-14)
        # Both fields kept per contact, as the module gives them.
        z = np.load(tmp_path / "fields" / f"{k}.npz")
        assert np.array_equal(z["u_lp"], a.u) and np.array_equal(z["u_cd"], b.u)
        assert np.array_equal(z["rot_lp"], a.rot) and np.array_equal(z["rot_cd"], b.rot)
    # At mu = 0.1 on 50 disks the fields are close but not equal (docs/probe.md: 0.96-0.9995).
    cos = [float(r["cosine"]) for r in table]
    assert min(cos) > 0.9 and min(cos) < 0.999
    s = json.loads((tmp_path / "fields.json").read_text())
    assert s["probes"] == 6 and s["exact"] == sum(r["exact"] == "1" for r in table)
    assert s["cosine"]["median"] == pytest.approx(np.median([float(r["cosine"]) for r in table
                                                              if r["exact"] == "1"]))
    assert s["mu"] == 0.1 and s["N"] == 50 and s["cd_start"] == "compliant"
    assert s["f_inertia_cd"]["max"] == max(float(r["f_inertia_cd"]) for r in table if r["exact"] == "1")
    assert (tmp_path / "cosines.png").stat().st_size > 0 and "| 6 |" in (tmp_path / "fields.md").read_text()
    # Gathered over packings (here one): the same median, N, mu and seed in the table.
    plot = [sys.executable, str(REPO / "scripts" / "plot_field_cosines.py")]
    r = subprocess.run(plot + [str(tmp_path), "--out", str(tmp_path / "all")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    row = [x for x in (tmp_path / "all.md").read_text().splitlines() if x.startswith("| 50 |")]
    assert len(row) == 1 and f"| 0.1 | 3 | 6 | {s['exact']} | {s['cosine']['median']:.3f} (" in row[0]
    assert (tmp_path / "all.png").stat().st_size > 0
    r = subprocess.run(plot + [str(tmp_path / "nowhere"), "--out", str(tmp_path / "x")], capture_output=True, text=True)
    assert r.returncode == 1 and "fields.json" in r.stderr


def test_without_friction_on_an_isostatic_packing_the_fields_are_one(tmp_path):
    # mu = 0, isostatic: removing the probed contact leaves one mechanism, which both probes
    # find (docs/probe.md, "The quasi-static limit"); F_crit agrees up to the step's inertia.
    pk = tmp_path / "p60"
    subprocess.run([UNJAM, "pack", "--n", "60", "--mu", "0", "--seed", "1", "--tol", "1e-6",
                    "--max-sweeps", "2000", "--threads", "1", "--out", str(pk)],
                   check=True, capture_output=True)
    p = unjam.read_packing(pk)
    ks = np.flatnonzero(p.contacts.fn > 1e-9 * p.F0)[::6]
    run(pk, "--contacts", *ks, "--out", tmp_path / "f")
    table = rows(tmp_path / "f")
    assert len(table) == len(ks) and all(r["exact"] == "1" for r in table)
    assert all(float(r["cosine"]) > 1 - 1e-9 for r in table)
    assert all(float(r["f_crit_cd"]) == pytest.approx(float(r["f_crit_lp"]), rel=2e-3) for r in table)


def test_a_second_run_keeps_what_is_done_and_probes_the_rest(tmp_path):
    run(P50, "--contacts", 0, 1, "--out", tmp_path)
    table = rows(tmp_path)
    table[0]["cosine"] = "0.5"  # a marker: the second run must not probe contact 0 again
    write_rows(tmp_path, table)
    r = run(P50, "--contacts", 2, 0, 1, "--out", tmp_path)
    assert "resuming: 2 contacts" in r.stdout
    again = rows(tmp_path)
    assert [x["contact"] for x in again] == ["2", "0", "1"] and again[1]["cosine"] == "0.5"
    # A table written before the f_inertia_cd column resumes too; its rows keep the cell empty.
    write_rows(tmp_path, [{k: v for k, v in x.items() if k != "f_inertia_cd"} for x in again[1:]])
    r = run(P50, "--contacts", 2, 0, 1, "--out", tmp_path)
    assert "resuming: 2 contacts" in r.stdout
    again = rows(tmp_path)
    assert [x["f_inertia_cd"] != "" for x in again] == [True, False, False]
    # Another list or other settings: refused, the table left as it is.
    before = (tmp_path / "fields.csv").read_text()
    r = run(P50, "--contacts", 0, 1, "--out", tmp_path, ok=False)
    assert r.returncode == 1 and "not listed ([2])" in r.stderr
    r = run(P50, "--contacts", 2, 0, 1, "--cd-start", "static", "--out", tmp_path, ok=False)
    assert r.returncode == 1 and "other settings" in r.stderr
    assert (tmp_path / "fields.csv").read_text() == before


def test_ctrl_c_keeps_every_probe_finished_before_it(tmp_path):
    """The cd probes run as one list and each is saved as it ends: a Ctrl-C after the first
    exits 3 with every finished probe in fields.csv, as an uninterrupted probe gives it."""
    p500 = REPO / "tests" / "fixtures" / "p500-mu0.1"
    p = unjam.read_packing(p500)
    ks = [int(k) for k in np.flatnonzero(p.contacts.fn > 1e-9 * p.F0)[:6]]  # ~2-4 s each
    proc = subprocess.Popen([sys.executable, SCRIPT, str(p500), "--contacts", *map(str, ks), "--threads", "2",
                             "--out", str(tmp_path)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert proc.stdout.readline().startswith("probes 1 / 6"), proc.stderr.read()
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 3, err
    table = rows(tmp_path)
    assert 1 <= len(table) < 6 and f"interrupted: {len(table)} of 6 contacts saved" in err
    assert [int(r["contact"]) for r in table] == [k for k in ks if str(k) in {r["contact"] for r in table}]
    again = unjam.probe(p, contacts=[int(r["contact"]) for r in table], method="cd", cd_start="compliant")
    assert [float(r["f_crit_cd"]) for r in table] == [q.f_crit for q in again]
    assert all((tmp_path / "fields" / f"{r['contact']}.npz").is_file() for r in table)


def test_long_probes_show_that_they_are_running(tmp_path):
    """--running-every S: a line per cd probe still running after every S seconds (0: at every
    piece), with its pieces so far; the table as without them."""
    r = run(P50, "--contacts", 0, 1, "--threads", 1, "--running-every", 0, "--out", tmp_path / "a")
    lines = [x for x in r.stdout.splitlines() if "probing for" in x]
    assert lines and {x.split(":")[0].strip() for x in lines} <= {"contact 0", "contact 1"}
    assert all(re.search(r"\(\d+ pieces so far\)$", x) for x in lines)
    run(P50, "--contacts", 0, 1, "--threads", 1, "--out", tmp_path / "b")
    assert rows(tmp_path / "a") == rows(tmp_path / "b")
    assert run(P50, "--contacts", 0, "--running-every", -1, ok=False).returncode == 2


def test_the_contacts_of_a_campaign(tmp_path):
    probe_campaign(P50, tmp_path / "c", "--sample", 5, "--seed", 2)
    with open(tmp_path / "c" / "probes.csv", newline="") as f:
        campaign = [r["contact"] for r in csv.DictReader(f)]
    run(P50, "--from-campaign", tmp_path / "c" / "probes.csv", "--limit", 3, "--out", tmp_path / "f")
    assert [r["contact"] for r in rows(tmp_path / "f")] == campaign[:3]


def test_a_cd_campaigns_own_settings_probe_its_contacts_again(tmp_path):
    # A cd campaign with settings away from the defaults: its contacts are probed again with
    # them, and every F_crit is the campaign's, bit for bit.
    p50 = str(REPO / "tests" / "fixtures" / "p50-mu1")
    c = tmp_path / "c"
    probe_campaign(p50, c, "--sample", 8, "--seed", 2, "--method", "cd", "--cd-start", "compliant",
                   "--cd-compliant-start", "1e-3", "--cd-max-pieces", 5000)
    run(p50, "--from-campaign", c / "probes.csv", "--threads", 1, "--out", tmp_path / "f")
    s = json.loads((tmp_path / "f" / "fields.json").read_text())
    assert s["settings_from_campaign"] and s["cd_start"] == "compliant" and s["dt"] == 0.01
    assert s["cd"]["compliant_start"] == 1e-3 and s["cd"]["max_pieces"] == 5000
    assert s["campaign_check"] == {"compared": 8, "equal": 8, "differ": [], "max_relative_difference": 0.0}
    with open(c / "probes.csv", newline="") as f:
        campaign = {r["contact"]: float(r["f_crit"]) for r in csv.DictReader(f)}
    assert all(float(r["f_crit_cd"]) == campaign[r["contact"]] for r in rows(tmp_path / "f"))
    # The check can fail: at the default first compliance (a record without it) the same
    # probes end on other bits of F_crit, and the script says so.
    summary = json.loads((c / "probe_summary.json").read_text())
    del summary["settings"]["cd_compliant_start"]
    (c / "probe_summary.json").write_text(json.dumps(summary))
    r = run(p50, "--from-campaign", c / "probes.csv", "--threads", 1, "--out", tmp_path / "g")
    s = json.loads((tmp_path / "g" / "fields.json").read_text())
    assert s["cd"]["compliant_start"] == 0.1 and s["campaign_check"]["differ"]
    assert 0 < s["campaign_check"]["max_relative_difference"] < 1e-6
    assert "differs from the campaign's" in r.stderr
    # Its options are the campaign's: given too, they are refused before anything is written.
    r = run(p50, "--from-campaign", c / "probes.csv", "--cd-start", "static", "--g", 1e-8,
            "--out", tmp_path / "h", ok=False)
    assert r.returncode == 1 and "leave out --cd-start, --g" in r.stderr
    assert not (tmp_path / "h").exists()
    # A setting unjam does not know is refused, not silently dropped; so is the record of a
    # campaign on another packing (its contact model).
    summary["settings"]["cd_new_thing"] = 1
    (c / "probe_summary.json").write_text(json.dumps(summary))
    r = run(p50, "--from-campaign", c / "probes.csv", "--out", tmp_path / "h", ok=False)
    assert r.returncode == 1 and "cd_new_thing" in r.stderr
    del summary["settings"]["cd_new_thing"]
    summary["settings"]["touch_gap"] *= 2
    (c / "probe_summary.json").write_text(json.dumps(summary))
    r = run(p50, "--from-campaign", c / "probes.csv", "--out", tmp_path / "h", ok=False)
    assert r.returncode == 1 and "touch_gap" in r.stderr
    assert not (tmp_path / "h").exists()


def test_a_windowed_interior_campaign_is_probed_again_as_it_was(tmp_path):
    # The interior start in a window of 3 mean diameters: the window and the interior start's
    # settings come back from the record, and every F_crit is the campaign's, bit for bit.
    c = tmp_path / "c"
    probe_campaign(P50, c, "--sample", 4, "--seed", 3, "--method", "cd", "--cd-start", "interior", "--window", 3,
                   "--cd-interior-iterations", 60)
    run(P50, "--from-campaign", c / "probes.csv", "--threads", 1, "--out", tmp_path / "f")
    s = json.loads((tmp_path / "f" / "fields.json").read_text())
    assert s["window"] == 3.0 and s["cd_start"] == "interior" and s["cd"]["interior_iterations"] == 60
    assert s["campaign_check"] == {"compared": 4, "equal": 4, "differ": [], "max_relative_difference": 0.0}
    assert json.loads((tmp_path / "f" / "settings.json").read_text())["window"] == 3.0


def test_the_cd_options_without_a_campaign(tmp_path):
    # --contacts with --cd-max-pieces and --cd-compliant-start: the probes of unjam.probe with
    # the same settings, recorded for the resume.
    ks = [2, 6, 45]
    run(P50, "--contacts", *ks, "--cd-max-pieces", 40, "--cd-compliant-start", 1e-3, "--threads", 1,
        "--out", tmp_path)
    p = unjam.read_packing(P50)
    cd = unjam.probe(p, contacts=ks, method="cd", cd=unjam.CdSettings(start="compliant", max_pieces=40,
                                                                       compliant_start=1e-3))
    assert [r["f_crit_cd"] for r in rows(tmp_path)] == [repr(x.f_crit) if x.residual < 1e300 else "" for x in cd]
    settings = json.loads((tmp_path / "settings.json").read_text())
    assert settings["cd"] == {"start": "compliant", "max_pieces": 40, "compliant_start": 1e-3}
    r = run(P50, "--contacts", *ks, "--threads", 1, "--out", tmp_path, ok=False)
    assert r.returncode == 1 and "other settings" in r.stderr
    r = run(P50, "--contacts", 0, "--cd-max-pieces", -1, ok=False)
    assert r.returncode == 2 and "--cd-max-pieces must be >= 0" in r.stderr


def test_bad_input_is_refused(tmp_path):
    r = run(tmp_path, "--contacts", 0, ok=False)
    assert r.returncode == 2 and "not a packing directory" in r.stderr
    r = run(P50, "--contacts", 0, "--limit", 2, ok=False)
    assert r.returncode == 2 and "--from-campaign" in r.stderr
    r = run(P50, "--contacts", 0, 0, ok=False)
    assert r.returncode == 1 and "listed twice" in r.stderr
    r = run(P50, "--contacts", 82, "--out", tmp_path / "o", ok=False)
    assert r.returncode == 1 and "the packing has 82 contacts" in r.stderr
    (tmp_path / "t").mkdir()
    (tmp_path / "t" / "fields.csv").write_text("contact,f_crit\n0,1\n")
    r = run(P50, "--contacts", 0, "--out", tmp_path / "t", ok=False)
    assert r.returncode == 1 and "not this script's table" in r.stderr
    assert (tmp_path / "t" / "fields.csv").read_text() == "contact,f_crit\n0,1\n"
    r = run(P50, "--contacts", 0, "--out", tmp_path / "t" / "fields.csv" / "x", ok=False)
    assert r.returncode == 1 and "cannot create the output directory" in r.stderr and "Traceback" not in r.stderr
