//! Settings a scene gives the models that read them: the reference's contact duration, the
//! contact model's stepping and solver, the compliant model's material and error tolerance.

use super::format::Stepping;

/// Settings of the reference model that a scene may fix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferenceSettings {
    /// The contact duration `t_c`, s (docs/MODEL.md §4 and §14). Instantaneous impacts hold
    /// only while they are further apart than a real contact lasts: on a line, a pair striking
    /// again within `t_c` is in persistent contact and its touching run is merged; in space, an
    /// impact within `t_c` of a ball's previous one is elastic and a pressed contact is kept
    /// open for `t_c`.
    pub contact_duration: f64,
}

/// The reference's contact duration when the scene sets none, s: a microsecond, shorter than
/// the contacts of centimetre steel balls at a damper's speeds (tens of microseconds).
pub const DEFAULT_CONTACT_DURATION: f64 = 1e-6;

impl Default for ReferenceSettings {
    fn default() -> Self {
        ReferenceSettings { contact_duration: DEFAULT_CONTACT_DURATION }
    }
}

/// Settings of the Rapier model that a scene may fix.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RapierSettings {
    /// How steps are chosen.
    pub stepping: Option<Stepping>,
    /// Fixed step (longest step when aligned), s.
    pub dt: Option<f64>,
    /// Solver iterations.
    pub solver_iterations: Option<u32>,
    /// Rapier's swept CCD on the balls.
    pub ccd: Option<bool>,
}

/// Material of balls and walls for the compliant contact model (docs/MODEL.md §9; steel by
/// default), and the error tolerance of its integration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CompliantSettings {
    /// Young's modulus `E`, Pa.
    pub youngs_modulus: f64,
    /// Poisson's ratio `nu`.
    pub poisson_ratio: f64,
    /// Error tolerance per step, relative to the contact scales.
    pub tolerance: f64,
}

/// The compliant model's error tolerance when the scene sets none.
pub const DEFAULT_COMPLIANT_TOLERANCE: f64 = 1e-9;

impl Default for CompliantSettings {
    fn default() -> Self {
        CompliantSettings { youngs_modulus: 200e9, poisson_ratio: 0.3, tolerance: DEFAULT_COMPLIANT_TOLERANCE }
    }
}
