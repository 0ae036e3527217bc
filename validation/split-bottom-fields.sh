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
# The checks (kernel width, other realisations) go apart: `rheodem wet-study` fits every run
# of a directory.
C=validation/runs-split-bottom-checks
mkdir -p "$V"
if [ ! -f "$V/settled/settled.bin" ]; then
  "$B" split-bottom --time-step mean-pair --duration 0.01 --average-from 0 --out "$V/settled" --quiet
fi
common=(--time-step mean-pair --quiet ${THREADS:+--threads "$THREADS"})
# run NAME [OPTIONS…]: Ω, duration and averaging start from OMEGA, DURATION, AVERAGE_FROM,
# the settled state from FROM (default: $V/settled), the run directory's parent from DEST
# (default: $V); worker threads from THREADS (default: all).
# A run that fails is reported and the next one goes on.
run() {
  local name=$1 dest=${DEST:-$V}; shift; echo "== $name"
  mkdir -p "$dest"
  "$B" split-bottom "${common[@]}" --from "${FROM:-$V/settled}" --omega "${OMEGA:-0.5}" --duration "${DURATION:-2.5}" \
    --average-from "${AVERAGE_FROM:-1.0}" --out "$dest/$name" "$@" 2>&1 | tee "$dest/$name.log" \
    || echo "== $name failed (see $dest/$name.log)"
}
names=("$@")
# wet dry|VOLUME_NL: the options of a dry run, or of a Willett bridge of that volume at 0.020 N/m.
wet() { [ "$1" = dry ] || echo "--law willett --surface-tension 0.02 --volume-nl $1"; }
# name:law:a:b — willett a = γ_s (N/m), b = V_b (nl); linear a = f_max (N), b = k_c (N/m), the
# equivalents of the 0.02 N/m Willett bridge from `rheodem contact equivalent` (equal f_max and
# adhesive energy E, or equal f_max and rupture distance S_c); rate: a = Ω (rad/s), b = duration
# (s), same total rotation as the Ω = 0.5 runs, averaged over the same angle; gravity: a = g
# (m/s²), from a state settled under that g; width: a = the kernel width cg_width (d_p), b = dry
# or a Willett volume (nl) at 0.020 N/m; seed: a = the filling's seed, b as for width, from a
# state settled from that filling; both into $C.
for spec in "dry:dry" "wet-g0.02-v75:willett:0.02:75" "wet-g0.02-v14:willett:0.02:14" \
            "wet-g0.02-v200:willett:0.02:200" "wet-g0.04-v75:willett:0.04:75" \
            "wet-g0.06-v75:willett:0.06:75" \
            "lin-E-v75:linear:1.2989e-4:0.3879" "lin-Sc-v75:linear:1.2989e-4:0.2622" \
            "lin-E-v14:linear:1.2989e-4:0.8448" "lin-Sc-v14:linear:1.2989e-4:0.4589" \
            "dry-omega0.25:rate:0.25:5.0" "wet-g0.02-v75-omega0.25:rate-wet:0.25:5.0" \
            "dry-g3:gravity:3" "dry-g30:gravity:30" \
            "dry-w0.5:width:0.5:dry" "dry-w2:width:2:dry" "dry-rerun:width:1:dry" \
            "wet-g0.02-v75-w0.5:width:0.5:75" "wet-g0.02-v75-w2:width:2:75" \
            "wet-g0.02-v75-rerun:width:1:75" \
            "dry-seed2:seed:2:dry" "wet-g0.02-v75-seed2:seed:2:75"; do
  IFS=: read -r name law a b <<< "$spec"
  if [ ${#names[@]} -gt 0 ] && [[ " ${names[*]} " != *" $name "* ]]; then continue; fi
  case $law in
    dry) run "$name" ;;
    willett) run "$name" --law willett --surface-tension "$a" --volume-nl "$b" ;;
    linear) run "$name" --law linear --max-force "$a" --adhesive-stiffness "$b" ;;
    gravity)
      # A shear run keeps the settled state's gravity: settle under this g first.
      if [ ! -f "$V/settled-g$a/settled.bin" ]; then
        "$B" split-bottom --time-step mean-pair --gravity "$a" --duration 0.01 --average-from 0 \
          --out "$V/settled-g$a" --quiet
      fi
      FROM=$V/settled-g$a run "$name" --gravity "$a" ;;
    rate) OMEGA=$a DURATION=$b AVERAGE_FROM=$(echo "$b * 0.4" | bc -l) run "$name" ;;
    rate-wet) OMEGA=$a DURATION=$b AVERAGE_FROM=$(echo "$b * 0.4" | bc -l) run "$name" \
                --law willett --surface-tension 0.02 --volume-nl 75 ;;
    width)
      # The same settled state and run, coarse-grained with another kernel width.
      mkdir -p "$C"
      printf 'cg_width = %s\n' "$a" > "$C/$name.toml"
      DEST=$C run "$name" --config "$C/$name.toml" $(wet "$b") ;;
    seed)
      if [ ! -f "$V/settled-seed$a/settled.bin" ]; then
        "$B" split-bottom --time-step mean-pair --seed "$a" --duration 0.01 --average-from 0 \
          --out "$V/settled-seed$a" --quiet
      fi
      DEST=$C FROM=$V/settled-seed$a run "$name" --seed "$a" $(wet "$b") ;;
  esac
done
