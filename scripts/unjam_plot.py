"""Shared helpers for unjam's plotting scripts (scripts/plot_*.py).

Reads unjam's outputs (docs/packing-format.md, docs/analysis.md) by column name, and
provides the force unit F0 = 2 R_avg P_ext, periodic images, the minimum image, and an
atomic PNG writer.  Only numpy and matplotlib (Agg backend) are used.

User errors (missing or corrupt input, bad options) raise UserError; scripts run their
main() through run_main(), which prints "SCRIPT: error: MESSAGE" to stderr and exits with
status 1, without a traceback.
"""

import argparse
import csv
import io
import json
import math
import os
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402

DPI = 150
# A contact carries force when fn > FORCE_THRESHOLD_F0 * F0 (as `unjam info`).
FORCE_THRESHOLD_F0 = 1e-9


class UserError(Exception):
    """An error in the user's input: reported as a message, exit status 1."""


def run_main(main):
    """Run main(); turn UserError (and unreadable files) into a message and exit 1."""
    prog = os.path.basename(sys.argv[0]) or "unjam-plot"
    try:
        main()
    except UserError as e:
        print(f"{prog}: error: {e}", file=sys.stderr)
        sys.exit(1)
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        sys.exit(130)


class ArgumentParser(argparse.ArgumentParser):
    """argparse with command-line errors as UserError: one message, exit status 1."""

    def error(self, message):
        raise UserError(message)


def warn(message):
    prog = os.path.basename(sys.argv[0]) or "unjam-plot"
    print(f"{prog}: warning: {message}", file=sys.stderr)


# ---------------------------------------------------------------------------------------
# Files


def _open_text(path):
    if not os.path.exists(path):
        raise UserError(f"{path}: file not found")
    if os.path.isdir(path):
        raise UserError(f"{path}: is a directory, expected a file")
    try:
        return open(path, newline="", encoding="utf-8")
    except OSError as e:
        raise UserError(f"{path}: cannot open: {e.strerror}") from None


def require_dir(path):
    """Check that path is an existing directory."""
    if not os.path.exists(path):
        raise UserError(f"{path}: directory not found")
    if not os.path.isdir(path):
        raise UserError(f"{path}: not a directory")
    return path


def _parse_number(text, path, line, column, allow_nan):
    s = text.strip() if text is not None else ""
    if s == "" and allow_nan:
        return math.nan
    try:
        v = float(s)
    except ValueError:
        raise UserError(f"{path} line {line}, column '{column}': not a number: '{s}'") from None
    if math.isnan(v) and allow_nan:
        return v
    if not math.isfinite(v):
        raise UserError(f"{path} line {line}, column '{column}': not a finite number: '{s}'")
    return v


def read_csv(path, columns, optional=(), text=(), allow_nan=(), min_rows=0):
    """Read a CSV table by header name.

    columns:   required numeric columns; optional: numeric columns that may be absent;
    text:      columns kept as strings (absent ones are skipped);
    allow_nan: numeric columns that may be empty or 'nan' (-> NaN).
    Other columns are ignored.  Returns {name: numpy array} (float for numeric columns).
    Raises UserError naming the file, line and column on any problem.
    """
    with _open_text(path) as f:
        try:
            # Header: first non-blank line; names stripped (spaces, CRLF).
            # Whitespace-only lines become empty rows, which DictReader skips (line numbers kept).
            lines = (ln if ln.strip() != "" else "\n" for ln in f)
            reader = csv.DictReader(lines, skipinitialspace=True)
            header = reader.fieldnames
            if not header:
                raise UserError(f"{path}: empty file (no header)")
            header = [h.strip() for h in header]
            reader.fieldnames = header
            missing = [c for c in columns if c not in header]
            if missing:
                raise UserError(
                    f"{path}: missing column{'s' if len(missing) > 1 else ''} "
                    f"{', '.join(repr(c) for c in missing)} (header: {','.join(header)})"
                )
            numeric = list(columns) + [c for c in optional if c in header]
            keep_text = [c for c in text if c in header]
            values = {c: [] for c in numeric + keep_text}
            nan_ok = set(allow_nan)
            for row in reader:
                i = reader.line_num
                if None in row:
                    raise UserError(f"{path} line {i}: expected {len(header)} fields, "
                                    f"got {len(header) + len(row[None])}")
                if any(v is None for v in row.values()):
                    n = sum(v is not None for v in row.values())
                    raise UserError(
                        f"{path} line {i}: expected {len(header)} fields, got {n}")
                for c in numeric:
                    values[c].append(_parse_number(row[c], path, i, c, c in nan_ok))
                for c in keep_text:
                    values[c].append(row[c].strip())
        except csv.Error as e:
            raise UserError(f"{path}: not a valid CSV file: {e}") from None
        except UnicodeDecodeError:
            raise UserError(f"{path}: not a text file") from None
    n_rows = len(values[numeric[0]]) if numeric else 0
    if n_rows < min_rows:
        raise UserError(f"{path}: no data rows" if n_rows == 0 else
                        f"{path}: {n_rows} data rows, need at least {min_rows}")
    out = {c: np.asarray(values[c], dtype=float) for c in numeric}
    out.update({c: np.asarray(values[c], dtype=object) for c in keep_text})
    return out


# How far an interval's ends may cross (fn_min above fn_max), relative to max(1, |fn_max|) in
# the file's force unit, and still be one point: the round-off of two LPs that reach the same
# optimum from either side (docs/ensemble.md, "Reading bounds.csv").
INTERVAL_ROUNDOFF = 1e-9


def read_intervals(path, columns=("a", "b", "fn_min", "fn_max"), min_rows=0):
    """A table of admissible intervals (bounds.csv of `unjam bounds`, or any CSV with fn_min
    and fn_max) by column, as read_csv gives it, read by the one rule every script shares:
    ends that cross by at most INTERVAL_ROUNDOFF are one point (fn_min set to fn_max, the
    end the lp probe takes for F_crit); a wider crossing is no interval, and a UserError names
    its line."""
    columns = list(columns) + [c for c in ("fn_min", "fn_max") if c not in columns]
    t = read_csv(path, columns, min_rows=min_rows)
    lo, hi = t["fn_min"], t["fn_max"]
    crossed = lo > hi
    wide = crossed & (lo - hi > INTERVAL_ROUNDOFF * np.maximum(1.0, np.abs(hi)))
    if wide.any():
        i = int(np.argmax(wide))
        raise UserError(f"{path}: data row {i + 1} has fn_min {float(lo[i])!r} above fn_max "
                        f"{float(hi[i])!r} by more than the LPs' round-off "
                        f"({INTERVAL_ROUNDOFF:g} relative): not an interval")
    t["fn_min"] = np.where(crossed, hi, lo)
    return t


def read_json(path):
    """Read a JSON object from path (UserError if missing, not JSON or not an object)."""
    with _open_text(path) as f:
        try:
            data = json.load(f)
        except (json.JSONDecodeError, UnicodeDecodeError) as e:
            raise UserError(f"{path}: not valid JSON: {e}") from None
    if not isinstance(data, dict):
        raise UserError(f"{path}: expected a JSON object")
    return data


def json_number(data, key, path, required=True, default=None, positive=False):
    """A finite number data[key] (dotted keys descend into objects)."""
    node = data
    for part in key.split("."):
        if not isinstance(node, dict) or part not in node:
            if required:
                raise UserError(f"{path}: missing '{key}'")
            return default
        node = node[part]
    if isinstance(node, bool) or not isinstance(node, (int, float)) or not math.isfinite(node):
        if node is None and not required:
            return default
        raise UserError(f"{path}: '{key}' is not a finite number: {node!r}")
    if positive and node <= 0:
        raise UserError(f"{path}: '{key}' must be > 0, got {node}")
    return float(node)


def read_meta(directory):
    """meta.json of a packing: returns dict with Lx, Ly, P_ext, mu (floats) plus the rest."""
    path = os.path.join(directory, "meta.json")
    meta = read_json(path)
    if "Lx" in meta or "Ly" in meta:
        Lx = json_number(meta, "Lx", path, positive=True)
        Ly = json_number(meta, "Ly", path, positive=True)
    elif "L" in meta:
        Lx = Ly = json_number(meta, "L", path, positive=True)
    else:
        raise UserError(f"{path}: missing the cell size ('L', or 'Lx' and 'Ly')")
    meta = dict(meta)
    meta["Lx"], meta["Ly"] = Lx, Ly
    meta["P_ext"] = json_number(meta, "P_ext", path, positive=True)
    meta["mu"] = json_number(meta, "mu", path)
    if meta["mu"] < 0:
        raise UserError(f"{path}: 'mu' must be >= 0, got {meta['mu']}")
    meta["_path"] = path
    return meta


def read_particles(directory):
    """particles.csv, rows ordered by id (ids must be 0..N-1): dict x, y, radius."""
    path = os.path.join(directory, "particles.csv")
    t = read_csv(path, ["x", "y", "radius"], optional=["id"], min_rows=1)
    if "id" in t:
        ids = t["id"]
        n = len(ids)
        if not np.all(ids == np.round(ids)) or not np.array_equal(np.sort(ids), np.arange(n)):
            raise UserError(f"{path}: ids are not a permutation of 0..{n - 1}")
        order = np.argsort(ids)
        t = {k: v[order] for k, v in t.items()}
    if np.any(t["radius"] <= 0):
        raise UserError(f"{path}: a radius is <= 0")
    return t


def read_contacts(directory, n_particles):
    """contacts.csv: dict a, b (int arrays), nx, ny, lx, ly, fn, ft."""
    path = os.path.join(directory, "contacts.csv")
    t = read_csv(path, ["a", "b", "nx", "ny", "lx", "ly", "fn", "ft"])
    for k in ("a", "b"):
        v = t[k]
        if np.any(v != np.round(v)) or np.any(v < 0) or np.any(v >= n_particles):
            raise UserError(f"{path}: column '{k}' holds a grain index outside 0..{n_particles - 1}")
        t[k] = v.astype(int)
    if np.any(t["a"] == t["b"]):
        raise UserError(f"{path}: a contact with a == b")
    return t


def force_unit(meta, radius=None):
    """F0 = 2 R_avg P_ext (from the radii when given, else meta.json's 'F0')."""
    if radius is not None and len(radius) > 0:
        return 2.0 * float(np.mean(radius)) * meta["P_ext"]
    if "F0" in meta:
        return json_number(meta, "F0", meta.get("_path", "meta.json"), positive=True)
    raise UserError(f"{meta.get('_path', 'meta.json')}: no 'F0' and no radii to compute it")


def force_carrying(fn, F0):
    """Mask of force-carrying contacts: fn > 1e-9 F0."""
    return fn > FORCE_THRESHOLD_F0 * F0


def packing_stats(meta, particles, contacts):
    """phi, z (rattlers excluded), rattler mask, F0, force-carrying mask, <F_cont>/F0."""
    N = len(particles["radius"])
    V = meta["Lx"] * meta["Ly"]
    F0 = force_unit(meta, particles["radius"])
    phi = float(np.sum(np.pi * particles["radius"] ** 2) / V)
    carrying = force_carrying(contacts["fn"], F0)
    carries = np.zeros(N, dtype=bool)
    carries[contacts["a"][carrying]] = True
    carries[contacts["b"][carrying]] = True
    n_prime = int(np.count_nonzero(carries))
    n_c = int(np.count_nonzero(carrying))
    z = 2.0 * n_c / n_prime if n_prime > 0 else 0.0
    f_cont = float(np.mean(contacts["fn"][carrying]) / F0) if n_c > 0 else 0.0
    return {"N": N, "phi": phi, "z": z, "rattler": ~carries, "F0": F0,
            "carrying": carrying, "N_c": n_c, "F_cont": f_cont}


# ---------------------------------------------------------------------------------------
# Periodic geometry


def min_image(d, L):
    """Minimum image of a separation component d in a period L."""
    return d - L * np.round(d / L)


def periodic_images(x, y, r, Lx, Ly):
    """Copies of disks that reach into the cell [0, Lx) x [0, Ly) from outside.

    Returns (index, x_image, y_image) arrays: every disk (wrapped into the cell) once, plus
    its shifted copies (by +-Lx, +-Ly and both) whose circle crosses into the cell.
    """
    x = np.mod(x, Lx)
    y = np.mod(y, Ly)
    idx, xs, ys = [np.arange(len(x))], [x], [y]
    for sx in (-1, 0, 1):
        for sy in (-1, 0, 1):
            if sx == 0 and sy == 0:
                continue
            xi, yi = x + sx * Lx, y + sy * Ly
            # Distance from the shifted centre to the cell rectangle.
            dx = np.maximum(np.maximum(0.0 - xi, xi - Lx), 0.0)
            dy = np.maximum(np.maximum(0.0 - yi, yi - Ly), 0.0)
            hit = dx * dx + dy * dy < r * r
            idx.append(np.nonzero(hit)[0])
            xs.append(xi[hit])
            ys.append(yi[hit])
    return np.concatenate(idx), np.concatenate(xs), np.concatenate(ys)


# ---------------------------------------------------------------------------------------
# Output



def cell_axes(ax, Lx, Ly):
    """Sets up axes showing the periodic cell [0, Lx] x [0, Ly]: equal aspect, no ticks, the
    cell outlined. Returns the outline patch (a clip path for what crosses the cell edge)."""
    from matplotlib.patches import Rectangle
    ax.set_xlim(-0.01 * Lx, 1.01 * Lx)
    ax.set_ylim(-0.01 * Ly, 1.01 * Ly)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    for s in ax.spines.values():
        s.set_visible(False)
    cell = Rectangle((0, 0), Lx, Ly, fill=False, edgecolor="0.3", linewidth=0.8, zorder=5)
    ax.add_patch(cell)
    return cell

def default_out(directory, name):
    return os.path.join(directory, name)


def write_file_atomic(out, write, binary=False):
    """Write out atomically: write(f) fills a temporary file beside out (mode 0666 & ~umask,
    fsync'ed), which then replaces out; UserError if any step fails, no temporary left."""
    out_dir = os.path.dirname(os.path.abspath(out))
    if not os.path.isdir(out_dir):
        raise UserError(f"{out}: output directory {out_dir} does not exist")
    fd, tmp = tempfile.mkstemp(dir=out_dir, prefix="." + os.path.basename(out) + ".",
                               suffix=".tmp")
    try:
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp creates 0600; give the usual permissions
        with (os.fdopen(fd, "wb") if binary
              else os.fdopen(fd, "w", encoding="utf-8", newline="")) as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, out)
    except OSError as e:
        raise UserError(f"{out}: cannot write: {e.strerror or e}") from None
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def csv_field(v):
    """Full precision (repr) for floats, empty for NaN or None."""
    if v is None:
        return ""
    if isinstance(v, float):
        return "" if math.isnan(v) else repr(v)
    return v


def csv_text(rows, columns):
    """rows (dicts) as CSV text with a header of columns, floats at full precision."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(columns)
    for r in rows:
        w.writerow([csv_field(r[c]) for c in columns])
    return buf.getvalue()


def json_value(v):
    """v with every non-finite float (NaN: no value) as None, for strict JSON."""
    if isinstance(v, float) and not math.isfinite(v):
        return None
    if isinstance(v, dict):
        return {k: json_value(x) for k, x in v.items()}
    if isinstance(v, list):
        return [json_value(x) for x in v]
    return v


def save_figure(fig, out):
    """Write fig as PNG (dpi 150) atomically (write_file_atomic) and print its path."""
    write_file_atomic(out, lambda f: fig.savefig(f, dpi=DPI, format="png"), binary=True)
    print(out)


def format_mu(mu):
    return f"{mu:g}"
