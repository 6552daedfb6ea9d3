//! The structure the damper protects: a spring-damped frame of one degree of freedom
//! (docs/MODEL.md §1, paper Eq. 5).

use std::f64::consts::PI;

/// The spring-damped primary structure (docs/MODEL.md §1, Eq. 5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// `ms`, kg.
    pub mass: f64,
    /// `ks`, N/m.
    pub stiffness: f64,
    /// `cs`, N s/m.
    pub damping: f64,
}

impl Frame {
    /// The bare frame's damped angular frequency, or `None` when it does not oscillate.
    pub fn damped_omega(&self) -> Option<f64> {
        let sigma = self.damping / (2.0 * self.mass);
        let w0sq = self.stiffness / self.mass;
        let wd2 = w0sq - sigma * sigma;
        (wd2 > 0.0).then(|| wd2.sqrt())
    }
    /// The frame's acceleration without impulses and contact forces, `-(cs vs + ks xs)/ms`
    /// (docs/MODEL.md §6, free vibration), as every model reports it.
    pub fn acceleration(&self, xs: f64, vs: f64) -> f64 {
        -(self.damping * vs + self.stiffness * xs) / self.mass
    }
    /// The frame's kinetic plus spring energy.
    pub fn energy(&self, xs: f64, vs: f64) -> f64 {
        0.5 * self.mass * vs * vs + 0.5 * self.stiffness * xs * xs
    }
    /// The natural frequency (Hz) at which driving this frame has no steady state: an undamped
    /// frame's, when it lies in `[from, to]` Hz (within 1e-12 relative, the round-off of
    /// `ks - ms w^2`); `None` otherwise. The one statement of that rule, for a scene's forcing
    /// (`from == to`) and a frequency sweep alike.
    pub fn resonance_without_steady_state(&self, from: f64, to: f64) -> Option<f64> {
        if self.damping != 0.0 || self.stiffness <= 0.0 {
            return None;
        }
        let natural = (self.stiffness / self.mass).sqrt() / (2.0 * PI);
        let slack = 0.5e-12 * natural;
        (from - slack <= natural && natural <= to + slack).then_some(natural)
    }
    /// `T = 2 pi / omega_d`, or 0 when the bare frame does not oscillate.
    pub fn damped_period(&self) -> f64 {
        self.damped_omega().map_or(0.0, |w| 2.0 * PI / w)
    }
}
