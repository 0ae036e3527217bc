#!/bin/bash
# Same physics, same bits: runs one set of short problems with two rheodem binaries and
# compares their time series byte for byte. For a restructuring that must not change the
# physics (a moved module, a new crate, a trait in place of a match): every line must say
# "same".
#
#   bash validation/same-bits.sh OLD_BINARY NEW_BINARY [THREADS]
#
# Problems (each well under a minute on one core):
#   - every scenario in examples/: `rheodem run`, or for a shear-box point (its first line
#     names `rheodem shear-box`) `rheodem shear-box --config` with the short box below;
#   - a short shear box (256 spheres, 0.5 strain units) for each cohesion law in each of
#     the three shear dynamics;
#   - a half-size split-bottom cell (--scale 0.5), filled, settled and sheared for 0.05 s,
#     dry and with Willett bridges.
# Output directories go to a temporary directory, removed at the end. Exit status 1 if any
# time series differs.
set -uo pipefail
if [ $# -lt 2 ]; then
  echo "usage: bash validation/same-bits.sh OLD_BINARY NEW_BINARY [THREADS]" >&2
  exit 2
fi
old=$(realpath "$1") new=$(realpath "$2") threads=${3:-1}
cd "$(dirname "$0")/.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
failed=0
# compare NAME ARGS…: runs `BINARY ARGS… --out DIR` with each binary, then compares
# DIR/timeseries.csv.
compare() {
  local name=$1; shift
  for side in old new; do
    local bin=${!side}
    if ! "$bin" "$@" --threads "$threads" --quiet --out "$tmp/$side-$name" \
      >"$tmp/$side-$name.log" 2>&1; then
      echo "$name: the $side binary failed (log: $(tail -n 2 "$tmp/$side-$name.log"))"
      failed=1
      return
    fi
  done
  if cmp -s "$tmp/old-$name/timeseries.csv" "$tmp/new-$name/timeseries.csv"; then
    echo "$name: same"
  else
    echo "$name: DIFFERENT"
    failed=1
  fi
}
short_box=(--particles 256 --strain 0.5 --transient-strain 0.25)
for scenario in examples/*.toml; do
  name=example-$(basename "$scenario" .toml)
  if head -n 1 "$scenario" | grep -q "rheodem shear-box"; then
    compare "$name" shear-box --config "$scenario" "${short_box[@]}"
  else
    compare "$name" run "$scenario"
  fi
done
for dynamics in lab peculiar-contacts affine-drag; do
  for law in none reversible liquid_bridge linear_irreversible; do
    bond=0
    [ "$law" = none ] || bond=1
    compare "shear-box-$law-$dynamics" shear-box --mu-p 0.5 --inertial 0.05 \
      --softness 0.01 --bond "$bond" --cohesion "$law" "${short_box[@]}" \
      --shear-dynamics "$dynamics"
  done
done
for law in dry willett; do
  compare "split-bottom-$law" split-bottom --scale 0.5 --law "$law" --duration 0.05 \
    --average-from 0.025 --time-step mean-pair
done
exit $failed
