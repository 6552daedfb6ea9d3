//! Exact metrics of free vibration (docs/MODEL.md §7): between events the frame's motion is
//! closed form, so its peaks, RMS, settling time and dissipation times come from that motion,
//! not from samples, and a run that keeps no series samples nothing. Forced runs are read at
//! the samples, as every model's are.
//!
//! Within one interval between events the frame is a free damped oscillator, whose extrema
//! (of `x`, and of the acceleration, itself a solution of the same equation) shrink
//! geometrically: the largest value on the interval is at an end or at the first extremum.
//! The integral of `x^2` follows from the values at the ends through the identities
//! `d(x^2/2) = x v`, `d(x v) = v^2 - 2 sigma x v - w0^2 x^2` and
//! `d(v^2/2) = -2 sigma v^2 - w0^2 x v`. The mechanical energy only falls inside an interval
//! (the damper) and at its events (impacts), so each level is crossed once and bisected.

use super::*;
use crate::run::{MotionMetrics, DISSIPATION_LEVELS, SETTLING_FRACTION};
use crate::scene::Frame;

/// Bisection steps that pin a crossing to an ulp of the time.
const BISECTIONS: u32 = 80;

/// Below this `sigma / w0` the integral's identities lose digits to cancellation (they divide
/// by `sigma`); quadrature is used instead.
const LIGHT_DAMPING: f64 = 1e-6;

/// The running exact metrics of a free run.
#[derive(Debug, Clone, Copy)]
pub(super) struct ExactTally {
    frame: Frame,
    /// Peaks count from the bare frame's damped period on, s.
    from: f64,
    band: f64,
    /// Initial mechanical energy, or 0 when the dissipation times are not watched.
    initial_energy: f64,
    peak_displacement: f64,
    peak_acceleration: f64,
    integral_x2: f64,
    /// The last interval on which `|xs|` reached the band.
    last_outside: Option<(Segment, f64, f64)>,
    /// Whether `|xs|` is at or above the band at the end of the last interval.
    outside_at_end: bool,
    dissipated: [Option<f64>; 2],
    horizon: f64,
}

impl ExactTally {
    /// The tally of a free run of `scene`, or `None` when it has no frame (the chain: `xs` is
    /// 0 throughout, the samples serve) or is forced.
    pub(super) fn new(scene: &Scene) -> Option<Self> {
        let frame = scene.frame?;
        if scene.forcing.is_some() || scene.structure.is_some() {
            return None;
        }
        let e0 = scene.initial_energy();
        Some(ExactTally {
            frame,
            from: frame.damped_period(),
            band: SETTLING_FRACTION * scene.initial_displacement.abs(),
            initial_energy: if e0 > 0.0 { e0 } else { 0.0 },
            peak_displacement: 0.0,
            peak_acceleration: 0.0,
            integral_x2: 0.0,
            last_outside: None,
            outside_at_end: false,
            dissipated: [None; 2],
            horizon: scene.horizon,
        })
    }

    /// Whether the energy is still watched (a dissipation time is still to be found).
    pub(super) fn wants_energy(&self) -> bool {
        self.initial_energy > 0.0 && self.dissipated[1].is_none()
    }

    /// Adds the interval `[a, b]` of free segment `seg` (no event inside), whose states at
    /// the ends are `ends`, the free balls carrying kinetic energy `free_energy` (read only
    /// when [`ExactTally::wants_energy`]).
    pub(super) fn interval(&mut self, seg: &Segment, a: f64, b: f64, ends: [(f64, f64); 2], free_energy: f64) {
        let osc = seg.osc;
        let [(xa, va), (xb, vb)] = ends;
        let reach = self.reach(seg, b, (xa, va));
        // Past the first period, an interval the frame's reach keeps inside the band and the
        // peak found so far changes neither (peaks count from `from`, where they start at 0).
        let x_bounded = reach.is_some_and(|(x, _)| x < self.band && x <= self.peak_displacement);
        // Bounded, the reach stands in for the largest `|xs|`: below the band and the peak.
        let max_x = match reach {
            Some((x, _)) if x_bounded => x,
            _ => xa.abs().max(xb.abs()).max(first_extremum_x(seg, a, b).abs()),
        };
        if max_x >= self.band {
            self.last_outside = Some((*seg, a, b));
        }
        self.outside_at_end = xb.abs() >= self.band;
        if a >= self.from {
            if reach.is_some_and(|(_, acc)| acc <= self.peak_acceleration) {
                self.peak_displacement = self.peak_displacement.max(max_x);
            } else {
                self.peaks(seg, (a, xa, va), max_x, b, (xb, vb));
            }
        } else if b >= self.from {
            // The interval that straddles the first bare period (once per run).
            let (x, v) = seg.state(self.from);
            let max_x = x.abs().max(xb.abs()).max(first_extremum_x(seg, self.from, b).abs());
            self.peaks(seg, (self.from, x, v), max_x, b, (xb, vb));
        }
        self.integral_x2 += integral_x2(seg, a, b, (xa, va), (xb, vb));
        if self.wants_energy() {
            let energy = |x: f64, v: f64| 0.5 * osc.mass * v * v + 0.5 * osc.stiffness * x * x + free_energy;
            for (level, time) in DISSIPATION_LEVELS.iter().zip(&mut self.dissipated) {
                let target = level * self.initial_energy;
                if time.is_some() {
                    continue;
                }
                if energy(xa, va) <= target {
                    *time = Some(a);
                } else if energy(xb, vb) <= target {
                    // Falls only: the first time at or below the level.
                    let (mut lo, mut hi) = (a, b);
                    for _ in 0..BISECTIONS {
                        let m = 0.5 * (lo + hi);
                        if m <= lo || m >= hi {
                            break;
                        }
                        let (x, v) = seg.state(m);
                        if energy(x, v) <= target {
                            hi = m;
                        } else {
                            lo = m;
                        }
                    }
                    *time = Some(hi);
                }
            }
        }
    }

    /// Bounds on `|xs|` and on the reported acceleration `|Frame::acceleration|` over an
    /// interval of `seg` ending at `b` whose state at its start is `(x, v)`, above anything the
    /// tally would evaluate there; `None` without a spring or with negative damping.
    ///
    /// `x` and the segment's acceleration are free solutions, bounded by their
    /// [`Oscillator::envelope`]; the reported acceleration is the segment's times `M / ms`.
    /// The round-off of the evaluated states (the start's, and any later one's) is
    /// added twice, with a relative millionth for the bounds' own arithmetic. With them the
    /// tally skips the extrema (a zero search and a closed-form evaluation each) of intervals
    /// that cannot raise a peak or reach the band, the usual case once the motion decays.
    fn reach(&self, seg: &Segment, b: f64, (x, v): (f64, f64)) -> Option<(f64, f64)> {
        let o = &seg.osc;
        let acc = o.accel(x, v);
        let jerk = -2.0 * o.sigma * acc - o.w0sq * v;
        let (envelope_x, envelope_a) = (o.envelope(x, v)?, o.envelope(acc, jerk)?);
        let tau = b - seg.t0;
        let err_x = 2.0 * o.roundoff(seg.x0, seg.v0, tau);
        let err_v = 2.0 * o.roundoff(seg.v0, o.accel(seg.x0, seg.v0), tau);
        let slack = 1.0 + 1e-6;
        let f = &self.frame;
        let reach_x = envelope_x * slack + err_x;
        let reach_a = envelope_a * (o.mass / f.mass) * slack + (f.stiffness * err_x + f.damping * err_v) / f.mass;
        Some((reach_x, reach_a))
    }

    /// Peaks on `[lo, b]`: of `|xs|`, whose largest there is `max_x`, and of the frame's
    /// acceleration as every model reports it ([`Frame::acceleration`], proportional to the
    /// segment's own).
    fn peaks(&mut self, seg: &Segment, (lo, x, v): (f64, f64, f64), max_x: f64, b: f64, (xb, vb): (f64, f64)) {
        let mut pa = self.frame.acceleration(x, v).abs().max(self.frame.acceleration(xb, vb).abs());
        if let Some(t) = seg.next_zero(Zeros::Jerk, lo).filter(|&t| t < b) {
            let (x, v) = seg.state(t);
            pa = pa.max(self.frame.acceleration(x, v).abs());
        }
        self.peak_displacement = self.peak_displacement.max(max_x);
        self.peak_acceleration = self.peak_acceleration.max(pa);
    }

    /// Ends the tally at `t`, before the horizon (a run stopped by its budget).
    pub(super) fn cut_at(&mut self, t: f64) {
        self.horizon = t;
    }

    /// The metrics of the run, its last interval having ended at the horizon.
    pub(super) fn finish(&self) -> MotionMetrics {
        let settling_time = match self.last_outside {
            None => Some(0.0),
            Some(_) if self.outside_at_end => None,
            Some((seg, a, b)) => Some(last_time_outside(&seg, a, b, self.band)),
        };
        MotionMetrics {
            peak_displacement: self.peak_displacement,
            peak_acceleration: self.peak_acceleration,
            rms_displacement: if self.horizon > 0.0 { (self.integral_x2 / self.horizon).sqrt() } else { 0.0 },
            settling_time,
            dissipation_times: self.dissipated,
            peak_drift: None,
            peak_roof_displacement: None,
            peak_floor_acceleration: None,
            // Read in closed form only in free vibration.
            driven: false,
        }
    }
}

/// `x` at the first extremum of `x` in `(a, b)` (0 when there is none): the largest `|x|`
/// inside the interval, the later extrema being smaller.
fn first_extremum_x(seg: &Segment, a: f64, b: f64) -> f64 {
    seg.next_zero(Zeros::Velocity, a).filter(|&t| t < b).map_or(0.0, |t| seg.state(t).0)
}

/// `integral_a^b x^2 dt` of the free segment `seg`, from the states at the ends.
fn integral_x2(seg: &Segment, a: f64, b: f64, (xa, va): (f64, f64), (xb, vb): (f64, f64)) -> f64 {
    if b <= a {
        return 0.0;
    }
    let o = seg.osc;
    if o.w0sq > 0.0 && o.sigma > LIGHT_DAMPING * o.w0sq.sqrt() {
        let xv = 0.5 * (xb * xb - xa * xa);
        let vv = -(0.5 * (vb * vb - va * va) + o.w0sq * xv) / (2.0 * o.sigma);
        return ((vv - 2.0 * o.sigma * xv - (xb * vb - xa * va)) / o.w0sq).max(0.0);
    }
    let rate = o.rate();
    let piece = if rate > 0.0 { std::f64::consts::FRAC_PI_4 / rate } else { b - a };
    gauss_legendre(a, b, piece, |t| {
        let x = seg.state(t).0;
        [x * x, 0.0]
    })[0]
}

/// The last time in `[a, b]` at which `|x| >= band`, given that it is at some point and not
/// at `b`. Between consecutive extrema `x` is monotone, and the extrema shrink, so the set
/// where `|x| >= band` ends in the interval after the last extremum that reaches the band
/// (or after `a`); there it is bisected.
fn last_time_outside(seg: &Segment, a: f64, b: f64, band: f64) -> f64 {
    let osc = seg.osc;
    let first = seg.next_zero(Zeros::Velocity, a).filter(|&t| t < b);
    // The extrema after a, as times: evenly spaced by pi / w when oscillating, at most one
    // otherwise.
    let extremum = |n: usize| -> Option<f64> {
        let t1 = first?;
        let t = match osc.damped_omega() {
            Some(w) => t1 + n as f64 * std::f64::consts::PI / w,
            None if n == 0 => t1,
            None => return None,
        };
        (t < b).then_some(t)
    };
    // The last extremum reaching the band (their sizes fall, so a binary search over n).
    let count = match (first, osc.damped_omega()) {
        (None, _) => 0,
        (Some(t1), Some(w)) => ((b - t1) * w / std::f64::consts::PI).ceil().max(1.0) as usize,
        (Some(_), None) => 1,
    };
    let reaches = |n: usize| extremum(n).is_some_and(|t| seg.state(t).0.abs() >= band);
    let (mut lo, mut hi) = (0usize, count);
    if count > 0 && reaches(0) {
        // reaches(lo) holds; find the last n with reaches(n).
        lo = 0;
        while hi - lo > 1 {
            let m = lo + (hi - lo) / 2;
            if reaches(m) {
                lo = m;
            } else {
                hi = m;
            }
        }
    }
    let start = if count > 0 && reaches(0) { extremum(lo).unwrap_or(a) } else { a };
    let end = extremum(if count > 0 && reaches(0) { lo + 1 } else { 0 }).filter(|&t| t > start).unwrap_or(b);
    let (mut l, mut h) = (start, end);
    for _ in 0..BISECTIONS {
        let m = 0.5 * (l + h);
        if m <= l || m >= h {
            break;
        }
        if seg.state(m).0.abs() >= band {
            l = m;
        } else {
            h = m;
        }
    }
    l
}
