#!/bin/sh
# The fields of the paper's probe (cd) against the stand-in's (lp) on the first probes of the
# stored campaigns (docs/probe.md, "300 probes per packing", the fields). Run in a directory
# holding the packings pN-muMU-sS (`unjam pack --n N --mu MU --seed S --out pN-muMU-sS`), with
# the path of an unjam repository whose build/release holds the Python module:
#   sh run.sh /path/to/unjam-repository
# Each cell's contacts are probed again with its campaign's own settings, and fields.json's
# campaign_check says whether every F_crit(cd) is the campaign's, bit for bit.
set -e
M=$1
for cell in N1000-mu0.05-s2:40 N1000-mu0.1-s2:40 N1000-mu1-s2:40 N2000-mu0.05-s1:12; do
    c=${cell%%:*}; limit=${cell##*:}
    p=$(echo "$c" | sed 's/^N\([0-9]*\)-mu\([0-9.]*\)-s\([0-9]*\)$/p\1-mu\2-s\3/')
    PYTHONPATH="$M/build/release/python" /usr/bin/python3 "$M/scripts/field_cosines.py" "$p" \
        --from-campaign "$M/docs/results/exact/$c/cd/probes.csv" --limit "$limit" --threads 1 \
        --out "$c"
done
/usr/bin/python3 "$M/scripts/plot_field_cosines.py" N1000-mu0.05-s2 N1000-mu0.1-s2 N1000-mu1-s2 \
    N2000-mu0.05-s1 --out all
