#!/bin/bash
# The contact laws added on the platform, run in the set-ups beside the laws they are
# compared with (issue: Hertz–Mindlin, the Rabinovich bridge, Luding's elasto-plastic
# adhesion). One pinned binary, built from $COMMIT into validation/.bin/ on first use (as in
# validation/split-bottom-rate.sh), one thread per run. Resumable: rerun the script.
# Usage: bash validation/platform-laws.sh GROUP…
#   luding     — the shear box at μ_p = 0.3, I = 0.02, p* = 0.01, Bo = 1 (w = 3, N = 4096,
#                strain 15, seed 1) with Luding's law (k_p = 5 k_n, φ_f = 0.05, k_c such
#                that a contact loaded to the plastic limit pulls off with Bo p d²), beside
#                the reversible law's point of the phase diagram
#                (validation/results-phase-diagram/mu0.3_i0.02_p0.01_bo1_reversible_w3_n4096_s1.json)
#   rabinovich — the split-bottom cell with Rabinovich bridges, 0.020 N/m, 75 nl, at
#                Ω = 0.5 rad/s over 0.5–1.25 rad from the rate series' settled state, beside
#                Willett's run of the same settings (runs-split-bottom-rate/wet-g0.02-v75-omega0.5)
#   rabinovich-tension — the same at 0.010 and 0.040 N/m: the cohesion against the surface
#                tension (with the dry run runs-split-bottom-rate/dry-omega0.5)
set -euo pipefail
cd "$(dirname "$0")/.."
COMMIT=41945d1
THREADS=${THREADS:-1}
OUT=validation/runs-platform-laws
RATE=validation/runs-split-bottom-rate
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
printf 'checkpoints = 40\n' > "$OUT/checkpoints.toml"
# rabinovich TENSION: the cell with Rabinovich bridges of 75 nl at TENSION (N/m), Ω = 0.5.
rabinovich() {
  local name="rabinovich-g$1-v75-omega0.5"
  echo "== $name"
  "$BIN" split-bottom --time-step mean-pair --quiet --threads "$THREADS" \
    --from "$RATE/settled" --omega 0.5 --duration 2.5 --average-from 1.0 \
    --config "$OUT/checkpoints.toml" --law rabinovich --surface-tension "$1" \
    --volume-nl 75 --out "$OUT/$name" 2>&1 | tee "$OUT/$name.log"
}
for group in "$@"; do
  case $group in
    luding)
      echo "== luding-bo1"
      "$BIN" shear-box --threads "$THREADS" --mu-p 0.3 --inertial 0.02 --softness 0.01 \
        --bond 1 --normal-law luding --strain 15 --seed 1 --out "$OUT/luding-bo1" 2>&1 \
        | tee "$OUT/luding-bo1.log" ;;
    rabinovich) rabinovich 0.02 ;;
    rabinovich-tension) rabinovich 0.01; rabinovich 0.04 ;;
    *) echo "unknown group $group (luding, rabinovich, rabinovich-tension)" >&2; exit 2 ;;
  esac
done
