#!/bin/bash
# The split-bottom cell compared with Roy et al. (2016) and Shi et al. (2020) like for like
# (issue: the papers' rotation rate and averaging window): the full-size 30° cell from one
# settled state, `--time-step mean-pair`, fields sampled every 0.1 s in the averaging window.
#
# Every run of a group is made by one binary, built from one commit and kept outside
# target/ (in validation/.bin/, not in git), with one thread count ($THREADS, default 1),
# so that a run resumed on another day or machine continues with the same bits while the
# code on main moves on. A binary is built on first use from a detached worktree of its
# commit. Each run's summary.json records the commit. The dry rate series was made by
# $RATE_COMMIT, before Willett's contact-only limit (0 nl) existed; every later group uses
# $COMMIT, and the group `bits` checks that the two give the same bits for a dry run.
#
# Resumable: rerun the script (or one group); a finished run (its summary.json says
# "completed") is skipped. The checkpoint of an unfinished long run is committed at the end
# of a working session (`git add -f …/checkpoint.bin`), so that another machine resumes it.
# Usage: bash validation/split-bottom-rate.sh GROUP…
#   settle — the settled state (committed as $V/settled/settled.bin: a new machine never
#            re-settles)
#   rate   — dry, Ω = 0.5, 0.25, 0.125 and 0.0628 rad/s over the same angles 0.5–1.25 rad
#   bits   — a 0.05 s dry shear from the settled state with both binaries: the time series
#            must be identical
#   wet05  — Willett at 0.020 N/m, 75 nl and 0 nl (the contact-only limit) at Ω = 0.5 over
#            0.5–1.25 rad: the references of the wet-excess candidates
#   seeds  — two more realisations (filling seeds 2 and 3, each settled on its own): dry and
#            75 nl at Ω = 0.5 over 0.5–1.25 rad, for the scatter of the wet–dry difference
#   wet0063 — the wet study at the papers' rate, Ω = 0.0628 rad/s over 0.5–1.75 rad: Willett
#            at 0.020 N/m with 75, 0, 14, 4.2 and 200 nl; 0.01, 0.04 and 0.06 N/m at 75 nl;
#            the two linear laws equivalent to 75 nl at 0.020 N/m (equal range and equal
#            energy, `rheodem contact equivalent`: f_a^max = 1.2989e-4 N, k_c = 0.2622 and
#            0.3879 N/m); and the dry cell over the same window
#   long   — the papers' window: dry and Willett 0.020 N/m, 75 nl at Ω = 0.0628 rad/s for
#            200 s, averaged over 80–200 s (5.03–12.57 rad), from the settled state (about
#            14 h of one thread per run; resumable from its 40 checkpoints)
#   grains — the wet-excess candidate "radius distribution": the papers' public driver draws
#            radii uniformly in [1, 2] × 1.1 mm/√2, i.e. w = 2 about a mean diameter of
#            2.333 mm (rheodem's default: 2.2 mm). A settled state of those grains
#            ($V/settled-grains, same cell and height), then dry and 75 nl at Ω = 0.5 over
#            0.5–1.25 rad; every result is scaled with the nominal d_p = 2.2 mm, as the papers'
#   shell  — the wet-excess candidate "wall construction": the settled state of seed 1
#            re-made by $SHELL_COMMIT with wall_shell = 1.1 (the papers' driver's 2.2 radii;
#            the same packing, frozen deeper: its settle rows must equal those of
#            $V/settled), then dry and 75 nl at Ω = 0.5 over 0.5–1.25 rad
set -euo pipefail
cd "$(dirname "$0")/.."
RATE_COMMIT=cac761ba48cd
COMMIT=75dfb0ac0cb2
# The first commit with the key wall_shell (the group shell).
SHELL_COMMIT=9ef5d50249a6
THREADS=${THREADS:-1}
V=validation/runs-split-bottom-rate
BIN_DIR=validation/.bin
# binary COMMIT: the path of the binary built from COMMIT (built now if missing).
binary() {
  local b=$BIN_DIR/rheodem-$1
  if [ ! -x "$b" ]; then
    echo "== building rheodem at $1 into $b" >&2
    local wt
    wt=$(mktemp -d)/rheodem-$1
    git worktree add --detach "$wt" "$1" >/dev/null
    cargo build --release --manifest-path "$wt/Cargo.toml" --target-dir "$wt/target" \
      -p rheodem-cli >&2
    mkdir -p "$BIN_DIR"
    cp "$wt/target/release/rheodem" "$b.tmp" && mv "$b.tmp" "$b"
    git worktree remove --force "$wt"
  fi
  echo "$b"
}
mkdir -p "$V"
common=(--time-step mean-pair --quiet --threads "$THREADS")
# Ω = 2π f_rot with f_rot = 0.01 /s, the papers' rate.
OMEGA_PAPER=0.0628318530718
settle() {
  if [ ! -f "$V/settled/settled.bin" ]; then
    echo "== settled"
    "$(binary $RATE_COMMIT)" split-bottom "${common[@]}" --duration 0.01 --average-from 0 \
      --out "$V/settled" 2>&1 | tee "$V/settled.log"
  fi
}
# settle_seed SEED: the settled state of another filling, in $V/settled-seedSEED.
settle_seed() {
  if [ ! -f "$V/settled-seed$1/settled.bin" ]; then
    echo "== settled-seed$1"
    "$(binary $COMMIT)" split-bottom "${common[@]}" --seed "$1" --duration 0.01 \
      --average-from 0 --out "$V/settled-seed$1" 2>&1 | tee "$V/settled-seed$1.log"
  fi
}
# run BINARY NAME OMEGA FROM_RAD TO_RAD [OPTIONS…]: shear at OMEGA (rad/s) up to the angle
# TO_RAD, averaged from FROM_RAD, from the settled state ($V/$FROM, default settled). A run
# that fails is reported and the next one goes on.
run() {
  local b=$1 name=$2 omega=$3 from=$4 to=$5; shift 5
  local duration average_from
  # A finished run is kept as it is: its checkpoint is not in git, so a new machine would
  # otherwise run it again from the start.
  if grep -q '"status": *"completed"' "$V/$name/summary.json" 2>/dev/null; then
    echo "== $name: finished (its summary says completed)"
    return
  fi
  duration=$(echo "$to / $omega" | bc -l)
  average_from=$(echo "$from / $omega" | bc -l)
  echo "== $name (Ω = $omega rad/s, $from–$to rad)"
  "$b" split-bottom "${common[@]}" --from "$V/${FROM:-settled}" --omega "$omega" \
    --duration "$duration" --average-from "$average_from" --out "$V/$name" \
    --config "${CONFIG:-$V/checkpoints.toml}" "$@" 2>&1 | tee "$V/$name.log" \
    || echo "== $name failed (see $V/$name.log)"
}
# variant_settle NAME BINARY KEY_LINE: the settled state of seed 1 in a cell changed by one
# key (written with the checkpoints' key to $V/NAME.toml), in $V/settled-NAME.
variant_settle() {
  printf 'checkpoints = 40\n%s\n' "$3" > "$V/$1.toml"
  if [ ! -f "$V/settled-$1/settled.bin" ]; then
    echo "== settled-$1"
    "$2" split-bottom "${common[@]}" --config "$V/$1.toml" --duration 0.01 \
      --average-from 0 --out "$V/settled-$1" 2>&1 | tee "$V/settled-$1.log"
  fi
}
# variant_runs NAME BINARY: dry and 75 nl at 0.020 N/m, Ω = 0.5 over 0.5–1.25 rad, from
# $V/settled-NAME.
variant_runs() {
  FROM=settled-$1 CONFIG=$V/$1.toml run "$2" "dry-omega0.5-$1" 0.5 0.5 1.25
  FROM=settled-$1 CONFIG=$V/$1.toml run "$2" "wet-g0.02-v75-omega0.5-$1" 0.5 0.5 1.25 \
    --law willett --surface-tension 0.02 --volume-nl 75
}
# Long runs keep 40 checkpoints, so that a kill loses at most 2.5 % of a run.
printf 'checkpoints = 40\n' > "$V/checkpoints.toml"
for group in "$@"; do
  case $group in
    settle) settle ;;
    rate)
      settle
      for omega in 0.5 0.25 0.125 $OMEGA_PAPER; do
        run "$(binary $RATE_COMMIT)" "dry-omega$(printf '%.4g' "$omega")" "$omega" 0.5 1.25
      done ;;
    bits)
      settle
      for c in $RATE_COMMIT $COMMIT; do
        "$(binary "$c")" split-bottom "${common[@]}" --from "$V/settled" --omega 0.5 \
          --duration 0.05 --average-from 0.025 --out "/tmp/rheodem-bits-$c" --force >/dev/null
      done
      if cmp "/tmp/rheodem-bits-$RATE_COMMIT/timeseries.csv" "/tmp/rheodem-bits-$COMMIT/timeseries.csv"; then
        echo "== bits: $RATE_COMMIT and $COMMIT give the same dry time series"
      else
        echo "== bits: $RATE_COMMIT and $COMMIT DIFFER on a dry run"; exit 1
      fi ;;
    wet05)
      settle
      for v in 75 0; do
        run "$(binary $COMMIT)" "wet-g0.02-v$v-omega0.5" 0.5 0.5 1.25 \
          --law willett --surface-tension 0.02 --volume-nl "$v"
      done ;;
    seeds)
      for seed in 2 3; do
        settle_seed "$seed"
        FROM=settled-seed$seed run "$(binary $COMMIT)" "dry-omega0.5-seed$seed" 0.5 0.5 1.25 \
          --seed "$seed"
        FROM=settled-seed$seed run "$(binary $COMMIT)" "wet-g0.02-v75-omega0.5-seed$seed" \
          0.5 0.5 1.25 --seed "$seed" --law willett --surface-tension 0.02 --volume-nl 75
      done ;;
    wet0063)
      settle
      # 0.5–1.75 rad at the papers' rate (about 28 s of shear).
      wet() { run "$(binary $COMMIT)" "$1" $OMEGA_PAPER 0.5 1.75 "${@:2}"; }
      wet wet-g0.02-v75-omega0.06283 --law willett --surface-tension 0.02 --volume-nl 75
      wet wet-g0.02-v0-omega0.06283 --law willett --surface-tension 0.02 --volume-nl 0
      wet dry-omega0.06283-to1.75
      for v in 14 4.2 200; do
        wet "wet-g0.02-v$v-omega0.06283" --law willett --surface-tension 0.02 --volume-nl "$v"
      done
      for g in 0.01 0.04 0.06; do
        wet "wet-g$g-v75-omega0.06283" --law willett --surface-tension "$g" --volume-nl 75
      done
      wet linear-range-v75-omega0.06283 --law linear --max-force 1.2989e-4 \
        --adhesive-stiffness 0.2622
      wet linear-energy-v75-omega0.06283 --law linear --max-force 1.2989e-4 \
        --adhesive-stiffness 0.3879 ;;
    long)
      settle
      from=$(echo "80 * $OMEGA_PAPER" | bc -l)
      to=$(echo "200 * $OMEGA_PAPER" | bc -l)
      run "$(binary $COMMIT)" dry-omega0.06283-200s $OMEGA_PAPER "$from" "$to"
      run "$(binary $COMMIT)" wet-g0.02-v75-omega0.06283-200s $OMEGA_PAPER "$from" "$to" \
        --law willett --surface-tension 0.02 --volume-nl 75 ;;
    grains)
      variant_settle grains "$(binary $COMMIT)" 'diameter = 2.3333333333333333e-3'
      variant_runs grains "$(binary $COMMIT)" ;;
    shell)
      settle
      variant_settle shell "$(binary $SHELL_COMMIT)" 'wall_shell = 1.1'
      if cmp <(grep ',settle,' "$V/settled/timeseries.csv") \
        <(grep ',settle,' "$V/settled-shell/timeseries.csv"); then
        echo "== shell: the same settling as $V/settled"
      else
        echo "== shell: the settling DIFFERS from $V/settled"; exit 1
      fi
      variant_runs shell "$(binary $SHELL_COMMIT)" ;;
    *) echo "unknown group $group (settle, rate, bits, wet05, seeds, wet0063, long, grains, shell)" >&2; exit 2 ;;
  esac
done
