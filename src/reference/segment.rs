//! The frame's motion between two changes of its velocity or mass (a segment): its state in
//! closed form, and where its acceleration changes sign, found in floating point (docs/MODEL.md
//! §10): every interval cleared is cleared with the round-off of evaluating it counted in.

use super::*;

/// The frame's motion since its last change of velocity or mass.
#[derive(Debug, Clone, Copy)]
pub(super) struct Segment {
    pub(super) t0: f64,
    pub(super) x0: f64,
    pub(super) v0: f64,
    /// Acceleration and jerk at `t0`, for the sign-change search (of the departure from the
    /// steady response, when forced).
    pub(super) a0: f64,
    pub(super) j0: f64,
    pub(super) osc: Oscillator,
    pub(super) forced: Option<Forced>,
    /// When the segment oscillates, the phase of each [`Zeros`]' zeros
    /// ([`Oscillator::zero_phase`], an `atan2` each), computed once; `None` for a solution
    /// that is identically zero. The velocity's and the jerk's only in free vibration.
    phases: [Option<f64>; 3],
    /// Unforced, the farthest the frame goes from 0 in this segment
    /// ([`Oscillator::envelope`] of its start); `None` when forced or unbounded.
    pub(super) reach: Option<f64>,
}

/// Zeros of a segment's motion that the reference looks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Zeros {
    /// Of the acceleration (of the departure from the steady response, when forced): where the
    /// force on the frame reverses.
    Acceleration = 0,
    /// Of the velocity: the extrema of `x` (free vibration).
    Velocity = 1,
    /// Of the jerk: the extrema of the acceleration (free vibration).
    Jerk = 2,
}

/// A forced segment: the motion is `xp(t)` plus the free motion of the departure from it.
#[derive(Debug, Clone, Copy)]
pub(super) struct Forced {
    pub(super) xp: Harmonic,
    /// Departure `(x - xp, v - xp')` at `t0`.
    pub(super) h0: (f64, f64),
    /// Longest scan step of the sign-change search: a sixteenth of the shorter period.
    pub(super) scan: f64,
    /// `|xp| w^n`, `n = 0..=5`: bounds on the steady response's derivatives.
    pub(super) particular: [f64; 6],
}

/// The forced acceleration at `s`, with its jerk and the free part's values that its bounds
/// are built from.
#[derive(Debug, Clone, Copy)]
pub(super) struct Probe {
    pub(super) s: f64,
    pub(super) a: f64,
    pub(super) jerk: f64,
    pub(super) ah: f64,
    pub(super) jh: f64,
}

/// The sign changes of the current forced segment's acceleration, found once and shared by
/// every search over the segment (both walls' contact searches and the release of held
/// balls): `roots` in time order, the scan done up to piece `pieces`.
#[derive(Debug, Default)]
pub(super) struct SignChanges {
    pub(super) segment: u64,
    pub(super) pieces: u64,
    pub(super) roots: Vec<f64>,
}

impl Segment {
    pub(super) fn new(t0: f64, x0: f64, v0: f64, osc: Oscillator, load: Option<(f64, f64, f64)>) -> Self {
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
        let j0 = -2.0 * osc.sigma * a0 - osc.w0sq * hv;
        let reach = if forced.is_none() { osc.envelope(x0, v0) } else { None };
        let mut seg = Segment { t0, x0, v0, a0, j0, osc, forced, phases: [None; 3], reach };
        if osc.damped_omega().is_some() {
            let which: &[Zeros] =
                if forced.is_none() { &[Zeros::Acceleration, Zeros::Velocity, Zeros::Jerk] } else { &[Zeros::Acceleration] };
            for &z in which {
                let (y0, y1) = seg.initial(z);
                seg.phases[z as usize] = osc.zero_phase(y0, y1);
            }
        }
        seg
    }
    #[inline]
    pub(super) fn state(&self, t: f64) -> (f64, f64) {
        match &self.forced {
            // At its start the segment is exactly the state it was made from (the forced sum
            // below would round it, and a released ball would then drift off its wall; the
            // free closed form gives it too, at the cost of an `exp` and a `sin_cos`).
            _ if t == self.t0 => (self.x0, self.v0),
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
    pub(super) fn forced_derivatives(&self, f: &Forced, t: f64) -> [(f64, f64); 3] {
        let o = &self.osc;
        let (ah, jh) = o.state(self.a0, self.j0, t - self.t0);
        let sh = -2.0 * o.sigma * jh - o.w0sq * ah;
        let d = f.xp.derivatives(t);
        let parts = [(ah, d[2]), (jh, d[3]), (sh, d[4])];
        std::array::from_fn(|n| (parts[n].0 + parts[n].1, parts[n].0.abs() + f.particular[n + 2]))
    }
    /// The value and slope at `t0` of the solution whose zeros are `z`.
    fn initial(&self, z: Zeros) -> (f64, f64) {
        match z {
            Zeros::Acceleration => (self.a0, self.j0),
            Zeros::Velocity => (self.v0, self.a0),
            Zeros::Jerk => (self.j0, self.osc.accel(self.a0, self.j0)),
        }
    }
    /// The first zero of `z` strictly after `t` (closed form), or `None`. A zero just after
    /// `t` in segment time can round onto `t` in absolute time: the next one is taken then, so
    /// that time always moves on.
    pub(super) fn next_zero(&self, z: Zeros, t: f64) -> Option<f64> {
        debug_assert!(z == Zeros::Acceleration || self.forced.is_none(), "extrema of a forced segment");
        let zero = |after: f64| match self.osc.damped_omega() {
            Some(w) => self.phases[z as usize].map(|phase| Oscillator::next_zero(w, phase, after)),
            None => {
                let (y0, y1) = self.initial(z);
                self.osc.next_sign_change(y0, y1, after)
            }
        };
        let mut after = t - self.t0;
        while let Some(tau) = zero(after) {
            if self.t0 + tau > t {
                return Some(self.t0 + tau);
            }
            after = tau;
        }
        None
    }
    /// Next time after `t` at which an unforced frame's acceleration changes sign (closed
    /// form), or infinity.
    pub(super) fn free_sign_change(&self, t: f64) -> f64 {
        self.next_zero(Zeros::Acceleration, t).unwrap_or(f64::INFINITY)
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
    pub(super) fn forced_sign_changes(&self, f: &Forced, a: f64, b: f64, roots: &mut Vec<f64>) {
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
    pub(super) fn probe(&self, f: &Forced, s: f64) -> Probe {
        let o = &self.osc;
        let (ah, jh) = o.state(self.a0, self.j0, s - self.t0);
        let d = f.xp.derivatives(s);
        Probe { s, a: ah + d[2], jerk: jh + d[3], ah, jh }
    }

    /// Whether `a` keeps its sign (`order` 0), or its jerk keeps its sign so that `a` is
    /// monotone (`order` 1), over `[l.s, r.s]`, with every round-off margin (see
    /// [`Segment::forced_sign_changes`]): a function `y` with `|y''| <= M` there is at least
    /// `min(|y(l)|, |y(r)|) - M h^2 / 8` in magnitude when its ends have one sign.
    pub(super) fn holds(&self, f: &Forced, l: &Probe, r: &Probe, order: usize) -> bool {
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
            err[k] = 2.0 * o.sigma * err[k - 1]
                + o.w0sq * err[k - 2]
                + 4.0 * eps * (2.0 * o.sigma * free[k - 1].abs() + o.w0sq * free[k - 2].abs());
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
    pub(super) fn first_sign_change(&self, f: &Forced, l: &Probe, r: &Probe) -> Option<f64> {
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
    pub(super) fn illinois(&self, f: &Forced, l: &Probe, r: &Probe) -> f64 {
        illinois((l.s, l.a), (r.s, r.a), |b| self.time_resolution(b, f), |m| self.probe(f, m).a)
    }

    /// Width below which a bracket of a sign change is not split further: a few ulps of time.
    pub(super) fn time_resolution(&self, s: f64, f: &Forced) -> f64 {
        8.0 * f64::EPSILON * s.abs().max(f.scan)
    }

    /// A bound on the round-off of the frame's position [`Segment::state`] at `t`.
    pub(super) fn position_roundoff(&self, t: f64) -> f64 {
        let tau = t - self.t0;
        match &self.forced {
            None => self.osc.roundoff(self.x0, self.v0, tau),
            Some(f) => self.osc.roundoff(f.h0.0, f.h0.1, tau) + f.xp.roundoff(t, 0),
        }
    }
}

/// The one root of a monotone function `y` between `(a, y(a))` and `(b, y(b))` (of opposite
/// signs), by the Illinois variant of regula falsi: the bracket shrinks from both sides until
/// it is no wider than `resolution` at its right end; the root is that end, where the sign has
/// changed.
pub(super) fn illinois(
    (mut a, mut fa): (f64, f64),
    (mut b, mut fb): (f64, f64),
    resolution: impl Fn(f64) -> f64,
    y: impl Fn(f64) -> f64,
) -> f64 {
    let mut side = 0;
    for _ in 0..MAX_ROOT_ITERATIONS {
        if b - a <= resolution(b) {
            break;
        }
        let mut m = (a * fb - b * fa) / (fb - fa);
        if !(m > a && m < b) {
            m = 0.5 * (a + b);
        }
        let fm = y(m);
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
