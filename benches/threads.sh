#!/usr/bin/env bash
# benches/threads.sh — instructions per particle-step against the thread count, counted by
# valgrind's cachegrind (exact on any machine, unlike the wall clock of a shared one).
#
# The problem: the standard problem repeated twice along each axis (32 768 spheres, the
# same law and shear rate), warmed up once natively and saved (`bench --save-state`). Each
# thread count T then runs from that state twice under cachegrind, STEPS_SHORT and
# STEPS_LONG steps, with `--members-in-turn`: the T members' parts of every parallel loop
# run one after another on one thread, with the same split of the work as T threads, so
# the count holds the extra work that T chunks cost (buffers, reductions, list pieces)
# and none of the spin-waits that valgrind, running threads one at a time, would count.
# The difference of the two counts divided by (STEPS_LONG − STEPS_SHORT) × N is the cost
# of one particle-step; the last column is its ratio to T = 1.
#
# Usage: bash benches/threads.sh [BINARY]
#   BINARY  rheodem binary (default: target/release/rheodem, built if missing)
# Environment: THREADS ("1 2 4 8 16"), REPLICATE (2), COHESION (none), WARMUP (2000),
#   STEPS_SHORT (20), STEPS_LONG (120), STATE (a saved state to start from instead of
#   warming up anew), SPLIT_BOTTOM (a split-bottom checkpoint, `checkpoint.bin` or
#   `settled.bin`, whose simulation is measured instead: `bench --split-bottom-state`),
#   KEEP=1 keeps the raw files.
# Minutes per thread count under valgrind: run it in the background, never in CI.
set -euo pipefail
cd "$(git -C "$(dirname "${BASH_SOURCE[0]}")" rev-parse --show-toplevel)"
BIN=${1:-target/release/rheodem}
THREADS=${THREADS:-1 2 4 8 16}
REPLICATE=${REPLICATE:-2}
COHESION=${COHESION:-none}
WARMUP=${WARMUP:-2000}
STEPS_SHORT=${STEPS_SHORT:-20}
STEPS_LONG=${STEPS_LONG:-120}
command -v valgrind >/dev/null || { echo "valgrind is needed (apt-get install valgrind)" >&2; exit 1; }
[ -x "$BIN" ] || cargo build --release -p rheodem-cli
TMP=$(mktemp -d)
[ "${KEEP:-0}" = 1 ] || trap 'rm -rf "$TMP"' EXIT
STATE=${STATE:-$TMP/state.bin}
if [ -n "${SPLIT_BOTTOM:-}" ]; then
  LOAD=(--split-bottom-state "$SPLIT_BOTTOM")
else
  LOAD=(--load-state "$STATE")
  if [ ! -f "$STATE" ]; then
    "$BIN" bench --threads 1 --replicate "$REPLICATE" --cohesion "$COHESION" \
      --warmup "$WARMUP" --save-state "$STATE" >&2
  fi
fi
# count T STEPS -> instruction count of the run
count() {
  valgrind --tool=cachegrind --cache-sim=no --cachegrind-out-file="$TMP/t$1-$2.out" \
    "$BIN" bench --threads "$1" --members-in-turn "${LOAD[@]}" --warmup 0 \
    --steps "$2" >"$TMP/t$1-$2.txt" 2>"$TMP/t$1-$2.log"
  awk '/^summary:/ {print $2}' "$TMP/t$1-$2.out"
}
particles=$("$BIN" bench --threads 1 "${LOAD[@]}" --warmup 0 --steps 1 \
  | awk '/^state/ {print $3; exit}')
printf "%-8s %-28s %s\n" threads "instructions/particle-step" "ratio to T = 1"
base=
for t in $THREADS; do
  short=$(count "$t" "$STEPS_SHORT")
  long=$(count "$t" "$STEPS_LONG")
  per=$(awk -v a="$short" -v b="$long" -v s="$((STEPS_LONG - STEPS_SHORT))" -v n="$particles" \
    'BEGIN { printf "%.1f", (b - a) / (s * n) }')
  base=${base:-$per}
  awk -v t="$t" -v p="$per" -v b="$base" 'BEGIN { printf "%-8s %-28s %.3f\n", t, p, p / b }'
done
echo "($particles particles, steps $STEPS_SHORT → $STEPS_LONG from the saved state, $(date -u +%F))"
if [ "${KEEP:-0}" = 1 ]; then echo "raw cachegrind files in $TMP"; fi
