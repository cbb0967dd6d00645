"""The paper's Fig. 2: d(r)/g, the mean displacement against the distance from the probe.

Usage:  /usr/bin/python3 scripts/plot_profile.py DIR [DIR ...] [--labels L [L ...]]
                                                [--no-fit] [--out FILE]

For each probe output DIR, reads DIR/response_profile.csv (r_mid, d_mean, d_sem, count:
logarithmic bins of the distance r from the probed contact, d = mean |u|/g, its standard
error) and DIR/probe_summary.json (alpha, alpha_err and the fit window fit.r_lo, fit.r_hi,
fit.log_A of d = A r^-alpha; mu and N for the default label).  Draws d(r) on log-log axes
with error bars (empty bins left out), and the fitted power law over its window as a line of
the same colour, its slope alpha +- err in the legend (a summary that records a
'fit_error' instead of alpha is drawn without the line, with a warning).  A dotted r^-1 guide (the 2D
incompressible-fluid exponent) is drawn for reference.  r is in simulation length units
(R_max = 1), as in the profile and the fit.  --no-fit draws the data only (no summary
needed).

Writes --out FILE (default: the first DIR/fig2-profile.png), PNG at 150 dpi.
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import unjam_plot as up  # noqa: E402

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.ticker import FuncFormatter, LogLocator  # noqa: E402

MARKERS = ["o", "s", "^", "D", "v", "<", ">", "p", "h", "*"]


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="Writes the first DIR/fig2-profile.png unless --out is given.")
    p.add_argument("dirs", metavar="DIR", nargs="+",
                   help="probe output directories (response_profile.csv, probe_summary.json)")
    p.add_argument("--labels", metavar="L", nargs="+",
                   help="legend labels, one per DIR (default: mu and N from probe_summary.json)")
    p.add_argument("--no-fit", action="store_true",
                   help="draw the data only, without the fitted power law")
    p.add_argument("--out", metavar="FILE", help="output PNG (default DIR/fig2-profile.png, first DIR)")
    args = p.parse_args(argv)
    if args.labels is not None and len(args.labels) != len(args.dirs):
        p.error(f"--labels: {len(args.labels)} labels for {len(args.dirs)} directories")
    return args


def read_output(d, need_fit):
    up.require_dir(d)
    path = os.path.join(d, "response_profile.csv")
    # Empty bins (count 0) have d_mean = d_sem = NaN.
    t = up.read_csv(path, ["r_mid", "d_mean", "d_sem", "count"], allow_nan=["d_mean", "d_sem"],
                    min_rows=1)
    keep = (t["count"] > 0) & (t["d_mean"] > 0) & (t["r_mid"] > 0)
    if not np.any(keep):
        raise up.UserError(f"{path}: no bin with count > 0 and d_mean > 0")
    prof = {k: v[keep] for k, v in t.items()}
    summary = None
    spath = os.path.join(d, "probe_summary.json")
    if need_fit or os.path.exists(spath):
        summary = up.read_json(spath)
        if need_fit and "alpha" not in summary and "fit_error" in summary:
            up.warn(f"{spath}: no power-law fit ({summary['fit_error']}): data only")
            need_fit = False
        if need_fit:
            fit = {"alpha": up.json_number(summary, "alpha", spath),
                   "alpha_err": up.json_number(summary, "alpha_err", spath, required=False,
                                               default=float("nan")),
                   "r_lo": up.json_number(summary, "fit.r_lo", spath, positive=True),
                   "r_hi": up.json_number(summary, "fit.r_hi", spath, positive=True),
                   "log_A": up.json_number(summary, "fit.log_A", spath)}
            if fit["r_hi"] <= fit["r_lo"]:
                raise up.UserError(f"{spath}: fit.r_hi <= fit.r_lo")
            summary["_fit"] = fit
        summary["_path"] = spath
    return prof, summary


def default_label(d, summary):
    if summary is not None:
        mu = up.json_number(summary, "mu", summary["_path"], required=False)
        N = up.json_number(summary, "N", summary["_path"], required=False)
        parts = []
        if mu is not None:
            parts.append(rf"$\mu$ = {mu:g}")
        if N is not None:
            parts.append(f"N = {N:g}")
        if parts:
            return ", ".join(parts)
    return os.path.basename(os.path.normpath(d))


def main(argv=None):
    args = parse_args(argv)
    data = [read_output(d, not args.no_fit) for d in args.dirs]

    fig, ax = plt.subplots(figsize=(6.4, 5.0))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    r_all, d_all = [], []
    for i, (d, (prof, summary)) in enumerate(zip(args.dirs, data)):
        c = colours[i % len(colours)]
        label = args.labels[i] if args.labels else default_label(d, summary)
        r, y, e = prof["r_mid"], prof["d_mean"], prof["d_sem"]
        # A log axis cannot show error bars below zero: clip the lower bar at y/100.
        lower = np.minimum(e, y * (1 - 1e-2))
        has_fit = summary is not None and "_fit" in summary
        if has_fit:
            f = summary["_fit"]
            if np.isfinite(f["alpha_err"]):
                label += rf":  $\alpha$ = {f['alpha']:.3f} $\pm$ {f['alpha_err']:.3f}"
            else:
                label += rf":  $\alpha$ = {f['alpha']:.3f}"
        ax.errorbar(r, y, yerr=[lower, e], fmt=MARKERS[i % len(MARKERS)], color=c, ms=4.5,
                    mfc="white" if i % 2 else c, capsize=2, elinewidth=0.8, label=label, zorder=3)
        if has_fit:
            rr = np.geomspace(f["r_lo"], f["r_hi"], 50)
            ax.plot(rr, np.exp(f["log_A"]) * rr ** (-f["alpha"]), "-", color=c, lw=1.8, zorder=4)
        r_all.append(r)
        d_all.append(y)

    # r^-1 guide through the geometric centre of the data.
    r_all, d_all = np.concatenate(r_all), np.concatenate(d_all)
    r0 = float(np.exp(np.mean(np.log(r_all))))
    d0 = float(np.exp(np.mean(np.log(d_all)))) * 2.0
    rr = np.geomspace(r_all.min(), r_all.max(), 20)
    ax.plot(rr, d0 * r0 / rr, ":", color="0.45", lw=1.0, label=r"$\propto r^{-1}$")

    ax.set_xscale("log")
    ax.set_yscale("log")
    y_lo = min(float(np.min(d_all)), float(np.min(d0 * r0 / rr)))
    y_hi = max(float(np.max(d_all)), float(np.max(d0 * r0 / rr)))
    for axis, span in ((ax.xaxis, r_all.max() / r_all.min()), (ax.yaxis, y_hi / y_lo)):
        # Plain numbers; over less than two decades label 2 and 5 as well.
        axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        if span < 100:
            axis.set_minor_locator(LogLocator(base=10, subs=(2.0, 5.0)))
            axis.set_minor_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.set_xlabel(r"$r$  (distance from the probed contact, units of $R_{max}$)")
    ax.set_ylabel(r"$d / g$")
    ax.set_title("Mean displacement against distance from the perturbed contact", fontsize=10)
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()

    out = args.out or up.default_out(args.dirs[0], "fig2-profile.png")
    up.save_figure(fig, out)
    plt.close(fig)


if __name__ == "__main__":
    up.run_main(main)
