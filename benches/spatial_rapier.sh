#!/bin/bash
# The contact model's (Rapier's) cost against the number of balls beyond one line: the
# particle box scaled to N balls (the same proportions of box and bed, 5 mm steel balls on a
# lattice, gravity, friction 0.3, e 0.6), on a frame whose mass and stiffness are in proportion
# to the balls' mass (the particle box's frequency and mass ratio), shaken by its initial
# displacement. Prints a table row per box: steps of 1 ms, impacts and the computing time.
# With SHAPE=floor the box grows along x and y only, so the bed keeps the particle box's depth
# (seven layers) whatever N: the cost at a constant depth.
# With BARE=path (the `bare_rapier_box` example's binary) a row also gives a bare Rapier
# pipeline's cost on the same box at the same step (docs/BENCHMARKS.md 3.9).
# With INSTRUCTIONS=1 a row also gives the instructions each model executes per ball and step
# over the horizon's second half (Valgrind's instruction count of a run over the whole horizon
# less that of a run over its first half): a count that does not depend on the machine or its
# caches, where the computing time does.
#   [SHAPE=box|floor] [BARE=path] [INSTRUCTIONS=1] bash benches/spatial_rapier.sh [LPC] [HORIZON] [N...]
#   (default: box, target/release/lpc, 0.5 s, 10 100 1000 10000)
set -euo pipefail
lpc=${1:-target/release/lpc}
horizon=${2:-0.5}
shift 2 || shift $# || true
counts=${*:-10 100 1000 10000}
shape=${SHAPE:-box}
dir=$(mktemp -d)
bare=${BARE:-}
instructions=${INSTRUCTIONS:-}
header='| balls | horizon | impacts | computed in | per simulated second | per ball and simulated second |'
rule='|---|---|---|---|---|---|'
if [ -n "$bare" ]; then header+=' bare Rapier: per simulated second | per ball and simulated second |'; rule+='---|---|'; fi
if [ -n "$instructions" ]; then
  header+=' instructions per ball and step |'; rule+='---|'
  if [ -n "$bare" ]; then header+=' bare Rapier: instructions per ball and step |'; rule+='---|'; fi
fi
printf '%s\n%s\n' "$header" "$rule"
# Instructions executed over the second half of HORIZON by a command given the horizon as
# its last argument, per ball and step of 1 ms.
instructions_per_ball_step() {
  local n=$1 full=$2; shift 2
  local half counts
  half=$(python3 -c "print($full / 2)")
  counts=$(for h in "$half" "$full"; do
    valgrind --tool=cachegrind --cache-sim=no --cachegrind-out-file=/dev/null "$@" "$h" 2>&1 >/dev/null | sed -n 's/.*I *refs: *//p' | tr -d ,
  done)
  python3 -c "import sys; a, b = map(int, sys.argv[1:3]); print(f'{(b - a) / ($n * $half / 0.001):,.0f}')" $counts
}
for n in $counts; do
  python3 - "$n" "$horizon" "$dir/box$n.toml" "$shape" <<'PY'
import sys
n, horizon, path, shape = int(sys.argv[1]), float(sys.argv[2]), sys.argv[3], sys.argv[4]
# The lattice fills 9 x 5 cells a layer in the particle box: a floor of N / 300 times its area
# (whole cells) keeps its depth.
scale = (n / 300) ** (1 / 2 if shape == "floor" else 1 / 3)
height = 0.1 if shape == "floor" else 0.1 * scale
lines = [f'name = "rapier-box-{n}"', "[frame]", f"mass = {1.35 * n / 300:.6g}", f"stiffness = {865.0 * n / 300:.6g}",
         "damping = 1.092", "initial_displacement = 0.0185", "[container]", f"length = {0.1 * scale:.6g}",
         f"width = {0.06 * scale:.6g}", f"height = {height:.6g}", "[world]", "gravity = [0.0, 0.0, -9.81]",
         "friction = 0.3", "restitution = 0.6", "[bed]", f"count = {n}", "radii = [0.005]", "density = 7800.0",
         'placement = "lattice"', "[rapier]", "dt = 0.001", "[run]", f"horizon = {horizon}", "sample_dt = 0.001"]
open(path, "w").write("\n".join(lines) + "\n")
PY
  "$lpc" run "$dir/box$n.toml" --model rapier --format json > "$dir/out$n.json"
  python3 - "$n" "$dir/out$n.json" <<'PY'
import json, sys
n, out = int(sys.argv[1]), json.load(open(sys.argv[2]))
wall, horizon, impacts = out["wall_time_s"], out["horizon"], out["impact_count"]
print(f"| {n:,} | {horizon:g} s | {impacts:,} | {wall:.2f} s | {wall / horizon:,.2f} s | {1e3 * wall / horizon / n:.2f} ms |", end="")
PY
  if [ -n "$bare" ]; then
    "$bare" "$dir/box$n.toml" 0.001 "$horizon" | python3 -c "
import re, sys
per = float(re.search(r'([0-9.]+) s per simulated second', sys.stdin.read()).group(1))
print(f' {per:,.2f} s | {1e3 * per / $n:.2f} ms |', end='')"
  fi
  if [ -n "$instructions" ]; then
    printf ' %s |' "$(instructions_per_ball_step "$n" "$horizon" "$lpc" run "$dir/box$n.toml" --model rapier --impacts count --format json --horizon)"
    if [ -n "$bare" ]; then
      printf ' %s |' "$(instructions_per_ball_step "$n" "$horizon" "$bare" "$dir/box$n.toml" 0.001)"
    fi
  fi
  echo
done
rm -rf "$dir"
