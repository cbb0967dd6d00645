"""The paper's Fig. 3: packing and response quantities against the friction coefficient mu.

Usage:  /usr/bin/python3 scripts/plot_friction_sweep.py TABLE.csv [--fixed TABLE2.csv]
                                                       [--linthresh T] [--out FILE]

TABLE.csv has one row per packing with the columns
    mu,N,seed,phi,z,F_cont_over_F0,F_crit_over_F_cont,alpha,alpha_err
(other columns are ignored; alpha and alpha_err may be empty or 'nan' where the fit failed).
Rows with the same mu and N are averaged; error bars are the standard deviation over the
seeds (for alpha with a single seed: that packing's alpha_err).  Each N is a series of its own
colour.

  (a) <F_cont>/F0 (full circles, left axis) and z (open circles, right axis) against mu;
  (b) <F_crit>/<F_cont> (full circles, left axis, solid reference line at 1) and alpha
      (open circles with error bars, right axis, dashed reference line at 1) against mu;
  (c) only with --fixed TABLE2.csv (same columns: one packing whose friction was changed):
      <F_crit>/<F_cont> of the new packings (full squares) and of the fixed packing (open
      squares), the paper's inset.

mu spans 0 ... 1, so the mu axis is symlog: logarithmic above --linthresh (default 0.01)
and linear below it, which puts mu = 0 on the axis.

Writes --out FILE (default: friction-sweep.png beside TABLE.csv), PNG at 150 dpi.
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import sweep_table  # noqa: E402
import unjam_plot as up  # noqa: E402

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.ticker import FixedLocator, FuncFormatter, NullLocator  # noqa: E402

COLUMNS = sweep_table.COLUMNS
RESULTS = sweep_table.RESULTS


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="Writes friction-sweep.png beside TABLE.csv unless --out is given.")
    p.add_argument("table", metavar="TABLE.csv", help="one row per packing (columns: see above)")
    p.add_argument("--fixed", metavar="TABLE2.csv",
                   help="the same columns for one packing whose friction was varied (panel c)")
    p.add_argument("--linthresh", type=float, default=0.01, metavar="T",
                   help="linear range [0, T] of the symlog mu axis (default 0.01)")
    p.add_argument("--out", metavar="FILE", help="output PNG (default friction-sweep.png beside TABLE)")
    args = p.parse_args(argv)
    if not args.linthresh > 0:
        p.error("--linthresh must be > 0")
    return args


def read_table(path):
    t = up.read_csv(path, COLUMNS, allow_nan=RESULTS, min_rows=1)
    if np.any(t["mu"] < 0):
        raise up.UserError(f"{path}: column 'mu' has a negative value")
    if np.any(t["N"] <= 0) or np.any(t["N"] != np.round(t["N"])):
        raise up.UserError(f"{path}: column 'N' must hold positive integers")
    return t


def aggregate(t):
    """{N: {"mu": [...], "<col>": mean, "<col>_std": std over seeds, "n": count}} from the
    shared aggregation (sweep_table.aggregate); alpha_std is alpha's error bar there."""
    rows = [{c: t[c][i] for c in COLUMNS} for i in range(len(t["mu"]))]
    groups = sweep_table.aggregate(rows)
    series = {}
    for N in sorted({n for _, n in groups}):
        keys = [k for k in groups if k[1] == N]
        s = {"mu": np.array([mu for mu, _ in keys]),
             "n": np.array([groups[k]["seeds"] for k in keys], dtype=int)}
        for c in RESULTS:
            s[c] = np.array([groups[k][c][0] for k in keys])
            s[c + "_std"] = np.array([groups[k][c][1] for k in keys])
        s["alpha_std"] = np.array([groups[k]["alpha_bar"] for k in keys])
        series[N] = s
    return series


def setup_mu_axis(ax, mu_max, linthresh):
    ax.set_xscale("symlog", linthresh=linthresh, linscale=0.6)
    hi = max(mu_max, linthresh) * 1.6
    ax.set_xlim(-0.25 * linthresh, hi)
    ticks = [0.0] + [10.0 ** k for k in range(int(np.floor(np.log10(linthresh))), 3)
                     if 10.0 ** k <= hi]
    ax.xaxis.set_major_locator(FixedLocator(ticks))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    minor = [m * 10.0 ** k for k in range(int(np.floor(np.log10(linthresh))), 3)
             for m in range(2, 10) if m * 10.0 ** k <= hi]
    ax.xaxis.set_minor_locator(FixedLocator(minor) if minor else NullLocator())
    ax.axvspan(-0.25 * linthresh, linthresh, color="0.93", zorder=0, lw=0)


def errorbar(ax, x, y, e, colour, marker, filled, **kw):
    ok = np.isfinite(y)
    if not np.any(ok):
        return None
    e = np.where(np.isfinite(e), e, 0.0)[ok]
    kw.setdefault("linestyle", "-")
    return ax.errorbar(x[ok], y[ok], yerr=e if np.any(e > 0) else None, fmt=marker,
                       color=colour, mfc=colour if filled else "white", mec=colour, ms=6,
                       lw=1.0, capsize=2.5, elinewidth=0.8, **kw)


def main(argv=None):
    args = parse_args(argv)
    table = read_table(args.table)
    fixed = read_table(args.fixed) if args.fixed else None
    series = aggregate(table)
    fixed_series = aggregate(fixed) if fixed is not None else None
    mu_max = float(np.max(table["mu"]))
    if fixed is not None:
        mu_max = max(mu_max, float(np.max(fixed["mu"])))

    n_panels = 3 if fixed is not None else 2
    fig, axes = plt.subplots(n_panels, 1, figsize=(6.6, 3.3 * n_panels), sharex=True)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    colour_of = {N: colours[i % len(colours)] for i, N in enumerate(sorted(series))}

    ax_a = axes[0]
    ax_a2 = ax_a.twinx()
    ax_b = axes[1]
    ax_b2 = ax_b.twinx()
    for N, s in sorted(series.items()):
        c = colour_of[N]
        errorbar(ax_a, s["mu"], s["F_cont_over_F0"], s["F_cont_over_F0_std"], c, "o", True)
        errorbar(ax_a2, s["mu"], s["z"], s["z_std"], c, "o", False, linestyle="--")
        errorbar(ax_b, s["mu"], s["F_crit_over_F_cont"], s["F_crit_over_F_cont_std"], c, "o", True)
        errorbar(ax_b2, s["mu"], s["alpha"], s["alpha_std"], c, "o", False, linestyle="--")
    ax_b.axhline(1.0, color="0.3", lw=0.9, ls="-", zorder=1)
    ax_b2.axhline(1.0, color="0.3", lw=0.9, ls="--", zorder=1)

    ax_a.set_ylabel(r"$\langle F_{cont}\rangle / F_0$  (full)")
    ax_a2.set_ylabel(r"$z$  (open)")
    ax_b.set_ylabel(r"$\langle F_{crit}\rangle / \langle F_{cont}\rangle$  (full)")
    ax_b2.set_ylabel(r"$\alpha$  (open)")
    ax_a.set_title("(a)", loc="left", fontsize=9, fontweight="bold")
    ax_b.set_title("(b)", loc="left", fontsize=9, fontweight="bold")

    handles = [Line2D([], [], color=colour_of[N], marker="o", ls="-", label=f"N = {N}")
               for N in sorted(series)]
    handles += [Line2D([], [], color="0.3", marker="o", ls="-", label="full: left axis"),
                Line2D([], [], color="0.3", marker="o", mfc="white", ls="--", label="open: right axis")]
    height = fig.get_size_inches()[1]
    # One row of legend up to 5 entries (3 sizes); more sizes wrap into two rows, which the
    # layout below makes room for.
    ncol = len(handles) if len(handles) <= 5 else (len(handles) + 1) // 2
    legend_rows = (len(handles) + ncol - 1) // ncol
    fig.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 1 - 0.3 / height),
               ncol=ncol, fontsize=8, frameon=False, handlelength=2.2)

    if fixed_series is not None:
        ax_c = axes[2]
        for N, s in sorted(series.items()):
            errorbar(ax_c, s["mu"], s["F_crit_over_F_cont"], s["F_crit_over_F_cont_std"],
                     colour_of[N], "s", True, label=f"new packing per $\\mu$, N = {N}")
        fc = ["#333333", "#8c564b", "#e377c2", "#7f7f7f"]
        for i, (N, s) in enumerate(sorted(fixed_series.items())):
            errorbar(ax_c, s["mu"], s["F_crit_over_F_cont"], s["F_crit_over_F_cont_std"],
                     fc[i % len(fc)], "s", False, linestyle="--",
                     label=f"fixed packing, N = {N}")
        ax_c.axhline(1.0, color="0.3", lw=0.9, ls="-", zorder=1)
        ax_c.set_ylabel(r"$\langle F_{crit}\rangle / \langle F_{cont}\rangle$")
        ax_c.set_title("(c)", loc="left", fontsize=9, fontweight="bold")
        ax_c.legend(fontsize=7, loc="best", framealpha=0.8)

    for ax in axes:
        setup_mu_axis(ax, mu_max, args.linthresh)
        ax.grid(True, which="major", axis="x", alpha=0.3)
    axes[-1].set_xlabel(rf"$\mu$  (symlog axis: linear below {args.linthresh:g})")
    fig.suptitle("Friction dependence of the packings and of their response", fontsize=10,
                 y=1 - 0.08 / height)
    fig.tight_layout(rect=(0, 0, 1, 1 - (0.4 + 0.2 * (legend_rows - 1)) / height))

    out = args.out or os.path.join(os.path.dirname(os.path.abspath(args.table)), "friction-sweep.png")
    up.save_figure(fig, out)
    plt.close(fig)


if __name__ == "__main__":
    up.run_main(main)
