"""Generates scenes/records/synthetic-kt.csv, the ground-motion record of
scenes/mdof-3storey-record.toml (python3, standard library only; the output is shipped).

White noise, one normal draw held over each step of 0.001 s (seed 2013), is filtered by the
Kanai-Tajimi soil filter (ground frequency 2.5 Hz, damping 0.6), shaped by a
trapezoidal-exponential envelope (rise over 2 s, strong motion to 8 s, then exp(-0.4 (t - 8))),
read every 0.01 s for 20 s, corrected so that the ground ends at rest (a constant is removed
from the acceleration), and scaled to a peak of 1 m/s^2.
"""
import math
import random

SEED = 2013
W_G, Z_G = 2.0 * math.pi * 2.5, 0.6
DT_FINE, DT_OUT, DURATION = 0.001, 0.01, 20.0


def envelope(t):
    if t < 2.0:
        return (t / 2.0) ** 2
    if t < 8.0:
        return 1.0
    return math.exp(-0.4 * (t - 8.0))


def main():
    rng = random.Random(SEED)
    x = v = 0.0  # the filter's state: x'' + 2 z w x' + w^2 x = -n(t)
    every = round(DT_OUT / DT_FINE)
    out = []
    steps = round(DURATION / DT_FINE)
    for k in range(steps + 1):
        t = k * DT_FINE
        if k % every == 0:
            out.append((t, envelope(t) * -(2.0 * Z_G * W_G * v + W_G * W_G * x)))
        n = rng.gauss(0.0, 1.0) / math.sqrt(DT_FINE)
        # Classical RK4 with the noise held over the step.
        def f(x, v):
            return v, -n - 2.0 * Z_G * W_G * v - W_G * W_G * x
        k1 = f(x, v)
        k2 = f(x + 0.5 * DT_FINE * k1[0], v + 0.5 * DT_FINE * k1[1])
        k3 = f(x + 0.5 * DT_FINE * k2[0], v + 0.5 * DT_FINE * k2[1])
        k4 = f(x + DT_FINE * k3[0], v + DT_FINE * k3[1])
        x += DT_FINE / 6.0 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
        v += DT_FINE / 6.0 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
    # The ground's final velocity (trapezoids: exact for the linear interpolation) made zero.
    final_velocity = sum(0.5 * (a + b[1]) * DT_OUT for (_, a), b in zip(out, out[1:]))
    shift = final_velocity / DURATION
    out = [(t, a - shift) for t, a in out]
    peak = max(abs(a) for _, a in out)
    with open("synthetic-kt.csv", "w") as f:
        f.write("# Synthetic ground acceleration: Kanai-Tajimi filtered white noise (synthetic-kt.py).\n")
        f.write("time_s,accel_m_s2\n")
        for t, a in out:
            f.write(f"{t:.2f},{a / peak:.9f}\n")


if __name__ == "__main__":
    main()
