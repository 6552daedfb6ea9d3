#!/bin/bash
# The driven box (docs/BENCHMARKS.md "The driven box"): benches/driven-box.toml run at several
# amplitudes A of its drive, at a fixed gap G = 30 mm; the energy each model's bed takes (its
# impacts' loss and, in the contact model, what Rapier's plastic contacts took) per cycle over
# the last ten of twenty cycles, in units of m_bed (A w)^2, against G / A, with
# the ideal block's (1 - cos theta)^2, theta - sin theta = G / A (for G / A <= pi). Each model
# runs MEMBERS beds placed at random (seeds 1 to MEMBERS, the same beds for every model); a cell
# gives the median and, for more than one member, the 5-95 % band, then the median number of
# impacts per cycle over the same ten cycles (the gas lives while they go on). The last ten
# cycles are the difference of a run to 2 s and the same run to 1 s (a run's first second does
# not depend on its horizon). A run that takes more than MAX_WALL_S of computing stops and is
# left out of its cell, which says how many stopped, and so is a seed whose bed cannot be placed
# at random (refused). CONTACT_DURATION, if given, is the reference's `[reference] contact_duration`
# (docs/MODEL.md §14). PLACEMENT "lattice" runs the scene's lattice instead (one member).
#   bash benches/driven_box.sh [LPC] [MODELS] [MAX_WALL_S] [CONTACT_DURATION] [MEMBERS] [PLACEMENT]
#   (default: target/release/lpc, "compliant reference rapier", 60, the scene's, 8, random)
set -euo pipefail
lpc=${1:-target/release/lpc}
models=${2:-compliant reference rapier}
budget=${3:-60}
contact_duration=${4:-}
members=${5:-8}
placement=${6:-random}
if [ "$placement" = lattice ]; then members=1; fi
dir=$(mktemp -d)
amplitudes="0.06 0.03 0.015 0.00955 0.006 0.004 0.003 0.002 0.0015"
jobs=()
for a in $amplitudes; do
  for k in $(seq 1 "$members"); do
    scene="$dir/box-$a-$k.toml"
    sed "s/^amplitude = [0-9.]*/amplitude = $a/; s/^placement = .*/placement = \"$placement\"/; s/^seed = .*/seed = $k/" \
      benches/driven-box.toml > "$scene"
    if [ -n "$contact_duration" ]; then
      printf '\n[reference]\ncontact_duration = %s\n' "$contact_duration" >> "$scene"
    fi
    for m in $models; do
      jobs+=("$m $a $k 1" "$m $a $k 2")
    done
  done
done
# Two runs at a time: each run is one thread.
printf '%s\n' "${jobs[@]}" | xargs -P 2 -L 1 bash -c \
  '"$0" run "$1/box-$4-$5.toml" --model "$3" --horizon "$6" --max-wall-time "$2" --format json > "$1/$3-$4-$5-$6.json" 2> /dev/null || true' \
  "$lpc" "$dir" "$budget"
python3 - "$dir" "$amplitudes" "$members" $models <<'PY'
import json, math, os, statistics, sys
folder, amplitudes, members, models = sys.argv[1], [float(a) for a in sys.argv[2].split()], int(sys.argv[3]), sys.argv[4:]
gap, mass, w = 0.03, 27 * 7800.0 * 4.0 / 3.0 * math.pi * 0.005**3, 2 * math.pi * 10.0
def block(ratio):
    if ratio > math.pi + 1e-9:
        return None
    lo, hi = 0.0, math.pi
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if mid - math.sin(mid) < ratio else (lo, mid)
    return (1 - math.cos(lo)) ** 2
print("| A | G / A | " + " | ".join(models) + " | ideal block |")
print("|---|---|" + "---|" * len(models) + "---|")
for a in amplitudes:
    cells = []
    for m in models:
        shares, rates, stopped, refused = [], [], 0, 0
        for k in range(1, members + 1):
            runs = [open(os.path.join(folder, f"{m}-{a:g}-{k}-{h}.json")).read() for h in (1, 2)]
            if not all(text.strip() for text in runs):
                refused += 1
                continue
            runs = [json.loads(text) for text in runs]
            if any("stop" in run for run in runs):
                stopped += 1
                continue
            taken = [r["energy"]["impact_loss"] + r["energy"].get("contact_loss", 0.0) for r in runs]
            shares.append((taken[1] - taken[0]) / 10 / (mass * (a * w) ** 2))
            rates.append((runs[1]["impact_count"] - runs[0]["impact_count"]) / 10)
        cell = "stopped" if not shares else f"{statistics.median(shares):.3f}"
        if len(shares) > 1:
            # The 5 % and 95 % points, interpolated between the members as NumPy does.
            cuts = statistics.quantiles(shares, n=20, method="inclusive")
            cell += f" ({cuts[0]:.3f}-{cuts[-1]:.3f})"
        if shares:
            cell += f", {statistics.median(rates):.0f}/cycle"
        if stopped:
            cell += f", {stopped} of {members} stopped"
        if refused:
            cell += f", {refused} of {members} refused"
        cells.append(cell)
    ideal = block(gap / a)
    print(f"| {a * 1000:g} mm | {gap / a:.2f} | " + " | ".join(cells) + f" | {'-' if ideal is None else f'{ideal:.3f}'} |")
PY
