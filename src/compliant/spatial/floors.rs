//! A structure's floors under the container (docs/MODEL.md §16-17): each floor's displacement
//! and velocity relative to the ground, stepped by the same velocity Verlet as the balls, the
//! container on the carrying floor taking the walls' contact forces.

use crate::scene::{Scene, Structure};

/// The floors relative to the ground, and the halves of their last step.
pub(super) struct Floors<'a> {
    pub(super) structure: &'a Structure,
    pub(super) u: Vec<f64>,
    pub(super) v: Vec<f64>,
    v_half: Vec<f64>,
    /// [`Floors::powers`] at the state now, which starts the next step's sums.
    pub(super) powers_now: (f64, f64),
}

impl<'a> Floors<'a> {
    /// The floors of `scene`'s structure at their initial state, if it has one.
    pub(super) fn new(scene: &'a Scene) -> Option<Self> {
        let s = scene.structure.as_deref()?;
        let mut floors = Floors {
            structure: s,
            u: s.initial_displacements.clone(),
            v: s.initial_velocities.clone(),
            v_half: vec![0.0; s.floors()],
            powers_now: (0.0, 0.0),
        };
        floors.powers_now = floors.powers(scene, 0.0);
        Some(floors)
    }

    /// The carrying floor's absolute displacement and velocity at `t`.
    pub(super) fn carrying(&self, scene: &Scene, t: f64) -> (f64, f64) {
        self.at(scene, t, self.structure.floor)
    }

    /// Floor `j`'s absolute displacement and velocity at `t`.
    pub(super) fn at(&self, scene: &Scene, t: f64, j: usize) -> (f64, f64) {
        let (xg, vg, _) = scene.ground_motion(t);
        (xg + self.u[j], vg + self.v[j])
    }

    /// Each floor's acceleration relative to the ground at `t`: the storeys' springs and
    /// dampers, a sine force on the carrying floor, the balls' contact forces `contact` on
    /// each floor, a recorded force on its floor, less the ground's acceleration.
    fn accelerations(&self, scene: &Scene, t: f64, contact: &[f64]) -> Vec<f64> {
        let (_, _, ag) = scene.ground_motion(t);
        let mut a = scene.floor_accelerations(t, &self.u, &self.v);
        for (j, f) in contact.iter().enumerate() {
            a[j] += f / self.structure.building.masses[j];
        }
        a.iter_mut().for_each(|a| *a -= ag);
        a
    }

    /// The power the storeys' dampers take and the one the excitation puts in at `t`, W.
    fn powers(&self, scene: &Scene, t: f64) -> (f64, f64) {
        let s = self.structure;
        let (_, vg, _) = scene.ground_motion(t);
        let restoring = s.building.restoring_forces(&self.u, &self.v);
        let sine =
            scene.forcing.filter(|g| g.kind == crate::scene::ForcingKind::Force).map_or(0.0, |g| g.force(t) * (self.v[s.floor] + vg));
        let recorded = s.force.as_ref().map_or(0.0, |f| s.recorded_force(t) * (self.v[f.floor] + vg));
        (s.building.damping_power(&self.v), vg * restoring.iter().sum::<f64>() + sine + recorded)
    }

    /// The first half of a step of `h` from `t0`: the half kick and the drift, and the
    /// velocities predicted at the step's end (for the dampers' forces there).
    pub(super) fn kick_and_drift(&mut self, scene: &Scene, t0: f64, h: f64, contact: &[f64]) {
        let a = self.accelerations(scene, t0, contact);
        for j in 0..self.u.len() {
            self.v_half[j] = self.v[j] + 0.5 * h * a[j];
            self.u[j] += h * self.v_half[j];
            self.v[j] = self.v_half[j] + 0.5 * h * a[j];
        }
    }

    /// The second half kick of a step of `h` ending at `t1`, with the contact force there, and
    /// the powers at its end.
    pub(super) fn kick(&mut self, scene: &Scene, t1: f64, h: f64, contact: &[f64]) {
        let a = self.accelerations(scene, t1, contact);
        for j in 0..self.u.len() {
            self.v[j] = self.v_half[j] + 0.5 * h * a[j];
        }
        self.powers_now = self.powers(scene, t1);
    }

    /// The floors' mechanical energy at `t` (kinetic in the ground's inertial frame, and the
    /// storeys' springs), J.
    pub(super) fn energy(&self, scene: &Scene, t: f64) -> f64 {
        let (_, vg, _) = scene.ground_motion(t);
        self.structure.energy(&self.u, &self.v, vg)
    }
}
