"""The lp and cd probes' fields against friction: scripts/field_cosines.py's outputs, gathered.

Usage:  /usr/bin/python3 scripts/plot_field_cosines.py DIR [DIR ...] --out OUT

Each DIR is an output directory of scripts/field_cosines.py (fields.json and fields.csv). Writes:
  OUT.png  per packing, against mu: the cosine of the lp and cd fields over the exact probes
           (median, quartiles as a bar, range as a thin line), and the median norm ratio
           |u_cd| / |u_lp|; mu = 0 is drawn at the left edge of the logarithmic axis
  OUT.md   one row per packing: N, mu, seed, probes, exact, cosine median (quartiles), range,
           the near field's cosine median (quartiles), norm ratio median
Exit codes: 0 done, 1 bad input (a directory without field_cosines' outputs).
"""

import argparse
import csv
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import unjam_plot  # noqa: E402


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dirs", nargs="+", metavar="DIR")
    ap.add_argument("--out", required=True, help="output path without extension")
    return ap.parse_args(argv)


def read_dir(d):
    s = unjam_plot.read_json(os.path.join(d, "fields.json"))
    for key in ("N", "mu", "seed", "probes", "exact"):
        if key not in s:
            raise unjam_plot.UserError(f"{d}/fields.json has no '{key}': not an output of field_cosines.py")
    path = os.path.join(d, "fields.csv")
    try:
        with open(path, newline="") as f:
            rows = [r for r in csv.DictReader(f) if r.get("exact") == "1"]
    except OSError as e:
        raise unjam_plot.UserError(f"cannot read {path}: {e}")
    cos = np.array([float(r["cosine"]) for r in rows if r["cosine"] not in ("", "nan")])
    ratio = np.array([float(r["norm_ratio"]) for r in rows if r["norm_ratio"] != ""])
    near = np.array([float(r["cosine_near"]) for r in rows if r.get("cosine_near", "") not in ("", "nan")])
    return {"dir": d, "N": s["N"], "mu": float(s["mu"]), "seed": s["seed"], "probes": s["probes"],
            "exact": s["exact"], "cos": cos, "ratio": ratio, "near": near,
            "near_diameters": s.get("near_diameters")}


def main(argv):
    a = parse(argv)
    packs = sorted((read_dir(d) for d in a.dirs), key=lambda p: (p["N"], p["mu"], p["seed"]))
    lines = ["| N | mu | seed | probes | exact | cosine median (quartiles) | range | "
             "near field: cosine median (quartiles) | norm ratio, median |",
             "|---|---|---|---|---|---|---|---|---|"]
    for p in packs:
        if len(p["cos"]):
            q = np.quantile(p["cos"], [0.0, 0.25, 0.5, 0.75, 1.0])
            cos = f"{q[2]:.3f} ({q[1]:.3f}–{q[3]:.3f}) | {q[0]:.3f}–{q[4]:.3f}"
        else:
            cos = "– | –"
        ratio = f"{np.median(p['ratio']):.3f}" if len(p["ratio"]) else "–"
        if len(p["near"]):
            qn = np.quantile(p["near"], [0.25, 0.5, 0.75])
            near = f"{qn[1]:.3f} ({qn[0]:.3f}–{qn[2]:.3f}), {p['near_diameters']:g} diameters"
        else:
            near = "–"
        lines.append(f"| {p['N']} | {p['mu']:g} | {p['seed']} | {p['probes']} | {p['exact']} | {cos} | {near} | {ratio} |")
    unjam_plot.write_file_atomic(a.out + ".md", lambda f: f.write(
        "The lp and cd probes' fields (scripts/field_cosines.py), exact probes only; "
        "norm ratio |u_cd| / |u_lp|\n\n" + "\n".join(lines) + "\n"))

    import matplotlib.pyplot as plt
    positive = [p["mu"] for p in packs if p["mu"] > 0]
    mu0 = min(positive) / 3 if positive else 1e-3  # where mu = 0 is drawn
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(9.0, 3.6))
    for i, p in enumerate(packs):
        if not len(p["cos"]):
            continue
        x = (p["mu"] if p["mu"] > 0 else mu0) * (1.0 + 0.06 * (i % 3 - 1))  # seeds side by side
        q = np.quantile(p["cos"], [0.0, 0.25, 0.5, 0.75, 1.0])
        ax0.plot([x, x], [q[0], q[4]], color="0.6", lw=0.8)
        ax0.plot([x, x], [q[1], q[3]], color="C0", lw=4, solid_capstyle="butt")
        ax0.plot([x], [q[2]], "o", color="k", ms=3)
        if len(p["near"]):
            ax0.plot([x * 1.04], [np.median(p["near"])], "s", color="C3", ms=3)
        if len(p["ratio"]):
            ax1.plot([x], [np.median(p["ratio"])], "o", color="C1", ms=4)
    for ax, label in ((ax0, "cosine of the fields, lp against cd"), (ax1, "median |u_cd| / |u_lp|")):
        ax.set_xscale("log")
        ax.set_xlabel(f"mu (mu = 0 drawn at {mu0:.2g})")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    lowest = min((p["cos"].min() for p in packs if len(p["cos"])), default=0.0)
    ax0.set_ylim(min(0.0, lowest) - 0.05, 1.02)
    ax1.axhline(1.0, color="0.5", lw=0.8)
    fig.suptitle("lp field against the paper's probe (cd), exact probes: median (black), quartiles, range; "
                 "near field's median (red)", fontsize=9)
    fig.tight_layout()
    unjam_plot.save_figure(fig, a.out + ".png")
    plt.close(fig)
    print("\n".join(lines))


if __name__ == "__main__":
    unjam_plot.run_main(lambda: main(sys.argv[1:]))
