//! Closed-form flights between events (docs/MODEL.md §14): a ball moves as `p + v t + a t^2 / 2`,
//! so a wall across the motion, a cell's face and a ball with the same acceleration are met at
//! the root of a quadratic; a ball with another acceleration (one flies, the other rests on the
//! floor) where a quartic first falls through zero, isolated between the sign changes of its
//! derivatives.

/// The roots of `c + b t + a t^2` (`a != 0`), `q / a` and `c / q` with
/// `q = -(b + sign(b) sqrt(b^2 - 4 a c)) / 2`, the form that does not cancel; `None` when they
/// are complex or `q` is zero.
fn quadratic_roots(a: f64, b: f64, c: f64) -> Option<(f64, f64)> {
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return None;
    }
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    (q != 0.0).then(|| (q / a, c / q))
}

/// The first `t >= 0` at which `c + b t + a t^2 = 0` with `c > 0` before it, or `None`: the
/// smaller non-negative root, computed in the form that does not cancel.
pub(super) fn first_root(a: f64, b: f64, c: f64) -> Option<f64> {
    if c <= 0.0 {
        // At the plane already (a contact just resolved, or round-off): now if it is closing,
        // else when the acceleration brings it back (the other root of `b t + a t^2`).
        if b < 0.0 || (b == 0.0 && a < 0.0) {
            return Some(0.0);
        }
        return (a < 0.0).then(|| -b / a);
    }
    if a == 0.0 {
        return (b < 0.0).then(|| c / -b);
    }
    // With c > 0 both roots have the sign of q / a (when a > 0) or opposite signs (a < 0,
    // the positive one is the root reached first from above).
    let (r1, r2) = quadratic_roots(a, b, c)?;
    let mut best: Option<f64> = None;
    for r in [r1, r2] {
        if r >= 0.0 && r.is_finite() {
            best = Some(best.map_or(r, |b: f64| b.min(r)));
        }
    }
    best
}

/// When a gap `g0 - s (v t + acc t^2 / 2)` to a plane first closes (`s` the side of the plane:
/// `+1` above the ball, `-1` below), or `None`.
pub(super) fn plane_time(g0: f64, s: f64, v: f64, acc: f64) -> Option<f64> {
    first_root(-0.5 * s * acc, -s * v, g0)
}

/// When two balls with relative position `dr`, velocity `dv` and acceleration `da` first touch
/// at centre distance `reach`, looking no further than `limit`: where the squared distance less
/// `reach^2`, a polynomial of degree two (equal accelerations) or four in time, first falls
/// through zero. A pair touching now meets now if it closes, else at its next fall through
/// zero (a ball bouncing on one that rests on the floor comes back). A touching pair that closes
/// no faster than `still` (the round-off of its velocities, [`still`]) does not close.
#[inline]
pub(super) fn pair_time(dr: [f64; 3], dv: [f64; 3], da: [f64; 3], reach: f64, still: f64, limit: f64) -> Option<f64> {
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let c0 = dot(dr, dr) - reach * reach;
    let mut c1 = 2.0 * dot(dr, dv);
    if c0 <= 0.0 && c1 < 0.0 && c1 >= -2.0 * reach * still {
        c1 = 0.0;
    }
    if da == [0.0; 3] {
        let a = dot(dv, dv);
        if c0 > 0.0 && a > 0.0 {
            // Apart and moving: `first_root`'s smaller root, computed before the tests of
            // whether the pair closes and meets, so that one branch decides (whether a
            // neighbour closes is as good as random, and a branch on it is mispredicted
            // half the time). With `c1 < 0` its `q` is this one, and both roots are positive.
            let disc = c1 * c1 - 4.0 * a * c0;
            let q = -0.5 * (c1 - disc.sqrt());
            let t = (q / a).min(c0 / q);
            return ((c1 < 0.0) & (disc >= 0.0) & (q > 0.0) & (t <= limit)).then_some(t);
        }
        if c1 >= 0.0 {
            return None;
        }
        return first_root(a, c1, c0).filter(|&t| t <= limit);
    }
    // c0 + c1 t + c2 t^2 + c3 t^3 + c4 t^4.
    let poly = [c0, c1, dot(dv, dv) + dot(dr, da), dot(dv, da), 0.25 * dot(da, da)];
    first_fall(&poly, limit)
}

/// The relative speed that velocities `vi` and `vj` cannot resolve: a few ulps of the larger.
pub(super) fn still(vi: [f64; 3], vj: [f64; 3]) -> f64 {
    let largest = vi.iter().chain(&vj).fold(0.0, |m: f64, c| m.max(c.abs()));
    8.0 * f64::EPSILON * largest
}

/// Value of the polynomial with coefficients `c` (constant first) at `t`.
fn eval(c: &[f64], t: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &k| acc * t + k)
}

/// A few numbers on the stack: a quartic's coefficients, or the points that split `[0, limit]`
/// for it (at most one more than its degree), so that a root search allocates nothing.
#[derive(Clone, Copy)]
struct Few {
    values: [f64; 6],
    len: usize,
}

impl Few {
    fn new() -> Few {
        Few { values: [0.0; 6], len: 0 }
    }

    fn push(&mut self, value: f64) {
        self.values[self.len] = value;
        self.len += 1;
    }

    fn as_slice(&self) -> &[f64] {
        &self.values[..self.len]
    }
}

/// The polynomial's derivative.
fn derivative(c: &[f64]) -> Few {
    let mut d = Few::new();
    for (k, &v) in c.iter().enumerate().skip(1) {
        d.push(k as f64 * v);
    }
    d
}

/// Every point of `[0, limit]` where the polynomial `c` (of degree four at most) changes sign,
/// in order: the derivative's sign changes split the interval into pieces where `c` is
/// monotone, and each piece holds at most one sign change, found by bisection to an ulp
/// (started from the closed form for a line or a parabola).
fn sign_changes(c: &[f64], limit: f64) -> Few {
    let mut roots = Few::new();
    let degree = c.iter().rposition(|&k| k != 0.0).unwrap_or(0);
    if degree == 0 {
        return roots;
    }
    let d = derivative(&c[..=degree]);
    let mut ends = Few::new();
    ends.push(0.0);
    if degree > 1 {
        for &r in sign_changes(d.as_slice(), limit).as_slice() {
            ends.push(r);
        }
    }
    ends.push(limit);
    for w in ends.as_slice().windows(2) {
        let (mut l, mut h) = (w[0], w[1]);
        let (fl, fh) = (eval(c, l), eval(c, h));
        if (fl > 0.0) == (fh > 0.0) || l >= h {
            continue;
        }
        let rising = fh > 0.0;
        let past = |f: f64| (f > 0.0) == rising;
        let after = |t: f64| past(eval(c, t));
        if degree == 1 {
            // A line changes sign at -c0 / c1 to an ulp or two, and its values in floating
            // point are monotone: narrowed to the floats around it, the bisection below ends
            // on the same two neighbouring floats as it does from the whole piece.
            (l, h) = narrow(l, h, -c[0] / c[1], after);
        } else if degree == 2 {
            // A parabola changes sign at one of its roots (in the form that does not cancel),
            // to a few ulps: narrowed around it likewise. Where its values in floating point
            // change sign once between floats, the result is the bisection's from the whole
            // piece; elsewhere it is another float of the same band of round-off.
            if let Some((r1, r2)) = quadratic_roots(c[2], c[1], c[0]) {
                let guess = if r1 > l && r1 < h { r1 } else { r2 };
                (l, h) = narrow(l, h, guess, after);
            }
        } else {
            // A cubic or a quartic: Newton's steps from the piece's ends, kept in the bracket.
            (l, h) = newton(c, d.as_slice(), (l, h), fl, fh, past);
        }
        roots.push(bisect(l, h, after));
    }
    roots
}

/// The bracket `[l, h]` of a sign change (`after` false at `l`, true at `h`) halved until its
/// ends are neighbouring floats: the first float past the change.
fn bisect(mut l: f64, mut h: f64, after: impl Fn(f64) -> bool) -> f64 {
    for _ in 0..200 {
        let m = 0.5 * (l + h);
        if m <= l || m >= h {
            break;
        }
        if after(m) {
            h = m;
        } else {
            l = m;
        }
    }
    h
}

/// Newton's steps on the bracket `(l, h)` of a sign change of the polynomial `c`, monotone on
/// it, with `d` its derivative, `fl` and `fh` its values at the ends and `past` true of the
/// values past the change: each step keeps the bracket by the sign of the value at its point,
/// and a step that would leave the bracket takes the midpoint instead. They stop when a step
/// moves by no more than a few ulps, or after `NEWTON_STEPS`; the bracket is then narrowed
/// around the last point, where the sign change is to round-off when the steps converged.
fn newton(c: &[f64], d: &[f64], (mut l, mut h): (f64, f64), fl: f64, fh: f64, past: impl Fn(f64) -> bool) -> (f64, f64) {
    // The secant's point first: it is inside the bracket, and on a short piece already close.
    let mut t = l + (h - l) * (fl / (fl - fh));
    if !(t > l && t < h) {
        t = 0.5 * (l + h);
    }
    for _ in 0..NEWTON_STEPS {
        let f = eval(c, t);
        if past(f) {
            h = t;
        } else {
            l = t;
        }
        let step = f / eval(d, t);
        let next = t - step;
        let next = if next > l && next < h { next } else { 0.5 * (l + h) };
        if !(next > l && next < h) {
            // The bracket is two neighbouring floats.
            break;
        }
        let converged = step.abs() <= 4.0 * f64::EPSILON * t.abs();
        t = next;
        if converged {
            break;
        }
    }
    narrow(l, h, t, |t| past(eval(c, t)))
}

/// Newton's steps at most, before the bisection finishes: from the secant's point a step
/// gains a few digits at first and doubles them near the root.
const NEWTON_STEPS: usize = 12;

/// The bracket `[l, h]` of a sign change (`after` false at `l`, true at `h`) narrowed to a
/// few floats around `guess` where the signs there allow, else as it is.
fn narrow(mut l: f64, mut h: f64, guess: f64, after: impl Fn(f64) -> bool) -> (f64, f64) {
    if !(guess > l && guess < h) {
        return (l, h);
    }
    if after(guess) {
        h = guess;
        let below = (0..4).fold(guess, |t, _| t.next_down());
        if below > l && !after(below) {
            l = below;
        }
    } else {
        l = guess;
        let above = (0..4).fold(guess, |t, _| t.next_up());
        if above < h && after(above) {
            h = above;
        }
    }
    (l, h)
}

/// The first time in `[0, limit]` at which the polynomial `c` falls to zero or below from
/// above (or `0` when it is at or below zero and falling now, or the start of a falling piece
/// that starts at or below zero), or `None`.
// Kept out of line, so that `pair_time` stays small enough to inline into the pairs'
// prediction: the quartic is the rare case, the quadratic the event loop's hottest path.
#[inline(never)]
fn first_fall(c: &[f64], limit: f64) -> Option<f64> {
    let d = derivative(c);
    let d = d.as_slice();
    if c[0] <= 0.0 && (d[0] < 0.0 || (d[0] == 0.0 && d[1] < 0.0)) {
        return Some(0.0);
    }
    let mut ends = Few::new();
    ends.push(0.0);
    for &r in sign_changes(d, limit).as_slice() {
        ends.push(r);
    }
    ends.push(limit);
    for w in ends.as_slice().windows(2) {
        let (mut l, mut h) = (w[0], w[1]);
        let (fl, fh) = (eval(c, l), eval(c, h));
        if !(fh <= 0.0 && fl > fh) {
            continue;
        }
        if fl <= 0.0 {
            // Falling from a rise that never cleared zero (a pair that touches and parts by
            // less than round-off): in contact again from the top of the rise.
            return Some(l);
        }
        let fallen = |f: f64| !(f > 0.0);
        (l, h) = newton(c, d, (l, h), fl, fh, fallen);
        return Some(bisect(l, h, |t| fallen(eval(c, t))));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_falling_ball_meets_the_floor_at_the_closed_form_time() {
        // A ball 0.1 m above the floor falling from rest: t = sqrt(2 h / g).
        let t = plane_time(0.1, -1.0, 0.0, -9.81).unwrap();
        assert!((t - (0.2f64 / 9.81).sqrt()).abs() < 1e-15);
        // Thrown up at 1 m/s from 0.1 m: t = (v + sqrt(v^2 + 2 g h)) / g.
        let t = plane_time(0.1, -1.0, 1.0, -9.81).unwrap();
        assert!((t - (1.0 + (1.0f64 + 2.0 * 9.81 * 0.1).sqrt()) / 9.81).abs() < 1e-15);
        // Towards a ceiling it never reaches: none.
        assert_eq!(plane_time(1.0, 1.0, 1.0, -9.81), None);
    }

    #[test]
    fn pairs_meet_at_the_closed_form_times_and_come_back() {
        // Head-on at 1 m/s, 0.1 m of gap.
        let t = pair_time([0.3, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0; 3], 0.2, 0.0, 10.0).unwrap();
        assert!((t - 0.1).abs() < 1e-15);
        // A ball dropping onto one at rest below it, 0.05 m of gap: sqrt(2 * 0.05 / g).
        let g = [0.0, 0.0, -9.81];
        let t = pair_time([0.0, 0.0, 0.25], [0.0; 3], g, 0.2, 0.0, 10.0).unwrap();
        let expect = (0.1f64 / 9.81).sqrt();
        assert!((t - expect).abs() < 1e-14, "{t} vs {expect}");
        // Touching and bouncing up at 1 m/s: back after 2 v / g.
        let t = pair_time([0.0, 0.0, 0.2], [0.0, 0.0, 1.0], g, 0.2, 0.0, 10.0).unwrap();
        assert!((t - 2.0 / 9.81).abs() < 1e-14, "{t}");
        // Touching and closing: now. Passing by a metre aside: never.
        assert_eq!(pair_time([0.0, 0.0, 0.2], [0.0, 0.0, -1.0], g, 0.2, 0.0, 10.0), Some(0.0));
        assert_eq!(pair_time([1.0, 0.0, 0.2], [0.0, 0.0, 1.0], g, 0.2, 0.0, 10.0), None);
        // Touching and parting by less than round-off before gravity brings them back (a
        // regression: the rise never cleared zero, and the return was missed).
        let dr = [-0.010430267903623017, 0.0, 0.0034942111353854];
        let dv = [0.011975274207752518, 0.0, 0.0357463784770707];
        assert!(pair_time(dr, dv, g, 0.011, 0.0, 1.75e-4).is_some_and(|t| t < 1e-8));
    }

    /// The bisection from a whole piece, as the search ran before it started from closed forms.
    fn bisected(c: &[f64], (mut l, mut h): (f64, f64), rising: bool) -> f64 {
        loop {
            let m = 0.5 * (l + h);
            if m <= l || m >= h {
                return h;
            }
            if (eval(c, m) > 0.0) == rising {
                h = m;
            } else {
                l = m;
            }
        }
    }

    /// Started from the closed form, the search ends where the bisection from the whole piece
    /// does: on the same floats for 10 000 random lines (their values in floating point are
    /// monotone), and within the band of round-off for 10 000 random parabolas with two roots
    /// in `[0, 1]` (about 96 % of their roots on the same floats: where the values in floating
    /// point change sign more than once, the two searches may end on different changes).
    #[test]
    fn closed_forms_start_the_search_where_the_bisection_ends() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
        for _ in 0..10_000 {
            let c = [rng.random_range(-1.0..1.0), rng.random_range(-10.0..10.0)];
            let roots = sign_changes(&c, 1.0);
            if let Some(&r) = roots.as_slice().first() {
                assert_eq!(r, bisected(&c, (0.0, 1.0), c[1] > 0.0), "{c:?}");
            }
        }
        for _ in 0..10_000 {
            let (r1, r2, a) = (rng.random_range(0.0..0.5), rng.random_range(0.5..1.0), rng.random_range(-10.0..10.0));
            let c = [a * r1 * r2, -a * (r1 + r2), a];
            let vertex = sign_changes(&derivative(&c).values[..2], 1.0).as_slice()[0];
            let roots = sign_changes(&c, 1.0);
            assert_eq!(roots.len, 2, "{c:?}");
            for (k, piece) in [(0.0, vertex), (vertex, 1.0)].into_iter().enumerate() {
                let rising = eval(&c, piece.1) > 0.0;
                let (found, expected) = (roots.values[k], bisected(&c, piece, rising));
                // The band in which the parabola's value is below its round-off (a few ulps of
                // the sum of its terms' magnitudes) against its slope there.
                let t = expected;
                let band = 8.0 * f64::EPSILON * (c[0].abs() + c[1].abs() * t + c[2].abs() * t * t) / (c[1] + 2.0 * c[2] * t).abs();
                assert!((found - expected).abs() <= band + 4.0 * f64::EPSILON, "{c:?}: {found} against {expected} (band {band})");
            }
        }
    }

    /// The band of round-off around a sign change of `c` at `t`: where its value is below a
    /// few ulps of the sum of its terms' magnitudes, against its slope there.
    fn band(c: &[f64], t: f64) -> f64 {
        let size: f64 = c.iter().enumerate().map(|(k, v)| v.abs() * t.powi(k as i32)).sum();
        8.0 * f64::EPSILON * size / eval(&derivative(c).values[..c.len() - 1], t).abs() + 4.0 * f64::EPSILON
    }

    /// Started from Newton's steps, the search ends where the bisection from the whole piece
    /// does, to the band of round-off: every sign change of 10 000 random cubics with three
    /// roots in `[0, 1]`, and the first fall of 10 000 random quartics with four (in a tenth
    /// of them the first two close together, as for balls that barely touch).
    #[test]
    fn newton_starts_the_search_where_the_bisection_ends() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(13);
        for _ in 0..10_000 {
            let r = [rng.random_range(0.0..0.33), rng.random_range(0.33..0.66), rng.random_range(0.66..1.0)];
            let a = rng.random_range(-10.0..10.0);
            // a (t - r0)(t - r1)(t - r2)
            let c = [-a * r[0] * r[1] * r[2], a * (r[0] * r[1] + r[0] * r[2] + r[1] * r[2]), -a * (r[0] + r[1] + r[2]), a];
            let mut ends = vec![0.0];
            ends.extend_from_slice(sign_changes(&derivative(&c).values[..3], 1.0).as_slice());
            ends.push(1.0);
            let roots = sign_changes(&c, 1.0);
            assert_eq!(roots.len, 3, "{c:?}");
            for (k, piece) in ends.windows(2).enumerate() {
                let rising = eval(&c, piece[1]) > 0.0;
                let (found, expected) = (roots.values[k], bisected(&c, (piece[0], piece[1]), rising));
                let band = band(&c, expected);
                assert!((found - expected).abs() <= band, "{c:?}: {found} against {expected} (band {band})");
            }
        }
        for _ in 0..10_000 {
            let r0 = rng.random_range(0.0..0.25);
            // The second root close to the first in a tenth of the draws.
            let r1 = if rng.random_bool(0.1) { r0 + rng.random_range(1e-6..1e-3) } else { rng.random_range(0.25..0.5) };
            let r = [r0, r1, rng.random_range(0.5..0.75), rng.random_range(0.75..1.0)];
            // a (t - r0)(t - r1)(t - r2)(t - r3), lowest power first: positive at 0, first
            // falling through zero at r0.
            let mut c = vec![rng.random_range(0.1..100.0)];
            for &root in &r {
                let mut times = vec![0.0; c.len() + 1];
                for (k, &v) in c.iter().enumerate() {
                    times[k + 1] += v;
                    times[k] -= root * v;
                }
                c = times;
            }
            let found = first_fall(&c, 1.0).expect("it falls at its first root");
            let top = sign_changes(&derivative(&c).values[..4], 1.0).as_slice()[0];
            let expected = bisected(&c, (0.0, top), false);
            let band = band(&c, expected);
            assert!((found - expected).abs() <= band, "{c:?}: {found} against {expected} (band {band})");
        }
    }

    /// Without acceleration, a pair apart meets at `first_root`'s time to the bit, or not at
    /// all when it says so: random pairs closing, parting, passing by and grazing, some with
    /// velocities at round-off and some moving tangentially only.
    #[test]
    fn pairs_apart_meet_at_the_first_roots_time() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(31);
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let (mut met, mut missed) = (0, 0);
        for _ in 0..100_000 {
            let reach = rng.random_range(1e-3..1e-1);
            let dr: [f64; 3] = std::array::from_fn(|_| rng.random_range(-3.0 * reach..3.0 * reach));
            let scale = [1.0, 1e-12, 1e-300][rng.random_range(0..3)];
            // Towards each other, give or take a random velocity of the same size.
            let towards = rng.random_range(0.0..2.0) / dot(dr, dr).sqrt();
            let mut dv: [f64; 3] = std::array::from_fn(|k| scale * (rng.random_range(-1.0..1.0) - towards * dr[k]));
            if rng.random_bool(0.1) {
                // Moving across the line of centres only: never closing.
                let along = dot(dv, dr) / dot(dr, dr);
                dv = std::array::from_fn(|k| dv[k] - along * dr[k]);
            }
            // About as far ahead as the pair takes to close the gap, on either side of it.
            let limit = rng.random_range(0.0..2.0) * dot(dr, dr).sqrt() / scale;
            let (c0, c1) = (dot(dr, dr) - reach * reach, 2.0 * dot(dr, dv));
            if c0 <= 0.0 {
                continue;
            }
            let expected = if c1 >= 0.0 { None } else { first_root(dot(dv, dv), c1, c0).filter(|&t| t <= limit) };
            let found = pair_time(dr, dv, [0.0; 3], reach, 0.0, limit);
            assert_eq!(found.map(f64::to_bits), expected.map(f64::to_bits), "{dr:?} {dv:?} {reach}");
            if found.is_some() {
                met += 1;
            } else {
                missed += 1;
            }
        }
        assert!(met > 20_000 && missed > 20_000, "{met} met, {missed} missed");
    }

    #[test]
    fn touching_balls_closing_by_round_off_do_not_meet() {
        // Two balls side by side on the floor sliding together at -0.2446 m/s, one ulp of
        // velocity apart (a regression: their impact could not separate them, and the run
        // stalled at one instant).
        let (vi, vj) = ([-0.24459535242340505, 0.0, 0.0], [-0.24459535242340508, 0.0, 0.0]);
        let dv = std::array::from_fn(|k| vj[k] - vi[k]);
        let reach = 0.010277931654699434;
        assert_eq!(pair_time([reach, 0.0, 0.0], dv, [0.0; 3], reach, still(vi, vj), 10.0), None);
        // Closing at a millimetre a second, they meet now.
        assert_eq!(pair_time([reach, 0.0, 0.0], [-1e-3, 0.0, 0.0], [0.0; 3], reach, still(vi, vj), 10.0), Some(0.0));
    }
}
