"""Draw a packing with its force chains.

Usage:  /usr/bin/python3 scripts/plot_packing.py DIR [--out FILE]

Reads DIR/meta.json (cell, P_ext, mu), DIR/particles.csv (id, x, y, radius) and
DIR/contacts.csv (a, b, lx, ly, fn).  Disks are drawn as light circles, with the periodic
images of those that cross the cell edge; rattlers (grains without a force-carrying
contact, fn > 1e-9 F0) in another colour.  Each force-carrying contact is a line from the
centre of a along the branch vector l = r_b - r_a (minimum image), drawn again from the
other end when it crosses the cell edge, with a width proportional to fn.  The title gives
N, mu, phi, z (rattlers excluded) and <F_cont>/F0 with F0 = 2 R_avg P_ext.

Writes DIR/packing.png (or --out FILE), PNG at 150 dpi.
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import unjam_plot as up  # noqa: E402

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import EllipseCollection, LineCollection  # noqa: E402

DISK_FACE = "#dce6f2"
DISK_EDGE = "#7f93ab"
RATTLER_FACE = "#f6d7b0"
RATTLER_EDGE = "#d08a3c"
CHAIN_COLOUR = "#8b1a1a"


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="Writes DIR/packing.png unless --out is given.")
    p.add_argument("dir", metavar="DIR", help="packing directory (meta.json, particles.csv, contacts.csv)")
    p.add_argument("--out", metavar="FILE", help="output PNG (default DIR/packing.png)")
    p.add_argument("--max-width", type=float, default=None, metavar="PT",
                   help="line width (points) of the largest force (default: from the disk size)")
    return p.parse_args(argv)


def disk_collection(ax, x, y, r, face, edge, lw, transform):
    d = 2.0 * np.asarray(r)
    coll = EllipseCollection(d, d, np.zeros_like(d), units="xy", offsets=np.column_stack([x, y]),
                             offset_transform=transform, facecolors=face, edgecolors=edge,
                             linewidths=lw)
    ax.add_collection(coll)
    return coll


def main(argv=None):
    args = parse_args(argv)
    d = up.require_dir(args.dir)
    meta = up.read_meta(d)
    P = up.read_particles(d)
    N = len(P["x"])
    C = up.read_contacts(d, N)
    Lx, Ly = meta["Lx"], meta["Ly"]
    st = up.packing_stats(meta, P, C)

    size = 7.0
    aspect = Ly / Lx
    height = size * aspect + 0.6
    fig, ax = plt.subplots(figsize=(size, height))
    fig.subplots_adjust(left=0.03, right=0.97, bottom=0.2 / height, top=1 - 0.5 / height)
    cell = up.cell_axes(ax, Lx, Ly)

    # Points per length unit, for line widths that follow the disk size.
    fig.canvas.draw()
    pts_per_unit = ax.transData.transform((1, 0))[0] - ax.transData.transform((0, 0))[0]
    pts_per_unit *= 72.0 / fig.dpi
    R_avg = float(np.mean(P["radius"]))
    edge_lw = float(np.clip(0.04 * R_avg * pts_per_unit, 0.1, 0.8))

    idx, xi, yi = up.periodic_images(P["x"], P["y"], P["radius"], Lx, Ly)
    ratt = st["rattler"][idx]
    colls = [
        disk_collection(ax, xi[~ratt], yi[~ratt], P["radius"][idx][~ratt], DISK_FACE, DISK_EDGE,
                        edge_lw, ax.transData),
        disk_collection(ax, xi[ratt], yi[ratt], P["radius"][idx][ratt], RATTLER_FACE, RATTLER_EDGE,
                        edge_lw, ax.transData),
    ]

    # Force chains: carrying contacts, drawn from a along l, and from b back along -l when
    # the segment crosses the cell edge (so both halves show inside the cell).
    carry = st["carrying"]
    a, b = C["a"][carry], C["b"][carry]
    lx, ly, fn = C["lx"][carry], C["ly"][carry], C["fn"][carry]
    xa, ya = np.mod(P["x"][a], Lx), np.mod(P["y"][a], Ly)
    xb, yb = np.mod(P["x"][b], Lx), np.mod(P["y"][b], Ly)
    seg1 = np.stack([np.column_stack([xa, ya]), np.column_stack([xa + lx, ya + ly])], axis=1)
    wraps = (np.abs(xa + lx - xb) > 1e-6 * Lx) | (np.abs(ya + ly - yb) > 1e-6 * Ly)
    seg2 = np.stack([np.column_stack([xb - lx, yb - ly]), np.column_stack([xb, yb])], axis=1)[wraps]
    segs = np.concatenate([seg1, seg2]) if len(seg1) else np.zeros((0, 2, 2))
    f = np.concatenate([fn, fn[wraps]])
    fmax = float(f.max()) if len(f) else 0.0
    max_w = args.max_width if args.max_width else float(np.clip(0.7 * R_avg * pts_per_unit, 0.6, 6.0))
    widths = max_w * f / fmax if fmax > 0 else np.zeros(0)
    chains = LineCollection(segs, linewidths=widths, colors=CHAIN_COLOUR, capstyle="round", zorder=3)
    ax.add_collection(chains)
    for c in colls + [chains]:
        c.set_clip_path(cell)

    n_ratt = int(np.count_nonzero(st["rattler"]))
    title = (f"N = {N},  $\\mu$ = {up.format_mu(meta['mu'])},  $\\phi$ = {st['phi']:.4f},  "
             f"z = {st['z']:.3f}\n"
             f"{st['N_c']} force-carrying contacts, {n_ratt} rattler{'' if n_ratt == 1 else 's'}"
             f"{' (orange)' if n_ratt else ''},  "
             f"$\\langle F_{{cont}}\\rangle/F_0$ = {st['F_cont']:.3f},  "
             f"line width $\\propto f_n$ (max {fmax / st['F0']:.2f} $F_0$)")
    ax.set_title(title, fontsize=9)

    out = args.out or up.default_out(d, "packing.png")
    up.save_figure(fig, out)
    plt.close(fig)


if __name__ == "__main__":
    up.run_main(main)
