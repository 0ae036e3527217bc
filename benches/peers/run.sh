#!/usr/bin/env bash
# benches/peers/run.sh — LAMMPS vs rheodem on the throughput problems.
#
# PROBLEM selects the contact law of the problem (the same spheres, shear and steps):
#   shear        Hooke + tangential history (default): LAMMPS `gran/hooke/history`
#                (benches/peers/lammps-in.shear), rheodem `bench`;
#   shear-hertz  Hertz–Mindlin with Tsuji's damping: LAMMPS `pair_style granular`
#                `hertz/material … tangential mindlin … damping tsuji`
#                (benches/peers/lammps-in.shear-hertz), rheodem `bench --normal hertz`;
#   chute        LAMMPS's own granular benchmark (bench/in.chute): 32 000 spheres flowing
#                on a frozen rough base, gravity at 26° (benches/peers/lammps-in.chute),
#                rheodem `bench --problem chute`. Its data file is not made from the packing:
#                `rheodem bench --problem chute --write-lammps-data` prepares the state once
#                (a stack fallen for 30 000 steps) and both codes start from that file.
#
# Runs, in one go and on the same machine:
#   * LAMMPS (Debian package, `pair_style gran/hooke/history`) on the input
#     benches/peers/lammps-in.shear, on 1 rank (plain `lmp`) and 2 MPI ranks
#     (`mpirun -np 2 lmp`), with 2000 warm-up steps then 3000 timed steps; its data file
#     bench.data is generated at each run, in the temp dir, from the packing the repository
#     ships (crates/rheodem/data/bench-packing.txt) by benches/peers/lammps_data.py;
#   * rheodem's own benchmark, `cargo run --release -p rheodem-cli -- bench --threads N`,
#     for N = 1 and 2;
# and prints a markdown block (table + machine + exact commands) for BENCHMARKS.md.
#
# Throughput is particle-steps per second = atoms * steps / loop seconds. For LAMMPS it is
# taken from the "Loop time of X on N procs for S steps with A atoms" line of the SECOND
# `run` (the timed one, after warm-up). For rheodem it is the number on the line
# `throughput: <number> particle-steps/s` that the `bench` subcommand prints.
#
# Repetitions are interleaved (rep 1 of every configuration, then rep 2, ...) so that slow
# drifts in background load hit all configurations alike; the table shows the median.
#
# Environment (all optional):
#   PROBLEM        shear or shear-hertz (above)               (default: shear)
#   LAMMPS_INPUT   LAMMPS input                               (default: <script dir>/lammps-in.$PROBLEM)
#   PYTHON         Python 3 for lammps_data.py                (default: python3)
#   REPEATS        repetitions per configuration              (default: 3)
#   NWARM, NRUN    LAMMPS warm-up / timed steps               (default: 2000 / 3000)
#   LMP            LAMMPS binary                              (default: first of lmp, lmp_serial,
#                                                              lmp_stable, lmp_mpi on PATH)
#   MPIRUN         MPI launcher                               (default: mpirun)
#   MPIRUN_FLAGS   extra launcher flags                       (default: --allow-run-as-root for
#                                                              Open MPI when run as root)
#   INSTALL        1 = apt-get install lammps if missing      (default: 1)
#   SKIP_LAMMPS=1  / SKIP_RHEODEM=1                           skip one side
#   PROBE_TIMEOUT  seconds allowed for `rheodem bench --help` (default: 300; it may rebuild)
#   KEEP_TMP=1     keep the temp dir with every raw log
#
# The packing is not a setting: rheodem's `bench` has the same file built in, and the two
# codes must run the same spheres.
#
# Everything it needs is in the repository. It needs Python 3 (standard library only) for the
# LAMMPS half, and no network except apt (only when LAMMPS is missing). Exit status is 0 as
# long as at least the LAMMPS half ran; a missing/broken rheodem `bench` subcommand is
# reported, not fatal.

set -euo pipefail

# ---------------------------------------------------------------------------------------
# Settings and locations
# ---------------------------------------------------------------------------------------
SCRIPT_DIR=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
REPO_ROOT=$(git -C "$SCRIPT_DIR" rev-parse --show-toplevel)
PACKING="$REPO_ROOT/crates/rheodem/data/bench-packing.txt"   # also built into `rheodem bench`
PROBLEM=${PROBLEM:-shear}
case $PROBLEM in
    shear) RHEODEM_LAW=""; LAMMPS_STYLE="gran/hooke/history" ;;
    shear-hertz) RHEODEM_LAW="--normal hertz"; LAMMPS_STYLE="granular hertz/material, mindlin, tsuji" ;;
    # The data file's path is only known below; rheodem_cmd appends it.
    chute) RHEODEM_LAW="--problem chute"; LAMMPS_STYLE="gran/hooke/history (chute)" ;;
    *) printf '[peers] ERROR: PROBLEM must be shear, shear-hertz or chute (got %s)\n' "$PROBLEM" >&2; exit 1 ;;
esac
LAMMPS_INPUT=${LAMMPS_INPUT:-"$SCRIPT_DIR/lammps-in.$PROBLEM"}
PYTHON=${PYTHON:-python3}
REPEATS=${REPEATS:-3}
NWARM=${NWARM:-2000}
NRUN=${NRUN:-3000}
INSTALL=${INSTALL:-1}
SKIP_LAMMPS=${SKIP_LAMMPS:-0}
SKIP_RHEODEM=${SKIP_RHEODEM:-0}
PROBE_TIMEOUT=${PROBE_TIMEOUT:-300}
KEEP_TMP=${KEEP_TMP:-0}
COUNTS=(1 2)                      # threads (rheodem) / MPI ranks (LAMMPS)

# Single-threaded ranks: the Debian LAMMPS is built with OpenMP support; pin it to 1 thread
# per rank so "2 ranks" really means 2 cores. Also applies to anything rayon-free we call.
export OMP_NUM_THREADS=1

log() { printf '[peers] %s\n' "$*" >&2; }
die() { printf '[peers] ERROR: %s\n' "$*" >&2; exit 1; }

[[ "$REPEATS" =~ ^[1-9][0-9]*$ ]] || die "REPEATS must be a positive integer (got '$REPEATS')"
if [[ "$SKIP_LAMMPS" != 1 ]]; then
    [[ -r "$PACKING" ]] || die "packing $PACKING not found or not readable"
    [[ -r "$LAMMPS_INPUT" ]] || die "LAMMPS input $LAMMPS_INPUT not found or not readable (set LAMMPS_INPUT)"
    command -v "$PYTHON" >/dev/null 2>&1 \
        || die "no '$PYTHON' on PATH: Python 3 is needed to write the LAMMPS data file (set PYTHON)"
fi
# Paths as shown in the report: relative to the repository root when they lie inside.
PACKING_SHOWN=${PACKING#"$REPO_ROOT"/}
LAMMPS_INPUT_SHOWN=${LAMMPS_INPUT#"$REPO_ROOT"/}

TMP=$(mktemp -d "${TMPDIR:-/tmp}/rheodem-peers.XXXXXX")
cleanup() {
    if [[ "$KEEP_TMP" == 1 ]]; then log "raw logs kept in $TMP"; else rm -rf "$TMP"; fi
}
trap cleanup EXIT

# The LAMMPS data file, written once per run from the packing (atom_style sphere, zero-tilt
# triclinic box); lammps_data.py says what is wrong if the packing is missing or malformed.
# (The chute's data file is written by rheodem once it is built, below.)
if [[ "$SKIP_LAMMPS" != 1 && "$PROBLEM" != chute ]]; then
    "$PYTHON" "$SCRIPT_DIR/lammps_data.py" "$PACKING" "$TMP/bench.data" \
        || die "could not write the LAMMPS data file from $PACKING (see above)"
fi
[[ "$SKIP_LAMMPS" == 1 ]] || cp "$LAMMPS_INPUT" "$TMP/lammps-in"

# ---------------------------------------------------------------------------------------
# Small numeric helpers (awk does the floating point)
# ---------------------------------------------------------------------------------------
# median of the arguments (mean of the two middle values for an even count); "" if none
median() {
    (($# > 0)) || { echo ""; return; }
    printf '%s\n' "$@" | sort -g | awk '{v[NR]=$1} END {
        if (NR % 2) printf "%.6g\n", v[(NR+1)/2]; else printf "%.6g\n", (v[NR/2]+v[NR/2+1])/2 }'
}
# a number in particle-steps/s as "3.56 M"
mega() { awk -v x="$1" 'BEGIN { printf "%.2f M", x/1e6 }'; }
# list of numbers as "3.51, 3.56, 3.60 M"
mega_list() { printf '%s\n' "$@" | awk '{ printf "%s%.2f", (NR>1 ? ", " : ""), $1/1e6 } END { print " M" }'; }
ratio() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", a/b }'; }

# ---------------------------------------------------------------------------------------
# LAMMPS: find (or install) the binary and an MPI launcher
# ---------------------------------------------------------------------------------------
find_lmp() {
    local c
    for c in ${LMP:-} lmp lmp_serial lmp_stable lmp_mpi; do
        if command -v "$c" >/dev/null 2>&1; then command -v "$c"; return 0; fi
    done
    return 1
}

LMP_BIN=""
LMP_HELP=""
MPI_CMD=()
if [[ "$SKIP_LAMMPS" != 1 ]]; then
    if ! LMP_BIN=$(find_lmp); then
        [[ "$INSTALL" == 1 ]] || die "no LAMMPS binary on PATH and INSTALL=0"
        log "LAMMPS not found: installing the Debian package 'lammps' (needs apt network)"
        SUDO=()
        if [[ $(id -u) -ne 0 ]]; then
            command -v sudo >/dev/null 2>&1 || die "not root and no sudo: install lammps by hand"
            SUDO=(sudo)
        fi
        # --no-install-recommends skips lammps-doc (large); the package pulls in Open MPI
        # (libopenmpi3 + mpi-default-bin, which provides mpirun).
        "${SUDO[@]}" apt-get update -q
        DEBIAN_FRONTEND=noninteractive "${SUDO[@]}" apt-get install -y -q --no-install-recommends lammps
        LMP_BIN=$(find_lmp) || die "installed 'lammps' but found no lmp binary"
    fi
    # The input needs the GRANULAR package (gran/hooke/history).
    # (Capture first: `lmp -h | grep -q` would trip pipefail when grep exits early.)
    LMP_HELP=$("$LMP_BIN" -h 2>/dev/null || true)
    grep -q 'gran/hooke/history' <<<"$LMP_HELP" \
        || die "$LMP_BIN lacks pair_style gran/hooke/history (GRANULAR package)"

    MPIRUN=${MPIRUN:-mpirun}
    if command -v "$MPIRUN" >/dev/null 2>&1; then
        if [[ -z "${MPIRUN_FLAGS+x}" ]]; then
            MPIRUN_FLAGS=""
            # Open MPI refuses to run as root without this flag (MPICH does not know it).
            if [[ $(id -u) -eq 0 && $("$MPIRUN" --version 2>&1 || true) == *"Open MPI"* ]]; then
                MPIRUN_FLAGS="--allow-run-as-root"
            fi
        fi
        # shellcheck disable=SC2206  # word splitting of the flag string is intended
        MPI_CMD=("$MPIRUN" $MPIRUN_FLAGS)
    else
        log "no '$MPIRUN' on PATH: LAMMPS will run on 1 rank only"
    fi
fi

# ---------------------------------------------------------------------------------------
# rheodem: build once, then probe for the `bench` subcommand
# ---------------------------------------------------------------------------------------
RHEODEM_OK=0
RHEODEM_WHY=""
if [[ "$SKIP_RHEODEM" != 1 ]]; then
    log "building rheodem-cli (release)…"
    if ! (cd "$REPO_ROOT" && cargo build --release -q -p rheodem-cli) >"$TMP/cargo-build.log" 2>&1; then
        RHEODEM_WHY="\`cargo build --release -p rheodem-cli\` failed (see below)"
        tail -n 20 "$TMP/cargo-build.log" >&2 || true
    else
        # The subcommand is recognised if `bench --help` exits 0 quickly and mentions
        # --threads. (A binary without argument parsing would start computing instead: the
        # timeout cuts that short and it counts as "not available".)
        if (cd "$REPO_ROOT" && timeout "$PROBE_TIMEOUT" \
                cargo run --release -q -p rheodem-cli -- bench --help) >"$TMP/probe.log" 2>&1 \
           && grep -q -- '--threads' "$TMP/probe.log"; then
            RHEODEM_OK=1
        else
            RHEODEM_WHY="the \`bench --threads N\` subcommand of rheodem-cli is not available yet"
        fi
    fi
    [[ "$RHEODEM_OK" == 1 ]] || log "rheodem skipped: $RHEODEM_WHY"
fi
# The chute's state, prepared once by rheodem (on 2 threads) for both codes.
if [[ "$PROBLEM" == chute ]]; then
    log "preparing the chute's state (rheodem bench --problem chute --write-lammps-data)…"
    (cd "$REPO_ROOT" && cargo run --release -q -p rheodem-cli -- bench --problem chute \
        --threads 2 --write-lammps-data "$TMP/bench.data") >&2 \
        || die "could not write the chute's LAMMPS data file (see above)"
    RHEODEM_LAW="--problem chute --lammps-data $TMP/bench.data"
fi

# ---------------------------------------------------------------------------------------
# One run of each kind. Each prints the throughput (particle-steps/s) on stdout, or
# returns non-zero after logging why.
# ---------------------------------------------------------------------------------------
# lammps_cmd N: the command line for N ranks (1 rank: plain binary, as in the README)
lammps_cmd() {
    local n=$1
    local args=(-in lammps-in -var nwarm "$NWARM" -var nrun "$NRUN")
    if ((n == 1)); then
        echo "$LMP_BIN ${args[*]}"
    else
        echo "${MPI_CMD[*]} -np $n $LMP_BIN ${args[*]}"
    fi
}

# run_lammps N REP
run_lammps() {
    local n=$1 rep=$2 dir="$TMP/lammps-np$1-rep$2" line x procs steps atoms
    mkdir -p "$dir"
    cp "$TMP/bench.data" "$TMP/lammps-in" "$dir/"
    # shellcheck disable=SC2046,SC2091  # the command string is split and run on purpose
    if ! (cd "$dir" && $(lammps_cmd "$n")) >"$dir/stdout.txt" 2>&1; then
        log "LAMMPS np=$n rep=$rep failed; last lines:"; tail -n 15 "$dir/stdout.txt" >&2
        return 1
    fi
    # The second "Loop time" line belongs to the timed run.
    line=$(grep '^Loop time of' "$dir/stdout.txt" | sed -n 2p)
    [[ -n "$line" ]] || { log "LAMMPS np=$n rep=$rep: no second 'Loop time' line"; return 1; }
    # "Loop time of X on N procs for S steps with A atoms"
    read -r x procs steps atoms < <(awk '{print $4, $6, $9, $12}' <<<"$line")
    if [[ "$procs" != "$n" || "$steps" != "$NRUN" ]]; then
        log "LAMMPS np=$n rep=$rep: unexpected '$line' (serial-only binary under mpirun?)"
        return 1
    fi
    log "LAMMPS np=$n rep=$rep: $line"
    awk -v a="$atoms" -v s="$steps" -v t="$x" 'BEGIN { printf "%.6g\n", a*s/t }'
}

rheodem_cmd() {
    echo "cargo run --release -p rheodem-cli -- bench --threads $1 --warmup $NWARM --steps $NRUN $RHEODEM_LAW"
}

# run_rheodem N REP
run_rheodem() {
    local n=$1 rep=$2 out="$TMP/rheodem-t$1-rep$2.txt" v
    # shellcheck disable=SC2046,SC2091  # the command string is split and run on purpose
    # stdout and stderr together: the `throughput:` line is accepted from either.
    if ! (cd "$REPO_ROOT" && $(rheodem_cmd "$n")) >"$out" 2>&1; then
        log "rheodem threads=$n rep=$rep failed; last lines:"; tail -n 15 "$out" >&2
        return 1
    fi
    # First number after "throughput:" (plain or scientific notation).
    v=$(awk '/^throughput:/ { print $2; exit }' "$out")
    if ! [[ "$v" =~ ^[0-9]+(\.[0-9]*)?([eE][+-]?[0-9]+)?$ ]]; then
        log "rheodem threads=$n rep=$rep: no 'throughput: <number>' line in its output"
        return 1
    fi
    log "rheodem threads=$n rep=$rep: $(grep -m1 '^throughput:' "$out")"
    echo "$v"
}

# ---------------------------------------------------------------------------------------
# Measure (interleaved repetitions)
# ---------------------------------------------------------------------------------------
LOAD_BEFORE=$(cut -d' ' -f1-3 /proc/loadavg)
declare -A RES=()                 # RES[code:N] = space-separated throughputs
NMEAS=0                           # successful measurements in all
for ((rep = 1; rep <= REPEATS; rep++)); do
    for n in "${COUNTS[@]}"; do
        if [[ "$SKIP_LAMMPS" != 1 ]] && { ((n == 1)) || ((${#MPI_CMD[@]} > 0)); }; then
            if v=$(run_lammps "$n" "$rep"); then RES[lammps:$n]+="$v "; NMEAS=$((NMEAS + 1)); fi
        fi
        if [[ "$RHEODEM_OK" == 1 ]]; then
            if v=$(run_rheodem "$n" "$rep"); then RES[rheodem:$n]+="$v "; NMEAS=$((NMEAS + 1)); fi
        fi
    done
done
LOAD_AFTER=$(cut -d' ' -f1-3 /proc/loadavg)

# LAMMPS steady state from the timed run(s), for cross-checking a new implementation:
# thermo rows of the second run with step > NWARM (the row at NWARM repeats the warm-up's last
# state and its contact count is not yet computed). Columns: Step Atoms KinEng c_pp c_pp[4] Xy c_z
# (c_pp = pair part of the pressure, c_pp[4] = pxy, so shear stress = -pxy; c_z = contacts/atom).
STEADY=""
if compgen -G "$TMP/lammps-np*-rep*/stdout.txt" >/dev/null; then
    STEADY=$(awk -v nwarm="$NWARM" -v problem="$PROBLEM" '
        FNR == 1 { block = 0 }
        /^Step / { block++; next }
        block >= 2 && $1 ~ /^[0-9]+$/ && NF == 7 && $1 > nwarm && problem != "chute" {
            n++; p += $4; s += -$5; z += $7 }
        END { if (n) printf "pressure %.1f, shear stress %.1f, contacts/particle %.2f (mean of %d thermo rows)", p/n, s/n, z/n, n }
        ' "$TMP"/lammps-np*-rep*/stdout.txt)
fi

# ---------------------------------------------------------------------------------------
# Report (markdown on stdout)
# ---------------------------------------------------------------------------------------
CPU_MODEL=$(awk -F': *' '/^model name/ { print $2; exit }' /proc/cpuinfo)
LMP_VERSION=""
if [[ -n "$LMP_BIN" ]]; then
    # e.g. "LAMMPS (29 Sep 2021 - Update 2)" from the banner, plus the Debian version if any
    LMP_VERSION=$(awk 'NF { sub(/^ +/, ""); print; exit }' <<<"$LMP_HELP")
    DEB_VERSION=$(dpkg-query -W -f='${Version}' lammps 2>/dev/null || true)
    LMP_VERSION="$LMP_BIN: ${LMP_VERSION:-unknown version}${DEB_VERSION:+, Debian package lammps $DEB_VERSION}"
fi
RHEODEM_REV=$(git -C "$REPO_ROOT" describe --always --dirty 2>/dev/null || echo unknown)

echo
echo "### Throughput problem $PROBLEM: rheodem vs LAMMPS"
echo
echo "- date: $(date -u '+%Y-%m-%d %H:%M UTC')"
echo "- machine: $(env -u OMP_NUM_THREADS -u OMP_THREAD_LIMIT nproc) logical CPUs (nproc), $CPU_MODEL"
echo "- load average (1/5/15 min) before: $LOAD_BEFORE, after: $LOAD_AFTER"
# Busy machine? 2 MPI ranks on 2 cores busy-poll, so any other load slows them several-fold.
if awk -v l="${LOAD_BEFORE%% *}" 'BEGIN { exit !(l > 0.5) }'; then
    echo "- **warning: the machine was not idle (1-min load ${LOAD_BEFORE%% *} > 0.5); the 2-rank/2-thread figures are unreliable**"
fi
if [[ "$PROBLEM" == chute ]]; then
    echo "- problem: LAMMPS's chute (32 800 spheres with the base, state written by rheodem bench --problem chute --write-lammps-data); $NWARM warm-up + $NRUN timed steps"
else
    echo "- problem: $PACKING_SHOWN (4096 spheres, phi 0.62, Lees-Edwards shear); $NWARM warm-up + $NRUN timed steps"
fi
echo "- repetitions: $REPEATS per configuration, interleaved; table shows the median"
if [[ -n "$LMP_VERSION" ]]; then
    echo "- LAMMPS: $LMP_VERSION; MPI launcher: ${MPI_CMD[*]:-none}; OMP_NUM_THREADS=1"
fi
echo "- rheodem: git $RHEODEM_REV"
echo
echo "| code | threads/ranks | median particle-steps/s | ratio rheodem/LAMMPS |"
echo "|---|---|---|---|"
for n in "${COUNTS[@]}"; do
    # shellcheck disable=SC2086  # lists of numbers
    lm=$(median ${RES[lammps:$n]:-})
    # shellcheck disable=SC2086
    rm_=$(median ${RES[rheodem:$n]:-})
    if [[ -n "$lm" ]]; then
        echo "| LAMMPS $LAMMPS_STYLE | $n $( ((n == 1)) && echo rank || echo ranks) | $(mega "$lm") | — |"
    elif [[ "$SKIP_LAMMPS" != 1 ]]; then
        echo "| LAMMPS $LAMMPS_STYLE | $n | not measured | — |"
    fi
    if [[ -n "$rm_" ]]; then
        echo "| rheodem | $n $( ((n == 1)) && echo thread || echo threads) | $(mega "$rm_") | $([[ -n "$lm" ]] && ratio "$rm_" "$lm" || echo —) |"
    elif [[ "$SKIP_RHEODEM" != 1 ]]; then
        echo "| rheodem | $n | not measured | — |"
    fi
done
if ((NMEAS > 0)); then printf '\nIndividual runs (particle-steps/s):\n'; fi
for code in lammps rheodem; do
    for n in "${COUNTS[@]}"; do
        if [[ -n "${RES[$code:$n]:-}" ]]; then
            # shellcheck disable=SC2086
            echo "- $code, $n: $(mega_list ${RES[$code:$n]})"
        fi
    done
done
if [[ -n "$STEADY" ]]; then
    echo
    echo "LAMMPS steady state (timed run): $STEADY."
fi
# rheodem's own report of the last 1-thread run (everything after cargo's "Running" line),
# so its steady-state figures can be compared with LAMMPS's above.
RH_LAST="$TMP/rheodem-t${COUNTS[0]}-rep$REPEATS.txt"
if [[ -n "${RES[rheodem:${COUNTS[0]}]:-}" && -s "$RH_LAST" ]]; then
    echo
    echo "rheodem's own report (threads ${COUNTS[0]}, last repetition):"
    echo
    echo '```text'
    awk '/^ *Running `/ { n = NR } { line[NR] = $0 } END { for (i = n + 1; i <= NR; i++) print line[i] }' "$RH_LAST"
    echo '```'
fi
if [[ "$SKIP_RHEODEM" != 1 && "$RHEODEM_OK" != 1 ]]; then
    echo
    echo "**rheodem not measured:** $RHEODEM_WHY."
fi
echo
echo "Commands (from the repo root; each LAMMPS run in a fresh copy of the folder D):"
echo
echo '```sh'
echo "export OMP_NUM_THREADS=1"
if [[ "$SKIP_LAMMPS" != 1 ]]; then
    if [[ "$PROBLEM" == chute ]]; then
        echo "cargo run --release -p rheodem-cli -- bench --problem chute --threads 2 --write-lammps-data D/bench.data"
    else
        echo "python3 benches/peers/lammps_data.py $PACKING_SHOWN D/bench.data"
    fi
    echo "cp $LAMMPS_INPUT_SHOWN D/lammps-in && cd D"
    for n in "${COUNTS[@]}"; do
        if ((n == 1)) || ((${#MPI_CMD[@]} > 0)); then lammps_cmd "$n"; fi
    done
fi
if [[ "$SKIP_RHEODEM" != 1 ]]; then
    [[ "$SKIP_LAMMPS" == 1 ]] || echo "cd -"
    for n in "${COUNTS[@]}"; do rheodem_cmd "$n"; done
fi
echo '```'
echo
echo "Produced by \`benches/peers/run.sh\` (REPEATS=$REPEATS)."

# Fail only if nothing at all was measured.
((NMEAS > 0)) || die "no measurement succeeded"
