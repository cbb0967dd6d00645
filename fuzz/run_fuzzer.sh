#!/usr/bin/env bash
# Runs one libFuzzer target for a bounded time from a fresh corpus of its seeds:
#   fuzz/run_fuzzer.sh BINARY CORPUS_DIR SECONDS [libFuzzer flags...]
# Fails (non-zero exit) on a crash, a sanitizer report, an uncaught exception, an accepted
# invalid input, an input slower than -timeout (s) or a leak; the input is saved as
# CORPUS_DIR/../<target>-crash-* (replay: BINARY FILE).
set -euo pipefail
bin=$1 corpus=$2 seconds=$3
shift 3
rm -rf "$corpus"
"$bin" --write-seeds "$corpus"
exec "$bin" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=65536 -print_final_stats=1 \
  -artifact_prefix="$(dirname "$corpus")/$(basename "$bin")-" "$@" "$corpus"
