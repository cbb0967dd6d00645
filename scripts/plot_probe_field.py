"""Draw one probe's displacement field: arrows on the disks, the probed contact marked.

Usage:  /usr/bin/python3 scripts/plot_probe_field.py DIR --contact K [--packing PDIR] [--out FILE]

Reads DIR/probe-K.csv (id, x, y, radius, ux_g, uy_g: lab-frame positions and the grains'
displacements divided by the gap g), the cell from meta.json (in PDIR, default DIR), and the
probed pair (a, b) from DIR/probes.csv (row with contact == K) or else from row K of
PDIR/contacts.csv.  Disks are drawn as light circles (periodic images included).  The
displacements |u|/g decay like a power law, so the arrows are compressed: an arrow's length
is proportional to (|u|/|u|_max)^P (P = --exponent, default 0.5; 1 = linear), the longest
being --max-arrow mean radii long, and its colour gives |u|/g on a log scale.  The probed
contact point r_a + R_a n is marked with a star and grains a and b are outlined in red.

Writes DIR/probe-K.png (or --out FILE), PNG at 150 dpi.
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import unjam_plot as up  # noqa: E402

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import EllipseCollection  # noqa: E402
from matplotlib.colors import LogNorm  # noqa: E402
from matplotlib.patches import Circle  # noqa: E402


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="Writes DIR/probe-K.png unless --out is given.")
    p.add_argument("dir", metavar="DIR", help="probe output directory holding probe-K.csv")
    p.add_argument("--contact", "-k", type=int, required=True, metavar="K",
                   help="index of the probed contact (row of contacts.csv)")
    p.add_argument("--packing", metavar="PDIR",
                   help="packing directory with meta.json and contacts.csv (default DIR)")
    p.add_argument("--exponent", type=float, default=0.5, metavar="P",
                   help="arrow length ~ |u|^P (default 0.5; 1 = linear)")
    p.add_argument("--max-arrow", type=float, default=2.0, metavar="M",
                   help="length of the longest arrow in mean radii (default 2)")
    p.add_argument("--out", metavar="FILE", help="output PNG (default DIR/probe-K.png)")
    args = p.parse_args(argv)
    if args.contact < 0:
        p.error("--contact must be >= 0")
    if not args.exponent > 0:
        p.error("--exponent must be > 0")
    if not args.max_arrow > 0:
        p.error("--max-arrow must be > 0")
    return args


def find_pair(args, pdir, n_grains):
    """(a, b, lx, ly or None, probe row or None) of the probed contact, or None if unknown."""
    K = args.contact
    probe_row = None
    a = b = None
    probes_path = os.path.join(args.dir, "probes.csv")
    if os.path.exists(probes_path):
        t = up.read_csv(probes_path, ["contact", "a", "b"],
                        optional=["f_cont", "f_crit", "converged", "sweeps"], text=["method"])
        rows = np.nonzero(t["contact"] == K)[0]
        if len(rows):
            i = rows[0]
            probe_row = {k: v[i] for k, v in t.items()}
            a, b = int(t["a"][i]), int(t["b"][i])
    contacts_path = os.path.join(pdir, "contacts.csv")
    lvec = None
    if os.path.exists(contacts_path):
        C = up.read_csv(contacts_path, ["a", "b", "lx", "ly"])
        if K < len(C["a"]):
            ca, cb = int(C["a"][K]), int(C["b"][K])
            if a is None or (ca, cb) == (a, b):
                a, b = ca, cb
                lvec = (C["lx"][K], C["ly"][K])
        elif a is None:
            raise up.UserError(f"{contacts_path}: has {len(C['a'])} contacts, no contact {K}")
    if a is None:
        return None
    if not (0 <= a < n_grains and 0 <= b < n_grains):
        raise up.UserError(f"probed pair ({a}, {b}) is outside the {n_grains} grains of probe-{K}.csv")
    return a, b, lvec, probe_row


def main(argv=None):
    args = parse_args(argv)
    d = up.require_dir(args.dir)
    pdir = up.require_dir(args.packing) if args.packing else d
    K = args.contact
    path = os.path.join(d, f"probe-{K}.csv")
    F = up.read_csv(path, ["x", "y", "radius", "ux_g", "uy_g"], optional=["id"], min_rows=1)
    if "id" in F:
        order = np.argsort(F["id"])
        F = {k: v[order] for k, v in F.items()}
        if not np.array_equal(F["id"], np.arange(len(order))):
            raise up.UserError(f"{path}: ids are not a permutation of 0..{len(order) - 1}")
    if np.any(F["radius"] <= 0):
        raise up.UserError(f"{path}: a radius is <= 0")
    if not args.packing and not os.path.exists(os.path.join(d, "meta.json")):
        raise up.UserError(f"{os.path.join(d, 'meta.json')}: file not found (probe outputs written "
                           f"with --out: give the packing directory with --packing)")
    meta = up.read_meta(pdir)
    Lx, Ly = meta["Lx"], meta["Ly"]
    N = len(F["x"])
    R = F["radius"]
    R_avg = float(np.mean(R))

    pair = find_pair(args, pdir, N)
    if pair is None:
        up.warn(f"contact {K} not found in {os.path.join(d, 'probes.csv')} or "
                f"{os.path.join(pdir, 'contacts.csv')}: the probed contact is not marked")

    size = 7.0
    aspect = Ly / Lx
    fig, ax = plt.subplots(figsize=(size + 1.3, size * aspect + 0.8))
    cell = up.cell_axes(ax, Lx, Ly)

    idx, xi, yi = up.periodic_images(F["x"], F["y"], R, Lx, Ly)
    dd = 2.0 * R[idx]
    disks = EllipseCollection(dd, dd, np.zeros_like(dd), units="xy", offsets=np.column_stack([xi, yi]),
                              offset_transform=ax.transData, facecolors="#eef1f5",
                              edgecolors="#a9b4c2", linewidths=0.4, zorder=1)
    ax.add_collection(disks)
    disks.set_clip_path(cell)

    ux, uy = F["ux_g"], F["uy_g"]
    mag = np.hypot(ux, uy)
    moving = mag > 0
    if not np.any(moving):
        up.warn(f"{path}: every displacement is zero")
    else:
        umax = float(mag.max())
        length = args.max_arrow * R_avg * (mag / umax) ** args.exponent
        with np.errstate(invalid="ignore", divide="ignore"):
            U = np.where(moving, ux / mag * length, 0.0)
            V = np.where(moving, uy / mag * length, 0.0)
        sel = moving[idx]
        positive = mag[moving]
        lo = float(positive.min())
        lo = max(lo, umax * 1e-4)
        norm = LogNorm(vmin=lo, vmax=umax) if umax > lo else None
        q = ax.quiver(xi[sel], yi[sel], U[idx][sel], V[idx][sel], np.clip(mag[idx][sel], lo, umax),
                      cmap="plasma", norm=norm, angles="xy", scale_units="xy", scale=1.0,
                      width=0.0035, headwidth=3.5, headlength=4.0, headaxislength=3.5,
                      pivot="tail", zorder=3)
        q.set_clip_path(cell)
        cb = fig.colorbar(q, ax=ax, shrink=0.8, pad=0.02)
        cb.set_label(r"$|u|/g$")

    title = f"probe of contact {K}"
    if pair is not None:
        a, b, lvec, row = pair
        if lvec is None:
            lvec = (up.min_image(F["x"][b] - F["x"][a], Lx), up.min_image(F["y"][b] - F["y"][a], Ly))
        lx, ly = lvec
        l = float(np.hypot(lx, ly))
        nx, ny = lx / l, ly / l
        xa, ya = np.mod(F["x"][a], Lx), np.mod(F["y"][a], Ly)
        xc, yc = xa + R[a] * nx, ya + R[a] * ny
        for g, (xg, yg) in ((a, (xa, ya)), (b, (xa + lx, ya + ly))):
            for sx in (-Lx, 0.0, Lx):
                for sy in (-Ly, 0.0, Ly):
                    c = Circle((xg + sx, yg + sy), R[g], fill=False, edgecolor="red", linewidth=1.4,
                               zorder=4)
                    ax.add_patch(c)
                    c.set_clip_path(cell)
        for sx in (-Lx, 0.0, Lx):
            for sy in (-Ly, 0.0, Ly):
                m, = ax.plot([np.mod(xc, Lx) + sx], [np.mod(yc, Ly) + sy], marker="*", color="red",
                             markersize=16, markeredgecolor="black", markeredgewidth=0.6, zorder=6,
                             linestyle="none")
                m.set_clip_path(cell)
        title += f" (grains {a}–{b})"
        if row is not None and "f_cont" in row and "f_crit" in row:
            F0 = up.force_unit(meta, R)
            title += (f":  $F_{{cont}}/F_0$ = {row['f_cont'] / F0:.3f},  "
                      f"$F_{{crit}}/F_0$ = {row['f_crit'] / F0:.3f}")
            if row["f_cont"] > 0:
                title += f",  $F_{{crit}}/F_{{cont}}$ = {row['f_crit'] / row['f_cont']:.3f}"
    title += (f"\nN = {N},  $\\mu$ = {up.format_mu(meta['mu'])};  arrow length $\\propto$ "
              f"$|u|^{{{args.exponent:g}}}$, colour = $|u|/g$")
    ax.set_title(title, fontsize=9)
    fig.tight_layout()

    out = args.out or up.default_out(d, f"probe-{K}.png")
    up.save_figure(fig, out)
    plt.close(fig)


if __name__ == "__main__":
    up.run_main(main)
