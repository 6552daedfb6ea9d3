#!/bin/bash
# Touching rows struck into a wall (docs/MODEL.md §9, "Stored impulses after the impact law"):
# rows of 1, 2, 3 and 5 touching steel-sized balls (r 6.75 mm, 10 g) fly at 1 m/s into the
# left end wall of a 1 m box on a frame too heavy to move, at e = 1, floating (no gravity,
# friction 0.1, on the spatial path) or resting on the floor (gravity, no friction), at steps
# of DTS (default 1 and 0.1 ms), for 30 ms. A row prints the energy left, or the reason the run
# stopped.
#   bash benches/touching_rows.sh [LPC] [DTS]   (default: target/release/lpc, "0.001 0.0001")
set -euo pipefail
lpc=${1:-target/release/lpc}
dts=${2:-0.001 0.0001}
dir=$(mktemp -d)
r=0.00675
for place in float floor; do
  for n in 1 2 3 5; do
    for dt in $dts; do
      f="$dir/row${n}_${place}_${dt}.toml"
      if [ "$place" = float ]; then
        world="restitution = 1.0\nfriction = 0.1"; z=0.0
      else
        world="restitution = 1.0\ngravity = [0.0, 0.0, -9.81]\nfriction = 0.0"; z=$(python3 -c "print(-0.025 + $r)")
      fi
      printf "[frame]\nmass = 1e6\nstiffness = 1e6\ndamping = 0.0\ninitial_displacement = 0.0\n[container]\nlength = 1.0\nwidth = 0.05\nheight = 0.05\n[world]\n$world\n[rapier]\ndt = $dt\n[run]\nhorizon = 0.03\nsample_dt = 0.03\n" > "$f"
      for k in $(seq 0 $((n - 1))); do
        x=$(python3 -c "print($r + 0.005 + 2 * $r * $k)")
        printf "[[ball]]\nposition = [$x, 0.0, $z]\nmass = 0.01\nradius = $r\nvelocity = [-1.0, 0.0, 0.0]\n" >> "$f"
      done
      out=$("$lpc" run "$f" --model rapier 2>&1 | grep -E "energy remaining|stopped" | head -1 || true)
      echo "row of $n, $place, dt $dt: ${out}"
    done
  done
done
