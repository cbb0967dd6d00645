"""The friction-sweep table (one row per packing) and its aggregation over seeds.

Shared by scripts/experiment.py (which writes the table and reports its aggregate) and
scripts/plot_friction_sweep.py (which draws it, the paper's Fig. 3).  Only the standard library.

The table's columns:
    mu,N,seed,phi,z,F_cont_over_F0,F_crit_over_F_cont,alpha,alpha_err
alpha and alpha_err are empty (or 'nan') where the power-law fit failed.
"""

import math

COLUMNS = ["mu", "N", "seed", "phi", "z", "F_cont_over_F0", "F_crit_over_F_cont", "alpha",
           "alpha_err"]
# The measured columns: averaged over the seeds of one (mu, N).
RESULTS = ["phi", "z", "F_cont_over_F0", "F_crit_over_F_cont", "alpha", "alpha_err"]
# mu values closer than 1e-12 are one friction coefficient.
MU_DIGITS = 12


def number(v):
    """float(v), or NaN for an empty or non-numeric field."""
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


def mean_std(values):
    """(mean, standard deviation with n - 1, n) over the finite values; std 0 for one value,
    (NaN, NaN, 0) for none."""
    v = [x for x in values if math.isfinite(x)]
    if not v:
        return math.nan, math.nan, 0
    m = sum(v) / len(v)
    s = math.sqrt(sum((x - m) ** 2 for x in v) / (len(v) - 1)) if len(v) > 1 else 0.0
    return m, s, len(v)


def aggregate(rows):
    """{(mu, N): group} over the rows (mappings with the COLUMNS), in increasing (mu, N).

    group: {"seeds": rows in the group, col: (mean, std, n) for col in RESULTS,
            "alpha_bar": the error bar of alpha: its std over the seeds, or the fit error
                         alpha_err of the packing when only one has an alpha (NaN if none)}.
    """
    groups = {}
    for r in rows:
        key = (round(number(r["mu"]), MU_DIGITS), int(number(r["N"])))
        groups.setdefault(key, []).append(r)
    out = {}
    for key, g in sorted(groups.items()):
        a = {"seeds": len(g)}
        for c in RESULTS:
            a[c] = mean_std([number(r[c]) for r in g])
        fitted = [r for r in g if math.isfinite(number(r["alpha"]))]
        a["alpha_bar"] = number(fitted[0]["alpha_err"]) if len(fitted) == 1 else a["alpha"][1]
        out[key] = a
    return out
