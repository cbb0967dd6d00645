#!/usr/bin/env bash
# Sets up, builds and runs the default test suite (every test label but validation; README,
# "Tests"). Long validation runs: ctest --preset validation
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
ctest --preset release
