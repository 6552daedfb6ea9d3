//! What carries the container on the spatial path: a frame on its spring, or a floor of a
//! structure (docs/MODEL.md §16-17). The loop asks the carrier where it is at a time, what a
//! step dissipated and what the excitation put in, and tells it the velocity the impacts leave
//! it with at a step's end.

use crate::floor_motion::FloorMotion;
use crate::oscillator::{gauss_legendre, Driven, Oscillator};
use crate::scene::Scene;

/// The carrying body's motion since the last step's end (a frame) or since the last impulse
/// on it (a floor), in closed form.
pub(super) enum Carrier<'a> {
    /// A frame: the closed-form oscillator from its state `(x0, v0)` at `t0`, carrying
    /// `carrying` kg of balls.
    Frame { scene: &'a Scene, motion: Driven, carrying: f64, x0: f64, v0: f64, t0: f64 },
    /// A structure's floors, and those that carry dampers (the carrying one for one damper).
    Floors(Box<FloorMotion>, Vec<usize>),
}

impl<'a> Carrier<'a> {
    /// The carrier of `scene` at its start.
    pub(super) fn new(scene: &'a Scene) -> Result<Self, String> {
        if let Some(s) = &scene.structure {
            return Ok(Carrier::Floors(Box::new(FloorMotion::new(s.clone(), scene.forcing)?), carrying_floors(scene)));
        }
        let f = scene.frame.ok_or("the scene has no frame")?;
        let motion = Driven::new(Oscillator::new(f.mass, f.damping, f.stiffness), scene.harmonic_load());
        Ok(Carrier::Frame { scene, motion, carrying: 0.0, x0: scene.initial_displacement, v0: 0.0, t0: 0.0 })
    }

    /// The carrying body's absolute displacement and velocity at `t` (not before the last
    /// restart).
    pub(super) fn state(&self, t: f64) -> (f64, f64) {
        match self {
            Carrier::Frame { motion, x0, v0, t0, .. } => motion.state(*x0, *v0, *t0, t),
            Carrier::Floors(m, _) => m.state(t),
        }
    }

    /// Each body that carries dampers ([`carrying_floors`]): its absolute displacement and
    /// velocity at `t` (not before the last restart).
    pub(super) fn states(&self, t: f64) -> Vec<(f64, f64)> {
        match self {
            Carrier::Floors(m, floors) if floors.len() > 1 => {
                let (z, (xg, vg)) = m.floors(t);
                let n = z.len() / 2;
                floors.iter().map(|&j| (xg + z[j], vg + z[n + j])).collect()
            }
            _ => vec![self.state(t)],
        }
    }

    /// What the carrier's dampers dissipated and the excitation put in over the step of `h`
    /// from `from` (since the last restart), J.
    pub(super) fn energy_flows(&self, from: f64, h: f64) -> (f64, f64) {
        match self {
            Carrier::Frame { scene, motion, x0, v0, t0, .. } => {
                let (xa, va) = if from == *t0 { (*x0, *v0) } else { motion.state(*x0, *v0, *t0, from) };
                if motion.xp.is_none() {
                    (motion.osc.dissipated(xa, va, h), 0.0)
                } else {
                    let [damping, work] = gauss_legendre(from, from + h, h, |tq| {
                        let (xq, vq) = motion.state(xa, va, from, tq);
                        [scene.damping_power(tq, vq), scene.forcing_power(tq, xq, vq)]
                    });
                    (damping, work)
                }
            }
            Carrier::Floors(m, _) => m.energy_between(from, from + h),
        }
    }

    /// Each carrying body's displacement and velocity at the last restart (at the start, its
    /// initial state), exactly.
    pub(super) fn starts(&self) -> Vec<(f64, f64)> {
        match self {
            Carrier::Frame { x0, v0, .. } => vec![(*x0, *v0)],
            Carrier::Floors(m, _) => self.states(m.t0),
        }
    }

    /// The mass of balls each carrying body's closed form carries since the last restart, kg.
    pub(super) fn carried(&self) -> Vec<f64> {
        match self {
            Carrier::Frame { carrying, .. } => vec![*carrying],
            Carrier::Floors(m, floors) => floors.iter().map(|&j| m.held()[j]).collect(),
        }
    }

    /// The carrying body, at `state` (displacement and velocity) at `t`, goes on from there at
    /// velocity `v` carrying `carried` kg of balls: a frame restarts at every step's end, the
    /// floors when an impulse changed the carrying floor's velocity or what it carries changed.
    pub(super) fn restart(&mut self, t: f64, state: (f64, f64), v: f64, carried: f64) -> Result<(), String> {
        match self {
            Carrier::Frame { scene, motion, carrying, x0, v0, t0 } => {
                if let (Some(f), true) = (scene.frame, *carrying != carried) {
                    *motion = Driven::new(Oscillator::new(f.mass + carried, f.damping, f.stiffness), scene.harmonic_load());
                    *carrying = carried;
                }
                (*x0, *v0, *t0) = (state.0, v, t);
                Ok(())
            }
            Carrier::Floors(m, _) => {
                let d = m.structure.floor;
                if v != state.1 || m.held()[d] != carried {
                    m.restart(t, v, carried)
                } else {
                    Ok(())
                }
            }
        }
    }

    /// [`Carrier::restart`] for every carrying body: at `states` at `t`, going on at `v` and
    /// carrying `carried` kg of balls, each moved `travel` m beyond its closed form by the
    /// impulses that landed within the step before `t` (docs/MODEL.md §9).
    pub(super) fn restart_bodies(
        &mut self,
        t: f64,
        states: &[(f64, f64)],
        v: &[f64],
        carried: &[f64],
        travel: &[f64],
    ) -> Result<(), String> {
        let moved = travel.iter().any(|&d| d != 0.0);
        match self {
            Carrier::Floors(m, floors) if floors.len() > 1 => {
                let struck: Vec<(usize, f64)> =
                    (0..floors.len()).filter(|&k| travel[k] != 0.0 || v[k] != states[k].1).map(|k| (floors[k], v[k])).collect();
                let mut held = vec![0.0; m.n()];
                for (&j, &c) in floors.iter().zip(carried) {
                    held[j] = c;
                }
                if !struck.is_empty() || m.held() != held.as_slice() {
                    m.restart_holding(t, &struck, &held)?;
                }
                if moved {
                    let shifts: Vec<(usize, f64)> = floors.iter().copied().zip(travel.iter().copied()).filter(|&(_, d)| d != 0.0).collect();
                    m.displace(&shifts);
                }
                Ok(())
            }
            Carrier::Floors(m, _) if moved => {
                let d = m.structure.floor;
                m.restart(t, v[0], carried[0])?;
                m.displace(&[(d, travel[0])]);
                Ok(())
            }
            _ => self.restart(t, (states[0].0 + travel[0], states[0].1), v[0], carried[0]),
        }
    }

    /// The change of the carrier's spring energy at `t` were each carrying body moved by
    /// `travel` m, J.
    pub(super) fn travel_energy(&self, t: f64, travel: &[f64]) -> f64 {
        match self {
            Carrier::Frame { scene, .. } => {
                let (x, v) = self.state(t);
                scene.frame_energy(t, x + travel[0], v) - scene.frame_energy(t, x, v)
            }
            Carrier::Floors(m, floors) => m.displaced_energy(t, &floors.iter().copied().zip(travel.iter().copied()).collect::<Vec<_>>()),
        }
    }

    /// The carrier's mechanical energy at `t` with the carrying body at `(x, v)`: the frame's
    /// kinetic and spring energy, or every floor's, J.
    pub(super) fn energy(&self, t: f64, x: f64, v: f64) -> f64 {
        match self {
            Carrier::Frame { scene, .. } => scene.frame_energy(t, x, v),
            Carrier::Floors(m, _) => m.energy(t),
        }
    }

    /// The floors' state `[u; u']` relative to the ground at `t` and the ground's displacement
    /// and velocity, when the carrier is a structure.
    pub(super) fn floors(&self, t: f64) -> Option<(Vec<f64>, (f64, f64))> {
        match self {
            Carrier::Frame { .. } => None,
            Carrier::Floors(m, _) => Some(m.floors(t)),
        }
    }
}

/// The floors that carry the scene's dampers, in the order their dampers first name them: one
/// body each, which the balls' wall impulses move (the carrying floor alone for one damper).
pub(super) fn carrying_floors(scene: &Scene) -> Vec<usize> {
    let mut floors: Vec<usize> = Vec::new();
    for d in scene.damper_list() {
        if !floors.contains(&d.floor) {
            floors.push(d.floor);
        }
    }
    floors
}
