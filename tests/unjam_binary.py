"""The unjam binary the script tests drive: $UNJAM (ctest sets it to the build's own), else
build/release/unjam; tests that need it are skipped when it is missing (`requires_unjam`).
Also how they run a script of scripts/ (`run_script`), read the CSV tables it writes
(`read_rows`) and change one in place (`edit_rows`)."""

import csv
import os
import subprocess
import sys
import unittest

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
UNJAM = os.path.abspath(os.environ.get("UNJAM") or os.path.join(REPO, "build", "release", "unjam"))

requires_unjam = unittest.skipUnless(
    os.path.isfile(UNJAM) and os.access(UNJAM, os.X_OK),
    f"{UNJAM} is missing: build it first (cmake --build build/release -j2)")



def run_script(script, *args, timeout=120):
    """scripts/SCRIPT with args by this Python, from the repository root: the finished process
    (stdout and stderr captured as text)."""
    return subprocess.run([sys.executable, os.path.join(REPO, "scripts", script), *args],
                          capture_output=True, text=True, cwd=REPO, timeout=timeout)


def read_rows(path):
    """The rows of a CSV table as dicts, by its header."""
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def edit_rows(path, edit):
    """The CSV table at path changed in place: edit(rows) edits its rows (dicts, by its header)."""
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        columns, rows = reader.fieldnames, list(reader)
    edit(rows)
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=columns, lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
