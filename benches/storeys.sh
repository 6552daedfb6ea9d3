#!/bin/bash
# A model on structures of several storeys (docs/BENCHMARKS.md "Structures of several
# storeys"): a uniform shear building of N storeys (1.35 kg floors, the fundamental mode at the
# paper's 4.03 Hz, every mode damped 1.6 %) with the paper's LSL damper on its top floor, shaken
# for 20 s by records/synthetic-kt.csv scaled to 0.5 m/s^2; the computing time of each run
# (best of three) against N, per simulated second and per impact, and the same building alone.
# MODEL (default reference) may be compliant, which integrates the floors with its balls, or
# rapier, which moves its container with the closed form step by step. DAMPER `box` puts the
# frictionless box of examples/scenes/small-box-building.toml (twelve 5 mm balls, the
# reference's contact duration 2.5 us) on the top floor instead, for the first 2 s of the record
# scaled to 2 m/s^2, as that scene.
#   bash benches/storeys.sh [LPC] [STOREYS] [MODEL] [DAMPER]
#   (default: target/release/lpc, "1 2 3 5 10 20", reference, lsl)
set -euo pipefail
lpc=${1:-target/release/lpc}
storeys=${2:-1 2 3 5 10 20}
model=${3:-reference}
damper=${4:-lsl}
horizon=20.0
scale=0.5
if [ "$damper" = box ]; then horizon=2.0; scale=2.0; fi
dir=$(mktemp -d)
cp -r scenes/records "$dir/"
echo "| storeys | impacts | with damper: ms (x real time) | per impact | building alone: ms |"
echo "|---|---|---|---|---|"
for n in $storeys; do
  python3 - "$n" "$dir" "$damper" "$horizon" "$scale" <<'PY'
import math, sys
n, folder, damper, horizon, scale = int(sys.argv[1]), sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5]
m, w1 = 1.35, 2 * math.pi * 4.03
k = m * w1 * w1 / (4 * math.sin(math.pi / (2 * (2 * n + 1))) ** 2)
row = lambda x: "[" + ", ".join([x] * n) + "]"
body = f"""name = "storeys-{n}"
[structure]
masses = {row(str(m))}
stiffnesses = {row(f"{k:.6f}")}
damping_ratios = {row("0.016")}
[forcing]
kind = "record"
file = "records/synthetic-kt.csv"
scale = {scale}
[run]
horizon = {horizon}
sample_dt = 0.001
"""
balls = """[balls]
arrangement = "LSL"
large_mass = 0.11
mass_ratio = 10.0
density = 8000.0
restitution = 0.9
gap = "0.25 Rr"
clearance = "2 Rr"
"""
box = """[container]
length = 0.06
width = 0.04
height = 0.05
[world]
gravity = [0.0, 0.0, -9.81]
friction = 0.0
restitution = 0.6
[bed]
count = 12
radii = [0.005]
density = 7800.0
placement = "lattice"
[compliant]
youngs_modulus = 2e9
[rapier]
dt = 0.0005
[reference]
contact_duration = 2.5e-6
"""
open(f"{folder}/with-{n}.toml", "w").write(body + (box if damper == "box" else balls))
open(f"{folder}/alone-{n}.toml", "w").write(body)
PY
  best() {
    local b=""
    for _ in 1 2 3; do
      "$lpc" run "$1" --model "$model" --format json > "$dir/out.json"
      b=$(python3 -c "import json,sys; s=json.load(open('$dir/out.json')); b='$b'; t=s['wall_time_s']; print(t if not b else min(t, float(b)))")
    done
    echo "$b"
  }
  with=$(best "$dir/with-$n.toml")
  impacts=$(python3 -c "import json; print(json.load(open('$dir/out.json'))['impact_count'])")
  alone=$(best "$dir/alone-$n.toml")
  python3 -c "w,a,i=$with,$alone,$impacts; print(f'| $n | {i} | {w*1e3:.1f} ({$horizon/w:.0f}x) | {w/max(i,1)*1e6:.0f} us | {a*1e3:.1f} |')"
done
