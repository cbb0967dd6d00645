#!/usr/bin/env bash
# Sets up, builds and runs the default test suite (every test label but validation; README,
# "Tests"), then the sanitizer pass (docs/testing.md): the tool's and the readers' tests under
# AddressSanitizer and UBSan, and each libFuzzer target of the readers for a bounded time
# (clang, build/sanitizers). Long validation runs: ctest --preset validation
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
ctest --preset release
cmake --preset sanitizers >/dev/null
cmake --build --preset sanitizer-pass -j "$(nproc)"
ctest --preset sanitizer-pass
