#!/bin/bash
# Inclined chute flow against its closed forms and against the shear box (issue: the chute
# on the platform). One pinned binary, built from $COMMIT into validation/.bin/ on first
# use (as in validation/split-bottom-rate.sh), one thread per run. Resumable: rerun the
# script; a finished run is read back, not rerun.
# Usage: bash validation/chute.sh GROUP…
#   settle   — one settled layer: 10 × 10 d_p, 20 d_p deep, the shear box's grains
#              (d_p = 2.2 mm, ρ_p = 2000 kg/m³, k_n = 100 N/m, e = 0.8) at w = 1.5, μ_p = 0.5
#   scan     — the dry layer tilted from it to 18, 21, 23 and 25°, 20 s of flow (about
#              1350 √(d_p/g)), averaged over the last 10 s: the steady range, the force
#              balance at every angle, Bagnold's profile
#   scan-more — the same at 24, 26, 22, 20 and 28°
#   box      — the shear box at μ_p = 0.5, w = 1.5, e = 0.8 at the bulk I and the
#              mid-depth p* of steady chute runs (ANGLES, default 23 24 25)
#   cohesive — the reversible law with f_a^max/(m g) = 5 (k_c = k_n) at 26, 28 and 30°
#   box-cohesive — the shear box at the bulk I, mid-depth p* and Bo of the steady cohesive
#              run at COHESIVE_ANGLE (default 28)
set -euo pipefail
cd "$(dirname "$0")/.."
COMMIT=162ad59
THREADS=${THREADS:-1}
OUT=validation/runs-chute
BIN=validation/.bin/rheodem-$COMMIT
if [ ! -x "$BIN" ]; then
  echo "== building rheodem at $COMMIT into $BIN" >&2
  wt=$(mktemp -d)/rheodem-$COMMIT
  git worktree add --detach "$wt" "$COMMIT" >/dev/null
  cargo build --release --manifest-path "$wt/Cargo.toml" --target-dir "$wt/target" -p rheodem-cli >&2
  mkdir -p validation/.bin
  cp "$wt/target/release/rheodem" "$BIN.tmp" && mv "$BIN.tmp" "$BIN"
  git worktree remove --force "$wt"
fi
mkdir -p "$OUT"
# The weight of a mean grain, m g (N), and the reversible law's strength 5 m g.
WEIGHT=$(python3 -c 'import math; print(2000 * math.pi / 6 * 2.2e-3**3 * 9.81)')
FMAX=$(python3 -c "print(5 * $WEIGHT)")
LAYER=(--height 20 --length 10 --width 10 --polydispersity 1.5 --mu-p 0.5 --seed 1)
FLOW=(--duration 20 --average-from 10 --rows 400 --snapshots 2 --checkpoints 20)
# chute NAME ANGLE [options…]: the settled layer tilted to ANGLE degrees.
chute() {
  local name=$1 angle=$2
  shift 2
  echo "== $name"
  "$BIN" chute --quiet --threads "$THREADS" "${LAYER[@]}" "${FLOW[@]}" --angle-deg "$angle" \
    --from "$OUT/settled" --out "$OUT/$name" "$@" 2>&1 | tee "$OUT/$name.log"
}
# box NAME CHUTE_RUN [options…]: the shear box at the chute run's bulk I and mid-depth p*
# (and, with --cohesion, its mid-depth Bo).
box() {
  local name=$1 run=$OUT/$2/summary.json
  shift 2
  read -r inertial softness bond < <(python3 -c "
import json, sys
b = json.load(open('$run'))['results']['bulk']
print(f\"{b['inertial_number']['mean']:.4g} {b['softness_mid']:.4g} {b['bond_mid']:.4g}\")")
  local bo=()
  if [ "${1:-}" = --cohesion ]; then bo=(--bond "$bond" --cohesion reversible); shift; fi
  echo "== $name: I = $inertial, p* = $softness ${bo[*]}"
  "$BIN" shear-box --threads "$THREADS" --mu-p 0.5 --inertial "$inertial" \
    --softness "$softness" --polydispersity 1.5 --restitution 0.8 --strain 20 \
    --transient-strain 5 --seed 1 "${bo[@]}" --out "$OUT/$name" 2>&1 | tee "$OUT/$name.log"
}
for group in "$@"; do
  case $group in
    settle)
      echo "== settled"
      "$BIN" chute --quiet --threads "$THREADS" "${LAYER[@]}" --angle-deg 0 --duration 0.05 \
        --average-from 0 --out "$OUT/settled" 2>&1 | tee "$OUT/settled.log" ;;
    scan)
      for a in 18 21 23 25; do chute "dry-theta$a" "$a"; done ;;
    scan-more)
      for a in 24 26 22 20 28; do chute "dry-theta$a" "$a"; done ;;
    box)
      for a in ${ANGLES:-23 24 25}; do box "box-dry-theta$a" "dry-theta$a"; done ;;
    cohesive)
      for a in 26 28 30; do
        chute "reversible5-theta$a" "$a" --law reversible --max-force "$FMAX" \
          --adhesive-stiffness 100
      done ;;
    box-cohesive)
      box "box-reversible5-theta${COHESIVE_ANGLE:-28}" "reversible5-theta${COHESIVE_ANGLE:-28}" \
        --cohesion ;;
    *) echo "unknown group $group (settle, scan, scan-more, box, cohesive, box-cohesive)" >&2; exit 2 ;;
  esac
done
