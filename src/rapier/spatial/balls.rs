//! The balls' state on the spatial path as `f64` arrays, read from Rapier and written back.

use bevy_rapier3d::rapier::prelude::Vector;

use super::contacts::{dot, Contact, Other};
use super::world::SpatialWorld;
use crate::scene::Wall;

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

    /// Gives the balls marked in `undone` back the free flight of a step of `h` under gravity
    /// `g` (of unit direction `down`) from `before`, undoing Rapier's solve of the step; a ball
    /// that `lies_on_floor` has only its motion along the floor undone, and keeps Rapier's
    /// velocity across the floor and its spin. Tells `undone_vx` each ball's x velocity change
    /// undone (Rapier's less free flight's).
    pub(super) fn undo_step(
        &mut self,
        before: &BallState,
        (undone, lies_on_floor): (&[bool], impl Fn(usize) -> bool),
        (g, down, h): ([f64; 3], [f64; 3], f64),
        mut undone_vx: impl FnMut(usize, f64),
    ) {
        for i in (0..self.v.len()).filter(|&i| undone[i]) {
            let mut free: [f64; 3] = std::array::from_fn(|a| before.v[i][a] + g[a] * h);
            if lies_on_floor(i) {
                let across = dot(self.v[i], down) - dot(free, down);
                free = std::array::from_fn(|a| free[a] + across * down[a]);
            } else {
                self.w[i] = before.w[i];
            }
            undone_vx(i, self.v[i][0] - free[0]);
            self.v[i] = free;
        }
    }

    /// Gives Rapier the positions of the balls marked in `which`, keeping what it will read
    /// back (the `f32` position).
    pub(super) fn write_positions(&mut self, world: &mut SpatialWorld, which: &[bool]) {
        for k in (0..world.balls.len()).filter(|&k| which[k]) {
            let x = self.x[k];
            let body = world.ball_mut(k);
            body.set_translation(Vector::new(x[0] as f32, x[1] as f32, x[2] as f32), true);
            let p = body.translation();
            self.x[k] = [p.x as f64, p.y as f64, p.z as f64];
        }
    }

    /// Puts every ball that `found` (the contacts at the step's end) shows sunk into a wall by
    /// more than `limit` back out along the wall's normal to `resting` (positions only: no
    /// velocity or energy changes), in Rapier too; the velocities are left to the impact law,
    /// which strikes a put-back ball that approaches its wall as any impact. Returns whether any
    /// ball moved, or a ball whose centre has crossed a wall (sunk by its radius or more: the
    /// ball, how deep, m, and the wall), which has left its container and cannot be put back.
    pub(super) fn put_back_sunk(
        &mut self,
        world: &mut SpatialWorld,
        found: &[Contact],
        radius: &[f64],
        (limit, resting): (f64, f64),
    ) -> Result<bool, (usize, f64, Wall)> {
        let mut moved = false;
        for c in found.iter().filter(|c| -c.gap > limit) {
            let Other::Wall(wall) = c.other else { continue };
            if -c.gap >= radius[c.ball] {
                return Err((c.ball, -c.gap, wall));
            }
            let back = -c.gap - resting;
            let x = &mut self.x[c.ball];
            for (xa, na) in x.iter_mut().zip(c.normal) {
                *xa -= na * back;
            }
            let body = world.ball_mut(c.ball);
            body.set_translation(Vector::new(x[0] as f32, x[1] as f32, x[2] as f32), true);
            let p = body.translation();
            *x = [p.x as f64, p.y as f64, p.z as f64];
            moved = true;
        }
        Ok(moved)
    }
}
