#!/bin/bash
# Gas boxes (docs/BENCHMARKS.md "Gas boxes against the reference"): N smooth 5 mm steel balls
# without gravity in a cubic box on the frame, one ball to a cell of a 12.5 mm lattice (the
# cells drawn at random), each with a random velocity of up to 0.5 m/s per component; the frame
# is released from 18.5 mm, in proportion to the balls' mass as in benches/spatial_reference.sh.
# Each model runs the same SEEDS boxes of each size; a row gives, per simulated second, the
# median impact rate, impact loss and (contact model) contact loss, with each median's ratio to
# the reference's.
#   bash benches/gas_boxes.sh [LPC] [E] [SEEDS] [N:HORIZON...]
#   (default: target/release/lpc, 0.9, 6, 20:0.5 100:0.2 300:0.2 1000:0.1)
set -euo pipefail
lpc=${1:-target/release/lpc}
restitution=${2:-0.9}
seeds=${3:-6}
shift 3 || shift $#
sizes=${*:-20:0.5 100:0.2 300:0.2 1000:0.1}
dir=$(mktemp -d)
for size in $sizes; do
  n=${size%%:*}
  horizon=${size##*:}
  for k in $(seq 1 "$seeds"); do
    python3 - "$n" "$dir/box-$n-$k.toml" "$k" "$restitution" "$horizon" <<'PY'
import random, sys
n, path, seed, e, horizon = int(sys.argv[1]), sys.argv[2], int(sys.argv[3]), float(sys.argv[4]), float(sys.argv[5])
r, pitch = 0.005, 0.0125
cells = 1
while cells ** 3 < n:
    cells += 1
side = cells * pitch
mass = 4.0 / 3.0 * 3.141592653589793 * r ** 3 * 7800.0
rng = random.Random(seed)
lines = [f'name = "gas-box-{n}"', "[frame]", f"mass = {1.35 * n / 300:.6g}", f"stiffness = {865.0 * n / 300:.6g}",
         "damping = 0.0", "initial_displacement = 0.0185", "[container]", f"length = {side:.6g}",
         f"width = {side:.6g}", f"height = {side:.6g}", "[world]", "gravity = [0.0, 0.0, 0.0]", "friction = 0.0",
         f"restitution = {e}", "[run]", f"horizon = {horizon}", "sample_dt = 0.001"]
order = list(range(cells ** 3))
rng.shuffle(order)
for cell in order[:n]:
    c = (cell % cells, (cell // cells) % cells, cell // cells ** 2)
    x, y, z = (c[0] + 0.5) * pitch, (c[1] + 0.5) * pitch - side / 2, (c[2] + 0.5) * pitch - side / 2
    v = [rng.uniform(-0.5, 0.5) for _ in range(3)]
    lines += ["[[ball]]", f"position = [{x:.6g}, {y:.6g}, {z:.6g}]", f"mass = {mass:.9g}", f"radius = {r}",
              f"velocity = [{v[0]:.6g}, {v[1]:.6g}, {v[2]:.6g}]"]
open(path, "w").write("\n".join(lines) + "\n")
PY
    for m in reference rapier; do
      "$lpc" run "$dir/box-$n-$k.toml" --model "$m" --format json > "$dir/$m-$n-$k.json" 2> /dev/null || true
    done
  done
done
python3 - "$dir" "$seeds" $sizes <<'PY'
import json, os, statistics, sys
folder, seeds, sizes = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
print("| balls | horizon | model | impacts per s | impact loss per s | contact loss per s | of the initial energy | stopped |")
print("|---|---|---|---|---|---|---|---|")
for size in sizes:
    n, horizon = size.split(":")
    medians = {}
    for m in ("reference", "rapier"):
        runs, stopped = [], 0
        for k in range(1, seeds + 1):
            text = open(os.path.join(folder, f"{m}-{n}-{k}.json")).read()
            run = json.loads(text) if text.strip() else {"stop": "refused"}
            if "stop" in run:
                stopped += 1
            else:
                runs.append(run)
        if not runs:
            print(f"| {n} | {horizon} s | {m} | - | - | - | - | {stopped} |")
            continue
        h = float(horizon)
        rate = statistics.median(r["impact_count"] / h for r in runs)
        loss = statistics.median(r["energy"]["impact_loss"] / h for r in runs)
        contact = statistics.median(r["energy"].get("contact_loss", 0.0) / h for r in runs)
        share = statistics.median(r["energy"].get("contact_loss", 0.0) / r["energy"]["initial"] for r in runs)
        medians[m] = (rate, loss)
        ratio = "", ""
        if m == "rapier" and "reference" in medians:
            ref = medians["reference"]
            ratio = f" ({rate / ref[0]:.3f})", f" ({loss / ref[1]:.3f})" if ref[1] > 0 else ""
        print(f"| {n} | {horizon} s | {m} | {rate:.0f}{ratio[0]} | {loss:.4g} J{ratio[1]} | {contact:.3g} J | {share * 100:.1f} % | {stopped} |")
PY
