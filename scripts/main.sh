#!/usr/bin/env bash
# The main job on its embedded default: sets up, builds, then runs the paper's experiment at
# demo scale (scripts/experiment.py: friction sweep of 400-disk packings, every contact
# probed, the fixed-packing series, the 50-disk ensemble, Figs. 1-4 and report.md) into
# runs/experiment (~7 min on two cores). A shorter tour of the tools: scripts/demo.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
/usr/bin/python3 scripts/experiment.py --scale demo --out "${1:-runs/experiment}"
