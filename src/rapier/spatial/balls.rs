//! The balls' state on the spatial path as `f64` arrays, read from Rapier and written back.

use bevy_rapier3d::rapier::prelude::Vector;

use super::world::SpatialWorld;

/// The balls' state as `f64` arrays, read from Rapier.
pub(super) struct BallState {
    /// Positions, m.
    pub(super) x: Vec<[f64; 3]>,
    /// Velocities, m/s.
    pub(super) v: Vec<[f64; 3]>,
    /// Angular velocities, rad/s.
    pub(super) w: Vec<[f64; 3]>,
}

impl BallState {
    /// Reads every ball's state from Rapier.
    pub(super) fn read(&mut self, world: &SpatialWorld) {
        for k in 0..world.balls.len() {
            let b = world.ball(k);
            let (p, v, w) = (b.translation(), b.linvel(), b.angvel());
            self.x[k] = [p.x as f64, p.y as f64, p.z as f64];
            self.v[k] = [v.x as f64, v.y as f64, v.z as f64];
            self.w[k] = [w.x as f64, w.y as f64, w.z as f64];
        }
    }

    /// Gives Rapier the angular velocities of the balls marked in `which`, keeping what it
    /// will read back.
    pub(super) fn write_spins(&mut self, world: &mut SpatialWorld, which: &[bool]) {
        for k in (0..world.balls.len()).filter(|&k| which[k]) {
            let w = self.w[k];
            let body = world.ball_mut(k);
            body.set_angvel(Vector::new(w[0] as f32, w[1] as f32, w[2] as f32), true);
            let r = body.angvel();
            self.w[k] = [r.x as f64, r.y as f64, r.z as f64];
        }
    }

    /// Gives Rapier the velocities of the balls marked in `which`, keeping what it will read
    /// back (the `f32` velocity).
    pub(super) fn write_velocities(&mut self, world: &mut SpatialWorld, which: &[bool]) {
        for k in 0..world.balls.len() {
            if which[k] {
                let v = self.v[k];
                let body = world.ball_mut(k);
                body.set_linvel(Vector::new(v[0] as f32, v[1] as f32, v[2] as f32), true);
                let r = body.linvel();
                self.v[k] = [r.x as f64, r.y as f64, r.z as f64];
            }
        }
    }
}
