#!/usr/bin/env bash
# The recorded calls replayed with one block size throughout and with blocks twice as wide beyond 30 m,
# alternating, on a checkout with two_level.patch applied (PYTHONPATH at its src/), from its perf/ folder.
# REC: the folder of the recordings (perf/replay_far_fields.py record, see README.md).
set -euo pipefail
REC=${REC:-/tmp/rec}
OUT=${OUT:-.}
for r in p1_50 p1_85 p2_80 p3_60; do
  for k in 1 2; do
    python replay_far_fields.py replay "$REC/$r.pkl" --repeats 3 --save "$OUT/${r}_whole.npz" > "$OUT/${r}_whole_$k.txt"
    python replay_far_fields.py replay "$REC/$r.pkl" --repeats 3 --coarse-radius-m 30 --save "$OUT/${r}_b30.npz" > "$OUT/${r}_b30_$k.txt"
  done
  python replay_far_fields.py diff "$OUT/${r}_whole.npz" "$OUT/${r}_b30.npz" > "$OUT/${r}_diff.txt"
done
