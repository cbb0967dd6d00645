#!/usr/bin/env bash
# The main job on a small embedded default: sets up, builds, then runs the demo pipeline
# (scripts/demo.sh) into runs/demo: packings, probes, force bounds, ensemble and figures.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
bash scripts/demo.sh "${1:-runs/demo}"
