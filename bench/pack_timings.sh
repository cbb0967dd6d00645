#!/usr/bin/env bash
# Wall time to a static packing with `unjam pack` (docs/benchmarks.md, "Time to static").
# Usage: bench/pack_timings.sh BUILD_DIR "N:SEED:THREADS ..."   e.g.
#   bench/pack_timings.sh build/h5 "500:1:1 500:1:2 2000:1:1"
# The one-thread runs write into the benchmark cache ($UNJAM_BENCH_CACHE or
# /tmp/unjam-bench-cache, same names as bench/scenes.cpp), so unjam_bench reuses them; the
# other runs write to $OUT (default /tmp/unjam-pack-timings) and are compared byte for byte
# with the one-thread packing (results must not depend on the thread count).
# TIMEOUT (optional, e.g. 300) stops a run with SIGINT (state saved, "stopped after N steps").
# TAG (optional) is appended to the log name, e.g. TAG=-passive OMP_WAIT_POLICY=passive.
set -euo pipefail
build=${1:?build dir}
runs=${2:?runs}
cache=${UNJAM_BENCH_CACHE:-/tmp/unjam-bench-cache}
out=${OUT:-/tmp/unjam-pack-timings}
mkdir -p "$cache" "$out/logs"
for run in $runs; do
  IFS=: read -r n seed threads <<<"$run"
  if [ "$threads" = 1 ]; then dir="$cache/static-n$n-mu0.1-seed$seed"; else dir="$out/n$n-seed$seed-t$threads"; fi
  log="$out/logs/n$n-seed$seed-t$threads${TAG:-}.log"
  { echo "# $(date -Is) $(uptime)  OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-unset}"; echo "# $build/unjam pack --n $n --mu 0.1 --seed $seed --out $dir --threads $threads --quiet"; } >"$log"
  status=0
  ${TIMEOUT:+timeout -s INT $TIMEOUT} /usr/bin/time -v "$build/unjam" pack --n "$n" --mu 0.1 --seed "$seed" --out "$dir" \
      --threads "$threads" --quiet >>"$log" 2>&1 || status=$?
  [ "$status" = 0 ] || echo "# exit status $status (not static: stopped or failed)" >>"$log"
  echo "# after: $(uptime)" >>"$log"
  if [ "$threads" != 1 ] && [ "$status" = 0 ]; then
    ref="$cache/static-n$n-mu0.1-seed$seed"
    if [ -f "$ref/particles.csv" ]; then
      if cmp -s "$ref/particles.csv" "$dir/particles.csv" && cmp -s "$ref/contacts.csv" "$dir/contacts.csv"; then
        echo "# identical to the one-thread packing" >>"$log"
      else
        echo "# DIFFERS from the one-thread packing" >>"$log"
      fi
    fi
  fi
  wall=$(grep -F "Elapsed (wall clock)" "$log" | awk '{print $NF}')
  summary=$(grep -E "phi|steps," "$log" | tr -s ' ' | tr '\n' '|')
  echo "N=$n seed=$seed T=$threads wall=$wall $summary"
done
