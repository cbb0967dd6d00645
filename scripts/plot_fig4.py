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
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import unjam_plot as up  # noqa: E402

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

SAMPLERS = [("hr", "hit-and-run range", "tab:blue", -0.18),
            ("walk", "random walk range", "tab:orange", 0.18)]
# Columns that may be empty: f_crit of a contact without force (no probe).
OPTIONAL = ["fn_min", "fn_max", "f_crit"] + [f"{p}_{s}" for p, *_ in SAMPLERS
                                             for s in ("min", "max")]


def force_unit(directory):
    """F0 from DIR/ensemble.json, else DIR/meta.json."""
    for name in ("ensemble.json", "meta.json"):
        path = os.path.join(directory, name)
        if os.path.exists(path):
            meta = up.read_json(path)
            if "F0" in meta:
                return up.json_number(meta, "F0", path, positive=True)
    raise up.UserError(f"no F0 in {directory}/ensemble.json or meta.json")


def read_ensemble(directory):
    """ensemble.csv by column (numpy arrays), with fn_min / fn_max from bounds.csv when absent."""
    path = os.path.join(directory, "ensemble.csv")
    if not os.path.isfile(path):
        raise up.UserError(f"no ensemble.csv in {directory} (run: unjam ensemble {directory})")
    t = up.read_csv(path, ["a", "b", "fn"], optional=OPTIONAL, text=["f_crit_method"],
                    allow_nan=OPTIONAL)
    if len(t["fn"]) == 0:
        raise up.UserError(f"{path} has no contacts")
    if "fn_min" not in t:
        bounds_path = os.path.join(directory, "bounds.csv")
        if not os.path.exists(bounds_path):
            raise up.UserError("no fn_min / fn_max in ensemble.csv and no bounds.csv")
        b = up.read_intervals(bounds_path)
        row = {(a, bb): i for i, (a, bb) in enumerate(zip(b["a"], b["b"]))}
        try:
            at = [row[(a, bb)] for a, bb in zip(t["a"], t["b"])]
        except KeyError as e:
            raise up.UserError(f"{bounds_path}: no row for contact {e.args[0]}") from None
        t["fn_min"], t["fn_max"] = b["fn_min"][at], b["fn_max"][at]
    return t


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dir", help="directory with ensemble.csv")
    parser.add_argument("--out", help="PNG to write (default DIR/fig4-ensemble.png)")
    parser.add_argument("--sort", choices=("fn", "fn_max"), default="fn",
                        help="order of the contacts along x")
    args = parser.parse_args()

    up.require_dir(args.dir)
    t = read_ensemble(args.dir)
    F0 = force_unit(args.dir)
    order = np.argsort(t[args.sort], kind="stable")
    x = np.arange(len(order))

    def column(name):
        return t[name][order] / F0

    fig, ax = plt.subplots(figsize=(10, 4.5))
    lo, hi = column("fn_min"), column("fn_max")
    ax.vlines(x, lo, hi, colors="0.55", linewidths=0.8, label="LP interval [fn_min, fn_max]")
    ax.scatter(np.concatenate([x, x]), np.concatenate([lo, hi]), marker="_", s=30, color="0.55",
               linewidths=0.8)
    for prefix, label, color, shift in SAMPLERS:
        if f"{prefix}_min" not in t:
            continue
        ax.vlines(x + shift, column(f"{prefix}_min"), column(f"{prefix}_max"), colors=color,
                  linewidths=2.2, alpha=0.8, label=label)
    ax.scatter(x, column("fn"), marker="o", s=22, facecolors="none", edgecolors="black",
               linewidths=0.9, label="original fn", zorder=3)
    if "f_crit" in t:
        methods = sorted({m for m in t.get("f_crit_method", []) if m})
        ax.scatter(x, column("f_crit"), marker="x", s=26, color="tab:red", linewidths=1.1,
                   label="F_crit (" + ", ".join(methods) + ")", zorder=4)
    ax.set_xlabel(f"contact (sorted by {args.sort})")
    ax.set_ylabel("normal force / F0")
    ax.set_xlim(-1, len(x))
    ax.set_ylim(bottom=-0.05)
    ax.legend(loc="upper left", fontsize=8, frameon=False)
    ax.set_title(f"{os.path.basename(os.path.normpath(args.dir))}: {len(x)} contacts",
                 fontsize=9)
    fig.tight_layout()
    up.save_figure(fig, args.out or up.default_out(args.dir, "fig4-ensemble.png"))
    plt.close(fig)


if __name__ == "__main__":
    up.run_main(main)
