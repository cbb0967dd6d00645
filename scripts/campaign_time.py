"""The CPU time of an `unjam probe` campaign from its probe_summary.json (docs/probe.md,
"Campaigns": the time of every run).

Used by scripts/compare_probes.py and scripts/experiment_stages.py; the standard library only.
"""

import math


def _number(x):
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def cpu_per_probe(summary, probes):
    """Busy seconds per probe of a campaign of `probes` probes: over every run that made it
    (all_runs: its busy seconds over the probes whose runs recorded their time), or, for a
    summary written before all_runs was recorded, its last run's ranks over all its probes
    (which understates a resumed campaign). NaN where neither is readable."""
    runs = summary.get("all_runs")
    if isinstance(runs, dict) and _number(runs.get("busy_seconds")) and _number(runs.get("untimed")):
        timed = probes - runs["untimed"]
        return float(runs["busy_seconds"]) / timed if timed > 0 else math.nan
    ranks = summary.get("ranks")
    if isinstance(ranks, list) and ranks and all(
            isinstance(x, dict) and _number(x.get("busy_seconds")) for x in ranks):
        return float(sum(x["busy_seconds"] for x in ranks)) / probes
    return math.nan
