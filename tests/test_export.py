"""`unjam export` read back by independent readers: VTK's own XML reader (Debian python3-vtk9)
for .vtp, and a parser of extended XYZ written here from the format's definition (ASE/OVITO:
line 1 the count, line 2 key=value pairs with Lattice and Properties=name:type:columns:...).
Run by ctest (export) with UNJAM and PYTHONPATH set, like test_python_module.py.
"""
import csv
import os
import shlex
import subprocess
from pathlib import Path

import numpy as np
import pytest
import vtk
from vtk.util.numpy_support import vtk_to_numpy

import unjam

UNJAM = os.environ.get("UNJAM", "build/release/unjam")
FIXTURE = str(Path(__file__).parent / "fixtures" / "p50-mu0.1")
K = 3  # the probed contact


def tool(*args):
    return subprocess.run([UNJAM, *map(str, args)], capture_output=True, text=True)


def read_vtp(path):
    reader = vtk.vtkXMLPolyDataReader()
    reader.SetFileName(str(path))
    reader.Update()
    assert reader.GetErrorCode() == 0
    return reader.GetOutput()


def read_extended_xyz(path):
    """(info dict, {property: (N, columns) array}) of a one-frame extended XYZ file."""
    lines = Path(path).read_text().splitlines()
    n = int(lines[0])
    info = dict(item.split("=", 1) for item in shlex.split(lines[1]))
    fields = info["Properties"].split(":")
    rows = [line.split() for line in lines[2:2 + n]]
    assert len(rows) == n and len(lines) == n + 2
    columns, c = {}, 0
    for name, kind, width in zip(fields[0::3], fields[1::3], map(int, fields[2::3])):
        cast = {"R": float, "I": int, "S": str}[kind]
        columns[name] = np.array([[cast(r[c + j]) for j in range(width)] for r in rows])
        c += width
    assert all(len(r) == c for r in rows)
    return info, columns


@pytest.fixture(scope="module")
def exports(tmp_path_factory):
    d = tmp_path_factory.mktemp("export")
    for args in (["probe", FIXTURE, "--contact", K, "--out", d],
                 ["export", FIXTURE, "--format", "vtk", "--probe", K, "--out", d / "probe.vtp"],
                 ["export", FIXTURE, "--format", "xyz", "--field", d / f"probe-{K}.csv",
                  "--out", d / "probe.xyz"]):
        r = tool(*args)
        assert r.returncode == 0, r.stderr
    field = list(csv.DictReader(open(d / f"probe-{K}.csv")))
    u = np.array([[float(x["ux"]), float(x["uy"])] for x in field])
    return d, unjam.read_packing(FIXTURE), u


def test_vtp_read_back_by_vtk(exports):
    d, p, u = exports
    poly = read_vtp(d / "probe.vtp")
    pts = vtk_to_numpy(poly.GetPoints().GetData())
    point = lambda name: vtk_to_numpy(poly.GetPointData().GetArray(name))
    cell = lambda name: vtk_to_numpy(poly.GetCellData().GetArray(name))
    N, M = p.N, len(p.contacts.fn)
    assert np.array_equal(pts[:N, :2], p.positions) and np.all(pts[:, 2] == 0)
    ids, image = point("id"), point("image")
    assert np.array_equal(ids[:N], np.arange(N)) and not image[:N].any() and image[N:].all()
    assert np.array_equal(point("radius"), p.radii[ids])
    assert np.array_equal(point("displacement")[:N, :2], u)
    assert poly.GetNumberOfLines() == M == poly.GetNumberOfCells()
    # Every contact line runs from r_a along the branch vector l, across the boundary if need be.
    lines = vtk_to_numpy(poly.GetLines().GetConnectivityArray()).reshape(M, 2)
    assert np.array_equal(lines[:, 0], p.contacts.a) and np.array_equal(ids[lines[:, 1]], p.contacts.b)
    assert np.allclose(pts[lines[:, 1], :2] - pts[lines[:, 0], :2], p.contacts.l, rtol=0, atol=1e-12)
    assert np.array_equal(cell("fn"), p.contacts.fn) and np.array_equal(cell("ft"), p.contacts.ft)
    tol = 1e-9 * p.F0
    expected = np.where(p.contacts.fn <= tol, 2,
                        np.where(p.mu * p.contacts.fn - np.abs(p.contacts.ft) <= tol, 1, 0))
    assert np.array_equal(cell("state"), expected) and (expected == 2).any()  # one open contact
    fd = poly.GetFieldData()
    assert vtk_to_numpy(fd.GetArray("Lx"))[0] == p.cell[0]
    assert vtk_to_numpy(fd.GetArray("probed_contact"))[0] == K
    assert fd.GetAbstractArray("command").GetValue(0).endswith(f"--probe {K} --out {d / 'probe.vtp'}")
    assert fd.GetAbstractArray("program_version").GetValue(0) == unjam.__version__


def test_extended_xyz_read_back(exports):
    d, p, u = exports
    info, col = read_extended_xyz(d / "probe.xyz")
    lattice = np.array(info["Lattice"].split(), float).reshape(3, 3)
    assert np.array_equal(np.diag(lattice)[:2], p.cell) and info["pbc"] == "T T F"
    assert np.array_equal(col["pos"][:, :2], p.positions) and np.all(col["pos"][:, 2] == 0)
    assert np.array_equal(col["radius"][:, 0], p.radii) and np.array_equal(col["id"][:, 0], np.arange(p.N))
    assert np.array_equal(col["disp"][:, :2], u)
    assert int(info["seed"]) == p.seed and float(info["mu"]) == p.mu


def test_module_export_equals_tool(exports, tmp_path):
    d, p, u = exports
    r = unjam.probe(p, contact=K)
    unjam.export(p, tmp_path / "py.xyz", format="xyz", probe=r)
    unjam.export(p, tmp_path / "py.vtp", probe=r)
    assert (tmp_path / "py.xyz").read_text().splitlines()[2:] == (d / "probe.xyz").read_text().splitlines()[2:]
    drop_record = lambda text: text[text.index("</FieldData>"):]
    assert drop_record((tmp_path / "py.vtp").read_text()) == drop_record((d / "probe.vtp").read_text())


def test_bad_input_is_refused(exports, tmp_path):
    d, p, u = exports
    r = tool("export", FIXTURE, "--format", "pdf")
    assert r.returncode != 0 and "pdf" in r.stderr
    r = tool("export", FIXTURE, "--format", "vtk", "--probe", 82, "--out", tmp_path / "x.vtp")
    assert r.returncode == 1 and "the packing has 82 contacts" in r.stderr
    (tmp_path / "short.csv").write_text("id,ux,uy,rot,ux_g,uy_g\n0,0,0,0,0,0\n")
    r = tool("export", FIXTURE, "--format", "xyz", "--field", tmp_path / "short.csv", "--out", tmp_path / "x.xyz")
    assert r.returncode == 1 and "1 grains, the packing has 50" in r.stderr
    assert not (tmp_path / "x.vtp").exists() and not (tmp_path / "x.xyz").exists()


def test_render_script_draws_the_export(exports, tmp_path):
    """scripts/render_export.py (VTK, under Xvfb) makes a picture of both panels."""
    d, p, u = exports
    script = Path(__file__).parent.parent / "scripts" / "render_export.py"
    r = subprocess.run(["xvfb-run", "-a", "/usr/bin/python3", str(script), str(d / "probe.vtp"),
                        str(tmp_path / "pic.png"), "--size", "200"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    png = vtk.vtkPNGReader()
    png.SetFileName(str(tmp_path / "pic.png"))
    png.Update()
    image = png.GetOutput()
    assert image.GetDimensions()[:2] == (400, 200)
    pixels = vtk_to_numpy(image.GetPointData().GetScalars())
    left, right = pixels.reshape(200, 400, -1)[:, :200], pixels.reshape(200, 400, -1)[:, 200:]
    # Coloured force chains on the left (red and blue ends of the map), dark red arrows on the right.
    assert (left[..., 0] > 200).any() and (left[..., 2] > 200).any() and (left[..., 1] < 100).any()
    assert ((right[..., 0] > 120) & (right[..., 1] < 60)).any()
    r = subprocess.run(["/usr/bin/python3", str(script), str(tmp_path / "missing.vtp"), "x.png"],
                       capture_output=True, text=True)
    assert r.returncode != 0
