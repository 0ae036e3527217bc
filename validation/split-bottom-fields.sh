#!/bin/bash
# The coarse-grained split-bottom runs of VALIDATION.md ("Split-bottom fields"): the full-size
# 30° cell sheared at Ω = 0.5 rad/s from one settled state, dry and wet (Willett bridges),
# with the fields sampled every 0.1 s over the averaging window (the default cg_* keys).
# Resumable: rerun the script; a finished run only rewrites its outputs.
# Usage: bash validation/split-bottom-fields.sh [path/to/rheodem] [names…]
set -euo pipefail
cd "$(dirname "$0")/.."
B=${1:-target/release/rheodem}
shift || true
V=validation/runs-split-bottom-fields
mkdir -p "$V"
if [ ! -f "$V/settled/settled.bin" ]; then
  "$B" split-bottom --time-step mean-pair --duration 0.01 --average-from 0 --out "$V/settled" --quiet
fi
common=(--omega 0.5 --duration 2.5 --average-from 1.0 --time-step mean-pair --quiet --from "$V/settled")
run() { local name=$1; shift; echo "== $name"; "$B" split-bottom "${common[@]}" --out "$V/$name" "$@" 2>&1 | tee "$V/$name.log"; }
names=("$@")
for spec in "dry" "wet-g0.02-v75:0.02:75" "wet-g0.02-v14:0.02:14" "wet-g0.02-v200:0.02:200" \
            "wet-g0.04-v75:0.04:75" "wet-g0.06-v75:0.06:75"; do
  IFS=: read -r name g v <<< "$spec"
  if [ ${#names[@]} -gt 0 ] && [[ " ${names[*]} " != *" $name "* ]]; then continue; fi
  if [ "$name" = dry ]; then run dry; else
    run "$name" --law willett --surface-tension "$g" --volume-nl "$v"; fi
done
