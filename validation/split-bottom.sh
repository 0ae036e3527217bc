#!/bin/bash
# The split-bottom validation runs of VALIDATION.md (full-size 30° cell unless named).
# Resumable: rerun the script; a finished run only rewrites its outputs.
# Usage: bash validation/split-bottom.sh [path/to/rheodem]   (default: target/release/rheodem)
set -euo pipefail
cd "$(dirname "$0")/.."
B=${1:-target/release/rheodem}
V=validation/runs-split-bottom
mkdir -p "$V"
common=(--duration 2.5 --average-from 1.0 --time-step mean-pair --quiet)
run() { local name=$1; shift; echo "== $name"; "$B" split-bottom "${common[@]}" --out "$V/$name" "$@" 2>&1 | tee "$V/$name.log"; }
run dry-omega0.5 --omega 0.5
run dry-omega0.25 --omega 0.25 --from "$V/dry-omega0.5"
for g in 0.01 0.02 0.04; do
  run wet-gamma$g --omega 0.5 --law willett --surface-tension $g --volume-nl 75 --from "$V/dry-omega0.5"
done
run dry-wedge60-omega0.5 --omega 0.5 --wedge-deg 60
# Ω = 0.25 over the same rotation angles as Ω = 0.5 (twice the time).
common=(--duration 5.0 --average-from 2.0 --time-step mean-pair --quiet)
run dry-omega0.25-long --omega 0.25 --from "$V/dry-omega0.5"
# Ω = 0.125 over the same rotation angles (four times the time).
common=(--duration 10.0 --average-from 4.0 --time-step mean-pair --quiet)
run dry-omega0.125 --omega 0.125 --from "$V/dry-omega0.5"
