#!/usr/bin/env bash
# The standard problem driven from Python (`Simulation.run`) beside `rheodem bench`, one
# thread (BENCHMARKS.md, "From Python"):
# 1. instructions per particle-step of both, counted by cachegrind as in
#    benches/instructions.sh (the difference of a 100- and a 500-step run after the same
#    2000 warm-up steps, so that start-up and the interpreter's import cancel);
# 2. wall-clock throughput of both in PAIRS interleaved pairs;
# 3. the cost of a measurement attached at every step with an empty Python function, on
#    one sphere (a step of well under a microsecond), over 200 000 steps.
# Needs the package installed in the Python named by PYTHON (default python3): `pip install
# .` or `maturin develop --release`; and the program (`cargo build --release`).
#
#   bash benches/python.sh [PAIRS]     (default 3; SKIP_INSTRUCTIONS=1 leaves part 1 out)
set -euo pipefail
cd "$(dirname "$0")/.."
pairs=${1:-3}
bin=${RHEODEM_BIN:-target/release/rheodem}
python=${PYTHON:-python3}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cat > "$tmp/standard.py" <<'PY'
import sys
import time
import rheodem
warmup, steps = int(sys.argv[1]), int(sys.argv[2])
sim = rheodem.Simulation.standard_problem(threads=1)
sim.run(steps=warmup)
start = time.perf_counter()
sim.run(steps=steps)
print(round(len(sim) * steps / (time.perf_counter() - start)))
PY
if [ "${SKIP_INSTRUCTIONS:-0}" != 1 ]; then
  count() { # program... -> instruction count
    valgrind --tool=cachegrind --cache-sim=no --cachegrind-out-file="$tmp/cg.out" "$@" \
      >/dev/null 2>"$tmp/cg.log"
    awk '/^summary:/ {print $2}' "$tmp/cg.out"
  }
  per_step() { # short long -> instructions per particle-step
    awk -v a="$1" -v b="$2" 'BEGIN { printf "%.0f", (b - a) / (400 * 4096) }'
  }
  cli=$(per_step "$(count "$bin" bench --threads 1 --cohesion none --steps 100)" \
    "$(count "$bin" bench --threads 1 --cohesion none --steps 500)")
  py=$(per_step "$(count "$python" "$tmp/standard.py" 2000 100)" \
    "$(count "$python" "$tmp/standard.py" 2000 500)")
  echo "instructions per particle-step: rheodem bench $cli, Python sim.run $py" \
    "(ratio $(awk -v a="$py" -v b="$cli" 'BEGIN { printf "%.4f", a / b }'))"
fi
for k in $(seq "$pairs"); do
  cli=$("$bin" bench --threads 1 --cohesion none --warmup 2000 --steps 3000 |
    sed -n 's/^throughput: \([0-9]*\) particle-steps.*/\1/p')
  py=$("$python" "$tmp/standard.py" 2000 3000)
  echo "pair $k: rheodem bench $cli, Python sim.run $py particle-steps/s" \
    "(ratio $(awk -v a="$py" -v b="$cli" 'BEGIN { printf "%.4f", a / b }'))"
done
"$python" - <<'PY'
import time
import rheodem
ONE = """
[domain]
size = [0.1, 0.1, 0.1]
[[species]]
name = "glass"
density = 2000.0
[[contact]]
normal = { stiffness = 100.0, restitution = 0.8 }
[[particles]]
kind = "explicit"
species = "glass"
spheres = [{ radius = 1.1e-3, position = [0.05, 0.05, 0.05] }]
[run]
steps = 1
"""
def per_step(every):
    sim = rheodem.Simulation(rheodem.Scenario.from_toml(ONE), threads=1)
    if every:
        sim.attach(lambda s: None, every=every)
    start = time.perf_counter()
    sim.run(steps=200_000)
    return (time.perf_counter() - start) / 200_000
bare = min(per_step(None) for _ in range(3))
each = min(per_step(1) for _ in range(3))
print(f"one sphere: a step takes {bare * 1e6:.2f} us without a measurement and "
      f"{each * 1e6:.2f} us with an empty one at every step: {(each - bare) * 1e6:.2f} us "
      "per call")
PY
