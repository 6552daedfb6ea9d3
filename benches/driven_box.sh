#!/bin/bash
# The driven box (docs/BENCHMARKS.md "The driven box"): benches/driven-box.toml run at several
# amplitudes A of its drive, at a fixed gap G = 30 mm; each model's energy taken by the impacts
# per cycle over the last ten of twenty cycles, in units of m_bed (A w)^2, against G / A, with
# the ideal block's (1 - cos theta)^2, theta - sin theta = G / A (for G / A <= pi). A run that
# takes more than MAX_WALL_S of computing stops and is reported as stopped, with the simulated
# time it reached. CONTACT_DURATION,
# if given, is the reference's `[reference] contact_duration` (docs/MODEL.md §14).
#   bash benches/driven_box.sh [LPC] [MODELS] [MAX_WALL_S] [CONTACT_DURATION]
#   (default: target/release/lpc, "compliant reference rapier", 60, the scene's)
set -euo pipefail
lpc=${1:-target/release/lpc}
models=${2:-compliant reference rapier}
budget=${3:-60}
contact_duration=${4:-}
dir=$(mktemp -d)
amplitudes="0.06 0.03 0.015 0.00955 0.006 0.004 0.003 0.002 0.0015"
for a in $amplitudes; do
  sed "s/^amplitude = [0-9.]*/amplitude = $a/" benches/driven-box.toml > "$dir/box-$a.toml"
  if [ -n "$contact_duration" ]; then
    printf '\n[reference]\ncontact_duration = %s\n' "$contact_duration" >> "$dir/box-$a.toml"
  fi
  for m in $models; do
    "$lpc" run "$dir/box-$a.toml" --model "$m" --max-wall-time "$budget" --format json --print-impacts > "$dir/$m-$a.json" 2> /dev/null || true
  done
done
python3 - "$dir" "$amplitudes" $models <<'PY'
import json, math, os, sys
folder, amplitudes, models = sys.argv[1], [float(a) for a in sys.argv[2].split()], sys.argv[3:]
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
        path = os.path.join(folder, f"{m}-{a:g}.json")
        text = open(path).read()
        if not text.strip():
            cells.append("stopped")
            continue
        s = json.loads(text)
        if "stop" in s:
            # Stopped at the budget: its summary covers the run up to there.
            cells.append(f'stopped at {s["horizon"]:.2f} s ({s["wall_time_s"]:.1f} s)')
            continue
        lost = sum(i["energy_lost"] for i in s["impacts"] if i["t"] >= 1.0)
        cells.append(f'{lost / 10 / (mass * (a * w) ** 2):.3f} ({s["wall_time_s"]:.1f} s)')
    ideal = block(gap / a)
    print(f"| {a * 1000:g} mm | {gap / a:.2f} | " + " | ".join(cells) + f" | {'-' if ideal is None else f'{ideal:.3f}'} |")
PY
