"""The exact probe's field against the lp probe's, contact by contact.

Usage:  /usr/bin/python3 scripts/field_cosines.py PACKING
                     (--contacts K [K ...] | --from-campaign PROBES_CSV [--limit M])
                     [--cd-start static|compliant|interior|inertial|interior-inertial] [--cd-max-pieces M]
                     [--cd-compliant-start C] [--g G] [--dt DT] [--threads T]
                     [--running-every S] [--out DIR]

The lp probe (`--method lp`) takes F_crit as the LP maximum and its field from the LP
optimum's active set; the paper's probe (`--method cd`) solves the contact-dynamics step
exactly (docs/probe.md). This probes every listed contact by both, through the Python module
(`unjam.probe`, built into build/release/python), and compares their displacement fields:

  cosine       u_lp . u_cd / (|u_lp| |u_cd|) over the grains' peculiar displacements u (N, 2)
               (rotations left out): 1 where both move the grains alike, 0 where the fields
               are unrelated, < 0 where they move them against each other
  cosine_near  the same over the grains within --near mean grain diameters of the probed pair's
               midpoint (periodic distance): the near field, which a floppy region far from
               the probe (grains that slide by far more than g) does not dominate
  norm_ratio   |u_cd| / |u_lp|

Outputs, in DIR (default PACKING-fields):
  fields.csv   contact, a, b, f_cont, f_crit_lp, f_crit_cd, residual_cd, exact (cd residual
               at most 1e-6 g: unjam's own verdict), cosine, cosine_near, norm_ratio,
               f_inertia_cd (the cd step's largest net force on a grain, in the units of
               f_crit: docs/probe.md, "The inertia of the step"), in the order of the list.
               Written after every probe (the cd probes run as one list on --threads
               threads, unjam.probe(progress=...)); a run stopped by Ctrl-C resumes
               from it (the same command skips the contacts it already holds; a table of
               other contacts or other settings is refused, not overwritten).
  settings.json  the packing, --cd-start, --g, --dt and --near the table was made with
  fields/K.npz the two fields of contact K (arrays u_lp, u_cd (N, 2), rot_lp, rot_cd (N,);
               peculiar displacements and rotations as unjam.ProbeResult gives them), for any
               other comparison
  fields.json  the counts, the cosine's median, quartiles and range over the exact probes,
               the packing, the settings, the program's version and the command
  fields.md    the same as a table
  cosines.png  the cosine's cumulative distribution over the exact probes, and the cosine
               against F_crit(cd) / F_crit(lp)

--from-campaign takes the contacts of a campaign's probes.csv in its order (e.g. the
`--sample 300 --seed 1` campaign whose F_crit the docs tabulate), --limit the first M of them.
Where that is a cd campaign (its probe_summary.json beside probes.csv says method cd), its own
g, dt, window and cd settings (start, budget of pieces, first compliance, the interior start's
settings), read back by unjam.campaign_settings from what the campaign recorded, probe the
contacts again, so the cd probes are the campaign's: fields.json's `campaign_check` counts the
contacts whose F_crit(cd) equals the campaign's bit for bit (a warning names the others: a
campaign made by another build, or settings it did not record). A record the tool would not
have written on this packing (an unknown setting, another packing's contact model) is refused. The options --cd-start, --cd-max-pieces, --cd-compliant-start,
--g and --dt are refused with such a campaign; with --contacts, or an lp campaign, they apply
(defaults: compliant start, no budget, first compliance 0.1, g = 1e-9, the quasi-static dt).
Exit codes: 0 done, 1 bad input or a failed probe (its message is printed), 3 interrupted
(run the same command again to resume).
"""

import argparse
import csv
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MODULE_DIR = os.path.join(REPO, "build", "release", "python")

from experiment_stages import write_table  # noqa: E402
from stage_runner import read_json, write_json  # noqa: E402
import unjam_plot  # noqa: E402

COLUMNS = ["contact", "a", "b", "f_cont", "f_crit_lp", "f_crit_cd", "residual_cd", "exact",
           "cosine", "cosine_near", "norm_ratio", "f_inertia_cd"]
# The columns of tables written before f_inertia_cd: resumed, with that cell left empty.
COLUMNS_BEFORE_INERTIA = COLUMNS[:-1]


def import_unjam():
    """The Python module: installed, on PYTHONPATH, or in build/release/python."""
    try:
        import unjam
    except ImportError:
        sys.path.insert(0, MODULE_DIR)
        try:
            import unjam
        except ImportError:
            sys.exit(f"field_cosines: the Python module unjam is not built ({MODULE_DIR}; "
                     "build it: cmake --build build/release -j2)")
    return unjam


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("packing")
    sel = ap.add_mutually_exclusive_group(required=True)
    sel.add_argument("--contacts", type=int, nargs="+", help="the contacts to probe")
    sel.add_argument("--from-campaign", metavar="PROBES_CSV",
                     help="the contacts of a campaign's probes.csv, in its order")
    ap.add_argument("--limit", type=int, help="with --from-campaign: the first M contacts only")
    ap.add_argument("--cd-start", choices=("static", "compliant", "interior", "inertial", "interior-inertial"),
                    help="where the exact probe's path starts (default compliant; interior: from "
                         "an interior-point iterate, faster at 500 disks and beyond: docs/probe.md, "
                         "\"Where the path starts\", \"An interior-point start\"); a cd "
                         "campaign's own by default with --from-campaign")
    ap.add_argument("--cd-max-pieces", type=int,
                    help="a cd probe's budget of pieces, as unjam probe --cd-max-pieces (default "
                         "none)")
    ap.add_argument("--cd-compliant-start", type=float,
                    help="the continuation's first compliance, as unjam probe --cd-compliant-start "
                         "(default 0.1)")
    ap.add_argument("--g", type=float, help="the probe's opening (default 1e-9)")
    ap.add_argument("--dt", type=float, help="the cd step's time step (default: the quasi-static "
                    "sqrt(g / 1e-5), as unjam probe --method cd)")
    ap.add_argument("--near", type=float, default=5.0,
                    help="radius of the near field, in mean grain diameters (default 5)")
    ap.add_argument("--threads", type=int, default=0, help="threads (0: all cores)")
    ap.add_argument("--running-every", type=float, default=300.0,
                    help="a line for every cd probe still running after another this many seconds "
                         "(default 300, as unjam probe --running-every)")
    ap.add_argument("--chunk", type=int, default=8, help=argparse.SUPPRESS)  # the table is saved after every probe
    ap.add_argument("--out", help="output directory (default: PACKING-fields)")
    a = ap.parse_args(argv)
    if not os.path.isfile(os.path.join(a.packing, "meta.json")):
        ap.error(f"{a.packing} is not a packing directory (no meta.json)")
    if a.limit is not None and (a.from_campaign is None or a.limit < 1):
        ap.error("--limit takes a positive count and goes with --from-campaign")
    for name in ("g", "dt", "cd_compliant_start"):
        v = getattr(a, name)
        if v is not None and not (0 < v < float("inf")):
            ap.error(f"--{name} must be a finite number > 0, got {v}")
    if not (0 <= a.running_every < float("inf")):
        ap.error(f"--running-every must be a finite number >= 0, got {a.running_every}")
    if not (0 < a.near < float("inf")):
        ap.error(f"--near must be a finite number > 0, got {a.near}")
    if a.threads < 0:
        ap.error("--threads must be >= 0")
    if a.cd_max_pieces is not None and a.cd_max_pieces < 0:
        ap.error(f"--cd-max-pieces must be >= 0 (0: none), got {a.cd_max_pieces}")
    a.out = a.out or a.packing.rstrip("/") + "-fields"
    return a


# The options that a cd campaign's own settings replace.
CAMPAIGN_OPTIONS = ("cd_start", "cd_max_pieces", "cd_compliant_start", "g", "dt")


def campaign_settings(a, unjam, p):
    """The settings (unjam.campaign_settings: g, dt, cd, window, ...) of the cd campaign behind
    --from-campaign, read back from its probe_summary.json as the tool recorded them, or None
    where there is none (--contacts, no probe_summary.json beside probes.csv, or a campaign by
    another method)."""
    if a.from_campaign is None:
        return None
    path = os.path.join(os.path.dirname(os.path.abspath(a.from_campaign)), "probe_summary.json")
    if not os.path.isfile(path):
        return None
    try:
        rec = unjam.campaign_settings(p, path)
    except unjam.Error as e:
        sys.exit(f"field_cosines: the campaign of {a.from_campaign}: {e}")
    if rec["method"] != "cd":
        return None
    given = [n for n in CAMPAIGN_OPTIONS if getattr(a, n) is not None]
    if given:
        sys.exit(f"field_cosines: {a.from_campaign} is a cd campaign, whose own settings probe its "
                 f"contacts again; leave out --{', --'.join(n.replace('_', '-') for n in given)}")
    return rec


def campaign_rows(a):
    """The contact, f_crit and residual columns of --from-campaign's probes.csv (None with
    --contacts), read once."""
    if a.from_campaign is None:
        return None
    return unjam_plot.read_csv(a.from_campaign, ["contact", "f_crit", "residual"], min_rows=1)


def campaign_f_crit(table):
    """contact -> the campaign's F_crit, None where its probe has no solution (residual
    1.8e308, as kNoSolution in probes.csv)."""
    return {int(k): (float(f) if float(r) < 1e300 else None)
            for k, f, r in zip(table["contact"], table["f_crit"], table["residual"])}


def campaign_check(rows, reference):
    """How many cd probes reproduce the campaign's: the same F_crit bit for bit, or no solution
    by both; the contacts of the others and their largest relative difference in F_crit."""
    both = [r for r in rows if int(r["contact"]) in reference]
    mine = {int(r["contact"]): (float(r["f_crit_cd"]) if r["f_crit_cd"] != "" else None) for r in both}
    differ = [k for k, f in mine.items() if f != reference[k]]
    rel = [abs(mine[k] / reference[k] - 1.0) for k in differ
           if mine[k] is not None and reference[k] not in (None, 0.0)]
    return {"compared": len(both), "equal": len(both) - len(differ), "differ": differ,
            "max_relative_difference": max(rel) if rel else 0.0}


def listed_contacts(a, table):
    """The contacts to probe: --contacts, or those of the campaign's table (its first --limit)."""
    if a.contacts is not None:
        ks = a.contacts
    else:
        ks = [int(k) for k in table["contact"]]
        ks = ks[:a.limit] if a.limit else ks
    if len(set(ks)) != len(ks):
        sys.exit("field_cosines: a contact is listed twice")
    return ks


def cosine(u, v):
    """u . v / (|u| |v|) of two (N, 2) fields; nan where either is zero."""
    nu, nv = np.linalg.norm(u), np.linalg.norm(v)
    if nu == 0.0 or nv == 0.0:
        return float("nan")
    return float(np.clip(np.dot(u.ravel(), v.ravel()) / (nu * nv), -1.0, 1.0))


def near_grains(p, contact, radius):
    """The grains within radius (in mean grain diameters) of the contact's midpoint, periodic."""
    L = np.asarray(p.cell, dtype=float)[:2]
    x = np.column_stack([p.x, p.y])
    xa, xb = x[p.contacts.a[contact]], x[p.contacts.b[contact]]
    d_ab = xb - xa - L * np.round((xb - xa) / L)
    d = x - (xa + 0.5 * d_ab)
    d -= L * np.round(d / L)
    return np.linalg.norm(d, axis=1) <= radius * 2.0 * np.mean(p.radii)


def save_fields(path, r_lp, r_cd):
    """The two fields of one contact, atomically."""
    unjam_plot.write_file_atomic(
        path, lambda f: np.savez(f, u_lp=r_lp.u, u_cd=r_cd.u, rot_lp=r_lp.rot, rot_cd=r_cd.rot), binary=True)


def read_done(a, ks, settings):
    """The rows of an earlier run into a.out with these settings and of listed contacts only."""
    path, saved = os.path.join(a.out, "fields.csv"), os.path.join(a.out, "settings.json")
    if not os.path.isfile(path):
        return []
    with open(path, newline="") as f:
        r = csv.DictReader(f)
        if r.fieldnames not in (COLUMNS, COLUMNS_BEFORE_INERTIA):
            sys.exit(f"field_cosines: {path} is not this script's table (columns {r.fieldnames}); "
                     "move it away or choose another --out")
        rows = [{"f_inertia_cd": "", **row} for row in r]
    recorded = read_json(saved)
    if recorded != settings:
        sys.exit(f"field_cosines: {path} was made with other settings ({saved}: {recorded}); "
                 "move it away or choose another --out")
    others = sorted({int(x["contact"]) for x in rows} - set(ks))
    if others:
        sys.exit(f"field_cosines: {path} holds contacts that are not listed ({others[:5]}"
                 f"{' ...' if len(others) > 5 else ''}); move it away or choose another --out")
    return rows


def quantiles(values):
    if not values:
        return None
    q = np.quantile(values, [0.0, 0.25, 0.5, 0.75, 1.0])
    return dict(zip(("min", "q1", "median", "q3", "max"), (float(x) for x in q)))


def plot(rows, path, title):
    import matplotlib.pyplot as plt
    exact = [r for r in rows if r["exact"] == "1"]
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(9.0, 3.6))
    c = np.sort([float(r["cosine"]) for r in exact])
    if len(c):
        ax0.step(c, np.arange(1, len(c) + 1) / len(c), where="post")
    ax0.set_xlabel("cosine of the fields, lp against cd")
    ax0.set_ylabel("fraction of exact probes")
    ax0.set_xlim(-1.0, 1.0)
    ax0.grid(alpha=0.3)
    x = [float(r["f_crit_cd"]) / float(r["f_crit_lp"]) for r in exact if float(r["f_crit_lp"]) > 0]
    y = [float(r["cosine"]) for r in exact if float(r["f_crit_lp"]) > 0]
    ax1.plot(x, y, ".", alpha=0.7)
    ax1.set_xlabel("F_crit(cd) / F_crit(lp)")
    ax1.set_ylabel("cosine")
    ax1.set_ylim(-1.0, 1.05)
    ax1.grid(alpha=0.3)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    unjam_plot.save_figure(fig, path)
    plt.close(fig)


def row(p, r_lp, r_cd, a):
    """The fields.csv row of one contact probed by both methods (its fields saved in
    a.out/fields where the cd step has a solution)."""
    solved = r_cd.residual < 1e300  # kNoSolution: no field to compare
    near = near_grains(p, r_cd.contact, a.near)
    if solved:
        save_fields(os.path.join(a.out, "fields", f"{r_cd.contact}.npz"), r_lp, r_cd)
    return {
        "contact": str(r_cd.contact), "a": str(r_cd.a), "b": str(r_cd.b), "f_cont": repr(r_cd.f_cont),
        "f_crit_lp": repr(r_lp.f_crit), "f_crit_cd": repr(r_cd.f_crit) if solved else "",
        "residual_cd": repr(r_cd.residual) if solved else "",
        "exact": "1" if r_cd.converged else "0",  # residual <= 1e-6 g (docs/probe.md)
        "cosine": repr(cosine(r_lp.u, r_cd.u)) if solved else "",
        "cosine_near": repr(cosine(r_lp.u[near], r_cd.u[near])) if solved else "",
        "norm_ratio": repr(float(np.linalg.norm(r_cd.u) / np.linalg.norm(r_lp.u)))
        if solved and np.linalg.norm(r_lp.u) > 0 else "",
        "f_inertia_cd": repr(r_cd.f_inertia) if solved else ""}


def main(argv):
    a = parse(argv)
    unjam = import_unjam()
    p = unjam.read_packing(a.packing)
    table_of_campaign = campaign_rows(a)
    ks = listed_contacts(a, table_of_campaign)
    from_campaign = campaign_settings(a, unjam, p)
    try:
        os.makedirs(os.path.join(a.out, "fields"), exist_ok=True)
    except OSError as e:
        sys.exit(f"field_cosines: cannot create the output directory {a.out}: {e.strerror or e}")
    table = os.path.join(a.out, "fields.csv")
    window = None  # the cd probes' window (mean diameters; None: the whole packing)
    if from_campaign is not None:
        a.g, a.dt, window = from_campaign["g"], from_campaign["dt"], from_campaign["window"]
        cd_fields = from_campaign["cd"].__getstate__()  # every unjam.CdSettings field, by name
        a.cd_start = cd_fields["start"]
    else:
        a.g = 1e-9 if a.g is None else a.g
        a.cd_start = a.cd_start or "compliant"
        cd_fields = {"start": a.cd_start}
        if a.cd_max_pieces is not None:
            cd_fields["max_pieces"] = a.cd_max_pieces
        if a.cd_compliant_start is not None:
            cd_fields["compliant_start"] = a.cd_compliant_start
    # The settings a table resumes with; the start alone where it is the only cd setting, as in
    # the tables made before the others were options.
    settings = {"packing": os.path.abspath(a.packing), "cd_start": a.cd_start, "g": a.g, "dt": a.dt,
                "near": a.near}
    if set(cd_fields) != {"start"}:
        settings["cd"] = cd_fields
    if window is not None:
        settings["window"] = window
    cd_settings = unjam.CdSettings(**cd_fields)  # range-checked as unjam probe checks its options
    rows = read_done(a, ks, settings)
    write_json(os.path.join(a.out, "settings.json"), settings)
    order = {k: i for i, k in enumerate(ks)}
    done = {int(r["contact"]) for r in rows}
    todo = [k for k in ks if k not in done]
    if done:
        print(f"resuming: {len(done)} contacts already in {table}", flush=True)
    common = dict(g=a.g, threads=a.threads)

    def finished(d):  # one cd probe done (unjam.probe's progress): its row, the table saved
        if d["event"] == "running":  # a sign of life of a long probe, every --running-every s of it
            print(f"  contact {d['contact']}: probing for {d['seconds']:.0f} s ({d['polls']} pieces so far)",
                  flush=True)
            return
        r_cd = d["result"]
        rows.append(row(p, lp[d["index"]], r_cd, a))
        rows.sort(key=lambda r: order[int(r["contact"])])
        write_table(table, rows, COLUMNS)
        print(f"probes {len(rows)} / {len(ks)}, ETA {d['eta_s']:.0f} s", flush=True)

    try:
        if todo:  # the lp probes first (short), then the cd probes in one call, each saved as it ends
            lp = unjam.probe(p, contacts=todo, method="lp", **common)
            unjam.probe(p, contacts=todo, method="cd", cd=cd_settings, dt=a.dt, window=window,
                        progress=finished, running_every=a.running_every, **common)
    except KeyboardInterrupt:
        write_table(table, rows, COLUMNS)
        print(f"interrupted: {len(rows)} of {len(ks)} contacts saved in {table}; "
              "run the same command again to resume", file=sys.stderr)
        sys.exit(3)
    except unjam.Error as e:
        write_table(table, rows, COLUMNS)
        sys.exit(f"field_cosines: {e}")

    exact = [r for r in rows if r["exact"] == "1"]
    cos = [float(r["cosine"]) for r in exact if r["cosine"] not in ("", "nan")]
    cos_near = [float(r["cosine_near"]) for r in exact if r["cosine_near"] not in ("", "nan")]
    ratio = [float(r["norm_ratio"]) for r in exact if r["norm_ratio"] != ""]
    summary = {
        "packing": os.path.abspath(a.packing), "N": p.N, "mu": p.mu, "seed": p.seed,
        "cd_start": a.cd_start, "g": a.g, "dt": a.dt, "cd": cd_fields, "window": window,
        "settings_from_campaign": from_campaign is not None,
        "probes": len(rows), "exact": len(exact),
        "without_solution": sum(1 for r in rows if r["f_crit_cd"] == ""),
        "cosine": quantiles(cos), "cosine_near": quantiles(cos_near), "near_diameters": a.near,
        "norm_ratio": quantiles(ratio),
        "f_inertia_cd": quantiles([float(r["f_inertia_cd"]) for r in exact if r["f_inertia_cd"] != ""]),
        "cosine_above_0.99": sum(1 for c in cos if c > 0.99),
        "cosine_below_0.5": sum(1 for c in cos if c < 0.5),
        "program_version": unjam.__version__,
        "command": " ".join([os.path.basename(sys.executable), *sys.argv]),
    }
    if from_campaign is not None:
        check = campaign_check(rows, campaign_f_crit(table_of_campaign))
        summary["campaign_check"] = check
        if check["differ"]:
            print(f"field_cosines: warning: F_crit(cd) differs from the campaign's on "
                  f"{len(check['differ'])} of {check['compared']} contacts (largest relative "
                  f"difference {check['max_relative_difference']:.3g}; contacts "
                  f"{check['differ'][:10]}{' ...' if len(check['differ']) > 10 else ''}): "
                  "the campaign was made by another build or with settings it did not record",
                  file=sys.stderr)
    write_json(os.path.join(a.out, "fields.json"), summary)
    q, qn = summary["cosine"], summary["cosine_near"]
    md = ["| probes | exact | cosine median (quartiles) | range | above 0.99 | below 0.5 | "
          f"near field ({a.near:g} diameters) median (quartiles) | norm ratio, median |",
          "|---|---|---|---|---|---|---|---|"]
    if q:
        md.append(f"| {len(rows)} | {len(exact)} | {q['median']:.3f} ({q['q1']:.3f}–{q['q3']:.3f}) | "
                  f"{q['min']:.3f}–{q['max']:.3f} | {summary['cosine_above_0.99']} | "
                  f"{summary['cosine_below_0.5']} | {qn['median']:.3f} ({qn['q1']:.3f}–{qn['q3']:.3f}) | "
                  f"{summary['norm_ratio']['median']:.3f} |")
    else:
        md.append(f"| {len(rows)} | {len(exact)} | – | – | – | – | – | – |")
    unjam_plot.write_file_atomic(os.path.join(a.out, "fields.md"), lambda f: f.write(
        f"Fields of {a.packing}, lp against cd (--cd-start {a.cd_start}"
        f"{', the settings of the campaign ' + a.from_campaign if from_campaign else ''}), exact probes only; "
        "norm ratio |u_cd| / |u_lp|\n\n" + "\n".join(md) + "\n"))
    plot(rows, os.path.join(a.out, "cosines.png"),
         f"{os.path.basename(a.packing.rstrip('/'))}: {len(exact)} exact probes of {len(rows)}")
    med = f"median {q['median']:.3f}" if q else "no exact probe"
    print(f"{len(rows)} probes, {len(exact)} exact; cosine of the fields lp vs cd: {med} "
          f"-> {a.out}/fields.csv")


if __name__ == "__main__":
    unjam_plot.run_main(lambda: main(sys.argv[1:]))
