"""Writes a gas box: N smooth 5 mm steel balls without gravity in a cubic box on the frame, one
ball to a cell of a 12.5 mm lattice, each with a random velocity of up to 0.5 m/s per component;
the frame's mass and stiffness in proportion to the balls' mass (the particle box's frequency and
mass ratio), released from 18.5 mm. The cells are the lattice's first N in order, or N drawn at
random. Used by benches/spatial_reference.sh and benches/gas_boxes.sh.

    python3 benches/gas_box.py N PATH [SEED] [RESTITUTION] [HORIZON] [ordered|random]
"""
import random
import sys

n, path = int(sys.argv[1]), sys.argv[2]
seed = int(sys.argv[3]) if len(sys.argv) > 3 else 1
restitution = float(sys.argv[4]) if len(sys.argv) > 4 else 0.9
horizon = float(sys.argv[5]) if len(sys.argv) > 5 else 0.1
cells_drawn = len(sys.argv) > 6 and sys.argv[6] == "random"
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
         f"restitution = {restitution!r}", "[run]", f"horizon = {horizon!r}", "sample_dt = 0.001"]
order = list(range(cells ** 3))
if cells_drawn:
    rng.shuffle(order)
for cell in order[:n]:
    c = (cell % cells, (cell // cells) % cells, cell // cells ** 2)
    x, y, z = (c[0] + 0.5) * pitch, (c[1] + 0.5) * pitch - side / 2, (c[2] + 0.5) * pitch - side / 2
    v = [rng.uniform(-0.5, 0.5) for _ in range(3)]
    lines += ["[[ball]]", f"position = [{x:.6g}, {y:.6g}, {z:.6g}]", f"mass = {mass:.9g}", f"radius = {r}",
              f"velocity = [{v[0]:.6g}, {v[1]:.6g}, {v[2]:.6g}]"]
open(path, "w").write("\n".join(lines) + "\n")
