#!/bin/bash
# Throughput of the sheared split-bottom cell (full size, 30° wedge), dry and wet, on 1 and
# 2 threads, from one settled state. Prints particle-steps per second (free and wall
# particles counted) and the projected wall time of the paper's run (200 s).
# Usage: bash benches/split_bottom.sh [SETTLED_DIR]
#   SETTLED_DIR: a split-bottom run directory holding settled.bin (the settled state is
#   git-ignored, so a clone's validation runs lack it); without the argument the script
#   settles a cell once into its own work folder and reuses it. A given directory is only
#   read: the script never settles into it (that would overwrite the run kept there).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q
B=target/release/rheodem
W=${TMPDIR:-/tmp}/rheodem-bench-split-bottom
if [ $# -ge 1 ]; then
  SETTLED=$1
  if [ ! -f "$SETTLED/settled.bin" ]; then
    echo "split_bottom.sh: $SETTLED/settled.bin not found; give a run directory that has" \
      "its settled state, or no argument to settle one in $W/settled" >&2
    exit 2
  fi
else
  SETTLED=$W/settled
  if [ ! -f "$SETTLED/settled.bin" ]; then
    "$B" split-bottom --time-step mean-pair --duration 0.01 --average-from 0 --out "$SETTLED" --force --quiet > /dev/null
  fi
fi
DURATION=${DURATION:-0.15}
printf "%-6s %-8s %10s %10s %14s %12s\n" law threads particles free "steps/s(M p)" "200 s run (h)"
for law in dry wet; do
  extra=()
  [ "$law" = wet ] && extra=(--law willett --surface-tension 0.02 --volume-nl 75)
  for t in 1 2; do
    out=$W/$law-$t
    "$B" split-bottom --from "$SETTLED" --time-step mean-pair --omega 0.5 --duration "$DURATION" \
      --average-from 0 --threads "$t" --out "$out" --force --quiet "${extra[@]}" > /dev/null
    python3 - "$out/summary.json" "$law" "$t" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
rate = s["particle_steps_per_second"]
steps = 200.0 / s["groups"]["dt"]
hours = s["particles"] * steps / rate / 3600.0
print(f"{sys.argv[2]:<6} {sys.argv[3]:<8} {s['particles']:>10} {s['free_particles']:>10} {rate/1e6:>14.2f} {hours:>12.1f}")
PY
  done
done
