#!/usr/bin/env bash
# The sanitizer pass: runs a test binary of the `sanitizers` build (tests of the tool and the
# readers) with every AddressSanitizer / UBSan / LeakSanitizer report of it and of the
# `unjam` processes it starts written to LOG_DIR; fails if a test fails or any report exists.
#   tests/sanitizer_pass.sh TEST_BINARY LOG_DIR [gtest flags...]
set -uo pipefail
bin=$1 logs=$2
shift 2
rm -rf "$logs"
mkdir -p "$logs"
export ASAN_OPTIONS="log_path=$logs/asan:detect_leaks=1:exitcode=86:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="log_path=$logs/ubsan:print_stacktrace=1:halt_on_error=1:exitcode=86:${UBSAN_OPTIONS:-}"
"$bin" "$@"
status=$?
reports=$(find "$logs" -type f | sort)
if [ -n "$reports" ]; then
  for f in $reports; do
    echo "==== $f"
    cat "$f"
  done
  echo "sanitizer reports: $(echo "$reports" | wc -l) (above)"
  exit 1
fi
exit $status
