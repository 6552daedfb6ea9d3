//! The reference model: an exact event-driven impulse-momentum solver (docs/MODEL.md §1-4), f64,
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
use crate::oscillator::{gauss_legendre, Harmonic, ROUNDOFF_ULPS};

/// Why the reference could not finish a scene.
#[derive(Debug, thiserror::Error)]
pub enum ReferenceError {
    /// The solver gives up rather than run forever: more events than [`MAX_EVENTS`], more
    /// than a thousand at one instant, or an instant whose impacts, merges
    /// and releases do not settle.
    #[error("scene `{scene}`: stalled after {events} events at t = {t} s: {why}")]
    Stalled {
        /// Scene name.
        scene: String,
        /// Events processed.
        events: u64,
        /// Simulated time reached.
        t: f64,
        /// Which limit was reached.
        why: String,
    },
    /// The postcondition of an event failed: a pair overlaps, or the pair whose contact was
    /// taken does not touch, beyond the contact tolerance. The reference then missed or
    /// mistimed a contact; it stops rather than go on with a wrong run.
    #[error("scene `{scene}`: the reference broke its contact invariant at t = {t} s: {pair} {broken} by {by:.3e} m (tolerance {tolerance:.3e} m); this is a bug of the reference, please report it with the scene file")]
    ContactInvariant {
        /// Scene name.
        scene: String,
        /// Simulated time of the event.
        t: f64,
        /// The two bodies, `left / right`.
        pair: String,
        /// What broke: `overlap` or `are apart at their contact`.
        broken: &'static str,
        /// By how much, m.
        by: f64,
        /// The contact tolerance there, m.
        tolerance: f64,
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
/// Contact tolerance relative to the scene's length scale (to which the round-off of
/// evaluating a gap is added, see [`Solver::frame_gap_tolerance`]).
const LENGTH_TOLERANCE: f64 = 1e-12;
/// Most iterations of one root search (Newton, bisection): bisection halves a bracket to an
/// ulp in at most about 1100 halvings of the whole f64 range, Newton on these smooth gaps in a
/// few dozen; this cap is never reached by a search that converges.
const MAX_ROOT_ITERATIONS: usize = 200;
/// Sign changes of a forced segment kept before those already past are dropped.
const SIGN_CHANGES_KEPT: usize = 1024;
/// A value is round-off (its sign carries no information) when it is below this fraction of
/// the size of the terms it was computed from.
const ROUNDOFF_RELATIVE: f64 = 1e-9;
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
    /// `|xp| w^n`, `n = 0..=5`: bounds on the steady response's derivatives.
    particular: [f64; 6],
}

/// The forced acceleration at `s`, with its jerk and the free part's values that its bounds
/// are built from.
#[derive(Debug, Clone, Copy)]
struct Probe {
    s: f64,
    a: f64,
    jerk: f64,
    ah: f64,
    jh: f64,
}

/// A pair's gap now (see [`Solver::pair_now`]).
#[derive(Debug, Clone, Copy)]
struct PairNow {
    g: f64,
    rate: f64,
    tol: f64,
    curvature: Option<f64>,
}

/// A pair at the current instant, as `resolve` judges it (see [`Solver::contact_now`]).
#[derive(Debug, Clone, Copy)]
struct Contact {
    approach: Option<f64>,
    pressed: bool,
    frame: bool,
}

/// The frame at the current instant (see [`Solver::frame_now`]).
#[derive(Debug, Clone, Copy)]
struct FrameNow {
    segment: u64,
    t: f64,
    xs: f64,
    vs: f64,
    accel_ahead: f64,
}

/// The sign changes of the current forced segment's acceleration, found once and shared by
/// every search over the segment (both walls' contact searches and the release of held
/// balls): `roots` in time order, the scan done up to piece `pieces`.
#[derive(Debug, Default)]
struct SignChanges {
    segment: u64,
    pieces: u64,
    roots: Vec<f64>,
}

impl Segment {
    fn new(t0: f64, x0: f64, v0: f64, osc: Oscillator, load: Option<(f64, f64, f64)>) -> Self {
        let forced = load.map(|(p, q, omega)| {
            let xp = osc.harmonic_response(p, q, omega);
            let (xp0, vp0) = xp.state(t0);
            let forcing_period = 2.0 * std::f64::consts::PI / omega;
            let frame_period = if osc.w0sq > 0.0 { 2.0 * std::f64::consts::PI / osc.w0sq.sqrt() } else { f64::INFINITY };
            let amp = xp.amplitude();
            Forced {
                xp,
                h0: (x0 - xp0, v0 - vp0),
                scan: forcing_period.min(frame_period) / 16.0,
                particular: std::array::from_fn(|n| amp * omega.powi(n as i32)),
            }
        });
        let (hx, hv) = forced.map_or((x0, v0), |f| f.h0);
        let a0 = osc.accel(hx, hv);
        Segment { t0, x0, v0, a0, j0: -2.0 * osc.sigma * a0 - osc.w0sq * hv, osc, forced }
    }
    #[inline]
    fn state(&self, t: f64) -> (f64, f64) {
        match &self.forced {
            None => self.osc.state(self.x0, self.v0, t - self.t0),
            // At its start the segment is exactly the state it was made from (the forced sum
            // below would round it, and a released ball would then drift off its wall).
            Some(_) if t == self.t0 => (self.x0, self.v0),
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
        std::array::from_fn(|n| (parts[n].0 + parts[n].1, parts[n].0.abs() + f.particular[n + 2]))
    }
    /// Next time after `t` at which an unforced frame's acceleration changes sign (closed
    /// form), or infinity.
    fn free_sign_change(&self, t: f64) -> f64 {
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

    /// The forced acceleration `a = a_h + a_p` has no closed-form roots; it is scanned with
    /// bounds on its slope and curvature, so that no sign change is stepped over, in floating
    /// point as in exact arithmetic (docs/MODEL.md, "Finding contacts in floating point").
    ///
    /// For `s' >= s` a free solution `y` (here the free part's jerk `j_h`, or its snap) keeps
    /// `y'^2 + w0^2 y^2` from growing, so `|a'| <= B = |j_h(s)| + h sqrt(j_h'(s)^2 + w0^2
    /// j_h(s)^2) + w^3 |xp|` over `[s, s + h]`, and likewise `|a''|` with one more derivative.
    /// The scan walks pieces of [`Forced::scan`] anchored at the segment's start (so every
    /// search over a segment finds the same roots), and judges each piece `[s, s + h]`:
    /// - end values of one sign, and `|a(s)|` above `B h` by the round-off bound of `a(s)`
    ///   (with `B` enlarged by the round-off of its own terms): no sign change, cleared;
    /// - end values of opposite signs, and `|a'(s)|` above the curvature bound times `h` with
    ///   the same margins: `a` is monotone there, the sign change is its only root, refined by
    ///   the Illinois method;
    /// - otherwise halved, left first, down to a few ulps of time, where the first end value of
    ///   the other sign is the root.
    ///
    /// Every root of the piece `[a, b]` after `from`, in time order, appended to `roots`.
    fn forced_sign_changes(&self, f: &Forced, a: f64, b: f64, roots: &mut Vec<f64>) {
        let mut left = self.probe(f, a);
        let right = self.probe(f, b);
        while let Some(root) = self.first_sign_change(f, &left, &right) {
            roots.push(root);
            if root >= b {
                return;
            }
            left = self.probe(f, root);
        }
    }

    /// The forced frame's acceleration at `s` with what the bounds need.
    #[inline]
    fn probe(&self, f: &Forced, s: f64) -> Probe {
        let o = &self.osc;
        let (ah, jh) = o.state(self.a0, self.j0, s - self.t0);
        let d = f.xp.derivatives(s);
        Probe { s, a: ah + d[2], jerk: jh + d[3], ah, jh }
    }

    /// Whether `a` keeps its sign (`order` 0), or its jerk keeps its sign so that `a` is
    /// monotone (`order` 1), over `[l.s, r.s]`, with every round-off margin (see
    /// [`Segment::forced_sign_changes`]): a function `y` with `|y''| <= M` there is at least
    /// `min(|y(l)|, |y(r)|) - M h^2 / 8` in magnitude when its ends have one sign.
    fn holds(&self, f: &Forced, l: &Probe, r: &Probe, order: usize) -> bool {
        let (yl, yr) = if order == 0 { (l.a, r.a) } else { (l.jerk, r.jerk) };
        if !((yl > 0.0 && yr > 0.0) || (yl < 0.0 && yr < 0.0)) {
            return false;
        }
        let o = &self.osc;
        let eps = f64::EPSILON;
        let h = r.s - l.s;
        // The free part's derivatives 2..=5 of x at `l`: the first two in closed form, the
        // rest from the equation of motion.
        let next = |y: f64, y1: f64| -2.0 * o.sigma * y1 - o.w0sq * y;
        let mut free = [l.ah, l.jh, 0.0, 0.0, 0.0];
        for k in 2..5 {
            free[k] = next(free[k - 2], free[k - 1]);
        }
        // `|y''|` over the piece: the free part's (a free solution, whose `y'^2 + w0^2 y^2`
        // never grows) plus the steady response's amplitude.
        let (d2, d3) = (free[order + 2], free[order + 3]);
        let curvature = d2.abs() + h * (d3 * d3 + o.w0sq * d2 * d2).sqrt() + f.particular[order + 4];
        let least = yl.abs().min(yr.abs());
        // Cheap test first: most pieces pass or fail by a wide margin.
        if least <= curvature * h * h / 8.0 {
            return false;
        }
        // Round-off of each term: closed forms by their bounds, the rest by propagation.
        let tau = l.s - self.t0;
        let snap0 = next(self.a0, self.j0);
        let mut err = [o.roundoff(self.a0, self.j0, tau), o.roundoff(self.j0, snap0, tau), 0.0, 0.0, 0.0];
        for k in 2..5 {
            err[k] = 2.0 * o.sigma * err[k - 1] + o.w0sq * err[k - 2] + 4.0 * eps * (2.0 * o.sigma * free[k - 1].abs() + o.w0sq * free[k - 2].abs());
        }
        // The values' own round-off at each end.
        let (y0, y1) = if order == 0 { (self.a0, self.j0) } else { (self.j0, snap0) };
        let value_err = |s: f64, y: f64| o.roundoff(y0, y1, s - self.t0) + f.xp.roundoff(s, order as u32 + 2) + eps * y.abs();
        let least = (yl.abs() - value_err(l.s, yl)).min(yr.abs() - value_err(r.s, yr));
        let (e2, e3) = (err[order + 2], err[order + 3]);
        let safe = (curvature + e2 + h * (e3 + o.w0sq.sqrt() * e2)) * (1.0 + ROUNDOFF_ULPS * eps);
        least > safe * h * h / 8.0
    }

    /// The first sign change of the forced acceleration in `(l.s, r.s]`: depth-first over
    /// halves, left first.
    fn first_sign_change(&self, f: &Forced, l: &Probe, r: &Probe) -> Option<f64> {
        let same_sign = (l.a > 0.0 && r.a > 0.0) || (l.a < 0.0 && r.a < 0.0);
        if same_sign && self.holds(f, l, r, 0) {
            return None;
        }
        if !same_sign && l.a != 0.0 && r.a != 0.0 && self.holds(f, l, r, 1) {
            return Some(self.illinois(f, l, r));
        }
        if r.s - l.s <= self.time_resolution(r.s, f) {
            return (!same_sign).then_some(r.s);
        }
        let m = self.probe(f, 0.5 * (l.s + r.s));
        self.first_sign_change(f, l, &m).or_else(|| self.first_sign_change(f, &m, r))
    }

    /// The one root of a monotone acceleration between `l` and `r` (of opposite signs), by
    /// the Illinois variant of regula falsi: the bracket shrinks from both sides, to a few
    /// ulps; the root is its right end, where the sign has changed.
    fn illinois(&self, f: &Forced, l: &Probe, r: &Probe) -> f64 {
        let (mut a, mut fa, mut b, mut fb) = (l.s, l.a, r.s, r.a);
        let mut side = 0;
        for _ in 0..MAX_ROOT_ITERATIONS {
            if b - a <= self.time_resolution(b, f) {
                break;
            }
            let mut m = (a * fb - b * fa) / (fb - fa);
            if !(m > a && m < b) {
                m = 0.5 * (a + b);
            }
            let fm = self.probe(f, m).a;
            if fm == 0.0 {
                return m;
            }
            if (fm > 0.0) == (fa > 0.0) {
                (a, fa) = (m, fm);
                if side == -1 {
                    fb *= 0.5;
                }
                side = -1;
            } else {
                (b, fb) = (m, fm);
                if side == 1 {
                    fa *= 0.5;
                }
                side = 1;
            }
        }
        b
    }

    /// Width below which a bracket of a sign change is not split further: a few ulps of time.
    fn time_resolution(&self, s: f64, f: &Forced) -> f64 {
        8.0 * f64::EPSILON * s.abs().max(f.scan)
    }

    /// A bound on the round-off of the frame's position [`Segment::state`] at `t`.
    fn position_roundoff(&self, t: f64) -> f64 {
        let tau = t - self.t0;
        match &self.forced {
            None => self.osc.roundoff(self.x0, self.v0, tau),
            Some(f) => self.osc.roundoff(f.h0.0, f.h0.1, tau) + f.xp.roundoff(t, 0),
        }
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
    /// Serial number of `seg` (segments can start at the same instant).
    segment: u64,
    sign_changes: std::cell::RefCell<SignChanges>,
    /// The frame's state and acceleration ahead at `t` under segment `segment`, kept while
    /// neither changes (a cascade of impulses at one instant asks for them every pass).
    now: std::cell::Cell<Option<FrameNow>>,
    /// Scratch of `resolve`: each pair's contact now.
    contacts: Vec<Contact>,
    t: f64,
    x: Vec<f64>,
    v: Vec<f64>,
    /// A bound on the rounding that advancing has added to each ball's position `x` so far.
    drift: Vec<f64>,
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
    /// The scene's speed scale (the frame's initial or forced speed, or a length per
    /// horizon), raised to the fastest approach of any impact so far: the speed at which
    /// contacts can be placed no closer than two ulps of time (see
    /// [`Solver::frame_gap_tolerance`]). It never falls, so bodies that met fast and move on
    /// together keep a tolerance their meeting needed.
    fastest: f64,
    /// The largest contact tolerance a touching pair has had so far (see
    /// [`Solver::check_contacts`]).
    accepted_overlap: f64,
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
        let samples = scene.sample_count();
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
            segment: 1,
            sign_changes: Default::default(),
            now: Default::default(),
            contacts: Vec::new(),
            t: 0.0,
            x: scene.initial_positions.clone(),
            v: scene.initial_velocities.clone(),
            drift: vec![0.0; n],
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
            fastest: speed_scale,
            accepted_overlap: 0.0,
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

    /// Next time after `t` at which the frame's acceleration changes sign, or `limit` if none
    /// comes first (unforced segments ignore `limit`: their sign changes are closed form).
    /// A forced segment's sign changes are scanned once and kept ([`SignChanges`]).
    fn next_sign_change(&self, t: f64, limit: f64) -> f64 {
        let Some(f) = &self.seg.forced else {
            return self.seg.free_sign_change(t);
        };
        if !(limit > t) {
            return limit;
        }
        let mut c = self.sign_changes.borrow_mut();
        if c.segment != self.segment {
            *c = SignChanges { segment: self.segment, pieces: 0, roots: Vec::new() };
        }
        // Searches start at the current time or later: older roots are never asked for again.
        if c.roots.len() > SIGN_CHANGES_KEPT {
            let now = self.t;
            c.roots.retain(|&r| r >= now);
        }
        loop {
            let k = c.roots.partition_point(|&r| r <= t);
            if let Some(&root) = c.roots.get(k) {
                return root.min(limit);
            }
            let scanned = self.seg.t0 + c.pieces as f64 * f.scan;
            if scanned >= limit {
                return limit;
            }
            let end = self.seg.t0 + (c.pieces + 1) as f64 * f.scan;
            self.seg.forced_sign_changes(f, scanned, end, &mut c.roots);
            c.pieces += 1;
        }
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

    /// A ball-frame pair's gap, its rate and its contact tolerance at `t`: the length
    /// tolerance plus what the gap's value can err by (the rounding accumulated in the ball's
    /// position, the round-off of the frame's closed form and of the gap's sum, and two ulps
    /// of time at the gap's rate or the fastest speed of the run so far, whichever is faster: a
    /// contact taken at that speed is placed no closer, and bodies that then move together
    /// keep that overlap). The reference
    /// takes no contact below minus this, and its postcondition checks it (docs/MODEL.md).
    fn frame_gap_tolerance(&self, ball: usize, s: f64, k: f64, t: f64) -> (f64, f64, f64) {
        let (xs, vs) = self.seg.state(t);
        let xb = self.x[ball] + self.v[ball] * (t - self.t);
        let rate = s * (self.v[ball] - vs);
        (s * (xb - xs) + k, rate, self.frame_tolerance(ball, t, xb, xs, k, rate))
    }

    /// The contact tolerance of a ball-frame gap `s (xb - xs) + k` of rate `rate` at `t` (see
    /// [`Solver::frame_gap_tolerance`]).
    fn frame_tolerance(&self, ball: usize, t: f64, xb: f64, xs: f64, k: f64, rate: f64) -> f64 {
        let eps = f64::EPSILON;
        self.tol
            + self.drift[ball]
            + self.seg.position_roundoff(t)
            + 4.0 * eps * (xb.abs() + xs.abs() + k.abs())
            + 2.0 * eps * t.abs() * rate.abs().max(self.fastest)
    }

    /// The contact tolerance of ball-ball pair `p` of rate `rate` now (see
    /// [`Solver::frame_gap_tolerance`]).
    fn ball_gap_tolerance(&self, p: usize, rate: f64) -> f64 {
        let (i, j) = (p - 1, p);
        let eps = f64::EPSILON;
        self.tol
            + self.drift[i]
            + self.drift[j]
            + 4.0 * eps * (self.x[i].abs() + self.x[j].abs() + self.radius[i] + self.radius[j])
            + 2.0 * eps * self.t.abs() * rate.abs().max(self.fastest)
    }

    /// Pair `p` now: its gap, the gap's rate, its contact tolerance and, for a ball-frame
    /// pair, the gap's curvature (positive when the wall accelerates away from the ball);
    /// `None` for a pair that moves as one body.
    fn pair_now(&self, p: usize) -> Option<PairNow> {
        match self.gap(p) {
            Gap::Fixed => None,
            Gap::Linear { g, rate } => Some(PairNow { g, rate, tol: self.ball_gap_tolerance(p, rate), curvature: None }),
            Gap::Frame { ball, s, k } => {
                let (xs, vs, a) = self.frame_now();
                let xb = self.x[ball];
                let rate = s * (self.v[ball] - vs);
                let tol = self.frame_tolerance(ball, self.t, xb, xs, k, rate);
                Some(PairNow { g: s * (xb - xs) + k, rate, tol, curvature: Some(-s * a) })
            }
        }
    }

    /// The postcondition of every event (docs/MODEL.md §10): the pair whose contact triggered
    /// it touches, and no pair overlaps, within the contact tolerance. An overlap accepted at a
    /// contact moves on with bodies that move together (held, merged, released), under a
    /// tolerance that may then be smaller (a held ball's gap carries the frame's round-off, a
    /// free pair's does not), so no pair may overlap by more than the largest tolerance a
    /// touching pair has had so far. A violation means a contact was missed or mistimed: an
    /// error naming the scene, the time and the pair, never a silent wrong run.
    fn check_contacts(&mut self, trigger: Option<usize>) -> Result<(), ReferenceError> {
        for p in self.pair_range() {
            let Some(PairNow { g, tol, .. }) = self.pair_now(p) else { continue };
            if g.abs() <= tol {
                self.accepted_overlap = self.accepted_overlap.max(tol);
            }
            let apart = trigger == Some(p) && g > tol;
            let allowed = tol.max(self.accepted_overlap);
            if g < -allowed || apart {
                let (a, b) = self.pair_bodies(p);
                return Err(ReferenceError::ContactInvariant {
                    scene: self.scene.name.clone(),
                    t: self.t,
                    pair: format!("{} / {}", Scene::body_name(a), Scene::body_name(b)),
                    broken: if apart { "are apart at their contact" } else { "overlap" },
                    by: g.abs(),
                    tolerance: if apart { tol } else { allowed },
                });
            }
        }
        Ok(())
    }

    /// The bodies either side of pair `p`.
    fn pair_bodies(&self, p: usize) -> (Body, Body) {
        (if p == 0 { Body::LeftWall } else { Body::Ball(p - 1) }, if p == self.n { Body::RightWall } else { Body::Ball(p) })
    }

    /// The frame's position, velocity and acceleration ahead ([`Solver::accel_ahead`]) now.
    fn frame_now(&self) -> (f64, f64, f64) {
        if let Some(n) = self.now.get() {
            if n.segment == self.segment && n.t == self.t {
                return (n.xs, n.vs, n.accel_ahead);
            }
        }
        let (xs, vs) = self.seg.state(self.t);
        let accel_ahead = self.accel_ahead(self.t);
        self.now.set(Some(FrameNow { segment: self.segment, t: self.t, xs, vs, accel_ahead }));
        (xs, vs, accel_ahead)
    }

    /// The frame's acceleration just after `t`: its value, with the sign of the first
    /// derivative that is not round-off when the acceleration itself is (at a sign change).
    /// Every sign involved is that of `-(c v + k x)` and its derivatives, whatever the mass
    /// the frame carries, so holding and releasing a ball always agree.
    fn accel_ahead(&self, t: f64) -> f64 {
        if let Some(f) = &self.seg.forced {
            let [(a, sa), (jerk, sj), (snap, _)] = self.seg.forced_derivatives(f, t);
            if a.abs() > ROUNDOFF_RELATIVE * sa {
                return a;
            }
            let sign = if jerk.abs() > ROUNDOFF_RELATIVE * sj {
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
        if a.abs() > ROUNDOFF_RELATIVE * (o.w0sq * x.abs() + rate * v.abs()) {
            return a;
        }
        let jerk = -2.0 * o.sigma * a - o.w0sq * v;
        let sign = if jerk.abs() > ROUNDOFF_RELATIVE * (rate * a.abs() + o.w0sq * v.abs()) {
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

    /// Pair `p`'s next contact after `from`, searched no further than `bound` (a later contact
    /// is reported as "none before `bound`").
    fn candidate(&self, p: usize, from: f64, bound: f64) -> Candidate {
        match self.gap(p) {
            Gap::Fixed => NO_EVENT,
            Gap::Linear { g, rate } => {
                if rate < 0.0 {
                    Candidate { t: self.t + g.max(0.0) / -rate, exact: true }
                } else {
                    NO_EVENT
                }
            }
            Gap::Frame { ball, s, k } => self.search_frame_pair(ball, s, k, from, bound),
        }
    }

    /// First contact of a ball with the frame after `from`, searched over one damped period
    /// at a time. The frame's acceleration keeps its sign between consecutive sign changes, so
    /// there the gap `g` has `g'' = -s a` of one sign: on a convex piece Newton's method from
    /// the left never passes the first root; on a concave piece a root exists only if `g` at
    /// the piece's end is not positive, and Newton from the right converges to it from above.
    fn search_frame_pair(&self, ball: usize, s: f64, k: f64, from: f64, bound: f64) -> Candidate {
        // Only a forced segment's search is cut at `bound`: its sign changes are scanned, so
        // looking further costs, where an unforced segment's come in closed form (and cutting
        // its pieces would change the roots' last bits, which chaotic runs amplify).
        let bound = if self.seg.forced.is_some() { bound } else { self.horizon };
        let limit = (from + self.span).min(self.horizon).min(bound);
        let mut a = from;
        loop {
            let b = self.next_sign_change(a, limit).min(limit);
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

    /// The first root of a gap that is convex on `[a, b]`: Newton from the left, whose
    /// iterates never pass the root in exact arithmetic. Should one land deeper than the
    /// contact tolerance all the same (round-off where the piece is barely convex), the
    /// crossing is bisected back between it and the previous iterate.
    fn convex_root(&self, ball: usize, s: f64, k: f64, a: f64, b: f64) -> Option<f64> {
        let mut t = a;
        let mut before = None;
        for _ in 0..MAX_ROOT_ITERATIONS {
            let (g, gp) = self.frame_gap_at(ball, s, k, t);
            if let Some(l) = before {
                if g < -self.frame_gap_tolerance(ball, s, k, t).2 {
                    return Some(self.bisect_crossing(ball, s, k, l, t));
                }
            }
            if gp >= 0.0 || (t == a && g <= self.tol && self.reopens(gp, -s * self.accel_ahead(a))) {
                return None; // convex and not decreasing (or about to): it only rises from here on
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
            before = Some(t);
            t = next;
        }
        Some(t)
    }

    /// Whether a touching pair whose gap changes at `rate` with curvature `curvature` (the
    /// wall accelerating away from the ball when positive) separates by itself: it approaches
    /// slower than `v_stick` (round-off: a forced frame's velocity re-evaluated after a
    /// release can differ from the ball's by an ulp) and turns within `t_stick`, sinking less
    /// than `v_stick t_stick / 2`, far below the contact tolerance. `resolve` and the contact
    /// search judge it alike, so they never disagree about a contact now.
    fn reopens(&self, rate: f64, curvature: f64) -> bool {
        rate < 0.0 && -rate < self.v_stick && curvature > 0.0 && -rate < curvature * self.t_stick
    }

    /// A crossing of the gap between `l` (gap above the tolerance) and `h` (below it): a time
    /// at which the gap is within the tolerance, or `h` once the bracket is an ulp wide.
    fn bisect_crossing(&self, ball: usize, s: f64, k: f64, mut l: f64, mut h: f64) -> f64 {
        for _ in 0..MAX_ROOT_ITERATIONS {
            let m = 0.5 * (l + h);
            if m <= l || m >= h {
                break;
            }
            let (g, _) = self.frame_gap_at(ball, s, k, m);
            if g.abs() <= self.tol {
                return m;
            }
            if g > 0.0 {
                l = m;
            } else {
                h = m;
            }
        }
        h
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
            for _ in 0..MAX_ROOT_ITERATIONS {
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
        for _ in 0..MAX_ROOT_ITERATIONS {
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
                self.next_sign_change(self.t, (self.t + self.span).min(self.horizon))
            } else {
                f64::INFINITY
            };
        }
        self.frame_dirty = false;
        // A pair's search need not look past the earliest exact event already known (the
        // frame pairs' searches are the costly ones): exact ball-ball times first, then the
        // frame pairs, each bounded by everything found so far.
        let mut bound = self.exact_event_bound(None);
        let mut frame = [usize::MAX; 2];
        let mut frames = 0;
        for p in self.pair_range() {
            if !self.dirty[p] {
                continue;
            }
            if matches!(self.gap(p), Gap::Frame { .. }) {
                // At most two: the free balls next to the walls (or to balls the frame holds).
                frame[frames.min(1)] = p;
                frames += 1;
            } else {
                self.cand[p] = self.candidate(p, self.t, bound);
                self.dirty[p] = false;
                if self.cand[p].exact {
                    bound = bound.min(self.cand[p].t);
                }
            }
        }
        debug_assert!(frames <= 2, "more than two ball-frame pairs");
        let frame = &frame[..frames.min(2)];
        match self.seg.forced {
            // Both frame pairs searched side by side over windows that double from a scan
            // step: the far wall's search then stops where the near wall's contact is. As
            // unforced, no search looks more than a span ahead; one that finds nothing by then
            // goes on when its time comes.
            Some(f) => {
                let (mut reached, mut window) = (self.t, f.scan);
                let mut bound = bound.min(self.t + self.span);
                loop {
                    let until = (reached + window).min(bound);
                    for &p in frame {
                        if let Gap::Frame { ball, s, k } = self.gap(p) {
                            self.cand[p] = self.search_frame_pair(ball, s, k, reached, until);
                            if self.cand[p].exact {
                                bound = bound.min(self.cand[p].t);
                            }
                        }
                    }
                    if until >= bound || frame.is_empty() {
                        break;
                    }
                    reached = until;
                    window = (2.0 * window).min(self.span);
                }
            }
            None => {
                for &p in frame {
                    self.cand[p] = self.candidate(p, self.t, bound);
                }
            }
        }
        for &p in frame {
            self.dirty[p] = false;
        }
    }

    /// The earliest exact event among the clean pairs but `except`, the release and the horizon.
    fn exact_event_bound(&self, except: Option<usize>) -> f64 {
        let mut bound = self.release_at.min(self.horizon);
        for p in self.pair_range() {
            if Some(p) != except && !self.dirty[p] && self.cand[p].exact {
                bound = bound.min(self.cand[p].t);
            }
        }
        bound
    }

    // ---- state changes --------------------------------------------------------------------

    fn advance(&mut self, t: f64) {
        let dt = t - self.t;
        for i in 0..self.n {
            if self.hold[i] == Hold::Free {
                let step = self.v[i] * dt;
                self.x[i] += step;
                // Every ball moves at every event, so a pair that moves as one (equal
                // velocities, no event of its own) sees its gap wander by this rounding.
                self.drift[i] += f64::EPSILON * (self.x[i].abs() + step.abs());
            }
        }
        self.t = t;
    }

    /// Starts a new frame segment at the current time with velocity `v` and the current load.
    fn set_frame(&mut self, v: f64) {
        self.book_segment_energy();
        let (xs, _, _) = self.frame_now();
        let osc = if self.seg.osc.mass == self.frame_mass + self.held_mass {
            self.seg.osc
        } else {
            Oscillator::new(self.frame_mass + self.held_mass, self.damping, self.stiffness)
        };
        self.seg = Segment::new(self.t, xs, v, osc, self.load);
        self.segment += 1;
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
        let (a, b) = self.pair_bodies(p);
        self.fastest = self.fastest.max(approach_speed);
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
                let (_, vs, _) = self.frame_now();
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
        self.pair_now(p).is_some_and(|q| q.g <= q.tol && q.rate.abs() < self.v_stick)
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
        let (_, vs, _) = self.frame_now();
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
            let (xs, _, _) = self.frame_now();
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
        let (xs, vs, a) = self.frame_now();
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
                self.drift[i] += f64::EPSILON * self.x[i].abs();
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

    /// What `resolve` needs of pair `p` now: the speed at which it approaches when it touches
    /// (`None` when it does not touch, does not approach, or drifts off a wall that
    /// accelerates away, see [`Solver::reopens`]), and whether the frame presses it together.
    fn contact_now(&self, p: usize) -> Contact {
        let Some(PairNow { g, rate, tol, curvature }) = self.pair_now(p) else {
            return Contact { approach: None, pressed: false, frame: false };
        };
        let frame = curvature.is_some();
        if g > tol {
            return Contact { approach: None, pressed: false, frame };
        }
        let drifting_off = curvature.is_some_and(|c| self.reopens(rate, c));
        Contact {
            approach: (rate < 0.0 && !drifting_off).then_some(-rate),
            pressed: curvature.is_some_and(|c| c < 0.0) && rate < self.v_stick,
            frame,
        }
    }

    /// Resolves everything that happens at the current instant: impacts of touching
    /// approaching pairs (fastest first), merges of slow ones, holds and releases.
    ///
    /// A cascade at one instant can take thousands of impulses (a light ball between heavy
    /// ones), so each pass re-reads only the pairs its last impulse changed: the pair's
    /// neighbours, and every ball-frame pair when the frame's velocity changed.
    fn resolve(&mut self) -> Result<(), ReferenceError> {
        let range = self.pair_range();
        let mut contacts = std::mem::take(&mut self.contacts);
        contacts.clear();
        contacts.resize(self.n + 1, Contact { approach: None, pressed: false, frame: false });
        let mut impulses = 0usize;
        // Pairs to re-read: all, or the neighbours of `changed` (and the frame's pairs).
        let mut all = true;
        let mut changed = (0usize, false);
        // Each pass changes the state (an impulse, a merge or a release); more passes than the
        // impulse cap allows plus a few per body means two judgements disagree and would
        // cycle: a stall to report, not a hang.
        let most_passes = MAX_IMPULSES_PER_INSTANT + 8 * (self.n + 1);
        for _ in 0..most_passes {
            if all {
                for p in range.clone() {
                    contacts[p] = self.contact_now(p);
                }
            } else {
                let (p, frame) = changed;
                for q in p.saturating_sub(1)..=p + 1 {
                    if range.contains(&q) {
                        contacts[q] = self.contact_now(q);
                    }
                }
                if frame {
                    for q in range.clone() {
                        if contacts[q].frame {
                            contacts[q] = self.contact_now(q);
                        }
                    }
                }
            }
            let mut fastest: Option<(usize, f64)> = None;
            let mut pressed: Option<usize> = None;
            for p in range.clone() {
                let c = contacts[p];
                if let Some(u) = c.approach {
                    if fastest.is_none_or(|(_, v)| u > v) {
                        fastest = Some((p, u));
                    }
                }
                if c.pressed && pressed.is_none() {
                    pressed = Some(p);
                }
            }
            all = true;
            if let Some((p, u)) = fastest {
                let bounce_returns_fast = match self.gap(p) {
                    Gap::Frame { s, .. } => {
                        let a = -s * self.frame_now().2;
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
                    (all, changed) = (false, (p, contacts[p].frame));
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
                self.contacts = contacts;
                return Ok(());
            }
        }
        Err(ReferenceError::Stalled {
            scene: self.scene.name.clone(),
            events: self.events,
            t: self.t,
            why: format!("{most_passes} impacts, merges and releases at one instant did not settle"),
        })
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
        self.resolve()?;
        loop {
            self.refresh_candidates();
            // The earliest candidate; at a tie an exact one, so that a search stopped at that
            // time is resumed only after it.
            let mut next = (self.horizon, None);
            let mut next_exact = true;
            for p in self.pair_range() {
                let c = self.cand[p];
                if c.t < next.0 || (c.t == next.0 && c.exact && !next_exact && next.1.is_some()) {
                    next = (c.t, Some(p));
                    next_exact = c.exact;
                }
            }
            // The release is an exact event too: it goes before a search stopped at its time.
            let release = self.release_at < next.0 || (self.release_at == next.0 && !next_exact);
            if release {
                next = (self.release_at, None);
            }
            let (t, pair) = next;
            if !release && pair.is_none() {
                break;
            }
            if let Some(p) = pair {
                if !self.cand[p].exact {
                    self.cand[p] = self.candidate(p, t, self.exact_event_bound(Some(p)));
                    continue;
                }
            }
            self.sample_until(t, false);
            same_instant = if t == self.t { same_instant + 1 } else { 0 };
            self.advance(t);
            self.check_contacts(pair)?;
            self.events += 1;
            if self.events > MAX_EVENTS || same_instant > MAX_EVENTS_PER_INSTANT {
                let why = if same_instant > MAX_EVENTS_PER_INSTANT {
                    format!("more than {MAX_EVENTS_PER_INSTANT} events at one instant")
                } else {
                    format!("more than {MAX_EVENTS} events")
                };
                return Err(ReferenceError::Stalled { scene: self.scene.name.clone(), events: self.events, t, why });
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
            self.resolve()?;
        }
        self.sample_until(self.horizon, true);
        self.advance(self.horizon);
        self.check_contacts(None)
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
            model: crate::run::Model::Reference,
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
