#!/bin/bash
# Settled beds (docs/BENCHMARKS.md 3.8, "From a settled bed"): SCENE (default
# benches/particle-box-settled.toml) with its bed settled from seeds 1 to MEMBERS (the same beds
# for every model), each model run to each of the HORIZONS. A row gives, per model and horizon,
# the median and the 5-95 % band over the members of the energy the bed took (the impacts' loss
# and, in the contact model, what Rapier's contacts took) and of the system's energy left, then
# the median computing time. A run's first part does not depend on its horizon. The contact
# model runs at each step of DTS (its `--dt`); "rapier" alone runs at the scene's step. A run
# that stops (budget MAX_WALL_S, or a reason) is left out of its cell, which says so.
#   bash benches/settled_beds.sh [LPC] [MODELS] [MEMBERS] [HORIZONS] [DTS] [MAX_WALL_S] [SCENE]
#   (default: target/release/lpc, "compliant rapier", 8, "0.5 2", "", 600,
#    benches/particle-box-settled.toml)
set -euo pipefail
lpc=${1:-target/release/lpc}
models=${2:-compliant rapier}
members=${3:-8}
horizons=${4:-0.5 2}
dts=${5:-}
budget=${6:-600}
source=${7:-benches/particle-box-settled.toml}
dir=$(mktemp -d)
jobs=()
runs=()
for m in $models; do
  if [ "$m" = rapier ] && [ -n "$dts" ]; then
    for dt in $dts; do runs+=("rapier:$dt"); done
  else
    runs+=("$m:")
  fi
done
for k in $(seq 1 "$members"); do
  # The bed's seed is the first `seed = ` under `[bed]`.
  awk -v k="$k" '/^\[/ { bed = ($0 == "[bed]") } bed && /^seed = / { next } { print } bed && /^placement = / { print "seed = " k }' \
    "$source" > "$dir/bed-$k.toml"
  for run in "${runs[@]}"; do
    for h in $horizons; do
      jobs+=("$run $k $h")
    done
  done
done
# Two runs at a time: each run is one thread.
printf '%s\n' "${jobs[@]}" | xargs -P 2 -L 1 bash -c '
  model=${3%%:*}; dt=${3#*:}
  extra=(); [ -n "$dt" ] && extra=(--dt "$dt")
  "$0" run "$1/bed-$4.toml" --model "$model" "${extra[@]}" --horizon "$5" --max-wall-time "$2" --impacts count --format json \
    > "$1/$3-$4-$5.json" 2> /dev/null || true' "$lpc" "$dir" "$budget"
python3 - "$dir" "$members" "$horizons" "${runs[@]}" <<'PY'
import json, os, statistics, sys
folder, members, horizons, runs = sys.argv[1], int(sys.argv[2]), sys.argv[3].split(), sys.argv[4:]
def cell(values, digits):
    if not values:
        return "-"
    text = f"{statistics.median(values):.{digits}f}"
    if len(values) > 1:
        cuts = statistics.quantiles(values, n=20, method="inclusive")
        text += f" ({cuts[0]:.{digits}f}-{cuts[-1]:.{digits}f})"
    return text
print("| model | horizon | bed takes, J | energy left, J | computing, s | stopped |")
print("|---|---|---|---|---|---|")
for run in runs:
    model, dt = run.split(":")
    name = model + (f", {dt} s" if dt else "")
    for h in horizons:
        taken, left, wall, stopped = [], [], [], 0
        for k in range(1, members + 1):
            text = open(os.path.join(folder, f"{run}-{k}-{h}.json")).read()
            r = json.loads(text) if text.strip() else {"stop": "refused"}
            if "stop" in r:
                stopped += 1
                continue
            e = r["energy"]
            taken.append(e["impact_loss"] + e.get("contact_loss", 0.0))
            left.append(e["final"])
            wall.append(r["wall_time_s"])
        print(f"| {name} | {h} s | {cell(taken, 5)} | {cell(left, 4)} | {cell(wall, 1)} | {stopped} of {members} |")
PY
