#!/bin/bash
# Gas boxes (docs/BENCHMARKS.md "Gas boxes against the reference"): benches/gas_box.py's boxes
# of N balls, their cells drawn at random, seeds 1 to SEEDS.
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
    python3 "$(dirname "$0")/gas_box.py" "$n" "$dir/box-$n-$k.toml" "$k" "$restitution" "$horizon" random
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
