"""The lp and cd probes' fields against friction: scripts/field_cosines.py's outputs, gathered.

Usage:  /usr/bin/python3 scripts/plot_field_cosines.py DIR [DIR ...] --out OUT

Each DIR is an output directory of scripts/field_cosines.py (its fields.json). Writes:
  OUT.png  per packing, against mu: the cosine of the lp and cd fields over the exact probes
           (median, quartiles as a bar, range as a thin line), and the median norm ratio
           |u_cd| / |u_lp|; mu = 0 is drawn at the left edge of the logarithmic axis
  OUT.md   one row per packing: N, mu, seed, probes, exact, cosine median (quartiles), range,
           the near field's cosine median (quartiles), norm ratio median
Exit codes: 0 done, 1 bad input (a directory without field_cosines' outputs).
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import unjam_plot  # noqa: E402


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dirs", nargs="+", metavar="DIR")
    ap.add_argument("--out", required=True, help="output path without extension")
    return ap.parse_args(argv)


def read_dir(d):
    """fields.json of one field_cosines.py output: the packing and its quantiles over the exact
    probes (min, q1, median, q3, max; null where no probe is exact)."""
    s = unjam_plot.read_json(os.path.join(d, "fields.json"))
    for key in ("N", "mu", "seed", "probes", "exact", "cosine", "cosine_near", "norm_ratio"):
        if key not in s:
            raise unjam_plot.UserError(f"{d}/fields.json has no '{key}': not an output of field_cosines.py")
    return {"N": s["N"], "mu": float(s["mu"]), "seed": s["seed"], "probes": s["probes"], "exact": s["exact"],
            "cos": s["cosine"], "near": s["cosine_near"], "ratio": s["norm_ratio"],
            "near_diameters": s.get("near_diameters")}


def main(argv):
    a = parse(argv)
    packs = sorted((read_dir(d) for d in a.dirs), key=lambda p: (p["N"], p["mu"], p["seed"]))
    lines = ["| N | mu | seed | probes | exact | cosine median (quartiles) | range | "
             "near field: cosine median (quartiles) | norm ratio, median |",
             "|---|---|---|---|---|---|---|---|---|"]
    for p in packs:
        q, qn, r = p["cos"], p["near"], p["ratio"]
        cos = f"{q['median']:.3f} ({q['q1']:.3f}–{q['q3']:.3f}) | {q['min']:.3f}–{q['max']:.3f}" if q else "– | –"
        near = (f"{qn['median']:.3f} ({qn['q1']:.3f}–{qn['q3']:.3f}), {p['near_diameters']:g} diameters"
                if qn else "–")
        ratio = f"{r['median']:.3f}" if r else "–"
        lines.append(f"| {p['N']} | {p['mu']:g} | {p['seed']} | {p['probes']} | {p['exact']} | {cos} | {near} | {ratio} |")
    unjam_plot.write_file_atomic(a.out + ".md", lambda f: f.write(
        "The lp and cd probes' fields (scripts/field_cosines.py), exact probes only; "
        "norm ratio |u_cd| / |u_lp|\n\n" + "\n".join(lines) + "\n"))

    import matplotlib.pyplot as plt
    positive = [p["mu"] for p in packs if p["mu"] > 0]
    mu0 = min(positive) / 3 if positive else 1e-3  # where mu = 0 is drawn
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(9.0, 3.6))
    # One colour per N (red is the near field's); the packings of one mu side by side, in the
    # order of N and seed.
    sizes = sorted({p["N"] for p in packs})
    palette = ["C0", "C2", "C4", "C1", "C5", "C6", "C8", "C9"]
    colour = {n: palette[k % len(palette)] for k, n in enumerate(sizes)}
    at_mu = {}
    for p in packs:
        at_mu.setdefault(p["mu"], []).append(p)
    for group in at_mu.values():
        for j, p in enumerate(group):
            q = p["cos"]
            if not q:
                continue
            x = (p["mu"] if p["mu"] > 0 else mu0) * (1.0 + 0.08 * (j - (len(group) - 1) / 2))
            ax0.plot([x, x], [q["min"], q["max"]], color="0.6", lw=0.8)
            ax0.plot([x, x], [q["q1"], q["q3"]], color=colour[p["N"]], lw=4, solid_capstyle="butt")
            ax0.plot([x], [q["median"]], "o", color="k", ms=3)
            if p["near"]:
                ax0.plot([x * 1.03], [p["near"]["median"]], "s", color="C3", ms=3)
            if p["ratio"]:
                ax1.plot([x], [p["ratio"]["median"]], "o", color=colour[p["N"]], ms=4)
    if len(sizes) > 1:
        for n in sizes:
            ax1.plot([], [], "o", color=colour[n], label=f"N = {n}")
        ax1.legend(fontsize=8)
    for ax, label in ((ax0, "cosine of the fields, lp against cd"), (ax1, "median |u_cd| / |u_lp|")):
        ax.set_xscale("log")
        ax.set_xlabel(f"mu (mu = 0 drawn at {mu0:.2g})")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    lowest = min((p["cos"]["min"] for p in packs if p["cos"]), default=0.0)
    ax0.set_ylim(min(0.0, lowest) - 0.05, 1.02)
    ax1.axhline(1.0, color="0.5", lw=0.8)
    fig.suptitle("lp field against the paper's probe (cd), exact probes: median (black), quartiles "
                 "(coloured by N), range; near field's median (red)", fontsize=9)
    fig.tight_layout()
    unjam_plot.save_figure(fig, a.out + ".png")
    plt.close(fig)
    print("\n".join(lines))


if __name__ == "__main__":
    unjam_plot.run_main(lambda: main(sys.argv[1:]))
