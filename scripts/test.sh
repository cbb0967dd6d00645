#!/usr/bin/env bash
# Sets up, builds and runs the default test suite (C++ unit and physics tests, and the
# plotting scripts' tests), then the sanitizer pass (docs/testing.md): the tool's and the
# readers' tests under AddressSanitizer and UBSan, and each libFuzzer target of the readers
# for a bounded time (clang, build/sanitizers). Long validation runs:
# ctest --test-dir build/release -R Validation
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
ctest --preset release
cmake --preset sanitizers >/dev/null
cmake --build --preset sanitizer-pass -j "$(nproc)"
ctest --preset sanitizer-pass
