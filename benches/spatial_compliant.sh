#!/bin/bash
# The compliant model's cost against the number of balls beyond one line: a box of
# 5 mm steel balls (lattice bed, gravity, friction 0.3, e 0.6) on a frame whose mass and
# stiffness are in proportion to the balls' mass (the particle box's frequency and mass ratio),
# shaken by its initial displacement for 0.02 s.
#   bash benches/spatial_compliant.sh [LPC] [N...]   (default: target/release/lpc, 30 300 3000)
set -euo pipefail
lpc=${1:-target/release/lpc}
shift || true
counts=${*:-30 300 3000}
dir=$(mktemp -d)
printf '| balls | horizon | impacts | computed in | per simulated second | per ball and simulated second |\n|---|---|---|---|---|---|\n'
for n in $counts; do
  python3 - "$n" "$dir/box$n.toml" <<'PY'
import math, sys
n, path = int(sys.argv[1]), sys.argv[2]
cells = math.ceil((n / 0.6) ** (1 / 3))
side = cells * 0.0105 + 0.001
lines = [f'name = "bed-box-{n}"', "[frame]", f"mass = {1.35 * n / 300:.6g}", f"stiffness = {865.0 * n / 300:.6g}",
         "damping = 1.092", "initial_displacement = 0.0185", "[container]", f"length = {side:.6g}",
         f"width = {side:.6g}", f"height = {side:.6g}", "[world]", "gravity = [0.0, 0.0, -9.81]", "friction = 0.3",
         "restitution = 0.6", "[bed]", f"count = {n}", "radii = [0.005]", "density = 7800.0", 'placement = "lattice"',
         "[run]", "horizon = 0.02", "sample_dt = 0.001"]
open(path, "w").write("\n".join(lines) + "\n")
PY
  "$lpc" run "$dir/box$n.toml" --model compliant --format json > "$dir/out$n.json"
  python3 - "$n" "$dir/out$n.json" <<'PY'
import json, sys
n, out = int(sys.argv[1]), json.load(open(sys.argv[2]))
wall, horizon, impacts = out["wall_time_s"], out["horizon"], out["impact_count"]
print(f"| {n:,} | {horizon:g} s | {impacts:,} | {wall:.2f} s | {wall / horizon:,.1f} s | {1e3 * wall / horizon / n:.2f} ms |")
PY
done
rm -rf "$dir"
