//! What the walls carry (docs/MODEL.md §9, "The frame felt the balls it carries a step late").
//! Rapier's walls are kinematic: the frame moves by its closed form over a step, and the balls
//! its walls push or drag along take their push in Rapier's solve and hand the frame its
//! momentum only at the step's end. Two rules keep that coupling within the step. The balls that
//! touch something step in their walls' reference, where the walls' acceleration is a steady
//! force, as gravity is, rather than a jump of the walls' velocity at each step's start
//! ([`enter_walls_reference`]). And each carrying body's closed form carries the mass its walls
//! drag along ([`CarriedMass`]), so that the frame feels those balls as it moves rather than a
//! step late, which acted as a dashpot of about `M h w^2 / 2` (the mass dragged along `M`, the
//! step `h`, the frame's rate `w`).

use bevy_rapier3d::rapier::prelude::Vector;

use super::world::SpatialWorld;

/// The walls' velocity over a step for each body that carries walls: at its start (`start`),
/// Rapier's kinematic walls' mean over it (`mean`) and at its end (`end`), m/s.
#[derive(Debug, Clone, Copy)]
pub struct WallsVelocity<'a> {
    /// At the step's start.
    pub start: &'a [f64],
    /// Rapier's kinematic walls' velocity over the step: their mean.
    pub mean: &'a [f64],
    /// At the step's end, before the step's impulses.
    pub end: &'a [f64],
}

/// Before a step of `h`: Rapier is given every ball in the reference of its walls, which
/// Rapier moves at their mean velocity over the step while they accelerate from their velocity
/// at the step's start to that at its end. A ball's velocity there is its velocity less the
/// walls' at the start plus their mean, and the walls' acceleration is a steady force on it,
/// as gravity is. Rapier's contacts then carry the walls' push as they carry the floor's hold
/// against gravity, a load that changes little from step to step, instead of a jump of the
/// walls' velocity at the step's start, of which Rapier's few iterations passed about half
/// through a pile. Only the balls marked in `resting` (touching a wall or a ball) step so: a
/// ball in flight flies straight in the ground's reference, where Rapier's substeps of the
/// walls' force would bend its path by `a h^2 / 2n` a step. `v` is every ball's velocity and
/// `body_of` the body that carries its walls.
pub fn enter_walls_reference(
    world: &mut SpatialWorld,
    v: &[[f64; 3]],
    (body_of, resting): (&[usize], &[bool]),
    walls: WallsVelocity,
    mass: &[f64],
    h: f64,
) {
    for (i, vi) in v.iter().enumerate().filter(|(i, _)| resting[*i]) {
        let b = body_of[i];
        let body = world.ball_mut(i);
        let u = body.linvel();
        body.set_linvel(Vector::new((vi[0] - walls.start[b] + walls.mean[b]) as f32, u.y, u.z), true);
        body.add_force(Vector::new((-mass[i] * (walls.end[b] - walls.start[b]) / h) as f32, 0.0, 0.0), true);
    }
}

/// After the step: the velocity `v` of every ball [`enter_walls_reference`] stepped in the walls'
/// reference, read from Rapier there, back in the ground's (its velocity there plus the walls'
/// at the step's end less their mean), given back to Rapier, and the walls' force taken off;
/// `v` keeps what Rapier will read back.
pub fn leave_walls_reference(world: &mut SpatialWorld, v: &mut [[f64; 3]], (body_of, resting): (&[usize], &[bool]), walls: WallsVelocity) {
    for (i, vi) in v.iter_mut().enumerate().filter(|(i, _)| resting[*i]) {
        let b = body_of[i];
        let body = world.ball_mut(i);
        body.reset_forces(true);
        let u = body.linvel();
        body.set_linvel(Vector::new((vi[0] + walls.end[b] - walls.mean[b]) as f32, u.y, u.z), true);
        vi[0] = body.linvel().x as f64;
    }
}

/// Steps over which the carried mass's estimate weighs the walls' pushes: the later ones
/// count most, one this many steps old by `1 / e` of the last.
pub const CARRIED_MEMORY_STEPS: f64 = 10.0;

/// Grid of the carried mass, as a fraction of the mass of the balls a body carries: a floor of a
/// structure needs its modes decomposed anew for every mass it carries, so the masses are kept
/// to a few, the same for a frame and for the one-storey structure it describes.
pub const CARRIED_GRID: f64 = 1.0 / 128.0;

/// How much of its balls' mass each carrying body drags along with its walls: the least-squares
/// ratio of the x momentum Rapier's step gave the balls no impact struck (their `response`) to
/// the walls' change of velocity over the step, over the last [`CARRIED_MEMORY_STEPS`] steps,
/// kept between zero and all of the body's balls, to [`CARRIED_GRID`] of them.
#[derive(Debug, Clone)]
pub struct CarriedMass {
    /// The mass each body drags along, kg.
    pub mass: Vec<f64>,
    /// The mass of each body's balls, kg.
    balls: Vec<f64>,
    response_by_change: Vec<f64>,
    change_squared: Vec<f64>,
}

impl CarriedMass {
    /// Nothing carried yet by bodies whose balls weigh `balls` kg each.
    pub fn new(balls: Vec<f64>) -> Self {
        let n = balls.len();
        CarriedMass { mass: vec![0.0; n], balls, response_by_change: vec![0.0; n], change_squared: vec![0.0; n] }
    }

    /// Takes in a step in which each body's walls changed their velocity by `change` m/s and
    /// Rapier gave its balls that no impact struck `response` N s along x.
    pub fn update(&mut self, response: &[f64], change: &[f64]) {
        let keep = (-1.0 / CARRIED_MEMORY_STEPS).exp();
        for b in 0..self.mass.len() {
            self.response_by_change[b] = keep * self.response_by_change[b] + response[b] * change[b];
            self.change_squared[b] = keep * self.change_squared[b] + change[b] * change[b];
            let ratio = if self.change_squared[b] > 0.0 { self.response_by_change[b] / self.change_squared[b] } else { 0.0 };
            let grid = CARRIED_GRID * self.balls[b];
            self.mass[b] = if grid > 0.0 { (ratio.clamp(0.0, self.balls[b]) / grid).round() * grid } else { 0.0 };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bodies whose balls answer each change of their walls' velocity with a third of their
    /// mass, with more than all of it and with a pull the other way are carried as that third
    /// (on the grid), as all of their balls and as none.
    #[test]
    fn carries_the_share_of_its_balls_the_walls_drag_along() {
        let mut carried = CarriedMass::new(vec![1.2, 1.2, 1.2]);
        for k in 0..50 {
            let change = 0.01 * (0.3 * k as f64).sin() + 0.002;
            carried.update(&[0.4 * change, 3.0 * change, -0.5 * change], &[change; 3]);
        }
        let grid = CARRIED_GRID * 1.2;
        assert_eq!(carried.mass, [(0.4 / grid).round() * grid, 1.2, 0.0]);
    }
}
