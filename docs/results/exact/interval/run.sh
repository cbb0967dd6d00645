#!/bin/sh
# The interval positions of docs/probe.md, "Where F_crit lies in the admissible interval".
# Each CELL-cd is a cd campaign (unjam probe P ... --method cd --cd-start interior), each
# CELL-bounds.csv `unjam bounds P --out CELL-bounds.csv --threads 1` of the same packing.
set -e
cells="fixture-p50-mu0.1 N50-mu0.1-s1 N50-mu0.1-s2 N50-mu0.1-s3 N50-mu0.1-s4 N50-mu0.1-s5 N50-mu0.1-s6 N50-mu0.1-s7 N50-mu0.1-s8 N50-mu0.1-s9 N50-mu0.1-s10 N100-mu0.1-s1 N100-mu0.1-s2 N100-mu0.1-s3 N100-mu0.1-s4 N100-mu0.1-s5 N200-mu0.1-s1 N500-mu0.1-s1 N1000-mu0.1-s1 N1000-mu0.1-s2 N1000-mu0.05-s2 N2000-mu0.05-s1 N500-mu0.5-s2 N500-mu1-s1 N1000-mu1-s1 N1000-mu1-s2 N1000-mu0.5-s1 N1000-mu0.5-s2 N1000-mu0.2-s1"
args=""
for c in $cells; do args="$args $c-cd $c-bounds.csv"; done
/usr/bin/python3 "$1/scripts/interval_position.py" $args N200-mu0.1-s1-cd-static N200-mu0.1-s1-bounds.csv \
    --label $cells N200-mu0.1-s1-static --out all
# the figure of docs/img/interval-position.png: one packing per size and friction
fig="fixture-p50-mu0.1 N100-mu0.1-s1 N200-mu0.1-s1 N500-mu0.1-s1 N1000-mu0.1-s1 N2000-mu0.05-s1 N500-mu0.5-s2 N500-mu1-s1 N1000-mu1-s1 N1000-mu1-s2 N1000-mu0.5-s1 N1000-mu0.5-s2 N1000-mu0.2-s1"
args=""
for c in $fig; do args="$args $c-cd $c-bounds.csv"; done
/usr/bin/python3 "$1/scripts/interval_position.py" $args --label $fig --out figure
