#!/usr/bin/env bash
# benches/instructions.sh — instructions per particle-step of the standard problem, in the
# sheared steady state, counted by valgrind's cachegrind (deterministic, unlike the wall clock
# of a shared machine).
#
# Runs `rheodem bench --threads 1` twice under cachegrind with the same 2000 warm-up steps and
# STEPS_SHORT then STEPS_LONG timed steps; the difference of the two instruction counts,
# divided by (STEPS_LONG − STEPS_SHORT) × 4096, is the cost of one particle-step after the
# warm-up, without the set-up. Prints one line per cohesion variant.
#
# Usage: bash benches/instructions.sh [BINARY] [COHESION...]
#   BINARY    rheodem binary (default: target/release/rheodem, built if missing)
#   COHESION  none | reversible | liquid-bridge | rabinovich | … (default: none)
# Environment: WARMUP (2000), STEPS_SHORT (100), STEPS_LONG (500), KEEP=1 keeps the raw files,
#   NORMAL (linear): the problem's normal law, `bench --normal` (hertz: Hertz with Mindlin's
#   sliding spring; luding); binaries before `bench --normal` existed take only linear.
set -euo pipefail
cd "$(git -C "$(dirname "${BASH_SOURCE[0]}")" rev-parse --show-toplevel)"
BIN=${1:-target/release/rheodem}
shift || true
VARIANTS=("${@:-none}")
WARMUP=${WARMUP:-2000}
STEPS_SHORT=${STEPS_SHORT:-100}
STEPS_LONG=${STEPS_LONG:-500}
command -v valgrind >/dev/null || { echo "valgrind is needed (apt-get install valgrind)" >&2; exit 1; }
[ -x "$BIN" ] || cargo build --release -p rheodem-cli
TMP=$(mktemp -d)
[ "${KEEP:-0}" = 1 ] || trap 'rm -rf "$TMP"' EXIT
NORMAL=${NORMAL:-linear}
NORMAL_ARGS=()
[ "$NORMAL" = linear ] || NORMAL_ARGS=(--normal "$NORMAL")
count() { # cohesion steps -> instruction count
  valgrind --tool=cachegrind --cache-sim=no --cachegrind-out-file="$TMP/$1-$2.out" \
    "$BIN" bench --threads 1 --cohesion "$1" "${NORMAL_ARGS[@]}" --warmup "$WARMUP" \
    --steps "$2" >/dev/null 2>"$TMP/$1-$2.log"
  awk '/^summary:/ {print $2}' "$TMP/$1-$2.out"
}
for c in "${VARIANTS[@]}"; do
  short=$(count "$c" "$STEPS_SHORT")
  long=$(count "$c" "$STEPS_LONG")
  awk -v a="$short" -v b="$long" -v s="$((STEPS_LONG - STEPS_SHORT))" -v c="$c" \
    -v n="$NORMAL" 'BEGIN { printf "%s, %s: %.0f instructions per particle-step (steady state, %d steps x 4096)\n", n, c, (b - a) / (s * 4096), s }'
done
# (an `if`, so that the script's status is 0 when KEEP is unset)
if [ "${KEEP:-0}" = 1 ]; then echo "raw cachegrind files in $TMP"; fi
