"""The paper's Fig. 1: the mean displacement field of the probes in the contact frame.

Usage:  /usr/bin/python3 scripts/plot_response_field.py DIR [--diameter D] [--packing PDIR]
                                                       [--style stream|arrows] [--linear]
                                                       [--extent E] [--out FILE]

Reads DIR/response_field.csv (x, y, ux, uy, count: bin centres of a square grid in the
contact frame, x along the probed contact's normal = the direction of separation, origin at
the contact point; the mean displacement per bin in units of the gap g; count = samples,
0 = empty bin).  Draws the magnitude |<u>|/g as a colour map (log scale unless --linear),
with streamlines (default) or direction arrows on top, empty bins masked (white).  Axes are
in units of the mean grain diameter <2R>: --diameter D, else from particles.csv in PDIR
(default DIR), else 'mean_diameter' in DIR/probe_summary.json; without any of these the
axes stay in simulation length units.  The two probed grains are sketched as dashed circles
of mean size on either side of the origin.  DIR/probe_summary.json, when present, supplies
N, mu and the number of probes for the title.

Writes DIR/fig1-field.png (or --out FILE), PNG at 150 dpi.
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import unjam_plot as up  # noqa: E402

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import LogNorm, Normalize  # noqa: E402
from matplotlib.patches import Circle  # noqa: E402


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="Writes DIR/fig1-field.png unless --out is given.")
    p.add_argument("dir", metavar="DIR", help="probe output directory with response_field.csv")
    p.add_argument("--diameter", type=float, metavar="D",
                   help="mean grain diameter <2R> in simulation units (length unit of the axes)")
    p.add_argument("--packing", metavar="PDIR",
                   help="packing directory whose particles.csv gives <2R> (default DIR)")
    p.add_argument("--style", choices=["stream", "arrows"], default="stream",
                   help="streamlines (default) or unit arrows for the direction of the field")
    p.add_argument("--linear", action="store_true", help="linear colour scale for |u|/g")
    p.add_argument("--extent", type=float, metavar="E",
                   help="show |x|, |y| <= E (in the axis unit); default: the whole grid")
    p.add_argument("--out", metavar="FILE", help="output PNG (default DIR/fig1-field.png)")
    args = p.parse_args(argv)
    if args.diameter is not None and not args.diameter > 0:
        p.error("--diameter must be > 0")
    if args.extent is not None and not args.extent > 0:
        p.error("--extent must be > 0")
    return args


def grid_axis(values, path, name):
    """Sorted distinct bin centres along one axis; checks that they are evenly spaced."""
    c = np.unique(values)
    if len(c) < 2:
        raise up.UserError(f"{path}: column '{name}' has fewer than 2 distinct bin centres")
    step = np.diff(c)
    h = float(np.median(step))
    if np.any(np.abs(step - h) > 1e-6 * h):
        raise up.UserError(f"{path}: column '{name}' is not an evenly spaced grid of bin centres")
    return c, h


def mean_diameter(args, summary):
    if args.diameter is not None:
        return args.diameter, True
    pdir = args.packing or args.dir
    if os.path.exists(os.path.join(pdir, "particles.csv")):
        P = up.read_particles(pdir)
        return 2.0 * float(np.mean(P["radius"])), True
    if args.packing:
        raise up.UserError(f"{os.path.join(pdir, 'particles.csv')}: file not found")
    if summary is not None and "mean_diameter" in summary:
        return up.json_number(summary, "mean_diameter", "probe_summary.json", positive=True), True
    up.warn("no --diameter, particles.csv or 'mean_diameter' in probe_summary.json: "
            "axes in simulation length units")
    return 1.0, False


def main(argv=None):
    args = parse_args(argv)
    d = up.require_dir(args.dir)
    path = os.path.join(d, "response_field.csv")
    # Empty bins (count 0) have ux = uy = NaN.
    t = up.read_csv(path, ["x", "y", "ux", "uy", "count"], allow_nan=["ux", "uy"], min_rows=4)
    if np.any(t["count"] < 0):
        raise up.UserError(f"{path}: column 'count' has a negative value")
    summary_path = os.path.join(d, "probe_summary.json")
    summary = up.read_json(summary_path) if os.path.exists(summary_path) else None

    xs, hx = grid_axis(t["x"], path, "x")
    ys, hy = grid_axis(t["y"], path, "y")
    nx, ny = len(xs), len(ys)
    if len(t["x"]) != nx * ny:
        raise up.UserError(f"{path}: {len(t['x'])} rows do not fill a {nx} x {ny} grid")
    ix = np.searchsorted(xs, t["x"])
    iy = np.searchsorted(ys, t["y"])
    if len(set(zip(ix.tolist(), iy.tolist()))) != nx * ny:
        raise up.UserError(f"{path}: a bin appears twice")
    UX = np.full((ny, nx), np.nan)
    UY = np.full((ny, nx), np.nan)
    CNT = np.zeros((ny, nx))
    UX[iy, ix], UY[iy, ix], CNT[iy, ix] = t["ux"], t["uy"], t["count"]
    empty = CNT <= 0
    if np.all(empty):
        raise up.UserError(f"{path}: every bin is empty (count = 0)")
    UX[empty] = np.nan
    UY[empty] = np.nan
    MAG = np.hypot(UX, UY)

    D, in_diam = mean_diameter(args, summary)
    X, Y = xs / D, ys / D
    hX, hY = hx / D, hy / D
    xe = np.concatenate([X - hX / 2, [X[-1] + hX / 2]])
    ye = np.concatenate([Y - hY / 2, [Y[-1] + hY / 2]])

    fig, ax = plt.subplots(figsize=(7.6, 6.4))
    mag_m = np.ma.masked_invalid(MAG)
    positive = MAG[np.isfinite(MAG) & (MAG > 0)]
    if args.linear or len(positive) == 0:
        norm = Normalize(vmin=0.0, vmax=float(np.nanmax(MAG)) or 1.0)
    else:
        vmax = float(positive.max())
        vmin = max(float(positive.min()), vmax * 1e-4)
        norm = LogNorm(vmin=vmin, vmax=vmax)
        mag_m = np.ma.masked_where(~np.isfinite(MAG) | (MAG <= 0), MAG)
        mag_m = np.ma.clip(mag_m, vmin, vmax)
    cmap = plt.get_cmap("viridis").copy()
    cmap.set_bad("white")
    mesh = ax.pcolormesh(xe, ye, mag_m, cmap=cmap, norm=norm, shading="flat", rasterized=True)
    cb = fig.colorbar(mesh, ax=ax, pad=0.02)
    cb.set_label(r"$|\langle u\rangle| / g$")

    if args.style == "stream":
        ax.streamplot(X, Y, np.ma.masked_invalid(UX), np.ma.masked_invalid(UY), color="white",
                      linewidth=0.7, density=1.6, arrowsize=0.9)
    else:
        step = max(1, int(round(max(nx, ny) / 28)))
        sl = (slice(step // 2, None, step), slice(step // 2, None, step))
        with np.errstate(invalid="ignore", divide="ignore"):
            U, V = UX / MAG, UY / MAG
        XX, YY = np.meshgrid(X, Y)
        ax.quiver(XX[sl], YY[sl], U[sl], V[sl], color="white", angles="xy", pivot="middle",
                  scale_units="xy", scale=1.0 / (0.8 * step * hX), width=0.003)

    # The probed pair: grain a at (-R, 0), grain b at (+R, 0) (mean size), sketched when the unit is <2R>.
    if in_diam:
        for cx in (-0.5, 0.5):
            ax.add_patch(Circle((cx, 0.0), 0.5, fill=False, edgecolor="red", linestyle="--",
                                linewidth=1.0))
    ax.plot([0], [0], marker="+", color="red", markersize=9, markeredgewidth=1.5)

    unit = r"\langle 2R\rangle" if in_diam else "R_{max}"
    ax.set_xlabel(f"$x / {unit}$  (along the contact normal: separation)")
    ax.set_ylabel(f"$y / {unit}$")
    ax.set_aspect("equal")
    if args.extent:
        ax.set_xlim(-args.extent, args.extent)
        ax.set_ylim(-args.extent, args.extent)
    else:
        ax.set_xlim(xe[0], xe[-1])
        ax.set_ylim(ye[0], ye[-1])

    title = "Mean displacement field in the contact frame"
    if summary is not None:
        parts = []
        for key, fmt in (("N", "N = {:g}"), ("mu", r"$\mu$ = {:g}"), ("probes", "{:g} probes")):
            v = up.json_number(summary, key, summary_path, required=False)
            if v is not None:
                parts.append(fmt.format(v))
        if parts:
            title += "\n" + ",  ".join(parts)
    ax.set_title(title, fontsize=10)
    fig.tight_layout()

    out = args.out or up.default_out(d, "fig1-field.png")
    up.save_figure(fig, out)
    plt.close(fig)


if __name__ == "__main__":
    up.run_main(main)
