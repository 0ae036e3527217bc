#!/usr/bin/env bash
# benches/instructions.sh — instructions per particle-step of the standard problem, in the
# sheared steady state, counted by valgrind's cachegrind (deterministic, unlike the wall clock
# of a shared machine).
#
# Runs `rheodem bench --threads 1` twice under cachegrind with the same 2000 warm-up steps and
# STEPS_SHORT then STEPS_LONG timed steps; the difference of the two instruction counts,
# divided by (STEPS_LONG − STEPS_SHORT) × 4096, is the cost of one particle-step after the
# warm-up, without the set-up. Prints one line per cohesion variant: that cost, and the pair
# loop's instructions (the functions `chunk_forces*`, everything inlined into them) per
# touching contact (`Z N / 2` at the end of the long run), the measure of the cohesive
# laws' cost per contact (adhesive packings hold more contacts than dry ones); the last
# column is the ratio to the first variant's.
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
count() { # cohesion steps -> "total pair-loop" instruction counts
  valgrind --tool=cachegrind --cache-sim=no --cachegrind-out-file="$TMP/$1-$2.out" \
    "$BIN" bench --threads 1 --cohesion "$1" "${NORMAL_ARGS[@]}" --warmup "$WARMUP" \
    --steps "$2" >"$TMP/$1-$2.txt" 2>"$TMP/$1-$2.log"
  local total loop
  total=$(awk '/^summary:/ {print $2}' "$TMP/$1-$2.out")
  # The function summary of cg_annotate: counts, then `file:function`, up to a blank line.
  loop=$(cg_annotate --show-percs=no "$TMP/$1-$2.out" 2>/dev/null | awk '
    /file:function/ && !done { on = 1; next }
    on && /^$/ { on = 0; done = 1 }
    on && /chunk_forces/ { gsub(",", "", $1); sum += $1 }
    END { printf "%.0f", sum }')
  echo "$total $loop"
}
first=
for c in "${VARIANTS[@]}"; do
  read -r short short_loop < <(count "$c" "$STEPS_SHORT")
  read -r long long_loop < <(count "$c" "$STEPS_LONG")
  z=$(sed -n 's/.*Z = \([0-9.]*\).*/\1/p' "$TMP/$c-$STEPS_LONG.txt" | tail -1)
  per_contact=$(awk -v a="$short_loop" -v b="$long_loop" -v s="$((STEPS_LONG - STEPS_SHORT))" \
    -v z="$z" 'BEGIN { printf "%.1f", (b - a) / (s * z * 4096 / 2) }')
  first=${first:-$per_contact}
  awk -v a="$short" -v b="$long" -v s="$((STEPS_LONG - STEPS_SHORT))" -v c="$c" \
    -v n="$NORMAL" -v pc="$per_contact" -v f="$first" -v z="$z" 'BEGIN { printf "%s, %s: %.0f instructions per particle-step (steady state, %d steps x 4096); pair loop %.1f per touching contact (Z = %s), %.3f of the first variant'"'"'s\n", n, c, (b - a) / (s * 4096), s, pc, z, pc / f }'
done
# (an `if`, so that the script's status is 0 when KEEP is unset)
if [ "${KEEP:-0}" = 1 ]; then echo "raw cachegrind files in $TMP"; fi
