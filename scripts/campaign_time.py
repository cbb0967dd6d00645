"""The CPU time of an `unjam probe` campaign from its probe_summary.json (docs/probe.md,
"Campaigns": the time of every run).

Used by scripts/compare_probes.py and scripts/experiment_stages.py; the standard library only.
"""

import math


def _number(x):
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def cpu_per_probe(summary, probes):
    """CPU seconds per probe of a campaign of `probes` probes: the mean of the CPU each probe
    took on its own thread (cpu_per_probe: its total over the probes that record it), which
    does not count the waits of a loaded machine. For a summary written before that was
    recorded, its busy seconds per probe: over every run that made it (all_runs: its busy
    seconds over the probes whose runs recorded their time), or, before all_runs was recorded,
    its last run's ranks over all its probes (which understates a resumed campaign). NaN
    where none is readable."""
    cpu = summary.get("cpu_per_probe")
    if isinstance(cpu, dict) and _number(cpu.get("total_seconds")) and _number(cpu.get("probes")) \
            and cpu["probes"] > 0:
        return float(cpu["total_seconds"]) / cpu["probes"]
    runs = summary.get("all_runs")
    if isinstance(runs, dict) and _number(runs.get("busy_seconds")) and _number(runs.get("untimed")):
        timed = probes - runs["untimed"]
        return float(runs["busy_seconds"]) / timed if timed > 0 else math.nan
    ranks = summary.get("ranks")
    if isinstance(ranks, list) and ranks and all(
            isinstance(x, dict) and _number(x.get("busy_seconds")) for x in ranks):
        return float(sum(x["busy_seconds"] for x in ranks)) / probes
    return math.nan
