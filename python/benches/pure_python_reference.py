"""A plain exact solver of the LPC damper in pure Python: the yardstick the reference's speed
is quoted against (docs/BENCHMARKS.md, "The reference against a pure-Python solver").

It is what a careful researcher would write in an afternoon, without NumPy: the frame in
closed form between events (an underdamped oscillator), balls in free flight, ball-ball
contact times from their linear gaps, ball-wall contact times by scanning the gap at a
thirty-second of the frame's period and refining the first sign change by regula falsi, impacts by Eq. 9-10
one pair at a time (fastest first), and a ball held by a wall when it strikes it too slowly or
too often to bounce (released when the frame's acceleration turns), the samples evaluated in
closed form at every output step. It reads the project's scene files for the free-vibration
scenes of the paper.

    python python/benches/pure_python_reference.py [--repeat N] scenes/lpc-lsl.toml ...

prints, per scene, the impacts, the final energy and the best time of N runs, and the sum over
the scenes given (the five figure scenes by default).
"""

import math
import sys
import time
import tomllib
from pathlib import Path

FIGURE_SCENES = ["no-damper", "conventional", "lpc-lsl", "lpc-lslsl", "chain-lll"]


def load(path):
    """The scene of a free-vibration damper file: frame, balls (mass, radius), container."""
    with open(path, "rb") as f:
        d = tomllib.load(f)
    fr = d["frame"]
    run = d.get("run", {})
    scene = {
        "m": fr["mass"], "k": fr["stiffness"], "c": fr["damping"],
        "horizon": run.get("horizon", 5.0), "dt": run.get("sample_dt", 1e-3),
        "masses": [], "radii": [], "x": [], "length": 0.0, "e": 1.0,
    }
    b = d.get("balls")
    rho = lambda m, dens: (3.0 * m / (4.0 * math.pi * dens)) ** (1.0 / 3.0)
    rr = rho(b["large_mass"], b["density"]) if b else 0.0
    length = lambda v: float(v.split()[0]) * rr if isinstance(v, str) else float(v)
    scene["x0"] = length(fr["initial_displacement"])
    if b:
        ml = b["large_mass"]
        ms = ml / b.get("mass_ratio", 1.0)
        for ch in b["arrangement"]:
            m = ml if ch == "L" else ms
            scene["masses"].append(m)
            scene["radii"].append(rho(m, b["density"]))
        gap = length(b["gap"])
        x = scene["x0"] + gap
        for r in scene["radii"]:
            scene["x"].append(x + r)
            x += 2.0 * r + gap
        scene["length"] = x - gap - scene["x0"] + length(b["clearance"])
        scene["e"] = b["restitution"]
    return scene


def solve(s):
    """The run: samples (t, xs, vs, [x_i], [v_i]) every dt, and the impacts."""
    n = len(s["masses"])
    M, R, e = s["masses"], s["radii"], s["e"]
    m0, k, c = s["m"], s["k"], s["c"]
    horizon, dt, L = s["horizon"], s["dt"], s["length"]
    x, v = list(s["x"]), [0.0] * n
    hold = [0] * n  # 0 free, -1 held by the left wall (stack), +1 by the right wall
    offset = [0.0] * n
    held_mass = 0.0
    # The frame's segment: start time, state, and its oscillator's constants.
    seg = {}

    def start_segment(t0, x0, v0):
        mass = m0 + held_mass
        sigma = c / (2.0 * mass)
        w = math.sqrt(k / mass - sigma * sigma)
        seg.update(t0=t0, x0=x0, v0=v0, sigma=sigma, w=w, w0sq=k / mass, period=2.0 * math.pi / w)

    def frame(t):
        tau = t - seg["t0"]
        sg, w = seg["sigma"], seg["w"]
        ex, co, si = math.exp(-sg * tau), math.cos(w * tau), math.sin(w * tau)
        b = (seg["v0"] + sg * seg["x0"]) / w
        xs = ex * (seg["x0"] * co + b * si)
        vs = ex * (seg["v0"] * co - (seg["w0sq"] * seg["x0"] + sg * seg["v0"]) / w * si)
        return xs, vs

    def accel(xs, vs):
        return -2.0 * seg["sigma"] * vs - seg["w0sq"] * xs

    start_segment(0.0, s["x0"], 0.0)
    tol = 1e-12 * max(L, abs(s["x0"]), 1e-9)
    v_stick = 1e-9 * math.sqrt(k / m0) * abs(s["x0"])
    t_stick = 1e-7 * seg["period"]
    samples = []
    impacts = []
    last_hit = {}
    t, next_sample = 0.0, 0
    count = int(horizon / dt * (1 + 1e-12)) + 1

    def gap(p, tt, xs):
        """Gap of pair p (between body p-1 and p; -1 and n the walls) at time tt."""
        def right_edge(i):  # of body i, the left body
            if i < 0:
                return xs
            return (xs + offset[i] if hold[i] else x[i] + v[i] * (tt - t)) + R[i]

        def left_edge(j):
            if j >= n:
                return xs + L
            return (xs + offset[j] if hold[j] else x[j] + v[j] * (tt - t)) - R[j]

        return left_edge(p) - right_edge(p - 1)

    def free(i):
        return 0 <= i < n and not hold[i]

    def frame_pair(p):
        return free(p - 1) != free(p)

    def body_velocity(i, vs):
        return vs if i < 0 or i >= n or hold[i] else v[i]

    def sample_until(until, inclusive):
        nonlocal next_sample
        while next_sample < count:
            ts = next_sample * dt
            if ts > until or (not inclusive and ts == until):
                break
            xs, vs = frame(ts)
            row = [ts, xs, vs]
            for i in range(n):
                if hold[i]:
                    row.append(xs + offset[i])
                    row.append(vs)
                else:
                    row.append(x[i] + v[i] * (ts - t))
                    row.append(v[i])
            samples.append(row)
            next_sample += 1

    def next_accel_zero(after):
        """The first time after `after` at which the frame's acceleration changes sign."""
        xs, vs = frame(seg["t0"])
        a0, j0 = accel(xs, vs), -2.0 * seg["sigma"] * accel(xs, vs) - seg["w0sq"] * vs
        w, sg = seg["w"], seg["sigma"]
        phase = math.atan2((j0 + sg * a0) / w, a0) + 0.5 * math.pi
        kk = math.floor((w * (after - seg["t0"]) - phase) / math.pi)
        while True:
            tz = seg["t0"] + (phase + kk * math.pi) / w
            if tz > after:
                return tz
            kk += 1

    def wall_contact(p, limit):
        """First time in (t, limit] at which frame pair p's gap closes, or None: the gap is
        scanned at a thirty-second of the period and the first sign change refined by the
        Illinois variant of regula falsi."""
        h = seg["period"] / 32.0
        ta = t
        ga = gap(p, ta, frame(ta)[0])
        while ta < limit:
            tb = min(ta + h, limit)
            gb = gap(p, tb, frame(tb)[0])
            if gb <= tol:
                lo, glo, hi, ghi = ta, ga - tol, tb, gb - tol
                side = 0
                while hi - lo > 4e-16 * hi:
                    mid = (lo * ghi - hi * glo) / (ghi - glo)
                    if not lo < mid < hi:
                        mid = 0.5 * (lo + hi)
                    gm = gap(p, mid, frame(mid)[0]) - tol
                    if gm <= 0.0:
                        hi, ghi = mid, gm
                        if side == -1:
                            glo *= 0.5
                        side = -1
                    else:
                        lo, glo = mid, gm
                        if side == 1:
                            ghi *= 0.5
                        side = 1
                    if gm == 0.0:
                        break
                return hi
            ta, ga = tb, gb
        return None

    def resolve():
        """Every impact, hold and release at the current instant."""
        nonlocal held_mass
        for _ in range(10000):
            xs, vs = frame(t)
            best = None
            for p in range(n + 1):
                if not (free(p - 1) or free(p)):
                    continue
                if gap(p, t, xs) > tol:
                    continue
                u = body_velocity(p - 1, vs) - body_velocity(p, vs)
                if u > 0.0 and (best is None or u > best[1]):
                    best = (p, u)
            if best is None:
                return
            p, u = best
            i, j = p - 1, p
            a = accel(xs, vs)
            wall_side = -1 if not free(i) else (1 if not free(j) else 0)
            repeat = last_hit.get(p, -1.0) > t - 1e-6 and last_hit.get(p) != t
            returns_fast = wall_side != 0 and (wall_side * a) < 0 and 2.0 * e * u / abs(a) < t_stick
            if wall_side != 0 and (u < v_stick or repeat or returns_fast):
                # The ball sticks to the wall (or to the balls the wall holds).
                b = j if wall_side < 0 else i
                mass = m0 + held_mass
                vc = (mass * vs + M[b] * v[b]) / (mass + M[b])
                lost = 0.5 * mass * vs * vs + 0.5 * M[b] * v[b] ** 2 - 0.5 * (mass + M[b]) * vc * vc
                hold[b] = wall_side
                offset[b] = x[b] + v[b] * 0.0 - xs
                held_mass += M[b]
                start_segment(t, xs, vc)
                impacts.append((t, p, u, lost))
                continue
            if wall_side == 0:
                m1, m2 = M[i], M[j]
                v1, v2 = v[i], v[j]
            else:
                m1 = M[i] if free(i) else m0 + held_mass
                m2 = M[j] if free(j) else m0 + held_mass
                v1, v2 = body_velocity(i, vs), body_velocity(j, vs)
            tot = m1 + m2
            vcm = (m1 * v1 + m2 * v2) / tot
            v1n = vcm - e * (v1 - v2) * m2 / tot
            v2n = vcm + e * (v1 - v2) * m1 / tot
            lost = 0.5 * (1 - e * e) * m1 * m2 / tot * u * u
            if free(i):
                v[i] = v1n
            if free(j):
                v[j] = v2n
            if wall_side != 0:
                start_segment(t, xs, v2n if not free(j) else v1n)
            impacts.append((t, p, u, lost))
            last_hit[p] = t

    def release():
        nonlocal held_mass
        xs, vs = frame(t)
        a = accel(xs, vs)
        changed = False
        for i in range(n):
            if hold[i] and hold[i] * a < 0:  # the wall would pull
                x[i] = xs + offset[i]
                v[i] = vs
                hold[i] = 0
                held_mass -= M[i]
                changed = True
        if changed:
            held_mass = max(held_mass, 0.0)
            start_segment(t, xs, vs)

    resolve()
    while True:
        # The next event: a ball-ball contact, a wall contact, a release, or the horizon.
        limit = horizon
        which = None
        for p in range(1, n):
            if free(p - 1) and free(p):
                rate = v[p] - v[p - 1]
                if rate < 0.0:
                    g = max(gap(p, t, 0.0), 0.0)
                    tc = t + g / -rate
                    if tc < limit:
                        limit, which = tc, ("ball", p)
        if held_mass > 0.0:
            tz = next_accel_zero(t)
            if tz < limit:
                limit, which = tz, ("release", None)
        for p in range(n + 1):
            if frame_pair(p):
                tc = wall_contact(p, limit)
                if tc is not None and tc < limit:
                    limit, which = tc, ("wall", p)
        sample_until(limit, which is None)
        for i in range(n):
            if not hold[i]:
                x[i] += v[i] * (limit - t)
        t = limit
        if which is None:
            break
        if which[0] == "release":
            release()
        resolve()
    xs, vs = frame(t)
    energy = 0.5 * m0 * vs * vs + 0.5 * k * xs * xs + sum(
        0.5 * M[i] * (vs if hold[i] else v[i]) ** 2 for i in range(n))
    return samples, impacts, energy


def main(argv):
    repeat = 5
    if len(argv) > 1 and argv[0] == "--repeat":
        repeat, argv = int(argv[1]), argv[2:]
    root = Path(__file__).resolve().parents[2]
    paths = argv or [str(root / "scenes" / f"{name}.toml") for name in FIGURE_SCENES]
    total = 0.0
    print(f"{'scene':<16} {'impacts':>8} {'samples':>8} {'final energy J':>16} {'best of ' + str(repeat) + ' ms':>14}")
    for p in paths:
        scene = load(p)
        best = math.inf
        for _ in range(repeat):
            start = time.perf_counter()
            samples, impacts, energy = solve(scene)
            best = min(best, time.perf_counter() - start)
        total += best
        print(f"{Path(p).stem:<16} {len(impacts):>8} {len(samples):>8} {energy:>16.6e} {1e3 * best:>14.2f}")
    print(f"{'all':<16} {'':>8} {'':>8} {'':>16} {1e3 * total:>14.2f}")


if __name__ == "__main__":
    main(sys.argv[1:])
