"""The Python module `unjam` against the `unjam` tool: the same seed gives the same bytes,
arrays have the documented shapes, dtypes and units, bad arguments raise, Ctrl-C stops a
long call. Run by ctest (python_module) with PYTHONPATH=build/<preset>/python and UNJAM set
to the tool; by hand: PYTHONPATH=build/release/python UNJAM=build/release/unjam \
/usr/bin/python3 -m pytest tests/test_python_module.py
"""
import copy
import csv
import json
import os
import pickle
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import unjam

UNJAM = os.environ.get("UNJAM", "build/release/unjam")
FIXTURE = str(Path(__file__).parent / "fixtures" / "p50-mu0.1")


def tool(*args, cwd=None):
    """Runs the tool, returns its standard output; fails the test on an error."""
    r = subprocess.run([UNJAM, *map(str, args)], capture_output=True, text=True, cwd=cwd)
    assert r.returncode == 0, r.stderr
    return r.stdout


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def p50():
    return unjam.read_packing(FIXTURE)


def test_pack_equals_tool_bit_for_bit(tmp_path):
    tool("pack", "--n", 40, "--mu", 0.1, "--seed", 5, "--out", tmp_path / "cli", "--quiet")
    p = unjam.pack(n=40, mu=0.1, seed=5)
    assert p.is_static and p.N == 40 and p.seed == 5
    p.write(tmp_path / "py")
    for table in ("particles.csv", "contacts.csv"):
        assert (tmp_path / "cli" / table).read_bytes() == (tmp_path / "py" / table).read_bytes()
    cli_meta = json.loads((tmp_path / "cli" / "meta.json").read_text())
    py_meta = json.loads((tmp_path / "py" / "meta.json").read_text())
    assert py_meta["command"].startswith("python: unjam.pack(n=40")
    for meta in (cli_meta, py_meta):
        meta.pop("command")
    assert cli_meta == py_meta


def test_packing_arrays_are_views_with_documented_shapes(p50):
    text = read_csv(Path(FIXTURE) / "particles.csv")
    N = len(text)
    assert p50.N == N
    assert p50.positions.shape == (N, 2) and p50.positions.dtype == np.float64
    assert p50.radii.shape == (N,) and p50.radii.dtype == np.float64
    assert [float(r["x"]) for r in text] == p50.x.tolist() == p50.positions[:, 0].tolist()
    assert [float(r["radius"]) for r in text] == p50.radii.tolist()
    assert p50.cell.shape == (2,) and p50.cell[0] * p50.cell[1] == pytest.approx(
        np.pi * np.sum(p50.radii**2) / p50.phi)
    # Views: the same memory every time, read-only, alive after the packing's name is dropped.
    address = lambda a: a.__array_interface__["data"][0]
    assert address(p50.x) == address(p50.x) and not p50.x.flags.writeable and not p50.x.flags.owndata
    assert not np.shares_memory(p50.positions, p50.x)  # positions: a copy
    with pytest.raises(ValueError):
        p50.radii[0] = 2.0
    c = p50.contacts
    rows = read_csv(Path(FIXTURE) / "contacts.csv")
    M = len(rows)
    assert c.a.dtype == np.int32 and c.a.shape == (M,) and c.n.shape == (M, 2) and c.l.shape == (M, 2)
    assert [int(r["b"]) for r in rows] == c.b.tolist()
    for name in ("gap", "fn", "ft"):
        assert [float(r[name]) for r in rows] == getattr(c, name).tolist()
    assert [[float(r["lx"]), float(r["ly"])] for r in rows] == c.l.tolist()
    # One array of structs: every column strides over whole contacts, fn follows gap.
    assert not c.fn.flags.writeable and c.fn.strides == c.gap.strides == c.a.strides
    assert c.fn.strides[0] >= 56 and address(c.fn) - address(c.gap) == 8
    fn = unjam.read_packing(FIXTURE).contacts.fn  # the packing object is gone, the view stays
    assert fn.tolist() == c.fn.tolist()


def test_stats_equal_info_json(p50):
    cli = json.loads(tool("info", FIXTURE, "--json"))
    py = unjam.stats(p50)
    assert cli.pop("packing") == FIXTURE and py.pop("packing") == ""
    assert cli == py
    assert py["rattlers"] >= 0 and 3.0 < py["z"] < 5.0


def test_probe_equals_tool_bit_for_bit(tmp_path, p50):
    tool("probe", FIXTURE, "--contact", 3, "--out", tmp_path)
    r = unjam.probe(p50, contact=3)
    rows = read_csv(tmp_path / "probe-3.csv")
    assert r.u.shape == (p50.N, 2) and r.rot.shape == (p50.N,) and r.u.dtype == np.float64
    assert [[float(x["ux"]), float(x["uy"])] for x in rows] == r.u.tolist()
    assert [float(x["rot"]) for x in rows] == r.rot.tolist()
    assert (r.a, r.b) == (p50.contacts.a[3], p50.contacts.b[3]) and r.converged
    # F_crit at full precision: the tool's probes.csv of a sample, the module on its contacts.
    tool("probe", FIXTURE, "--sample", 3, "--out", tmp_path, "--quiet")
    sample = read_csv(tmp_path / "probes.csv")
    ks = np.array([int(x["contact"]) for x in sample] + [3])  # any sequence of ints, numpy too
    results = unjam.probe(p50, contacts=ks, threads=2)
    assert [q.contact for q in results] == ks.tolist()
    assert [float(x["f_crit"]) for x in sample] == [q.f_crit for q in results[:-1]]
    assert [float(x["f_cont"]) for x in sample] == [q.f_cont for q in results[:-1]]
    assert results[-1].u.tolist() == r.u.tolist() and results[-1].f_crit == r.f_crit
    # In parallel, each thread reusing its LP model: the same bytes for any thread count.
    serial = unjam.probe(p50, contacts=ks[::-1], threads=1)[::-1]
    assert [q.f_crit for q in serial] == [q.f_crit for q in results]
    assert all(np.array_equal(q.u, s.u) and np.array_equal(q.rot, s.rot) for q, s in zip(results, serial))


def test_probe_reports_each_finished_probe(p50):
    """progress= gets one dict per finished probe, with its ProbeResult: the same results as
    the returned list, every position once, done counting up to the total."""
    ks = [3, 17, 3, 40, 61, 8, 25]
    for threads in (1, 2):
        seen = []
        results = unjam.probe(p50, contacts=ks, threads=threads, progress=seen.append)
        assert {d["event"] for d in seen} == {"finished"}  # lp probes do not report running
        assert [d["done"] for d in seen] == list(range(1, len(ks) + 1))
        assert {d["total"] for d in seen} == {len(ks)}
        assert sorted(d["index"] for d in seen) == list(range(len(ks)))
        for d in seen:
            assert d["contact"] == ks[d["index"]] == d["result"].contact
            assert d["result"].f_crit == results[d["index"]].f_crit
            assert np.array_equal(d["result"].u, results[d["index"]].u)
            assert d["elapsed_s"] >= 0.0 and d["eta_s"] >= 0.0
        assert seen[-1]["eta_s"] == 0.0
        if threads == 1:  # one thread: in the order of the list
            assert [d["index"] for d in seen] == list(range(len(ks)))
    # One probe (contact=K) is reported too.
    one = []
    r = unjam.probe(p50, contact=5, progress=one.append)
    assert len(one) == 1 and one[0]["result"].f_crit == r.f_crit and one[0]["total"] == 1


def test_each_probe_says_how_much_cpu_it_took(p50):
    # ProbeResult.cpu_seconds: measured on the probe's own thread by unjam.probe, whatever the
    # thread count; a measurement, so it is not compared between runs, only checked to exist.
    for threads in (1, 2):
        results = unjam.probe(p50, contacts=[0, 3, 5], method="cd", threads=threads)
        assert all(r.cpu_seconds >= 0.0 for r in results)
        assert sum(r.cpu_seconds for r in results) > 0.0


def test_a_long_probe_reports_that_it_is_running(p50):
    """running_every=0: a 'running' event at every poll of an nlgs probe (one per 16 sweeps),
    with its contact and its polls so far, then its 'finished' event."""
    seen = []
    r = unjam.probe(p50, contact=3, method="nlgs", velocity_tol=1e-14, max_sweeps=3200, running_every=0.0,
                    progress=seen.append)
    running = [d for d in seen if d["event"] == "running"]
    assert seen[-1]["event"] == "finished" and seen[-1]["result"].sweeps == r.sweeps == 3200
    assert len(running) >= 100 and {d["contact"] for d in running} == {3}
    assert [d["polls"] for d in running] == sorted(d["polls"] for d in running) and running[-1]["polls"] >= 100
    assert all(d["done"] == 0 and d["total"] == 1 and d["seconds"] >= 0.0 for d in running)
    quiet = []  # the default interval (300 s, as --running-every): none for this short probe
    unjam.probe(p50, contact=3, method="nlgs", velocity_tol=1e-14, max_sweeps=3200, progress=quiet.append)
    assert [d["event"] for d in quiet] == ["finished"]
    with pytest.raises(unjam.Error, match="running_every"):
        unjam.probe(p50, contact=3, running_every=-1.0, progress=print)


def test_an_exception_of_the_probe_progress_stops_the_probes():
    """The callback's exception is raised, and no probe is reported after it."""
    p = unjam.read_packing(FIXTURE)
    calls = []

    def stop_at_third(d):
        calls.append(d["done"])
        assert d["event"] == "finished"
        if len(calls) == 3:
            raise RuntimeError("enough")

    with pytest.raises(RuntimeError, match="enough"):
        unjam.probe(p, contacts=list(range(82)) * 20, threads=2, progress=stop_at_third)
    assert calls == [1, 2, 3]
    with pytest.raises(TypeError):
        unjam.probe(p, contact=3, progress=42)


def test_bounds_equal_tool_bit_for_bit(tmp_path, p50):
    tool("bounds", FIXTURE, "--threads", 1, "--out", tmp_path / "bounds.csv")
    b = unjam.bounds(p50, threads=1)
    rows = read_csv(tmp_path / "bounds.csv")
    for name in ("fn", "fn_min", "fn_max"):
        assert [float(x[name]) for x in rows] == b[name].tolist()
    assert [int(x["a"]) for x in rows] == b["a"].tolist()
    assert b["contact"].dtype == np.int32
    assert np.all(p50.contacts.a[b["contact"]] == b["a"])
    j = json.loads((tmp_path / "bounds.json").read_text())
    for key in ("dimension", "min_lps_skipped", "iterations", "lps_at_looser_tolerance",
                "lps_finished_by_simplex", "lps_solved_unscaled"):
        assert b[key] == j[key], key
    assert b["iterations"] > 0
    assert np.all(b["fn_min"] <= b["fn"] + 1e-9) and np.all(b["fn"] <= b["fn_max"] + 1e-9)


def test_bounds_lp_tolerances_as_the_tools_and_checked(tmp_path, p50):
    """lp_tol and open_tol are --lp-tol and --open-tol: the same intervals to the bit, recorded
    in bounds.json and in the result; values outside their ranges raise unjam.Error before any
    LP. A wider open tolerance only turns small minima into 0."""
    tool("bounds", FIXTURE, "--threads", 1, "--lp-tol", "1e-8", "--open-tol", "1e-4",
         "--out", tmp_path / "bounds.csv")
    b = unjam.bounds(p50, threads=1, lp_tol=1e-8, open_tol=1e-4)
    rows = read_csv(tmp_path / "bounds.csv")
    for name in ("fn_min", "fn_max"):
        assert [float(x[name]) for x in rows] == b[name].tolist()
    params = json.loads((tmp_path / "bounds.json").read_text())["parameters"]
    assert params["lp_tolerance"] == b["lp_tolerance"] == 1e-8
    assert params["open_tol_F0"] == b["open_tol_F0"] == 1e-4
    # Two shards of a job array with the same tolerances merge to the same intervals and record.
    for i in (0, 1):
        tool("bounds", FIXTURE, "--threads", 1, "--lp-tol", "1e-8", "--open-tol", "1e-4", "--shard", f"{i}/2",
             "--out", tmp_path / "shards" / "bounds.csv")
    tool("merge", FIXTURE, "--out", tmp_path / "shards")
    assert read_csv(tmp_path / "shards" / "bounds.csv") == rows
    merged = json.loads((tmp_path / "shards" / "bounds.json").read_text())["parameters"]
    assert (merged["lp_tolerance"], merged["open_tol_F0"]) == (1e-8, 1e-4)
    default = unjam.bounds(p50, threads=1)
    assert default["lp_tolerance"] == 1e-9 and default["open_tol_F0"] == 1e-9
    F0 = p50.F0
    assert np.all((b["fn_min"] == 0) | (b["fn_min"] > 1e-4 * F0))
    assert np.all(b["fn_min"] <= default["fn_min"] + 1e-7 * F0)
    for bad, why in ((dict(lp_tol=1e-3), "LP tolerance must be in"), (dict(lp_tol=0.0), "LP tolerance"),
                     (dict(open_tol=float("nan")), "open tolerance must be in"), (dict(open_tol=0.5), "open tolerance")):
        with pytest.raises(unjam.Error, match=why):
            unjam.bounds(p50, **bad)


def test_friction_threshold_equals_tool(tmp_path, p50):
    """unjam.friction_threshold gives `unjam threshold`'s bracket, to the bit, and from a
    bracket the same end; a bracket whose ends are not as stated raises unjam.Error."""
    tool("threshold", FIXTURE, "--quiet", "--out", tmp_path / "t.json")
    j = json.loads((tmp_path / "t.json").read_text())
    t = unjam.friction_threshold(p50)
    keys = ["mu_s_low", "mu_s_high", "lps", "simplex_iterations"]
    assert [t[k] for k in keys] == [j[k] for k in keys]
    assert t["mu"] == 0.1 and t["contacts"] == j["contacts_used"]
    assert 0.048 < t["mu_s_low"] < t["mu_s_high"] <= t["mu_s_low"] + 1e-4 + 1e-15
    u = unjam.friction_threshold(p50, between=(0.025, 0.05))
    assert (u["mu_s_low"], u["mu_s_high"]) == (t["mu_s_low"], t["mu_s_high"])
    with pytest.raises(unjam.Error, match="not empty at mu_low"):
        unjam.friction_threshold(p50, between=(0.049, 0.1))


def test_friction_threshold_resumes_the_tools_checkpoint(tmp_path, p50):
    """checkpoint= resumes the bracket a stopped `unjam threshold` kept, to the bracket and the
    LP count of one uninterrupted run, and removes the file; a checkpoint of other settings, or
    one beside between=, is refused and kept; a checkpoint file that is not there is only
    written while the run goes on."""
    whole = unjam.friction_threshold(p50)
    assert whole["runs"] == 1 and whole["resumed_from"] is None
    out = tmp_path / "t.json"
    stopped = subprocess.run([str(UNJAM), "threshold", str(FIXTURE), "--quiet", "--stop-after", "5",
                              "--out", str(out)], capture_output=True, text=True)
    assert stopped.returncode == 3, stopped.stderr
    checkpoint = tmp_path / "t_checkpoint.json"
    saved = checkpoint.read_text()
    kept = json.loads(saved)
    with pytest.raises(unjam.Error, match="rel_tol: 0.001 there, 0.002 here"):
        unjam.friction_threshold(p50, rel_tol=2e-3, checkpoint=checkpoint)
    with pytest.raises(unjam.Error, match="holds the bracket of a stopped run"):
        unjam.friction_threshold(p50, between=(0.025, 0.05), checkpoint=checkpoint)
    assert checkpoint.read_text() == saved
    t = unjam.friction_threshold(p50, checkpoint=checkpoint)
    assert not checkpoint.exists()
    assert (t["mu_s_low"], t["mu_s_high"]) == (whole["mu_s_low"], whole["mu_s_high"])
    assert t["lps"] == whole["lps"] and t["runs"] == 2
    assert t["resumed_from"] == (kept["mu_low"], kept["mu_high"])
    fresh = tmp_path / "fresh_checkpoint.json"
    u = unjam.friction_threshold(p50, checkpoint=fresh)
    assert not fresh.exists()
    assert (u["mu_s_low"], u["mu_s_high"], u["lps"], u["runs"]) == (
        whole["mu_s_low"], whole["mu_s_high"], whole["lps"], 1)


def test_friction_threshold_reports_its_progress_and_a_callbacks_exception_stops_it(tmp_path, p50):
    """progress= gets a dict after every LP with the bracket so far, narrowing to the result's;
    an exception it raises stops the bisection as Ctrl-C does: raised, the bracket kept in the
    checkpoint, from which the next call ends on the bracket of one uninterrupted run."""
    seen = []
    whole = unjam.friction_threshold(p50, progress=seen.append)
    assert [d["done"] for d in seen] == list(range(1, whole["lps"] + 1))
    assert seen[-1]["done"] == seen[-1]["total"] and seen[-1]["eta_s"] == 0.0
    assert (seen[-1]["mu_s_low"], seen[-1]["mu_s_high"]) == (whole["mu_s_low"], whole["mu_s_high"])
    widths = [d["mu_s_high"] - d["mu_s_low"] for d in seen]
    assert all(b <= a for a, b in zip(widths, widths[1:]))
    assert all(d["elapsed_s"] >= 0.0 and d["eta_s"] >= 0.0 for d in seen)

    def stop(d):
        if d["done"] == 4:
            raise RuntimeError("stop at 4")

    checkpoint = tmp_path / "checkpoint.json"
    with pytest.raises(RuntimeError, match="stop at 4"):
        unjam.friction_threshold(p50, checkpoint=checkpoint, progress=stop)
    assert json.loads(checkpoint.read_text())["lps"] == 4
    t = unjam.friction_threshold(p50, checkpoint=checkpoint)
    assert (t["mu_s_low"], t["mu_s_high"], t["lps"], t["runs"]) == (
        whole["mu_s_low"], whole["mu_s_high"], whole["lps"], 2)


def test_bounds_report_their_progress_and_a_callbacks_exception_stops_them(tmp_path, p50):
    """progress= gets a dict at the first LP, every 2 s and at the end (done = total = 2 N_c);
    an exception it raises stops the LPs as Ctrl-C does: raised, the checkpoint saved, and
    the resumed run gives the intervals of one uninterrupted run."""
    seen = []
    whole = unjam.bounds(p50, threads=2, progress=seen.append)
    total = 2 * len(whole["contact"])
    assert seen[0]["done"] >= 1 and seen[-1]["done"] == seen[-1]["total"] == total
    assert [d["done"] for d in seen] == sorted({d["done"] for d in seen})  # rising, each once
    assert all(d["elapsed_s"] >= 0.0 and d["eta_s"] >= 0.0 for d in seen) and seen[-1]["eta_s"] == 0.0

    def stop(d):
        raise RuntimeError(f"stop at {d['done']}")

    checkpoint = tmp_path / "checkpoint.json"
    with pytest.raises(RuntimeError, match="stop at"):
        unjam.bounds(p50, threads=2, checkpoint=checkpoint, progress=stop)
    saved = json.loads(checkpoint.read_text())
    assert 0 < sum(x is not None for x in saved["fn_min"] + saved["fn_max"]) < total
    resumed = unjam.bounds(p50, threads=1, checkpoint=checkpoint)
    assert not checkpoint.exists()
    for name in ("fn_min", "fn_max"):
        assert resumed[name].tolist() == whole[name].tolist()


def test_bounds_resume_a_stopped_runs_checkpoint_bit_for_bit(tmp_path, p50):
    """The checkpoint of `unjam bounds --stop-after` (its packing unnamed, as the module names
    it) resumed by unjam.bounds(checkpoint=...): the intervals of one uninterrupted run, the
    file removed at the end; a checkpoint of other settings is refused and kept."""
    tool("bounds", FIXTURE, "--threads", 1, "--out", tmp_path / "whole" / "bounds.csv")
    whole = read_csv(tmp_path / "whole" / "bounds.csv")
    r = subprocess.run([UNJAM, "bounds", FIXTURE, "--threads", "1", "--stop-after", "30", "--out",
                        str(tmp_path / "stopped" / "bounds.csv")], capture_output=True, text=True)
    assert r.returncode == 3, r.stderr
    saved = json.loads((tmp_path / "stopped" / "bounds_checkpoint.json").read_text())
    known = sum(x is not None for x in saved["fn_min"] + saved["fn_max"])
    assert 30 <= known < 2 * len(whole)
    saved["settings"]["packing"] = ""
    checkpoint = tmp_path / "checkpoint.json"
    checkpoint.write_text(json.dumps(saved))
    with pytest.raises(unjam.Error, match=r"fn_tol: 1e-09 there, 1e-08 here"):
        unjam.bounds(p50, fn_tol=1e-8, checkpoint=checkpoint)
    with pytest.raises(unjam.Error, match="method"):
        unjam.bounds(p50, method="simplex", checkpoint=checkpoint)
    with pytest.raises(unjam.Error, match=r"lp_tolerance: none there, 1e-08 here"):
        unjam.bounds(p50, lp_tol=1e-8, checkpoint=checkpoint)
    assert json.loads(checkpoint.read_text()) == saved
    b = unjam.bounds(p50, threads=2, checkpoint=checkpoint)
    for name in ("fn_min", "fn_max"):
        assert [float(x[name]) for x in whole] == b[name].tolist()
    for i, (lo, hi) in enumerate(zip(saved["fn_min"], saved["fn_max"])):
        assert lo in (None, b["fn_min"][i]) and hi in (None, b["fn_max"][i])
    assert not checkpoint.exists()
    # A checkpoint file that is not there yet: a run from scratch, nothing left behind.
    b = unjam.bounds(p50, threads=1, checkpoint=checkpoint)
    assert [float(x["fn_max"]) for x in whole] == b["fn_max"].tolist() and not checkpoint.exists()


def test_places_that_cannot_be_written_are_refused_before_the_work(tmp_path, p50):
    """A bounds checkpoint that cannot be written is refused at once, not at its first save; a
    packing directory that pack and relax cannot write, before the compaction."""
    (tmp_path / "a-file").write_text("kept")
    with pytest.raises(unjam.Error, match="cannot create directory"):
        unjam.bounds(p50, checkpoint=tmp_path / "a-file" / "checkpoint.json")
    steps = []
    def compaction_started(progress):  # called every 2 s of the compaction; stops it
        steps.append(progress["step"])
        raise KeyboardInterrupt
    with pytest.raises(unjam.Error, match="cannot create directory"):
        unjam.pack(n=8000, seed=1, out=tmp_path / "a-file" / "p", progress=compaction_started)
    assert steps == [], "refused only after the compaction had begun"
    with pytest.raises(unjam.Error, match="cannot create directory"):
        unjam.relax(p50, mu=0.5, out=tmp_path / "a-file" / "p")
    assert (tmp_path / "a-file").read_text() == "kept"


def help_defaults(command):
    """{option: default} from `unjam COMMAND --help` (CLI11 prints "--n INT=500", and with a
    check of the value "--threads INT:NUMBER >= 0=0")."""
    out = tool(command, "--help")
    return {m[1]: m[2] for m in re.finditer(r"--([\w-]+) \w+(?::[^\n]*?)?=(\S+)(?=\s|$)", out)}


def signature_defaults(function):
    """{argument: default} from a pybind11 function's first docstring line."""
    line = function.__doc__.splitlines()[0]
    return {m[1]: m[2] for m in re.finditer(r"(\w+): [\w.\[\], |]+? = ([^,)]+)", line)}


@pytest.mark.parametrize("command,function,names", [
    ("pack", unjam.pack, {"n": "n", "mu": "mu", "seed": "seed", "threads": "threads",
                          "p-ext": "p_ext", "phi-gas": "phi_gas", "dt": "dt", "m-lambda": "m_lambda",
                          "tol": "tol", "max-sweeps": "max_sweeps", "static-tol": "static_tol",
                          "max-steps": "max_steps"}),
    ("probe", unjam.probe, {"method": "method", "g": "g", "velocity-tol": "velocity_tol",
                            "max-sweeps": "max_sweeps", "cd-start": "cd_start",
                            "cd-softer-starts": "cd_softer_starts", "cd-max-pieces": "cd_max_pieces",
                            "cd-interior-states-pieces": "cd_interior_states_pieces",
                            "cd-interior-states-stall": "cd_interior_states_stall",
                            "cd-interior-states-retries": "cd_interior_states_retries",
                            "cd-interior-iterations": "cd_interior_iterations",
                            "cd-interior-neighbourhood": "cd_interior_neighbourhood",
                            "cd-compliant-start": "cd_compliant_start",
                            "cd-accept-residual": "cd_accept_residual"}),
    ("bounds", unjam.bounds, {"gap-tol": "gap_tol", "fn-tol": "fn_tol", "threads": "threads",
                              "method": "method"}),
])
def test_defaults_equal_the_tool(command, function, names):
    cli, py = help_defaults(command), signature_defaults(function)
    for option, argument in names.items():
        a, b = cli[option], py[argument].strip("'")
        assert a == b or float(a) == float(b), (option, a, b)


def test_the_exact_probe_defaults_to_the_quasi_static_time_step(p50):
    # dt=None: the method's default, as `unjam probe` without --dt (lemke, cd: sqrt(g / 1e-5),
    # 1e-2 at g = 1e-9; docs/probe.md, "The quasi-static limit").
    default = unjam.probe(p50, contact=0, method="cd")
    assert default.f_crit == unjam.probe(p50, contact=0, method="cd", dt=1e-2).f_crit
    assert default.f_crit != unjam.probe(p50, contact=0, method="cd", dt=1e-3).f_crit
    assert (unjam.probe(p50, contact=0, method="cd", g=1e-7).f_crit
            == pytest.approx(unjam.probe(p50, contact=0, method="cd", g=1e-7, dt=0.1).f_crit))
    # The inertia of the step: the largest net force on a grain, m |u| / dt^2 (m = pi R^2),
    # from the result's own field; the tool's probes.csv holds the same number. lp: NaN.
    m = np.pi * p50.radii ** 2
    assert default.f_inertia == pytest.approx(np.max(m * np.hypot(default.u[:, 0], default.u[:, 1])) / 1e-4,
                                              rel=1e-12)
    assert np.isnan(unjam.probe(p50, contact=0).f_inertia)


def test_probes_csv_records_the_inertia_the_module_returns(tmp_path, p50):
    tool("probe", FIXTURE, "--sample", 3, "--method", "cd", "--threads", 1, "--out", tmp_path, "--quiet")
    rows = read_csv(tmp_path / "probes.csv")
    results = unjam.probe(p50, contacts=[int(x["contact"]) for x in rows], method="cd")
    assert [float(x["f_inertia"]) for x in rows] == [q.f_inertia for q in results]


def test_the_exact_probe_takes_its_start_as_the_tool(tmp_path):
    # cd_start as `unjam probe --cd-start`: the same field and F_crit, bit for bit. On contact 14
    # of p200-mu1 the compliant continuation is exact (docs/probe.md, "Where the path starts")
    # and the static network's path ends elsewhere (F_crit 2.36 against 2.01 F0, residual
    # 1.4e-6 g), so the start is not ignored.
    fixture = str(Path(__file__).parent / "fixtures" / "p200-mu1")
    p = unjam.read_packing(fixture)
    tool("probe", fixture, "--contact", 14, "--method", "cd", "--cd-start", "compliant", "--out", tmp_path)
    rows = read_csv(tmp_path / "probe-14.csv")
    compliant = unjam.probe(p, contact=14, method="cd", cd_start="compliant")
    assert [[float(x["ux"]), float(x["uy"])] for x in rows] == compliant.u.tolist()
    table = read_csv(tmp_path / "probe-14-forces.csv")
    forces = {int(x["contact"]): float(x["fn"]) for x in table}
    assert forces[14] == compliant.f_crit and compliant.converged
    # the contacts the step opens and sets sliding, as the tool's table of states counts them
    loaded = [x for x in table if int(x["contact"]) != 14 and float(x["fn0"]) > 1e-6 * p.F0]
    assert compliant.opened == sum(x["state"] == "open" for x in loaded) > 0
    assert compliant.sliding == sum(x["state"] == "slide" for x in loaded) > 0
    assert unjam.probe(p, contact=14, method="lp").opened == -1
    static = unjam.probe(p, contact=14, method="cd")
    assert abs(static.f_crit - compliant.f_crit) > 0.1 * compliant.f_crit
    # the interior-point start, as the tool's (bit for bit) and exact
    tool("probe", fixture, "--contact", 14, "--method", "cd", "--cd-start", "interior", "--out", tmp_path / "ip")
    interior = unjam.probe(p, contact=14, method="cd", cd_start="interior")
    assert interior.converged
    assert [[float(x["ux"]), float(x["uy"])] for x in read_csv(tmp_path / "ip" / "probe-14.csv")] == interior.u.tolist()
    with pytest.raises(unjam.Error, match="must be static, lp, compliant, interior, inertial or interior-inertial"):
        unjam.probe(p, contact=14, method="cd", cd_start="soft")
    with pytest.raises(unjam.Error, match="the cd start 'compliant' applies to the cd method only"):
        unjam.probe(p, contact=14, method="lp", cd_start="compliant")


def test_a_budget_of_pieces_stops_the_exact_probe_as_the_tool_does(p50, tmp_path):
    # cd_max_pieces as `unjam probe --cd-max-pieces` (docs/probe.md, "A budget of pieces per
    # probe"): contact 38 takes 86 pieces; within a budget of 86 it is the same probe, with 70
    # it stops at the 71st piece without a solution; below 0 is refused.
    free = unjam.probe(p50, contact=38, method="cd")
    assert free.converged and free.sweeps == 86
    same = unjam.probe(p50, contact=38, method="cd", cd_max_pieces=86)
    assert same.converged and same.f_crit == free.f_crit and same.sweeps == 86
    cut = unjam.probe(p50, contact=38, method="cd", cd_max_pieces=70)
    assert not cut.converged and cut.sweeps == 71
    with pytest.raises(unjam.Error, match="--cd-max-pieces must be >= 0"):
        unjam.probe(p50, contact=38, method="cd", cd_max_pieces=-1)


def test_the_interior_start_takes_its_settings_as_the_tool(p50, tmp_path):
    # cd_interior_* as `unjam probe --cd-interior-*` (docs/probe.md, "The iterate's own
    # states", "The interior-point method's iterations"): on the sample of seed 4 (contacts 32,
    # 72, 77) each gives the tool's F_crit and pieces, bit for bit, and changes the pieces of
    # contact 32 (68 by default; 284, 38, 48 and 47 pieces with the values below); a value out
    # of range is refused.
    default = unjam.probe(p50, contact=32, method="cd", cd_start="interior")
    assert default.converged and default.sweeps == 68
    for option, argument, value in [("--cd-interior-iterations", "cd_interior_iterations", 3),
                                    ("--cd-interior-states-pieces", "cd_interior_states_pieces", 0),
                                    ("--cd-interior-states-retries", "cd_interior_states_retries", 0),
                                    ("--cd-interior-states-stall", "cd_interior_states_stall", 1)]:
        out = tmp_path / argument
        tool("probe", FIXTURE, "--sample", 3, "--seed", 4, "--method", "cd", "--cd-start", "interior", option, value,
             "--threads", 1, "--out", out, "--quiet")
        rows = read_csv(out / "probes.csv")
        results = unjam.probe(p50, contacts=[int(x["contact"]) for x in rows], method="cd", cd_start="interior",
                              **{argument: value})
        assert [(float(x["f_crit"]), int(x["sweeps"])) for x in rows] == [(r.f_crit, r.sweeps) for r in results]
        assert all(r.converged for r in results), argument
        assert results[0].contact == 32 and results[0].sweeps != default.sweeps, argument
    for argument, value, message in [("cd_interior_iterations", 0, "--cd-interior-iterations must be >= 1"),
                                     ("cd_interior_states_pieces", -0.5, "--cd-interior-states-pieces must be >= 0"),
                                     ("cd_interior_states_pieces", float("nan"), "must be >= 0 and finite"),
                                     ("cd_interior_states_stall", -1, "--cd-interior-states-stall must be >= 0"),
                                     ("cd_interior_states_retries", -1, "--cd-interior-states-retries must be >= 0"),
                                     ("cd_interior_neighbourhood", 1.0, "--cd-interior-neighbourhood must be in")]:
        with pytest.raises(unjam.Error, match=message):
            unjam.probe(p50, contact=32, method="cd", cd_start="interior", **{argument: value})


def test_the_interior_start_takes_its_neighbourhood_as_the_tool(tmp_path):
    # cd_interior_neighbourhood as `unjam probe --cd-interior-neighbourhood`: on contact 48 of
    # p200-mu1 plain Mehrotra stalls (natural residual 0.53) and the second run in the wide
    # neighbourhood starts the path at the step's solution (0 pieces); without it the paths take
    # 118 pieces to the same F_crit (docs/probe.md, "Keeping the iterates centred").
    fixture = str(Path(__file__).parent / "fixtures" / "p200-mu1")
    p = unjam.read_packing(fixture)
    for value, pieces in [(1e-3, 0), (0, 118)]:
        out = tmp_path / str(value)
        tool("probe", fixture, "--contact", 48, "--method", "cd", "--cd-start", "interior",
             "--cd-interior-neighbourhood", value, "--threads", 1, "--out", out, "--quiet")
        rows = read_csv(out / "probe-48.csv")
        r = unjam.probe(p, contact=48, method="cd", cd_start="interior", cd_interior_neighbourhood=value)
        assert r.converged and r.sweeps == pieces, (value, r.sweeps)
        assert [[float(x["ux"]), float(x["uy"])] for x in rows] == r.u.tolist()
        assert abs(r.f_crit / (1.382824 * p.F0) - 1.0) < 1e-6


def test_the_continuation_takes_its_first_compliance_as_the_tool(tmp_path):
    # cd_compliant_start as `unjam probe --cd-compliant-start`: on contact 14 of p200-mu1 (dt =
    # 1e-3) the continuation from 0.1 stops at a fold and its restart is exact in 403 pieces in
    # all; started at 1e-3 its first path is exact in 199 (docs/probe.md, "Where the continuation
    # starts"). Refused for the static start and for a value <= 0.
    fixture = str(Path(__file__).parent / "fixtures" / "p200-mu1")
    p = unjam.read_packing(fixture)
    for value, pieces in [(1e-3, 199), (0.1, 403)]:
        out = tmp_path / str(value)
        tool("probe", fixture, "--contact", 14, "--dt", 1e-3, "--method", "cd", "--cd-start", "compliant",
             "--cd-compliant-start", value, "--threads", 1, "--out", out, "--quiet")
        rows = read_csv(out / "probe-14.csv")
        r = unjam.probe(p, contact=14, method="cd", dt=1e-3, cd_start="compliant", cd_compliant_start=value)
        assert r.converged and r.sweeps == pieces, (value, r.sweeps)
        assert [[float(x["ux"]), float(x["uy"])] for x in rows] == r.u.tolist()
    with pytest.raises(unjam.Error, match="applies to the cd method's compliant and interior starts only"):
        unjam.probe(p, contact=14, method="cd", cd_compliant_start=1e-3)
    with pytest.raises(unjam.Error, match="--cd-compliant-start must be positive"):
        unjam.probe(p, contact=14, method="cd", cd_start="compliant", cd_compliant_start=0.0)


def test_the_exact_probe_accepts_a_near_exact_solution_as_the_tool(tmp_path):
    # cd_accept_residual as `unjam probe --cd-accept-residual`: on contact 8 of p200-mu1 (the
    # quasi-static step, compliant start) the first path ends near-exact at 1.04e-5 g in 200
    # pieces and the restart is exact (279 in all); accepting 1e-4, the probe stops at the first
    # (docs/probe.md, "Accepting a near-exact solution"). Refused outside [1e-6, 1e-3] g.
    fixture = str(Path(__file__).parent / "fixtures" / "p200-mu1")
    p = unjam.read_packing(fixture)
    for value, pieces, converged in [(1e-4, 200, False), (1e-6, 279, True)]:
        out = tmp_path / str(value)
        tool("probe", fixture, "--contact", 8, "--method", "cd", "--cd-start", "compliant",
             "--cd-accept-residual", value, "--threads", 1, "--out", out, "--quiet")
        rows = read_csv(out / "probe-8.csv")
        r = unjam.probe(p, contact=8, method="cd", cd_start="compliant", cd_accept_residual=value)
        assert r.converged == converged and r.sweeps == pieces, (value, r.sweeps)
        assert (r.residual <= value) and (converged or r.residual > 1e-6), r.residual
        assert [[float(x["ux"]), float(x["uy"])] for x in rows] == r.u.tolist()
    with pytest.raises(unjam.Error, match=r"--cd-accept-residual must be in \[1e-06, 0.001\] g"):
        unjam.probe(p, contact=8, method="cd", cd_start="compliant", cd_accept_residual=1e-2)


def test_a_campaigns_settings_are_read_back_from_its_record(tmp_path, p50):
    # unjam.campaign_settings: the settings `unjam probe --sample` recorded, under unjam.probe's
    # argument names; probing a campaign's contact with them gives its row, bit for bit.
    out = tmp_path / "c"
    tool("probe", FIXTURE, "--sample", 3, "--seed", 5, "--method", "cd", "--cd-start", "interior",
         "--cd-max-pieces", 4000, "--cd-interior-neighbourhood", 1e-3, "--window", 4, "--max-inertia", 0.5,
         "--threads", 1, "--out", out, "--quiet")
    d = unjam.campaign_settings(p50, out / "probe_summary.json")
    assert {k: d[k] for k in ("method", "g", "dt", "window", "max_inertia", "sample", "seed", "displacement")} == \
        {"method": "cd", "g": 1e-9, "dt": 0.01, "window": 4.0, "max_inertia": 0.5, "sample": 3, "seed": 5,
         "displacement": "peculiar"}
    assert d["cd"] == unjam.CdSettings(start="interior", max_pieces=4000, interior_neighbourhood=1e-3)
    row = read_csv(out / "probes.csv")[0]
    r = unjam.probe(p50, contact=int(row["contact"]), method=d["method"], g=d["g"], dt=d["dt"], cd=d["cd"],
                    window=d["window"])
    assert r.f_crit == float(row["f_crit"]) and r.sweeps == int(row["sweeps"])
    lp = tmp_path / "lp"
    tool("probe", FIXTURE, "--sample", 2, "--threads", 1, "--out", lp, "--quiet")
    d = unjam.campaign_settings(p50, lp / "probe_summary.json")
    assert (d["method"], d["dt"], d["window"], d["cd"], d["lp_tol"]) == ("lp", None, None, unjam.CdSettings(), 1e-9)
    # The lp probe's LP tolerance: recorded by `--lp-tol`, read back, and the module's probe at it
    # gives the campaign's F_crit and the maxima of unjam.bounds over the same set (the packing's
    # touch gap, 1e-6) at the same tolerance, bit for bit.
    tol = tmp_path / "lp-tol"
    tool("probe", FIXTURE, "--sample", 4, "--lp-tol", 1e-8, "--threads", 1, "--out", tol, "--quiet")
    d = unjam.campaign_settings(p50, tol / "probe_summary.json")
    assert (d["method"], d["lp_tol"]) == ("lp", 1e-8)
    rows = read_csv(tol / "probes.csv")
    results = unjam.probe(p50, contacts=[int(x["contact"]) for x in rows], method=d["method"], lp_tol=d["lp_tol"])
    assert [q.f_crit for q in results] == [float(x["f_crit"]) for x in rows]
    b = unjam.bounds(p50, gap_tol=1e-6, lp_tol=1e-8, threads=1)
    fn_max = {(int(a), int(c)): m for a, c, m in zip(b["a"], b["b"], b["fn_max"])}
    assert [q.f_crit for q in results] == [fn_max[(q.a, q.b)] for q in results]
    with pytest.raises(unjam.Error, match="--lp-tol applies to the lp method, not to cd"):
        unjam.probe(p50, contact=3, method="cd", lp_tol=1e-8)
    # Refused: a record the tool would not have written on this packing (another contact
    # model, a value of the wrong type), a file without one.
    record = json.loads((out / "probe_summary.json").read_text())
    record["settings"]["M_lambda"] *= 2
    (tmp_path / "model.json").write_text(json.dumps(record))
    with pytest.raises(unjam.Error, match="not what unjam probe records on this packing .M_lambda"):
        unjam.campaign_settings(p50, tmp_path / "model.json")
    record = json.loads((out / "probe_summary.json").read_text())
    record["settings"]["cd_softer_starts"] = "two"
    (tmp_path / "bad.json").write_text(json.dumps(record))
    with pytest.raises(unjam.Error, match="bad.json"):
        unjam.campaign_settings(p50, tmp_path / "bad.json")
    (tmp_path / "none.json").write_text("{}")
    with pytest.raises(unjam.Error, match="holds no campaign settings"):
        unjam.campaign_settings(p50, tmp_path / "none.json")
    (tmp_path / "text.json").write_text("not json")
    with pytest.raises(unjam.Error, match="is not JSON"):
        unjam.campaign_settings(p50, tmp_path / "text.json")
    with pytest.raises(unjam.Error):
        unjam.campaign_settings(p50, tmp_path / "missing.json")


def test_the_cd_settings_are_one_typed_object():
    # unjam.CdSettings: the cd method's settings as `unjam probe --cd-*` sets them, the tool's
    # defaults, every assignment range-checked (a refused one leaves the object as it was), and
    # unjam.probe(cd=...) the same probe as the keywords: contact 8 of p200-mu1 as in the test
    # above (near-exact in 200 pieces accepting 1e-4, compliant start, continuation from 0.1).
    d = unjam.CdSettings()
    assert (d.start, d.compliant_start, d.softer_starts, d.max_pieces, d.accept_residual) == \
        ("static", 0.1, 2, 0, 1e-6)
    assert (d.interior_states_pieces, d.interior_states_stall, d.interior_states_retries,
            d.interior_iterations, d.interior_neighbourhood, d.settle_compliance, d.lost_factor,
            d.restart_floor, d.interior_share) == (0.1, 20, 2, 100, 0.0, 0.0, 0.0, 0.0, 0.5)
    assert (d.inertial_factor, d.inertial_stages, d.inertial_halvings, d.inertial_retries,
            d.inertial_jumps) == (10.0, 4, 3, 1, 8)
    s = unjam.CdSettings(start="compliant", accept_residual=1e-4)
    assert s != d and s == unjam.CdSettings(start="compliant", accept_residual=1e-4)
    assert repr(s).startswith("CdSettings(start='compliant', compliant_start=0.1, softer_starts=2, "
                              "max_pieces=0, accept_residual=0.0001, ")
    assert eval("unjam." + repr(s)) == s and copy.deepcopy(s) == s
    assert pickle.loads(pickle.dumps(s)) == s and pickle.loads(pickle.dumps(d)) == d
    state = s.__getstate__()  # a damaged pickle is refused as a bad assignment is
    state["accept_residual"] = 1e-2
    with pytest.raises(unjam.Error, match=r"--cd-accept-residual must be in"):
        unjam.CdSettings.__new__(unjam.CdSettings).__setstate__(state)
    for field, value, message in [("accept_residual", 1e-2, r"--cd-accept-residual must be in \[1e-06"),
                                  ("compliant_start", 0.0, "--cd-compliant-start must be positive"),
                                  ("compliant_start", float("inf"), "--cd-compliant-start must be positive"),
                                  ("max_pieces", -1, "--cd-max-pieces must be >= 0"),
                                  ("softer_starts", -1, "--cd-softer-starts must be >= 0"),
                                  ("interior_iterations", 0, "--cd-interior-iterations must be >= 1"),
                                  ("interior_neighbourhood", 1.0, "--cd-interior-neighbourhood must be in"),
                                  ("settle_compliance", -1e-5, "--cd-settle-compliance must be >= 0"),
                                  ("settle_compliance", float("nan"), "--cd-settle-compliance must be >= 0"),
                                  ("lost_factor", -1.0, "--cd-lost-factor must be >= 0"),
                                  ("lost_factor", float("inf"), "--cd-lost-factor must be >= 0"),
                                  ("restart_floor", -1e-5, "--cd-restart-floor must be >= 0"),
                                  ("restart_floor", float("nan"), "--cd-restart-floor must be >= 0"),
                                  ("interior_share", 0.0, r"--cd-interior-share must be in \(0, 1\)"),
                                  ("interior_share", 1.0, r"--cd-interior-share must be in \(0, 1\)"),
                                  ("inertial_factor", 1.0, "--cd-inertial-factor must be > 1 and finite"),
                                  ("inertial_factor", float("inf"), "--cd-inertial-factor must be > 1 and finite"),
                                  ("inertial_stages", 0, "--cd-inertial-stages must be >= 1"),
                                  ("inertial_halvings", -1, "--cd-inertial-halvings must be >= 0"),
                                  ("inertial_retries", -1, "--cd-inertial-retries must be >= 0"),
                                  ("inertial_jumps", -1, "--cd-inertial-jumps must be >= 0"),
                                  ("start", "soft", "--cd-start must be static, lp, compliant, interior, inertial or interior-inertial")]:
        t = copy.copy(s)
        with pytest.raises(unjam.Error, match=message):
            setattr(t, field, value)
        assert t == s, field
        with pytest.raises(unjam.Error, match=message):
            unjam.CdSettings(**{field: value})
    fixture = str(Path(__file__).parent / "fixtures" / "p200-mu1")
    p = unjam.read_packing(fixture)
    typed = unjam.probe(p, contact=8, method="cd", cd=s)
    keywords = unjam.probe(p, contact=8, method="cd", cd_start="compliant", cd_accept_residual=1e-4)
    assert (typed.converged, typed.sweeps) == (False, 200)
    assert (typed.f_crit, typed.residual, typed.u.tolist()) == \
        (keywords.f_crit, keywords.residual, keywords.u.tolist())
    s.accept_residual = 1e-6  # the default again: the search goes on to the exact restart
    assert (unjam.probe(p, contact=8, method="cd", cd=s).sweeps, s.accept_residual) == (279, 1e-6)
    # what depends on the method is checked where the settings are used, as the tool does
    with pytest.raises(unjam.Error, match="applies to the cd method's compliant and interior starts only"):
        unjam.probe(p, contact=8, method="cd", cd=unjam.CdSettings(compliant_start=1e-3))
    with pytest.raises(unjam.Error, match="not both"):
        unjam.probe(p, contact=8, method="cd", cd=s, cd_max_pieces=100)
    with pytest.raises(unjam.Error, match="not both"):
        unjam.probe(p, contact=8, method="cd", cd=s, cd_start="interior")
    # settle_compliance (`--cd-settle-compliance`, through cd= only): contact 34 ends at its first
    # exact solution below a compliance of 1e-5, in 8 pieces against 134 (docs/probe.md,
    # "Settling at an exact solution"); pickled and compared with the other fields.
    settled = unjam.CdSettings(start="compliant", settle_compliance=1e-5)
    assert repr(settled).endswith("settle_compliance=1e-05, lost_factor=0.0, restart_floor=0.0, "
                                  "interior_share=0.5, inertial_factor=10.0, inertial_stages=4, "
                                  "inertial_halvings=3, inertial_retries=1, inertial_jumps=8)")
    assert pickle.loads(pickle.dumps(settled)) == settled
    assert settled != unjam.CdSettings(start="compliant")
    a = unjam.probe(p, contact=34, method="cd", cd=settled)
    b = unjam.probe(p, contact=34, method="cd", cd_start="compliant")
    assert (a.converged, a.sweeps, b.converged, b.sweeps) == (True, 8, True, 134)
    assert abs(a.f_crit / b.f_crit - 1) < 1e-4 and a.f_crit != b.f_crit
    # lost_factor (`--cd-lost-factor`, through cd= only): at 1e-12 every path that reaches the
    # full opening counts as one that lost its digits, so contact 34 has no solution; at 1e300
    # none does, and the probe is the default's (docs/probe.md, "Paths that lose their digits").
    lost = unjam.probe(p, contact=34, method="cd", cd=unjam.CdSettings(start="compliant", lost_factor=1e-12))
    kept = unjam.probe(p, contact=34, method="cd", cd=unjam.CdSettings(start="compliant", lost_factor=1e300))
    assert (lost.converged, lost.residual) == (False, sys.float_info.max)
    assert (kept.f_crit, kept.sweeps) == (b.f_crit, b.sweeps)
    # restart_floor (`--cd-restart-floor`, through cd= only): contact 8's exact solution comes
    # from a restart (the search above); with no restart allowed the probe takes other paths
    floored = unjam.CdSettings(start="compliant", restart_floor=1.0)
    assert pickle.loads(pickle.dumps(floored)) == floored and floored != unjam.CdSettings(start="compliant")
    assert unjam.probe(p, contact=8, method="cd", cd=floored).sweeps != 279
    with pytest.raises(unjam.Error, match="applies to the cd method's compliant and interior starts only"):
        unjam.probe(p, contact=8, method="cd", cd=unjam.CdSettings(restart_floor=1e-3))
    # interior_share (`--cd-interior-share`, the interior-inertial start only): contact 0 within
    # 150 pieces, the interior start's share 75 (not exact there) and the continuation in dt's the
    # rest, reaches 2.844066 F0 in 116 pieces (tests/test_cd_step.cpp); with a share of 0.7
    # (105) the interior start is exact in its 99 pieces, 2.795944 F0
    half = unjam.probe(p, contact=0, method="cd", cd=unjam.CdSettings(start="interior-inertial", max_pieces=150))
    most = unjam.probe(p, contact=0, method="cd",
                       cd=unjam.CdSettings(start="interior-inertial", max_pieces=150, interior_share=0.7))
    assert (half.converged, half.sweeps, most.converged, most.sweeps) == (True, 116, True, 99)
    assert abs(half.f_crit / p.F0 - 2.844066) < 1e-6 and abs(most.f_crit / p.F0 - 2.795944) < 1e-6
    with pytest.raises(unjam.Error, match="--cd-interior-share applies to the cd method's interior-inertial start only"):
        unjam.probe(p, contact=0, method="cd", cd=unjam.CdSettings(start="interior", interior_share=0.7))
    # the continuation in dt's settings (`--cd-inertial-*`, the inertial and interior-inertial
    # starts only): in one stage from a tenth of dt instead of four, the same solution of contact
    # 0; from dt / 3 its first stage is not solved within the budget, and the probe has none
    one = unjam.probe(p, contact=0, method="cd",
                      cd=unjam.CdSettings(start="interior-inertial", max_pieces=150, inertial_stages=1))
    assert one.converged and abs(one.f_crit / p.F0 - 2.844066) < 1e-6
    three = unjam.probe(p, contact=0, method="cd",
                        cd=unjam.CdSettings(start="interior-inertial", max_pieces=150, inertial_factor=3.0))
    assert (three.converged, three.sweeps) == (False, 151)
    with pytest.raises(unjam.Error, match="--cd-inertial-factor applies to the cd method's inertial and interior-inertial "
                                          "starts only"):
        unjam.probe(p, contact=0, method="cd", cd=unjam.CdSettings(start="interior", inertial_factor=3.0))


def test_the_exact_probe_takes_its_window_as_the_tool(p50, tmp_path):
    # window as `unjam probe --window`: the same field and F_crit, bit for bit; zero outside
    # the window; another F_crit than the whole packing's (docs/probe.md, "A window around
    # the probed pair"); refused for lp and for a radius <= 0.
    tool("probe", FIXTURE, "--contact", 1, "--method", "cd", "--window", 2.5, "--out", tmp_path)
    rows = read_csv(tmp_path / "probe-1.csv")
    w = unjam.probe(p50, contact=1, method="cd", window=2.5)
    assert w.converged
    assert [[float(x["ux"]), float(x["uy"])] for x in rows] == w.u.tolist()
    forces = {int(x["contact"]): float(x["fn"]) for x in read_csv(tmp_path / "probe-1-forces.csv")}
    assert forces[1] == w.f_crit and len(forces) < 82
    assert np.count_nonzero(np.hypot(w.u[:, 0], w.u[:, 1])) < len(p50.radii)
    assert abs(w.f_crit / unjam.probe(p50, contact=1, method="cd").f_crit - 1) > 1e-3
    with pytest.raises(unjam.Error, match="--window applies to the exact methods"):
        unjam.probe(p50, contact=1, method="lp", window=2.5)
    with pytest.raises(unjam.Error, match="window must be > 0"):
        unjam.probe(p50, contact=1, method="cd", window=0.0)


def test_bad_arguments_raise(p50, tmp_path):
    with pytest.raises(unjam.Error, match="does not exist"):
        unjam.read_packing(tmp_path / "missing")
    with pytest.raises(unjam.Error, match="exactly one"):
        unjam.probe(p50)
    with pytest.raises(unjam.Error, match="the packing has 82 contacts"):
        unjam.probe(p50, contact=82)
    with pytest.raises(unjam.Error, match="contact -1: the packing has 82"):
        unjam.probe(p50, contacts=[0, -1])
    with pytest.raises(unjam.Error, match="threads"):
        unjam.probe(p50, contact=0, threads=-2)
    with pytest.raises(unjam.Error, match="lp, nlgs, lemke or cd"):
        unjam.probe(p50, contact=0, method="simplex")
    with pytest.raises(unjam.Error, match="must be positive"):
        unjam.probe(p50, contact=0, g=-1.0)
    with pytest.raises(unjam.Error, match="number of disks"):
        unjam.pack(n=1)
    with pytest.raises(unjam.Error, match="mu"):
        unjam.pack(n=10, mu=-0.5)
    with pytest.raises(unjam.Error, match="threads"):
        unjam.pack(n=10, threads=-1)
    with pytest.raises(unjam.Error, match="barrier or simplex"):
        unjam.bounds(p50, method="interior")
    with pytest.raises(unjam.Error, match="non-negative"):
        unjam.stats(p50, threshold=-1.0)
    with pytest.raises(unjam.Error, match="vtk or xyz"):
        unjam.export(p50, tmp_path / "x.obj", format="obj")
    with pytest.raises(TypeError):
        unjam.pack(n="many")
    assert issubclass(unjam.Error, ValueError)


def test_ctrl_c_stops_a_long_pack(tmp_path):
    """SIGINT during a long compaction: KeyboardInterrupt within a second, state saved."""
    code = ("import unjam\n"
            f"unjam.pack(n=4000, seed=1, threads=1, out={str(tmp_path / 'p')!r})\n")
    proc = subprocess.Popen([sys.executable, "-c", code], stderr=subprocess.PIPE, text=True,
                            env=os.environ.copy())
    time.sleep(2.0)
    assert proc.poll() is None, proc.stderr.read()
    sent = time.monotonic()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=30)
    assert time.monotonic() - sent < 5.0
    assert proc.returncode != 0 and "KeyboardInterrupt" in err
    meta = json.loads((tmp_path / "p" / "meta.json").read_text())
    assert meta["state"]["static"] is False and meta["state"]["step"] > 0


def interrupted(code):
    """Runs `code` in a fresh interpreter and sends SIGINT 0.3 s after it prints 'ready';
    returns (seconds from SIGINT to exit, return code, stdout, stderr)."""
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=os.environ.copy())
    assert proc.stdout.readline() == "ready\n", proc.stderr.read()
    time.sleep(0.3)
    sent = time.monotonic()
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    return time.monotonic() - sent, proc.returncode, out, err


@pytest.mark.parametrize("setup,call", [
    # bounds (ForceBoundsOptions::should_stop): ~600 LPs of a 150-disk packing, stopped between LPs
    ("p = unjam.pack(n=150, seed=3, threads=1)", "unjam.bounds(p, threads=2)"),
    # probe(contacts=[...]): 1640 probes (~5 s of CPU), stopped between batches
    (f"p = unjam.read_packing({FIXTURE!r})", "unjam.probe(p, contacts=list(range(82)) * 20, threads=2)"),
    # one nlgs probe of 1e7 sweeps (~30 s of CPU), abandoned inside (ProbeSettings::cancel)
    (f"p = unjam.read_packing({FIXTURE!r})",
     "unjam.probe(p, contact=3, method='nlgs', velocity_tol=1e-14, max_sweeps=10000000, threads=1)"),
    # ensemble: in the hit-and-run sampler, in the random walk, inside its nlgs probes
    (f"p = unjam.read_packing({FIXTURE!r})", "unjam.ensemble(p, method='hit-and-run', probe='none', samples=10**9)"),
    (f"p = unjam.read_packing({FIXTURE!r})", "unjam.ensemble(p, method='walk', probe='none', samples=10**8)"),
    (f"p = unjam.read_packing({FIXTURE!r})",
     "unjam.ensemble(p, method='hit-and-run', samples=10, probe='nlgs', probe_velocity_tol=1e-14, threads=1)"),
])
def test_ctrl_c_stops_a_long_call(setup, call):
    seconds, rc, out, err = interrupted(
        f"import unjam\n{setup}\nprint('ready', flush=True)\n{call}\nprint('done', flush=True)\n")
    assert seconds < 5.0 and rc != 0 and "done" not in out
    assert "KeyboardInterrupt" in err and "line 4" in err  # in the call


def test_ensemble_equals_tool_bit_for_bit(tmp_path):
    """unjam.ensemble: the tool's ensemble.csv, its samples and ensemble.json's numbers, bit for
    bit, from the same seed; its progress and bad arguments."""
    d = tmp_path / "p"
    tool("pack", "--n", 30, "--mu", 0.2, "--seed", 4, "--out", d, "--quiet")
    tool("ensemble", d, "--samples", 400, "--seed", 7, "--probe", "cd", "--threads", 2, "--write-samples")
    p = unjam.read_packing(d)
    steps = []
    e = unjam.ensemble(p, samples=400, seed=7, probe="cd", threads=1, keep_samples=True, progress=steps.append)
    rows = read_csv(d / "ensemble.csv")
    assert len(rows) == len(e["a"]) > 0 and e["contact"].dtype == np.int32
    for name in rows[0]:
        if name == "f_crit_method":
            continue
        unprobed = {"probe_sweeps": -1.0, "probe_converged": 0.0}.get(name, float("nan"))  # the module's marks
        want = [float(x[name]) if x[name] != "" else unprobed for x in rows]
        got = np.asarray(e[name], dtype=float).tolist()
        assert np.array_equal(np.array(got), np.array(want), equal_nan=True), name
    probed = ~np.isnan(e["f_crit"])
    assert probed.sum() == sum(x["f_crit_method"] == "cd" for x in rows) > 0
    assert np.all(e["fn"][probed] > 1e-9 * e["F0"]) and e["probe_converged"][probed].all()
    samples = read_csv(d / "ensemble-samples.csv")
    assert e["samples_fn"].shape == (400, len(rows))
    assert e["samples_fn"].tolist() == [[float(v) for v in s.values()] for s in samples]
    j = json.loads((d / "ensemble.json").read_text())
    for m in ("hit_and_run", "walk"):
        for k in ("eta", "mean_fn", "mean_coverage_of_lp_width", "samples"):
            assert e["methods"][m][k] == j["methods"][m][k], (m, k)
    assert e["probe"]["f_crit_over_fn_max"] == j["probe"]["f_crit_over_fn_max"]
    assert e["probe"]["position_in_interval"] == j["probe"]["position_in_interval"]
    assert e["parameters"] == j["parameters"] and (e["mu"], e["F0"], e["seed"]) == (0.2, j["F0"], 7)
    assert {s["what"] for s in steps} == {"random walk (steps)", "probe cd (contacts)"}
    assert steps[-1]["done"] == steps[-1]["total"] == probed.sum()
    # The cd probe's settings as one unjam.CdSettings: the tool's --cd-* options.
    tool("ensemble", d, "--samples", 10, "--method", "hit-and-run", "--probe", "cd", "--cd-start", "interior",
         "--cd-max-pieces", 4000, "--threads", 2)
    c = unjam.ensemble(p, samples=10, method="hit-and-run", probe="cd",
                       cd=unjam.CdSettings(start="interior", max_pieces=4000))
    assert np.array_equal(c["f_crit"], np.array([float(x["f_crit"] or "nan") for x in read_csv(d / "ensemble.csv")]),
                          equal_nan=True)
    assert c["probe"]["settings"]["start"] == "interior" and c["probe"]["settings"]["cd_max_pieces"] == 4000
    with pytest.raises(unjam.Error, match="applies to the cd method, not to lp"):
        unjam.ensemble(p, samples=10, probe="lp", cd=unjam.CdSettings(max_pieces=10))
    # One sampler, no probe: only its columns.
    h = unjam.ensemble(p, method="hit-and-run", probe="none", samples=50)
    assert "walk_mean" not in h and "f_crit" not in h and "samples_fn" not in h and h["probe"] == {"method": "none"}
    with pytest.raises(RuntimeError, match="enough"):
        unjam.ensemble(p, method="walk", probe="none", samples=10**6,
                       progress=lambda s: (_ for _ in ()).throw(RuntimeError("enough")))
    for bad, match in [(dict(method="gibbs"), "method must be hit-and-run, walk or both"),
                       (dict(probe="lemke"), "probe must be nlgs, lp, cd or none"),
                       (dict(probe="simplex"), "simplex"), (dict(samples=0), "samples must be >= 1"),
                       (dict(lp_tol=1e-13), "LP tolerance"), (dict(open_tol=0.0), "open tolerance"),
                       (dict(walk_tol=float("nan")), "walk_tol"), (dict(threads=-1), "threads")]:
        with pytest.raises(unjam.Error, match=match):
            unjam.ensemble(p, **{"samples": 10, **bad})


def test_ctrl_c_of_a_probe_list_keeps_what_progress_was_given(tmp_path):
    """Ctrl-C raises KeyboardInterrupt and returns nothing, but the probes handed to progress
    before it are kept, and they are those of an uninterrupted run."""
    seconds, rc, out, err = interrupted(
        f"import unjam\np = unjam.read_packing({FIXTURE!r})\nkept = []\nprint('ready', flush=True)\n"
        "try:\n    unjam.probe(p, contacts=list(range(82)) * 20, threads=2, progress=kept.append)\n"
        "except KeyboardInterrupt:\n"
        "    print(*(f\"{d['index']} {d['result'].f_crit!r}\" for d in kept), sep='\\n', flush=True)\n"
        "    raise\n")
    assert seconds < 5.0 and rc != 0 and "KeyboardInterrupt" in err
    kept = [line.split() for line in out.splitlines()]
    assert 0 < len(kept) < 82 * 20
    p = unjam.read_packing(FIXTURE)
    indices = [int(i) for i, _ in kept]
    assert len(set(indices)) == len(indices)
    again = unjam.probe(p, contacts=[i % 82 for i in indices], threads=1)
    assert [float(f) for _, f in kept] == [r.f_crit for r in again]


def test_ctrl_c_of_bounds_saves_its_checkpoint_and_the_resumed_run_loses_nothing(tmp_path):
    """unjam.bounds(checkpoint=...) stopped by Ctrl-C saves the intervals known so far; the
    same call resumes from them and ends with the intervals of one uninterrupted run."""
    checkpoint = tmp_path / "bounds_checkpoint.json"
    seconds, rc, out, err = interrupted(
        f"import unjam\np = unjam.pack(n=150, seed=3, threads=1)\np.write({str(tmp_path / 'p')!r})\n"
        f"print('ready', flush=True)\nunjam.bounds(p, threads=2, checkpoint={str(checkpoint)!r})\n"
        "print('done', flush=True)\n")
    assert seconds < 5.0 and rc != 0 and "done" not in out and "KeyboardInterrupt" in err
    saved = json.loads(checkpoint.read_text())
    known = sum(x is not None for x in saved["fn_min"] + saved["fn_max"])
    assert 0 < known < 2 * len(saved["fn_max"]) and saved["runs"]["runs"] == 1
    p = unjam.read_packing(tmp_path / "p")
    resumed = unjam.bounds(p, threads=1, checkpoint=checkpoint)
    whole = unjam.bounds(p, threads=2)
    assert not checkpoint.exists()
    for name in ("fn_min", "fn_max"):
        assert resumed[name].tolist() == whole[name].tolist()


def test_pack_progress_callback_and_its_exception():
    """progress gets the compaction's report every 2 s; an exception it raises stops the
    compaction and reaches the caller."""
    reports = []

    def progress(report):
        reports.append(report)
        raise RuntimeError("enough")

    with pytest.raises(RuntimeError, match="enough"):
        unjam.pack(n=4000, seed=1, threads=1, progress=progress)
    assert len(reports) == 1
    r = reports[0]
    assert r["step"] > 0 and 0.0 < r["phi"] < 1.0 and r["elapsed_s"] >= 2.0 and r["contacts"] >= 0
    assert set(r) >= {"time", "P_in_over_P_ext", "v_mean", "sweeps_per_step", "eta_s", "static_attempts"}


def test_relax_equals_tool_from(tmp_path, p50):
    """unjam.relax(p, mu=...) is `unjam pack --from DIR --mu ...`: the same bytes."""
    tool("pack", "--from", FIXTURE, "--mu", 0.4, "--p-ext", 2.0, "--out", tmp_path / "cli", "--quiet")
    before = np.array(p50.contacts.fn)
    q = unjam.relax(p50, mu=0.4, p_ext=2.0)
    assert q.mu == 0.4 and q.P_ext == 2.0 and q.is_static and q.seed == p50.seed
    assert np.array_equal(p50.contacts.fn, before) and p50.mu == 0.1  # the packing given stays
    q.write(tmp_path / "py")
    for table in ("particles.csv", "contacts.csv"):
        assert (tmp_path / "cli" / table).read_bytes() == (tmp_path / "py" / table).read_bytes()
    cli_meta = json.loads((tmp_path / "cli" / "meta.json").read_text())
    py_meta = json.loads((tmp_path / "py" / "meta.json").read_text())
    assert py_meta.pop("command") == "python: unjam.relax(packing, mu=0.40000000000000002, p_ext=2, threads=0)"
    cli_meta.pop("command")
    assert cli_meta == py_meta
    with pytest.raises(TypeError):
        unjam.relax(p50)  # mu is required
