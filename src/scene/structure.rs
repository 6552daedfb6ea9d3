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

/// A primary structure of several storeys, or one storey under a ground-motion record: what
/// the closed form of [`crate::storeys`] moves (docs/MODEL.md §16-17). A scene's `frame` is
/// then its carrying floor's mass, which takes the balls' impulses, on a spring that gives it
/// the structure's fundamental period.
#[derive(Debug, Clone, PartialEq)]
pub struct Structure {
    /// Floors, storeys and damping.
    pub building: Building,
    /// The floor that carries the container, 0 at the bottom.
    pub floor: usize,
    /// Each floor's initial displacement relative to the ground, m.
    pub initial_displacements: Vec<f64>,
    /// Each floor's initial velocity relative to the ground, m/s.
    pub initial_velocities: Vec<f64>,
    /// The ground's acceleration, when it moves.
    pub ground: Option<std::sync::Arc<GroundRecord>>,
    /// A recorded force on one floor, when one acts (never with a moving ground).
    pub force: Option<FloorForce>,
}

/// A force on one floor, recorded as a ground motion is: linear between its points, N.
#[derive(Debug, Clone, PartialEq)]
pub struct FloorForce {
    /// The floor it acts on, 0 at the bottom.
    pub floor: usize,
    /// The force's points (its `accel` is the force, N; its ground integrals mean nothing).
    pub record: std::sync::Arc<GroundRecord>,
}

impl Structure {
    /// Number of floors.
    pub fn floors(&self) -> usize {
        self.building.floors()
    }
    /// What the structure's record drives ([`Load::Ground`] when it has none).
    pub fn load(&self) -> Load {
        self.force.as_ref().map_or(Load::Ground, |f| Load::Floor(f.floor))
    }
    /// The stretch of the structure's record (the ground's acceleration or a floor's force)
    /// that holds `t`, when a record drives it: the load is linear on it.
    pub fn record_stretch(&self, t: f64) -> Option<super::record::Stretch> {
        match (&self.ground, &self.force) {
            (Some(g), _) => Some(g.stretch(t)),
            (None, Some(f)) => Some(f.record.stretch(t)),
            (None, None) => None,
        }
    }
    /// The recorded force on its floor at `t`, N (0 without one).
    pub fn recorded_force(&self, t: f64) -> f64 {
        self.force.as_ref().map_or(0.0, |f| {
            let stretch = f.record.stretch(t);
            stretch.g0 + stretch.g1 * (t - stretch.start)
        })
    }
    /// Whether a record drives the structure (its ground or a floor's force).
    pub fn is_recorded(&self) -> bool {
        self.ground.is_some() || self.force.is_some()
    }
    /// The floors' mechanical energy with the floors at `u` relative to the ground and moving
    /// at `v` relative to it, the ground at velocity `vg`: kinetic energy in the ground's
    /// inertial frame, `sum m (v + vg)^2 / 2`, plus the springs' `u^T K u / 2`, J.
    pub fn energy(&self, u: &[f64], v: &[f64], vg: f64) -> f64 {
        let kinetic: f64 = self.building.masses.iter().zip(v).map(|(m, v)| 0.5 * m * (v + vg) * (v + vg)).sum();
        kinetic + self.building.spring_energy(u)
    }
    /// The floors' absolute accelerations without impulses, `-M^-1 (C v + K u)`, m/s^2.
    pub fn accelerations(&self, u: &[f64], v: &[f64]) -> Vec<f64> {
        self.building.restoring_forces(u, v).iter().zip(&self.building.masses).map(|(f, m)| f / m).collect()
    }
}

use super::record::GroundRecord;
use crate::storeys::{Building, Load};
