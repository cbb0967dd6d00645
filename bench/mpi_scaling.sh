#!/usr/bin/env bash
# Parallel efficiency of a probe campaign from 1 to K MPI ranks, one thread each
# (docs/benchmarks.md, "Campaigns over MPI ranks").
# Usage: bench/mpi_scaling.sh BUILD_DIR PACKING "ARGS" [K] [REPEATS]   e.g.
#   bench/mpi_scaling.sh build/release /tmp/p2000 "--sample 20 --seed 3 --method lp" 2 3
# Runs `unjam probe PACKING ARGS --threads 1` on 1 and on K ranks, alternately REPEATS times,
# and prints per run: wall time, CPU time (user + sys) of every rank, the per-rank probes and
# busy seconds of probe_summary.json, and the efficiency T_1 / (K T_K). The outputs of every
# run are compared byte for byte with the first one-rank run (they must not depend on K).
set -euo pipefail
build=${1:?build dir}
packing=${2:?packing dir}
args=${3:?probe arguments}
k=${4:-2}
repeats=${5:-1}
out=${OUT:-/tmp/unjam-mpi-scaling}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1  # needed only as root
rm -rf "$out" && mkdir -p "$out"
run() {  # run RANKS NAME -> prints the wall seconds
  local ranks=$1 dir=$out/$2 t0 t1
  mkdir -p "$dir"
  t0=$(date +%s.%N)
  # shellcheck disable=SC2086
  mpirun -n "$ranks" --oversubscribe --bind-to none sh -c '/usr/bin/time -f "cpu %U %S" -o "$0/cpu-$OMPI_COMM_WORLD_RANK" "$@"' \
    "$dir" "$build/unjam" probe "$packing" $args --threads 1 --quiet --out "$dir" >"$dir/log" 2>&1
  t1=$(date +%s.%N)
  python3 - "$dir" "$t0" "$t1" <<'PY'
import glob, json, sys
d, t0, t1 = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
cpu = [sum(map(float, open(f).read().split()[-2:])) for f in sorted(glob.glob(d + "/cpu-*"))]
s = json.load(open(d + "/probe_summary.json"))
loads = " ".join(f"r{r['rank']}:{r['probes']}p/{r['busy_seconds']:.1f}s" for r in s["ranks"])
print(f"{d.split('/')[-1]:8s} wall {t1 - t0:7.2f} s  cpu {sum(cpu):7.2f} s ({' + '.join(f'{c:.2f}' for c in cpu)})  {loads}")
print(t1 - t0, file=open(d + "/wall", "w"))
PY
}
echo "# $(date -Is) $(uptime)"
echo "# unjam probe $packing $args --threads 1, 1 and $k ranks"
for i in $(seq 1 "$repeats"); do
  run 1 "k1-$i"
  run "$k" "k$k-$i"
  for f in probes.csv response_profile.csv response_field.csv; do
    cmp -s "$out/k1-1/$f" "$out/k$k-$i/$f" || { echo "DIFFERENT $f (k$k-$i)"; exit 1; }
  done
  python3 -c "import sys; t1=float(open('$out/k1-$i/wall').read()); tk=float(open('$out/k$k-$i/wall').read()); print(f'efficiency {t1/($k*tk):.2f}')"
done
echo "# after: $(uptime)"
