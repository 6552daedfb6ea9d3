//! What drives the structure: free vibration, or harmonic forcing of the frame by a force or
//! by the ground under its spring and damper (docs/MODEL.md §5).

use std::f64::consts::PI;

use super::format::ForcingKind;

/// Harmonic excitation of the frame. Either way the frame obeys
/// `ms xs'' + cs xs' + ks xs = P sin(w t) + Q cos(w t)` ([`Forcing::harmonic_load`]), and its
/// smooth force is [`super::Scene::frame_force`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Forcing {
    /// Force on the frame, or motion of the ground.
    pub kind: ForcingKind,
    /// `F0`, N (force) or `Y`, m (base).
    pub amplitude: f64,
    /// Hz.
    pub frequency: f64,
}

impl Forcing {
    /// `w = 2 pi f`, rad/s.
    pub fn omega(&self) -> f64 {
        2.0 * PI * self.frequency
    }
    /// The external force `Fe(t)` on the frame (0 for base excitation), N.
    pub fn force(&self, t: f64) -> f64 {
        match self.kind {
            ForcingKind::Force => self.amplitude * (self.omega() * t).sin(),
            ForcingKind::Base => 0.0,
        }
    }
    /// The ground's displacement and velocity `(y, y')` (zero for a force), m and m/s.
    pub fn ground(&self, t: f64) -> (f64, f64) {
        match self.kind {
            ForcingKind::Force => (0.0, 0.0),
            ForcingKind::Base => {
                let w = self.omega();
                let (s, c) = (w * t).sin_cos();
                (self.amplitude * s, self.amplitude * w * c)
            }
        }
    }
    /// `(P, Q)` of the load `P sin(w t) + Q cos(w t)` on a frame with damping `c` and
    /// stiffness `k`: `(F0, 0)` for a force, `(k Y, c w Y)` for base motion.
    pub fn harmonic_load(&self, damping: f64, stiffness: f64) -> (f64, f64) {
        match self.kind {
            ForcingKind::Force => (self.amplitude, 0.0),
            ForcingKind::Base => (stiffness * self.amplitude, damping * self.omega() * self.amplitude),
        }
    }
}
