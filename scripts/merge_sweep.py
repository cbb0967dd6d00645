"""Merge friction-sweep tables (sweep.csv) and packings into one table.

Usage:  /usr/bin/python3 scripts/merge_sweep.py TABLE.csv [--add CSV ...] [--packings DIR ...]
                                                [--out FILE]

Adds to TABLE.csv the rows of other tables with the same columns (--add, e.g. the sweep.csv of
a run at other sizes) and rows read from probed packing directories (--packings: one row per
DIR from its probe_summary.json, exactly as scripts/experiment.py writes its table; mu, N and
seed are those the summary records).  A packing is one (mu, N, seed): a row added later
replaces an earlier row of the same packing.  The rows are written in the order of the
experiment's tables (N, then mu, then seed), to --out (default: TABLE.csv in place).
Nothing is recomputed: every number is copied from its source.
"""

import argparse
import csv
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import sweep_table  # noqa: E402
from experiment_stages import summary_row, write_table  # noqa: E402
from stage_runner import read_json  # noqa: E402


def read_rows(path):
    with open(path, newline="") as f:
        r = csv.DictReader(f)
        if r.fieldnames != sweep_table.COLUMNS:
            raise SystemExit(f"merge_sweep: {path} has the columns {r.fieldnames}, not "
                             f"{sweep_table.COLUMNS}")
        return list(r)


def packing_row(d):
    s = read_json(os.path.join(d, "probe_summary.json"))
    if not s or not all(k in s for k in ("mu", "N", "seed")):
        raise SystemExit(f"merge_sweep: {d}/probe_summary.json is missing or has no mu, N, seed")
    return summary_row(d, float(s["mu"]), int(s["N"]), int(s["seed"]))


def key(row):
    return (int(sweep_table.number(row["N"])),
            round(sweep_table.number(row["mu"]), sweep_table.MU_DIGITS),
            int(sweep_table.number(row["seed"])))


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=__doc__.split("\n\n", 2)[2])
    p.add_argument("table", metavar="TABLE.csv", help="the table to add to")
    p.add_argument("--add", metavar="CSV", nargs="+", default=[],
                   help="tables whose rows are added (same columns)")
    p.add_argument("--packings", metavar="DIR", nargs="+", default=[],
                   help="probed packing directories, one row each from probe_summary.json")
    p.add_argument("--out", metavar="FILE", help="output table (default: TABLE.csv in place)")
    args = p.parse_args(argv)
    rows = {}
    for path in [args.table] + args.add:
        for r in read_rows(path):
            rows[key(r)] = r
    for d in args.packings:
        r = packing_row(d)
        rows[key(r)] = r
    out = args.out or args.table
    write_table(out, [rows[k] for k in sorted(rows)])
    print(f"merge_sweep: {len(rows)} rows -> {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
