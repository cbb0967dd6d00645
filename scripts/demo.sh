#!/usr/bin/env bash
# The demo pipeline: a 500-disk packing at mu = 0.1 compacted from a gas, every contact
# probed (critical force, mean displacement field, d(r)), the exact force bounds, and the
# paper's Fig. 4 on a 50-disk packing; figures as PNG. About two minutes on two cores.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-runs/demo}"
unjam=build/release/unjam
py=/usr/bin/python3
mkdir -p "$out"

echo "== 1. compaction: 500 disks, mu = 0.1"
$unjam pack --n 500 --mu 0.1 --seed 1 --out "$out/p500-mu0.1" --quiet
$unjam info "$out/p500-mu0.1"

echo "== 2. probe every contact (LP critical force + kinematic displacement field)"
$unjam probe "$out/p500-mu0.1" --all --quiet
first=$(awk -F, 'NR == 2 { print $1 }' "$out/p500-mu0.1/probes.csv")
$unjam probe "$out/p500-mu0.1" --contact "$first" > /dev/null

echo "== 3. exact per-contact force bounds (linear programs)"
$unjam bounds "$out/p500-mu0.1" > /dev/null

echo "== 4. force-network ensemble of a 50-disk packing (the paper's Fig. 4)"
$unjam pack --n 50 --mu 0.1 --seed 3 --out "$out/p50-mu0.1" --quiet > /dev/null
$unjam ensemble "$out/p50-mu0.1" --samples 2000 --probe lp > /dev/null

echo "== 5. figures"
$py scripts/plot_packing.py "$out/p500-mu0.1"
$py scripts/plot_probe_field.py "$out/p500-mu0.1" --contact "$first"
$py scripts/plot_response_field.py "$out/p500-mu0.1"
$py scripts/plot_profile.py "$out/p500-mu0.1" --no-fit --out "$out/p500-mu0.1/fig2-profile.png"
$py scripts/plot_fig4.py "$out/p50-mu0.1"
echo
echo "results in $out:"
find "$out" -name "*.png" -o -name "probe_summary.json" -o -name "bounds.json" -o -name "ensemble.json" | sort
