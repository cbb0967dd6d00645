#!/usr/bin/python3
"""The paper's Fig. 4 from `unjam ensemble DIR` (docs/ensemble.md).

Per contact of the admissible set, normal forces in units of F0 = 2 R_avg P_ext:
  - the exact LP interval [fn_min, fn_max] (thin grey line with caps),
  - the sampled range [min, max] of each sampler present in ensemble.csv (hit-and-run:
    columns hr_*, the paper's random walk: walk_*) as a vertical bar,
  - the original force fn (open circle) and the critical force F_crit (cross).
x is the contact index sorted by fn (default) or by fn_max.

Reads DIR/ensemble.csv, F0 from DIR/ensemble.json (else DIR/meta.json) and, if ensemble.csv
lacks fn_min / fn_max, the intervals from DIR/bounds.csv. Writes DIR/fig4-ensemble.png
(dpi 150) or --out FILE.

    /usr/bin/python3 scripts/plot_fig4.py DIR [--out FILE] [--sort fn|fn_max]
"""
import argparse
import csv
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after the backend is chosen)


def read_rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def number(text):
    """A float, or NaN for an empty field (a contact without a probe)."""
    return float(text) if text not in ("", None) else math.nan


def force_unit(directory):
    for name in ("ensemble.json", "meta.json"):
        path = os.path.join(directory, name)
        if os.path.exists(path):
            with open(path) as f:
                meta = json.load(f)
            if "F0" in meta:
                return float(meta["F0"])
    sys.exit(f"plot_fig4: no F0 in {directory}/ensemble.json or meta.json")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dir", help="directory with ensemble.csv")
    parser.add_argument("--out", help="PNG to write (default DIR/fig4-ensemble.png)")
    parser.add_argument("--sort", choices=("fn", "fn_max"), default="fn",
                        help="order of the contacts along x")
    args = parser.parse_args()

    csv_path = os.path.join(args.dir, "ensemble.csv")
    if not os.path.isfile(csv_path):
        sys.exit(f"plot_fig4: error: no ensemble.csv in {args.dir} (run: unjam ensemble {args.dir})")
    rows = read_rows(csv_path)
    if not rows:
        sys.exit("plot_fig4: ensemble.csv has no contacts")
    if "fn_min" not in rows[0]:
        bounds_path = os.path.join(args.dir, "bounds.csv")
        if not os.path.exists(bounds_path):
            sys.exit("plot_fig4: no fn_min / fn_max in ensemble.csv and no bounds.csv")
        bounds = {(b["a"], b["b"]): b for b in read_rows(bounds_path)}
        for r in rows:
            r["fn_min"] = bounds[(r["a"], r["b"])]["fn_min"]
            r["fn_max"] = bounds[(r["a"], r["b"])]["fn_max"]
    F0 = force_unit(args.dir)
    rows.sort(key=lambda r: number(r[args.sort]))
    x = list(range(len(rows)))

    def column(name):
        return [number(r[name]) / F0 for r in rows]

    fig, ax = plt.subplots(figsize=(10, 4.5))
    lo, hi = column("fn_min"), column("fn_max")
    ax.vlines(x, lo, hi, colors="0.55", linewidths=0.8, label="LP interval [fn_min, fn_max]")
    ax.scatter(x + x, lo + hi, marker="_", s=30, color="0.55", linewidths=0.8)
    samplers = [("hr", "hit-and-run range", "tab:blue", -0.18),
                ("walk", "random walk range", "tab:orange", 0.18)]
    for prefix, label, color, shift in samplers:
        if f"{prefix}_min" not in rows[0]:
            continue
        xs = [i + shift for i in x]
        ax.vlines(xs, column(f"{prefix}_min"), column(f"{prefix}_max"), colors=color,
                  linewidths=2.2, alpha=0.8, label=label)
    ax.scatter(x, column("fn"), marker="o", s=22, facecolors="none", edgecolors="black",
               linewidths=0.9, label="original fn", zorder=3)
    if "f_crit" in rows[0]:
        methods = sorted({r["f_crit_method"] for r in rows if r["f_crit_method"]})
        ax.scatter(x, column("f_crit"), marker="x", s=26, color="tab:red", linewidths=1.1,
                   label="F_crit (" + ", ".join(methods) + ")", zorder=4)
    ax.set_xlabel(f"contact (sorted by {args.sort})")
    ax.set_ylabel("normal force / F0")
    ax.set_xlim(-1, len(rows))
    ax.set_ylim(bottom=-0.05)
    ax.legend(loc="upper left", fontsize=8, frameon=False)
    ax.set_title(f"{os.path.basename(os.path.normpath(args.dir))}: {len(rows)} contacts",
                 fontsize=9)
    fig.tight_layout()
    out = args.out or os.path.join(args.dir, "fig4-ensemble.png")
    fig.savefig(out, dpi=150)
    print(out)


if __name__ == "__main__":
    main()
