//! The metrics read from the motion itself, tallied sample by sample as a model runs (docs/MODEL.md
//! §7): peaks of `|xs|` and `|a|` from one bare period on, the RMS of `xs`, the settling time and
//! the dissipation times. A run that keeps no series (an ensemble member) tallies exactly what one
//! that keeps it does.

use crate::scene::Scene;

/// Fraction of `|xs0|` that counts as settled.
pub const SETTLING_FRACTION: f64 = 0.05;

/// The metrics read from the motion itself: peaks of `|xs|` and `|a|` from one bare period on,
/// RMS of `xs`, the settling time and the dissipation times, as docs/MODEL.md §7 defines them.
/// Every model reads them at its samples ([`SampleTally`]); the reference computes them exactly from its
/// closed-form motion in free vibration.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MotionMetrics {
    /// max |xs| for t >= T, m.
    pub peak_displacement: f64,
    /// max |a| for t >= T, m/s^2.
    pub peak_acceleration: f64,
    /// RMS of xs over the horizon, m.
    pub rms_displacement: f64,
    /// Last time |xs| >= 5 % of |xs0|, `None` when that still holds at the horizon.
    pub settling_time: Option<f64>,
    /// First times the energy has fallen to each of [`DISSIPATION_LEVELS`].
    pub dissipation_times: [Option<f64>; 2],
    /// A structure's largest interstorey drift over its floors for t >= T, m (`None` without
    /// a structure).
    pub peak_drift: Option<f64>,
    /// A structure's top floor's largest displacement relative to the ground for t >= T, m.
    pub peak_roof_displacement: Option<f64>,
    /// The largest absolute acceleration of any floor for t >= T, m/s^2.
    pub peak_floor_acceleration: Option<f64>,
    /// Whether an excitation drives the run: energy is then put in as it goes, and what is
    /// left at the end says nothing of the damper.
    pub driven: bool,
}

/// Energy fractions left at which the dissipation times are read: 10 % and 1 %.
pub const DISSIPATION_LEVELS: [f64; 2] = [0.1, 0.01];

/// The metrics that read the sampled motion, accumulated sample by sample in time order:
/// peaks of `|xs|` and `|a|` from one bare period on, the sum of `xs^2`, the last sample
/// outside the settling band and the first samples at which the energy fell to each of
/// [`DISSIPATION_LEVELS`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SampleTally {
    /// Peaks count from this time on (the bare frame's damped period), s.
    from: f64,
    /// `|xs|` at or above this is outside the settling band, m.
    band: f64,
    /// Initial mechanical energy when the dissipation times are watched (free vibration with
    /// energy), else 0.
    initial_energy: f64,
    driven: bool,
    peak_displacement: f64,
    peak_acceleration: f64,
    sum_sq: f64,
    samples: usize,
    last_outside: Option<f64>,
    last_is_outside: bool,
    dissipated: [Option<f64>; 2],
    peak_drift: Option<f64>,
    peak_roof_displacement: Option<f64>,
    peak_floor_acceleration: Option<f64>,
}

impl SampleTally {
    /// An empty tally for a run of `scene`.
    pub fn new(scene: &Scene) -> Self {
        let initial_energy = scene.initial_energy();
        SampleTally {
            from: scene.frame.map_or(0.0, |f| f.damped_period()),
            band: SETTLING_FRACTION * scene.initial_displacement.abs(),
            // Energy only falls in free vibration: a forced run has no dissipation time.
            initial_energy: if !scene.is_driven() && initial_energy > 0.0 { initial_energy } else { 0.0 },
            driven: scene.is_driven(),
            ..Default::default()
        }
    }
    /// Whether the next sample's mechanical energy is still needed (a dissipation time is
    /// still to be found): computing it costs a pass over the balls.
    #[inline]
    pub fn wants_energy(&self) -> bool {
        self.initial_energy > 0.0 && self.dissipated[1].is_none()
    }
    /// Adds the sample at `t`: the frame's displacement and acceleration, and the mechanical
    /// energy when [`SampleTally::wants_energy`] (ignored otherwise).
    #[inline]
    pub fn add(&mut self, t: f64, xs: f64, a: f64, energy: f64) {
        if t >= self.from {
            self.peak_displacement = self.peak_displacement.max(xs.abs());
            self.peak_acceleration = self.peak_acceleration.max(a.abs());
        }
        self.sum_sq += xs * xs;
        self.samples += 1;
        self.last_is_outside = xs.abs() >= self.band;
        if self.last_is_outside {
            self.last_outside = Some(t);
        }
        if self.wants_energy() {
            for (level, time) in DISSIPATION_LEVELS.iter().zip(&mut self.dissipated) {
                if time.is_none() && energy <= level * self.initial_energy {
                    *time = Some(t);
                }
            }
        }
    }
    /// The metrics tallied.
    pub fn finish(&self) -> MotionMetrics {
        MotionMetrics {
            peak_displacement: self.peak_displacement,
            peak_acceleration: self.peak_acceleration,
            rms_displacement: if self.samples == 0 { 0.0 } else { (self.sum_sq / self.samples as f64).sqrt() },
            settling_time: self.settling_time(),
            dissipation_times: self.dissipated,
            peak_drift: self.peak_drift,
            peak_roof_displacement: self.peak_roof_displacement,
            peak_floor_acceleration: self.peak_floor_acceleration,
            driven: self.driven,
        }
    }
    /// Adds a structure's floors at `t`, bottom to top: displacements `u` relative to the
    /// ground, absolute accelerations `a`.
    #[inline]
    pub fn add_floors(&mut self, t: f64, u: &[f64], a: &[f64]) {
        let mut drift = self.peak_drift.unwrap_or(0.0);
        let mut roof = self.peak_roof_displacement.unwrap_or(0.0);
        let mut accel = self.peak_floor_acceleration.unwrap_or(0.0);
        if t >= self.from {
            let mut below = 0.0;
            for &x in u {
                drift = drift.max((x - below).abs());
                below = x;
            }
            roof = roof.max(below.abs());
            accel = a.iter().fold(accel, |m, a| m.max(a.abs()));
        }
        self.peak_drift = Some(drift);
        self.peak_roof_displacement = Some(roof);
        self.peak_floor_acceleration = Some(accel);
    }
    /// The last sampled time at which `|xs| >= 5 % |xs0|`, or `None` if the last sample still
    /// is (not settled within the horizon). A series that never reaches the band settles at 0.
    pub fn settling_time(&self) -> Option<f64> {
        match self.last_outside {
            None => Some(0.0),
            Some(_) if self.last_is_outside => None,
            t => t,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settling_time(xs: &[f64]) -> Option<f64> {
        let mut tally = SampleTally { band: SETTLING_FRACTION, ..Default::default() };
        for (k, &x) in xs.iter().enumerate() {
            tally.add(k as f64, x, 0.0, 0.0);
        }
        tally.settling_time()
    }

    #[test]
    fn settling_is_last_time_outside_the_band() {
        assert_eq!(settling_time(&[1.0, -0.5, 0.01, 0.0]), Some(1.0));
        assert_eq!(settling_time(&[1.0, 0.0, 0.0, 0.06]), None);
        assert_eq!(settling_time(&[0.01, 0.0, 0.0, 0.0]), Some(0.0));
    }

    #[test]
    fn dissipation_times_are_the_first_samples_below_each_level() {
        let mut tally = SampleTally { initial_energy: 1.0, ..Default::default() };
        for (k, e) in [1.0, 0.5, 0.1, 0.2, 0.05, 0.01, 0.001].into_iter().enumerate() {
            tally.add(k as f64, 0.0, 0.0, e);
        }
        assert_eq!(tally.finish().dissipation_times, [Some(2.0), Some(5.0)]);
    }
}
