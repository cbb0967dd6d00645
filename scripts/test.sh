#!/usr/bin/env bash
# Sets up, builds and runs the default test suite (C++ unit and physics tests, and the
# plotting scripts' tests). Long validation runs: ctest --test-dir build/release -R Validation
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
ctest --preset release
