#!/usr/bin/python3
"""The paper's Fig. 3 by its own probe and by the stand-in: <F_crit>/<F_cont> and alpha against
mu, by the exact probe step (cd) and by the LP maximum (lp) on the same contacts.

Usage:  /usr/bin/python3 scripts/plot_exact_sweep.py TABLE.csv [--out FILE] [--title TEXT]

TABLE.csv has one row per packing with the columns
    mu,N,seed,F_crit_over_F_cont_lp,F_crit_over_F_cont_cd
and optionally F_crit_over_F_cont_lp_err, F_crit_over_F_cont_cd_err (the standard errors of the
means over the sampled contacts, compare_probes.py), alpha_lp, alpha_cd (empty or 'nan' where
the fit failed) and alpha_lp_err, alpha_cd_err (other columns are ignored): the experiment's
exact-probe.csv (scripts/experiment.py --cd-sample K), compare.csv of
scripts/compare_probes.py, or docs/results/exact/summary.csv.

  (a) <F_crit>/<F_cont> by lp (open squares, dashed line) and by cd (filled circles, solid
      line), one colour per N, a marker per packing (error bars: the means' standard errors,
      where the table has them) and the lines through the means over its seeds; the line at
      1 is the paper's value at both ends of the mu range;
  (b) alpha the same way (error bars: the fits' own, where the table has them); the band is
      the paper's range 0.7-1.4.
mu spans 0 ... 1, so the mu axis is symlog, linear below 0.01 (mu = 0 on the axis).

Writes --out FILE (default: exact-sweep.png beside TABLE.csv), PNG at 150 dpi, atomically.
Exit codes: 0 done, 1 bad input (the message is printed, no traceback), 2 a bad command line.
"""

import argparse
import math
import os
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import unjam_plot as up  # noqa: E402

REQUIRED = ["mu", "N", "seed", "F_crit_over_F_cont_lp", "F_crit_over_F_cont_cd"]
ALPHAS = ["alpha_lp", "alpha_cd", "alpha_lp_err", "alpha_cd_err"]
# Optional columns, NaN where absent or empty: the fits of alpha and the means' standard errors.
OPTIONAL = ALPHAS + ["F_crit_over_F_cont_lp_err", "F_crit_over_F_cont_cd_err"]
# The paper's range of alpha (docs/results/README.md, "Where it does not agree").
PAPER_ALPHA = (0.7, 1.4)


def friction_figure(pairs, title=None):
    """<F_crit>/<F_cont> and alpha by both methods against mu, one colour per N: each packing
    a marker (lp open, cd filled), the lines through the means over its seeds. pairs: dicts
    with mu, N and the columns of REQUIRED and OPTIONAL (NaN where absent)."""
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(9.6, 4.0))
    sizes = sorted({p["N"] for p in pairs}, key=lambda n: (n is None, n or 0))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    panels = ((axes[0], "F_crit_over_F_cont_{}", "F_crit_over_F_cont_{}_err", "<F_crit> / <F_cont>"),
              (axes[1], "alpha_{}", "alpha_{}_err", "alpha  (d(r) ~ r^-alpha)"))
    for i, n in enumerate(sizes):
        group = [p for p in pairs if p["N"] == n and math.isfinite(p["mu"])]
        colour = colours[i % len(colours)]
        for ax, key, err, _ in panels:
            for m, marker, face in (("lp", "s", "none"), ("cd", "o", colour)):
                pts = [(p["mu"], p[key.format(m)], p.get(err.format(m), math.nan) if err else math.nan)
                       for p in group if math.isfinite(p[key.format(m)])]
                if not pts:
                    continue
                ax.errorbar([x for x, _, _ in pts], [y for _, y, _ in pts],
                            yerr=[e if math.isfinite(e) else 0.0 for _, _, e in pts],
                            fmt=marker, mfc=face, mec=colour, ecolor=colour, ms=5,
                            linestyle="none")
                mus = sorted({x for x, _, _ in pts})
                means = [statistics.fmean(y for x, y, _ in pts if x == mu) for mu in mus]
                ax.plot(mus, means, color=colour, linestyle="--" if m == "lp" else "-",
                        linewidth=1.0, label=f"{m}, N = {n}" if n is not None else m)
    for ax, _, _, ylabel in panels:
        ax.set_xscale("symlog", linthresh=0.01)
        ax.set_xlim(left=-0.002)  # the mu = 0 markers whole
        ax.set_xlabel("mu (linear below 0.01)")
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
    axes[0].axhline(1.0, color="0.4", linewidth=0.8)
    band = axes[1].axhspan(*PAPER_ALPHA, color="0.85", zorder=0, label="the paper's range")
    axes[0].legend(fontsize=8)
    axes[1].legend(handles=[band], fontsize=8)
    axes[0].set_title(title or "lp (open, dashed) and cd (filled, solid) on the same contacts",
                      fontsize=9)
    fig.tight_layout()
    return fig


def read_table(path):
    """The table's rows as dicts (REQUIRED and OPTIONAL, NaN where absent or empty)."""
    t = up.read_csv(path, REQUIRED, optional=OPTIONAL, allow_nan=OPTIONAL, min_rows=1)
    rows = []
    for i in range(len(t["mu"])):
        row = {c: float(t[c][i]) if c in t else math.nan for c in REQUIRED + OPTIONAL}
        if not (math.isfinite(row["mu"]) and row["mu"] >= 0):
            raise up.UserError(f"{path}: row {i + 1}: mu must be a finite number >= 0, got {row['mu']}")
        if not (math.isfinite(row["N"]) and row["N"] == int(row["N"]) and row["N"] > 0):
            raise up.UserError(f"{path}: row {i + 1}: N must be a positive integer, got {row['N']}")
        row["N"] = int(row["N"])
        rows.append(row)
    return rows


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=__doc__.split("\n\n", 2)[2])
    p.add_argument("table")
    p.add_argument("--out", help="the PNG to write (default: exact-sweep.png beside TABLE)")
    p.add_argument("--title", help="the left panel's title (default: which marker is which)")
    a = p.parse_args()
    rows = read_table(a.table)
    out = a.out or os.path.join(os.path.dirname(os.path.abspath(a.table)), "exact-sweep.png")
    up.save_figure(friction_figure(rows, a.title), out)


if __name__ == "__main__":
    up.run_main(main)
