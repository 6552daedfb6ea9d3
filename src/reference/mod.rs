//! The reference model: an exact event-driven impulse-momentum solver (MODEL.md §1-3), f64,
//! no engine. It is the ground truth every other model is measured against.
//!
//! Between events the frame moves in closed form ([`crate::oscillator`]) and free balls fly in straight
//! lines, so the state at any time is exact up to round-off. Events are
//! - ball-ball contacts, whose times are exact (linear gaps);
//! - contacts between a ball and the frame (a wall, or a ball stuck to it), found by
//!   [`Solver::search_frame_pair`], which splits time at the sign changes of the frame's
//!   acceleration: on each piece the gap is convex or concave, and the first root is bracketed
//!   by Newton iteration from the safe side, so a graze is never stepped over;
//! - the reversal of the force that holds a stuck group of balls against a wall (release).
//!
//! Impacts follow [`impact_law`]. Persistent contact is a state, not a stream of impacts: when
//! two touching bodies approach slower than `v_stick`, or a ball would bounce off an
//! accelerating wall and return within `t_stick`, the touching run of bodies is merged
//! (perfectly inelastic, momentum kept, the energy lost booked as an impact). A run that reaches
//! a wall moves with the frame (its mass joins the frame's oscillator) until the wall would pull
//! it, and is then released. Chattering, inelastic collapse and resting balls therefore end in
//! a bounded number of events with the energy balance intact.

pub mod impact_law;

use std::time::Instant;

use crate::run::{EnergyAccount, Impact, Run, Series};
use crate::scene::{Body, Scene};
pub use impact_law::impact_law;
pub use crate::oscillator::Oscillator;
use crate::oscillator::{gauss_legendre, Harmonic};

/// Why the reference could not finish a scene.
#[derive(Debug, thiserror::Error)]
pub enum ReferenceError {
    /// More events than [`MAX_EVENTS`]: the solver gives up rather than run forever.
    #[error("scene `{scene}`: stalled after {events} events at t = {t} s (limit {MAX_EVENTS})")]
    Stalled {
        /// Scene name.
        scene: String,
        /// Events processed.
        events: u64,
        /// Simulated time reached.
        t: f64,
    },
}

/// Most events one run may process before it is declared stalled.
pub const MAX_EVENTS: u64 = 20_000_000;
/// Shortest time between two impacts of one pair that are resolved as separate impacts, s.
///
/// The impulse model treats impacts as instantaneous, which holds only while they are further
/// apart than a real contact lasts (tens of microseconds for centimetre steel balls at these
/// speeds). Closer repeats, such as a light elastic ball squeezed between two heavy ones
/// (whose bounce rate grows without bound as the gap closes), are persistent contact: the
/// touching run is merged, with the energy booked as an impact loss.
pub const CONTACT_DURATION: f64 = 1e-6;
/// Most events at one instant: everything at an instant is resolved by one `resolve`, so a
/// second event at the same time already means two judgements disagree.
const MAX_EVENTS_PER_INSTANT: u64 = 1000;
/// Most impacts resolved at one instant before the touching run is merged.
const MAX_IMPULSES_PER_INSTANT: usize = 10_000;
/// Contact tolerance relative to the scene's length scale.
const LENGTH_TOLERANCE: f64 = 1e-12;
/// Sticking speed relative to the scene's speed scale.
const STICK_SPEED: f64 = 1e-9;
/// Bounce-return time below which a ball sticks to the frame, relative to the time scale.
const STICK_TIME: f64 = 1e-7;

/// Runs the reference model on `scene`.
pub fn simulate(scene: &Scene) -> Result<Run, ReferenceError> {
    let start = Instant::now();
    let mut solver = Solver::new(scene);
    solver.run()?;
    let mut run = solver.finish();
    run.wall_time_s = start.elapsed().as_secs_f64();
    Ok(run)
}

/// Speed scale of base motion (`w Y`), 0 otherwise.
fn base_motion_speed(scene: &Scene) -> f64 {
    scene.forcing.filter(|g| g.kind == crate::scene::ForcingKind::Base).map_or(0.0, |g| g.omega() * g.amplitude)
}

/// Samples stepped by the transition matrix between two closed-form evaluations.
const REANCHOR: u32 = 32;

/// Where frame sampling stands: the last sample's state and the step matrix of its segment.
#[derive(Debug, Clone, Copy)]
struct SampleCursor {
    seg_t0: f64,
    k: usize,
    x: f64,
    v: f64,
    steps: u32,
    mass: f64,
    transition: [[f64; 2]; 2],
}

/// Which wall a stuck ball is held by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Hold {
    Free,
    Left,
    Right,
}

/// The frame's motion since its last change of velocity or mass.
#[derive(Debug, Clone, Copy)]
struct Segment {
    t0: f64,
    x0: f64,
    v0: f64,
    /// Acceleration and jerk at `t0`, for the sign-change search (of the departure from the
    /// steady response, when forced).
    a0: f64,
    j0: f64,
    osc: Oscillator,
    forced: Option<Forced>,
}

/// A forced segment: the motion is `xp(t)` plus the free motion of the departure from it.
#[derive(Debug, Clone, Copy)]
struct Forced {
    xp: Harmonic,
    /// Departure `(x - xp, v - xp')` at `t0`.
    h0: (f64, f64),
    /// Longest scan step of the sign-change search: a sixteenth of the shorter period.
    scan: f64,
}

impl Segment {
    fn new(t0: f64, x0: f64, v0: f64, osc: Oscillator, load: Option<(f64, f64, f64)>) -> Self {
        let forced = load.map(|(p, q, omega)| {
            let xp = osc.harmonic_response(p, q, omega);
            let (xp0, vp0) = xp.state(t0);
            let forcing_period = 2.0 * std::f64::consts::PI / omega;
            let frame_period = if osc.w0sq > 0.0 { 2.0 * std::f64::consts::PI / osc.w0sq.sqrt() } else { f64::INFINITY };
            Forced { xp, h0: (x0 - xp0, v0 - vp0), scan: forcing_period.min(frame_period) / 16.0 }
        });
        let (hx, hv) = forced.map_or((x0, v0), |f| f.h0);
        let a0 = osc.accel(hx, hv);
        Segment { t0, x0, v0, a0, j0: -2.0 * osc.sigma * a0 - osc.w0sq * hv, osc, forced }
    }
    #[inline]
    fn state(&self, t: f64) -> (f64, f64) {
        match &self.forced {
            None => self.osc.state(self.x0, self.v0, t - self.t0),
            Some(f) => {
                let (xh, vh) = self.osc.state(f.h0.0, f.h0.1, t - self.t0);
                let (xp, vp) = f.xp.state(t);
                (xh + xp, vh + vp)
            }
        }
    }
    /// Acceleration, jerk and snap of a forced frame at `t`, with the size of each (the sum of
    /// its parts' magnitudes) to judge round-off against.
    fn forced_derivatives(&self, f: &Forced, t: f64) -> [(f64, f64); 3] {
        let o = &self.osc;
        let (ah, jh) = o.state(self.a0, self.j0, t - self.t0);
        let sh = -2.0 * o.sigma * jh - o.w0sq * ah;
        let d = f.xp.derivatives(t);
        let parts = [(ah, d[2]), (jh, d[3]), (sh, d[4])];
        let amp = f.xp.amplitude();
        let w = f.xp.omega;
        let mut out = [(0.0, 0.0); 3];
        for (n, (h, p)) in parts.into_iter().enumerate() {
            out[n] = (h + p, h.abs() + amp * w.powi(n as i32 + 2));
        }
        out
    }
    /// Next time after `t` at which the frame's acceleration changes sign, or `limit` if none
    /// comes first (unforced segments ignore `limit`: their sign changes are closed form).
    fn next_sign_change(&self, t: f64, limit: f64) -> f64 {
        if let Some(f) = &self.forced {
            return self.forced_sign_change(f, t, limit);
        }
        // A root just after `t` in segment time can round onto `t` in absolute time: take the
        // next one then, so that time always moves on.
        let mut after = t - self.t0;
        while let Some(tau) = self.osc.next_sign_change(self.a0, self.j0, after) {
            if self.t0 + tau > t {
                return self.t0 + tau;
            }
            after = tau;
        }
        f64::INFINITY
    }
    /// The forced acceleration `a = a_h + a_p` has no closed-form roots; it is scanned with a
    /// bound on its slope, so no sign change is stepped over. For `s' >= s`, the free part's
    /// jerk `j_h` (a free solution itself) keeps `j_h'^2 + w0^2 j_h^2` from growing, so
    /// `|a'| <= |j_h(s)| + h sqrt(j_h'(s)^2 + w0^2 j_h(s)^2) + w^3 |xp|` over `[s, s + h]`, and
    /// `a` cannot change sign there while `|a(s)|` exceeds that times `h`. Pieces that cannot be
    /// cleared are halved down to a few ulps.
    fn forced_sign_change(&self, f: &Forced, t: f64, limit: f64) -> f64 {
        if !(limit > t) {
            return limit;
        }
        let o = &self.osc;
        let amp3 = f.xp.amplitude() * f.xp.omega.powi(3);
        // The scan needs the acceleration alone.
        let accel = |s: f64| o.state(self.a0, self.j0, s - self.t0).0 + f.xp.derivative(s, 2);
        let slope_bound = |s: f64, h: f64| {
            let (ah, jh) = o.state(self.a0, self.j0, s - self.t0);
            let sh = -2.0 * o.sigma * jh - o.w0sq * ah;
            jh.abs() + h * (sh * sh + o.w0sq * jh * jh).sqrt() + amp3
        };
        let tiny = |s: f64| 8.0 * f64::EPSILON * s.abs().max(f.scan);
        // Depth-first over halves, left first: the first sign change in [a, b], if any.
        fn first(seg: &dyn Fn(f64) -> f64, bound: &dyn Fn(f64, f64) -> f64, tiny: &dyn Fn(f64) -> f64, a: f64, b: f64, fa: f64) -> Option<f64> {
            let h = b - a;
            if fa.abs() > bound(a, h) * h {
                return None;
            }
            let fb = seg(b);
            if h <= tiny(b) {
                return ((fa > 0.0) != (fb > 0.0) || fb == 0.0).then_some(b);
            }
            let m = 0.5 * (a + b);
            let fm = seg(m);
            first(seg, bound, tiny, a, m, fa).or_else(|| first(seg, bound, tiny, m, b, fm))
        }
        let mut a = t;
        let mut fa = accel(a);
        while a < limit {
            let b = (a + f.scan).min(limit);
            if let Some(root) = first(&accel, &slope_bound, &tiny, a, b, fa) {
                if root > t {
                    return root;
                }
            }
            a = b;
            fa = accel(a);
        }
        limit
    }
}

/// The gap of a pair as a function of time.
#[derive(Debug, Clone, Copy)]
enum Gap {
    /// Both sides move with the frame: the gap never changes.
    Fixed,
    /// Two free balls: `g(t) = g + rate (t - t_now)`.
    Linear { g: f64, rate: f64 },
    /// A free ball `ball` against the frame: `g(t) = s (x_ball(t) - xs(t)) + k`.
    Frame { ball: usize, s: f64, k: f64 },
}

/// A pair's next event: at `t` when `exact`, else "no contact before `t`" (search again from `t`).
#[derive(Debug, Clone, Copy)]
struct Candidate {
    t: f64,
    exact: bool,
}

const NO_EVENT: Candidate = Candidate { t: f64::INFINITY, exact: true };

struct Solver<'a> {
    scene: &'a Scene,
    n: usize,
    walls: bool,
    mass: Vec<f64>,
    radius: Vec<f64>,
    e: f64,
    frame_mass: f64,
    damping: f64,
    stiffness: f64,
    length: f64,
    seg: Segment,
    t: f64,
    x: Vec<f64>,
    v: Vec<f64>,
    hold: Vec<Hold>,
    offset: Vec<f64>,
    held_mass: f64,
    packed: bool,
    cand: Vec<Candidate>,
    dirty: Vec<bool>,
    frame_dirty: bool,
    release_at: f64,
    tol: f64,
    v_stick: f64,
    t_stick: f64,
    span: f64,
    horizon: f64,
    damping_loss: f64,
    forcing_work: f64,
    /// The harmonic load `(P, Q, w)` on the frame, when forced.
    load: Option<(f64, f64, f64)>,
    impact_loss: f64,
    impacts: Vec<Impact>,
    last_impact: Vec<Option<usize>>,
    events: u64,
    series: Series,
    next_sample: usize,
    sample_count: usize,
    cursor: SampleCursor,
}

impl<'a> Solver<'a> {
    fn new(scene: &'a Scene) -> Self {
        let n = scene.balls.len();
        let (frame_mass, damping, stiffness) =
            scene.frame.map_or((f64::INFINITY, 0.0, 0.0), |f| (f.mass, f.damping, f.stiffness));
        let walls = scene.container.is_some();
        let length = scene.container.map_or(0.0, |c| c.length);
        let osc = Oscillator::new(if frame_mass.is_finite() { frame_mass } else { 1.0 }, damping, stiffness);
        let xs0 = scene.initial_displacement;
        let span_len = if walls {
            length
        } else {
            match (scene.initial_positions.first(), scene.initial_positions.last()) {
                (Some(a), Some(b)) => b - a,
                _ => 0.0,
            }
        };
        let length_scale = span_len.max(xs0.abs()).max(scene.balls.iter().map(|b| b.radius).fold(0.0, f64::max)).max(1e-9);
        let bare_omega = osc.w0sq.sqrt();
        let time_scale = scene.frame.map_or(scene.horizon, |f| {
            let p = f.damped_period();
            if p > 0.0 {
                p
            } else {
                scene.horizon
            }
        });
        let load = scene.harmonic_load();
        let forced_speed =
            load.map_or(0.0, |(p, q, w)| osc.harmonic_response(p, q, w).amplitude() * w + base_motion_speed(scene));
        let speed_scale = (bare_omega * xs0.abs()).max(forced_speed)
            .max(scene.initial_velocities.iter().fold(0.0, |m: f64, v| m.max(v.abs())))
            .max(length_scale / scene.horizon);
        let samples = (scene.horizon / scene.sample_dt * (1.0 + 1e-12)).floor() as usize + 1;
        let mut s = Solver {
            scene,
            n,
            walls,
            mass: scene.balls.iter().map(|b| b.mass).collect(),
            radius: scene.balls.iter().map(|b| b.radius).collect(),
            e: scene.restitution,
            frame_mass,
            damping,
            stiffness,
            length,
            seg: Segment::new(0.0, xs0, 0.0, osc, load),
            t: 0.0,
            x: scene.initial_positions.clone(),
            v: scene.initial_velocities.clone(),
            hold: vec![Hold::Free; n],
            offset: vec![0.0; n],
            held_mass: 0.0,
            packed: false,
            cand: vec![NO_EVENT; n + 1],
            dirty: vec![true; n + 1],
            frame_dirty: true,
            release_at: f64::INFINITY,
            tol: LENGTH_TOLERANCE * length_scale,
            v_stick: STICK_SPEED * speed_scale,
            t_stick: STICK_TIME * time_scale,
            span: f64::INFINITY,
            horizon: scene.horizon,
            damping_loss: 0.0,
            forcing_work: 0.0,
            load,
            impact_loss: 0.0,
            impacts: Vec::new(),
            last_impact: vec![None; n + 1],
            events: 0,
            series: Series::with_capacity(n, samples),
            next_sample: 0,
            sample_count: samples,
            cursor: SampleCursor { seg_t0: f64::NAN, k: 0, x: 0.0, v: 0.0, steps: 0, mass: f64::NAN, transition: [[0.0; 2]; 2] },
        };
        s.span = s.group_span();
        s
    }

    fn has_frame(&self) -> bool {
        self.frame_mass.is_finite()
    }

    /// One damped period of the frame with what it carries, or the horizon.
    fn group_span(&self) -> f64 {
        self.seg.osc.damped_omega().map_or(self.horizon, |w| 2.0 * std::f64::consts::PI / w)
    }

    /// Pairs that can touch: `p` lies between body `p - 1` and body `p` (body `-1` is the left
    /// wall, body `n` the right wall).
    fn pair_range(&self) -> std::ops::Range<usize> {
        if self.walls {
            0..self.n + 1
        } else {
            1..self.n.max(1)
        }
    }

    // ---- geometry -------------------------------------------------------------------------

    fn gap(&self, p: usize) -> Gap {
        // Right edge of the left body and left edge of the right body: either a free ball's
        // (`Ok((ball, edge offset))`) or the frame's (`Err(offset from xs)`).
        let left = if p == 0 {
            Err(0.0)
        } else {
            let i = p - 1;
            if self.hold[i] == Hold::Free {
                Ok((i, self.radius[i]))
            } else {
                Err(self.offset[i] + self.radius[i])
            }
        };
        let right = if p == self.n {
            Err(self.length)
        } else if self.hold[p] == Hold::Free {
            Ok((p, -self.radius[p]))
        } else {
            Err(self.offset[p] - self.radius[p])
        };
        match (left, right) {
            (Err(_), Err(_)) => Gap::Fixed,
            (Ok((i, ri)), Ok((j, rj))) => {
                Gap::Linear { g: (self.x[j] + rj) - (self.x[i] + ri), rate: self.v[j] - self.v[i] }
            }
            (Err(c), Ok((j, rj))) => Gap::Frame { ball: j, s: 1.0, k: rj - c },
            (Ok((i, ri)), Err(c)) => Gap::Frame { ball: i, s: -1.0, k: c - ri },
        }
    }

    /// Gap and its rate for a ball-frame pair at time `t` (the ball flies from `self.t`).
    #[inline]
    fn frame_gap_at(&self, ball: usize, s: f64, k: f64, t: f64) -> (f64, f64) {
        let (xs, vs) = self.seg.state(t);
        let xb = self.x[ball] + self.v[ball] * (t - self.t);
        (s * (xb - xs) + k, s * (self.v[ball] - vs))
    }

    /// The frame's acceleration just after `t`: its value, with the sign of the first
    /// derivative that is not round-off when the acceleration itself is (at a sign change).
    /// Every sign involved is that of `-(c v + k x)` and its derivatives, whatever the mass
    /// the frame carries, so holding and releasing a ball always agree.
    fn accel_ahead(&self, t: f64) -> f64 {
        if let Some(f) = &self.seg.forced {
            let [(a, sa), (jerk, sj), (snap, _)] = self.seg.forced_derivatives(f, t);
            if a.abs() > 1e-9 * sa {
                return a;
            }
            let sign = if jerk.abs() > 1e-9 * sj {
                jerk.signum()
            } else if snap == 0.0 {
                return 0.0;
            } else {
                snap.signum()
            };
            return sign * a.abs().max(f64::MIN_POSITIVE);
        }
        let (x, v) = self.seg.state(t);
        let o = &self.seg.osc;
        let a = o.accel(x, v);
        // Scales of a and its derivative over the motion (w0 |v| matters where x passes 0).
        let rate = 2.0 * o.sigma + o.w0sq.sqrt();
        if a.abs() > 1e-9 * (o.w0sq * x.abs() + rate * v.abs()) {
            return a;
        }
        let jerk = -2.0 * o.sigma * a - o.w0sq * v;
        let sign = if jerk.abs() > 1e-9 * (rate * a.abs() + o.w0sq * v.abs()) {
            jerk.signum()
        } else {
            let snap = -2.0 * o.sigma * jerk - o.w0sq * a;
            if snap == 0.0 {
                return 0.0;
            }
            snap.signum()
        };
        sign * a.abs().max(f64::MIN_POSITIVE)
    }

    // ---- event search ---------------------------------------------------------------------

    fn candidate(&self, p: usize, from: f64) -> Candidate {
        match self.gap(p) {
            Gap::Fixed => NO_EVENT,
            Gap::Linear { g, rate } => {
                if rate < 0.0 {
                    Candidate { t: self.t + g.max(0.0) / -rate, exact: true }
                } else {
                    NO_EVENT
                }
            }
            Gap::Frame { ball, s, k } => self.search_frame_pair(ball, s, k, from),
        }
    }

    /// First contact of a ball with the frame after `from`, searched over one damped period
    /// at a time. The frame's acceleration keeps its sign between consecutive sign changes, so
    /// there the gap `g` has `g'' = -s a` of one sign: on a convex piece Newton's method from
    /// the left never passes the first root; on a concave piece a root exists only if `g` at
    /// the piece's end is not positive, and Newton from the right converges to it from above.
    fn search_frame_pair(&self, ball: usize, s: f64, k: f64, from: f64) -> Candidate {
        let limit = (from + self.span).min(self.horizon);
        let mut a = from;
        loop {
            let b = self.seg.next_sign_change(a, limit).min(limit);
            // The sign just after `a` holds over the whole piece; judged as `resolve` judges it,
            // so that the two agree even where the acceleration is round-off (a frame at rest).
            let curvature = -s * self.accel_ahead(a);
            let root = if curvature >= 0.0 {
                self.convex_root(ball, s, k, a, b)
            } else {
                self.concave_root(ball, s, k, a, b)
            };
            if let Some(t) = root {
                return Candidate { t, exact: true };
            }
            if b >= limit {
                return if limit >= self.horizon { NO_EVENT } else { Candidate { t: limit, exact: false } };
            }
            a = b;
        }
    }

    fn convex_root(&self, ball: usize, s: f64, k: f64, a: f64, b: f64) -> Option<f64> {
        let mut t = a;
        for _ in 0..200 {
            let (g, gp) = self.frame_gap_at(ball, s, k, t);
            if gp >= 0.0 {
                return None; // convex and not decreasing: it only rises from here on
            }
            if g <= self.tol {
                return Some(t);
            }
            let next = t - g / gp;
            if next > b {
                return None;
            }
            if next <= t {
                return Some(t);
            }
            t = next;
        }
        Some(t)
    }

    fn concave_root(&self, ball: usize, s: f64, k: f64, a: f64, b: f64) -> Option<f64> {
        let (ga, gpa) = self.frame_gap_at(ball, s, k, a);
        if ga <= self.tol && gpa <= 0.0 {
            // Touching and not separating: a contact now if the wall presses, judged exactly as
            // `resolve` judges it (a piece can be an ulp long at a sign change, and its
            // midpoint then disagrees); otherwise the ball is about to leave the wall.
            return (-s * self.accel_ahead(a) < 0.0).then_some(a);
        }
        let (gb, _) = self.frame_gap_at(ball, s, k, b);
        if gb > self.tol {
            return None; // a concave function's minimum lies at an end of the piece
        }
        let mut lo = a;
        if ga <= self.tol {
            // Touching but separating: the return is after the maximum of g (where g' = 0,
            // g' decreasing on a concave piece).
            let (mut l, mut h) = (a, b);
            for _ in 0..200 {
                let m = 0.5 * (l + h);
                if m <= l || m >= h {
                    break;
                }
                if self.frame_gap_at(ball, s, k, m).1 > 0.0 {
                    l = m;
                } else {
                    h = m;
                }
            }
            lo = l;
            if self.frame_gap_at(ball, s, k, lo).0 <= self.tol {
                return Some(lo);
            }
        }
        // g decreases on [lo, b] from above tol to at most tol: one root; Newton from the right.
        let (mut l, mut h) = (lo, b);
        let mut t = b;
        for _ in 0..200 {
            let (g, gp) = self.frame_gap_at(ball, s, k, t);
            if g >= -self.tol && g <= self.tol {
                return Some(t);
            }
            if g > 0.0 {
                l = t;
            } else {
                h = t;
            }
            let newton = t - g / gp;
            t = if gp < 0.0 && newton > l && newton < h { newton } else { 0.5 * (l + h) };
            if h - l <= 4.0 * f64::EPSILON * h.abs() {
                return Some(h);
            }
        }
        Some(h)
    }

    fn refresh_candidates(&mut self) {
        if self.frame_dirty && self.has_frame() {
            for p in self.pair_range() {
                if matches!(self.gap(p), Gap::Frame { .. }) {
                    self.dirty[p] = true;
                }
            }
            self.release_at = if self.held_mass > 0.0 && !self.packed {
                // Forced: at most one span ahead; if nothing changed sign by then, `release`
                // finds nothing to let go and the search goes on from there.
                self.seg.next_sign_change(self.t, (self.t + self.span).min(self.horizon))
            } else {
                f64::INFINITY
            };
        }
        self.frame_dirty = false;
        for p in self.pair_range() {
            if self.dirty[p] {
                self.cand[p] = self.candidate(p, self.t);
                self.dirty[p] = false;
            }
        }
    }

    // ---- state changes --------------------------------------------------------------------

    fn advance(&mut self, t: f64) {
        let dt = t - self.t;
        for i in 0..self.n {
            if self.hold[i] == Hold::Free {
                self.x[i] += self.v[i] * dt;
            }
        }
        self.t = t;
    }

    /// Starts a new frame segment at the current time with velocity `v` and the current load.
    fn set_frame(&mut self, v: f64) {
        self.book_segment_energy();
        let (xs, _) = self.seg.state(self.t);
        let osc = if self.seg.osc.mass == self.frame_mass + self.held_mass {
            self.seg.osc
        } else {
            Oscillator::new(self.frame_mass + self.held_mass, self.damping, self.stiffness)
        };
        self.seg = Segment::new(self.t, xs, v, osc, self.load);
        self.span = self.group_span();
        self.frame_dirty = true;
    }

    /// Books what the frame's damper dissipated, and the excitation put in, over the current
    /// segment up to now: closed form when free; when forced, Gauss-Legendre on pieces of a
    /// sixteenth of the shorter period (exact to round-off, see [`gauss_legendre`]).
    fn book_segment_energy(&mut self) {
        let tau = self.t - self.seg.t0;
        let Some(f) = self.seg.forced else {
            self.damping_loss += self.seg.osc.dissipated(self.seg.x0, self.seg.v0, tau);
            return;
        };
        let seg = self.seg;
        let scene = self.scene;
        let [damping, work] = gauss_legendre(seg.t0, self.t, f.scan, |t| {
            let (xs, vs) = seg.state(t);
            [scene.damping_power(t, vs), scene.forcing_power(t, xs, vs)]
        });
        self.damping_loss += damping;
        self.forcing_work += work;
    }

    fn touch_ball(&mut self, i: usize) {
        self.dirty[i] = true;
        self.dirty[i + 1] = true;
    }

    fn record(&mut self, p: usize, approach_speed: f64, energy_lost: f64, impulses: u32) {
        let a = if p == 0 { Body::LeftWall } else { Body::Ball(p - 1) };
        let b = if p == self.n { Body::RightWall } else { Body::Ball(p) };
        self.impact_loss += energy_lost;
        // Sequential impulses across one pair at one instant are one impact of that pair.
        if let Some(k) = self.last_impact[p] {
            let last = &mut self.impacts[k];
            if last.t == self.t {
                last.energy_lost += energy_lost;
                last.impulses += impulses;
                return;
            }
        }
        self.last_impact[p] = Some(self.impacts.len());
        self.impacts.push(Impact { t: self.t, a, b, approach_speed, energy_lost, impulses, peak_force: None, contact_duration: None });
    }

    /// An impact with restitution `e` across pair `p`.
    fn collide(&mut self, p: usize, approach_speed: f64) {
        match self.gap(p) {
            Gap::Fixed => {}
            Gap::Linear { .. } => {
                let (i, j) = (p - 1, p);
                let (vi, vj, lost) = impact_law(self.mass[i], self.v[i], self.mass[j], self.v[j], self.e);
                self.v[i] = vi;
                self.v[j] = vj;
                self.touch_ball(i);
                self.touch_ball(j);
                self.record(p, approach_speed, lost, 1);
            }
            Gap::Frame { ball, .. } => {
                let (_, vs) = self.seg.state(self.t);
                let group = self.frame_mass + self.held_mass;
                let (vb, vf, lost) = impact_law(self.mass[ball], self.v[ball], group, vs, self.e);
                self.v[ball] = vb;
                self.touch_ball(ball);
                self.set_frame(vf);
                self.record(p, approach_speed, lost, 1);
            }
        }
    }

    /// Is pair `p` touching and slow enough (relative speed below `v_stick`) to move as one?
    fn stuck_pair(&self, p: usize) -> bool {
        match self.gap(p) {
            Gap::Fixed => false,
            Gap::Linear { g, rate } => g <= self.tol && rate.abs() < self.v_stick,
            Gap::Frame { ball, s, k } => {
                let (g, gp) = self.frame_gap_at(ball, s, k, self.t);
                g <= self.tol && gp.abs() < self.v_stick
            }
        }
    }

    /// Perfectly inelastic merge of the run of touching slow bodies around pair `p`; a run that
    /// reaches the frame is held by it.
    fn merge_run(&mut self, p: usize, approach_speed: f64) {
        let range = self.pair_range();
        let (mut lo, mut hi) = (p, p);
        // Extend across pairs of free balls only: the frame's group is one body already.
        while lo > range.start && self.left_body_free(lo) && self.stuck_pair(lo - 1) {
            lo -= 1;
        }
        while hi + 1 < range.end && self.right_body_free(hi) && self.stuck_pair(hi + 1) {
            hi += 1;
        }
        // The run holds bodies lo-1 ..= hi (body -1 and body n being the walls).
        let reaches_left = lo == 0 || self.hold[lo - 1] != Hold::Free;
        let reaches_right = hi == self.n || self.hold[hi] != Hold::Free;
        let with_frame = self.has_frame() && self.walls && (reaches_left || reaches_right);
        let balls: Vec<usize> =
            (lo.saturating_sub(1)..(hi + 1).min(self.n)).filter(|&i| self.hold[i] == Hold::Free).collect();
        let (_, vs) = self.seg.state(self.t);
        let group = self.frame_mass + self.held_mass;
        let (mut pm, mut m) = (0.0, 0.0);
        for &i in &balls {
            pm += self.mass[i] * self.v[i];
            m += self.mass[i];
        }
        if with_frame {
            pm += group * vs;
            m += group;
        }
        let vc = pm / m;
        let mut lost = 0.0;
        for &i in &balls {
            lost += 0.5 * self.mass[i] * (self.v[i] - vc).powi(2);
            self.v[i] = vc;
            self.touch_ball(i);
        }
        if with_frame {
            lost += 0.5 * group * (vs - vc).powi(2);
            let (xs, _) = self.seg.state(self.t);
            let side = if reaches_left { Hold::Left } else { Hold::Right };
            for &i in &balls {
                self.hold[i] = side;
                self.offset[i] = self.x[i] - xs;
                self.held_mass += self.mass[i];
            }
            if reaches_left && reaches_right {
                self.packed = true;
            }
            self.set_frame(vc);
        }
        self.record(p, approach_speed, lost, balls.len() as u32 + with_frame as u32);
    }

    fn left_body_free(&self, p: usize) -> bool {
        p >= 1 && self.hold[p - 1] == Hold::Free
    }
    fn right_body_free(&self, p: usize) -> bool {
        p < self.n && self.hold[p] == Hold::Free
    }

    /// Releases the held runs whose wall would now pull on them.
    fn release(&mut self) -> bool {
        if self.held_mass == 0.0 || self.packed {
            return false;
        }
        let a = self.accel_ahead(self.t);
        let (xs, vs) = self.seg.state(self.t);
        let mut released = false;
        for i in 0..self.n {
            let pulled = match self.hold[i] {
                Hold::Left => a < 0.0,
                Hold::Right => a > 0.0,
                Hold::Free => false,
            };
            if pulled {
                self.hold[i] = Hold::Free;
                self.x[i] = xs + self.offset[i];
                self.v[i] = vs;
                self.held_mass -= self.mass[i];
                self.touch_ball(i);
                released = true;
            }
        }
        if released {
            if self.hold.iter().all(|h| *h == Hold::Free) {
                self.held_mass = 0.0; // no round-off residue
            }
            self.set_frame(vs);
        }
        released
    }

    /// Resolves everything that happens at the current instant: impacts of touching
    /// approaching pairs (fastest first), merges of slow ones, holds and releases.
    fn resolve(&mut self) {
        let mut impulses = 0usize;
        loop {
            let mut fastest: Option<(usize, f64)> = None;
            let mut pressed: Option<usize> = None;
            for p in self.pair_range() {
                let (g, rate, pushed) = match self.gap(p) {
                    Gap::Fixed => continue,
                    Gap::Linear { g, rate } => (g, rate, false),
                    Gap::Frame { ball, s, k } => {
                        let (g, gp) = self.frame_gap_at(ball, s, k, self.t);
                        (g, gp, -s * self.accel_ahead(self.t) < 0.0)
                    }
                };
                if g > self.tol {
                    continue;
                }
                if rate < 0.0 && fastest.is_none_or(|(_, u)| -rate > u) {
                    fastest = Some((p, -rate));
                }
                if pushed && rate < self.v_stick && pressed.is_none() {
                    pressed = Some(p);
                }
            }
            if let Some((p, u)) = fastest {
                let bounce_returns_fast = match self.gap(p) {
                    Gap::Frame { s, .. } => {
                        let a = -s * self.accel_ahead(self.t);
                        a < 0.0 && 2.0 * self.e * u / -a < self.t_stick
                    }
                    _ => false,
                };
                // With e = 0 a touching approaching run ends as one body: merge it at once
                // instead of converging to that through a geometric series of impulses.
                // A pair striking again within a contact duration is in persistent contact.
                let repeats_within_contact = self.last_impact[p]
                    .is_some_and(|k| self.impacts[k].t < self.t && self.t - self.impacts[k].t < CONTACT_DURATION);
                if self.e > 0.0
                    && u >= self.v_stick
                    && !bounce_returns_fast
                    && !repeats_within_contact
                    && impulses < MAX_IMPULSES_PER_INSTANT
                {
                    self.collide(p, u);
                    impulses += 1;
                } else {
                    self.merge_run(p, u);
                }
                continue;
            }
            if let Some(p) = pressed {
                self.merge_run(p, 0.0);
                continue;
            }
            if !self.release() {
                break;
            }
        }
    }

    // ---- output ---------------------------------------------------------------------------

    /// Writes every sample with time `<= until` (strictly before when `inclusive` is false).
    fn sample_until(&mut self, until: f64, inclusive: bool) {
        let dt = self.scene.sample_dt;
        while self.next_sample < self.sample_count {
            let ts = self.next_sample as f64 * dt;
            if ts > until || (!inclusive && ts == until) {
                break;
            }
            let has_frame = self.has_frame();
            let (xs, vs) = if has_frame { self.frame_sample(ts) } else { (0.0, 0.0) };
            let s = &mut self.series;
            s.push_frame(self.scene, ts, xs, vs);
            for i in 0..self.n {
                let (x, v) = match self.hold[i] {
                    Hold::Free => (self.x[i] + self.v[i] * (ts - self.t), self.v[i]),
                    _ => (xs + self.offset[i], vs),
                };
                s.x[i].push(x);
                s.v[i].push(v);
            }
            self.next_sample += 1;
        }
    }

    /// The frame's state at sample `self.next_sample` (time `ts`): one step of the exact
    /// transition matrix from the previous sample when it lies in the same segment, the closed
    /// form every [`REANCHOR`] samples so that round-off cannot drift.
    fn frame_sample(&mut self, ts: f64) -> (f64, f64) {
        if self.seg.forced.is_some() {
            return self.seg.state(ts);
        }
        let c = &mut self.cursor;
        let k = self.next_sample;
        if c.seg_t0 == self.seg.t0 && c.k + 1 == k && c.steps < REANCHOR && k > 0 {
            let [[a, b], [cc, d]] = c.transition;
            (c.x, c.v) = (a * c.x + b * c.v, cc * c.x + d * c.v);
            c.steps += 1;
        } else {
            if c.mass != self.seg.osc.mass {
                c.transition = self.seg.osc.transition(self.scene.sample_dt);
                c.mass = self.seg.osc.mass;
            }
            (c.x, c.v) = self.seg.state(ts);
            c.seg_t0 = self.seg.t0;
            c.steps = 0;
        }
        c.k = k;
        (c.x, c.v)
    }

    fn run(&mut self) -> Result<(), ReferenceError> {
        let mut same_instant = 0u64;
        self.resolve();
        loop {
            self.refresh_candidates();
            let mut next = (self.horizon, None);
            for p in self.pair_range() {
                if self.cand[p].t < next.0 {
                    next = (self.cand[p].t, Some(p));
                }
            }
            let release = self.release_at < next.0;
            if release {
                next = (self.release_at, None);
            }
            let (t, pair) = next;
            if !release && pair.is_none() {
                break;
            }
            if let Some(p) = pair {
                if !self.cand[p].exact {
                    self.cand[p] = self.candidate(p, t);
                    continue;
                }
            }
            self.sample_until(t, false);
            same_instant = if t == self.t { same_instant + 1 } else { 0 };
            self.advance(t);
            self.events += 1;
            if self.events > MAX_EVENTS || same_instant > MAX_EVENTS_PER_INSTANT {
                return Err(ReferenceError::Stalled { scene: self.scene.name.clone(), events: self.events, t });
            }
            if release {
                self.release_at = f64::INFINITY;
                self.frame_dirty = true;
            }
            if let Some(p) = pair {
                // Searched again from now even if resolving changes nothing (a contact that
                // turns out not to be one), or its cached time would fire forever.
                self.dirty[p] = true;
            }
            self.resolve();
        }
        self.sample_until(self.horizon, true);
        self.advance(self.horizon);
        Ok(())
    }

    fn mechanical_energy(&self) -> f64 {
        let (xs, vs) = if self.has_frame() { self.seg.state(self.t) } else { (0.0, 0.0) };
        let frame = self.scene.frame_energy(self.t, xs, vs);
        frame
            + (0..self.n)
                .map(|i| {
                    let v = if self.hold[i] == Hold::Free { self.v[i] } else { vs };
                    0.5 * self.mass[i] * v * v
                })
                .sum::<f64>()
    }

    fn finish(mut self) -> Run {
        if self.has_frame() {
            self.book_segment_energy();
        }
        let (_, vs) = if self.has_frame() { self.seg.state(self.t) } else { (0.0, 0.0) };
        let final_velocities =
            (0..self.n).map(|i| if self.hold[i] == Hold::Free { self.v[i] } else { vs }).collect();
        let energy = EnergyAccount::forced(
            self.scene.initial_energy(),
            self.mechanical_energy(),
            self.damping_loss,
            self.impact_loss,
            self.forcing_work,
        );
        Run {
            scene: self.scene.name.clone(),
            model: "reference".into(),
            horizon: self.horizon,
            sample_dt: self.scene.sample_dt,
            initial_displacement: self.scene.initial_displacement,
            damped_period: self.scene.frame.map_or(0.0, |f| f.damped_period()),
            series: self.series,
            impacts: self.impacts,
            energy,
            events: self.events,
            final_velocities,
            peak_true_acceleration: None,
            wall_time_s: 0.0,
        }
    }
}
