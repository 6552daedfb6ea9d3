//! What the spatial path writes down: its samples, each impact's record, and the stop of a run
//! whose ball Rapier's solve left sunk through a wall.

use super::carrier::Carrier;
use super::contacts::{Contact, Other};
use super::contacts_dot;
use crate::model::{Model, ModelError};
use crate::run::{Impact, Recorder};
use crate::scene::{Body, Scene, Wall};

/// The stop of a run in which Rapier's solve left a ball sunk into a wall (`sunk`: the ball,
/// by how much, m, and the wall) by its radius `radius` or more at `t`, its centre past the
/// wall, the frame accelerating at `frame_acceleration` over the step.
pub(super) fn sunk_too_deep(scene: &Scene, t: f64, sunk: (usize, f64, Wall), radius: f64, frame_acceleration: f64) -> ModelError {
    let (ball, depth, wall) = sunk;
    let into = match wall {
        Wall::Left => "the left wall".into(),
        Wall::Right => "the right wall".into(),
        Wall::Front => "the front wall".into(),
        Wall::Back => "the back wall".into(),
        Wall::Floor => "the floor".into(),
        Wall::Ceiling => "the ceiling".into(),
        Wall::Divider(k) => format!("divider {}", k + 1),
    };
    ModelError::Unstable {
        scene: scene.name.clone(),
        model: Model::Rapier,
        t,
        reason: format!(
            "at t = {t:.6e} s ball{} has sunk {:.3e} m into {into}, its radius of {:.3e} m or more: its centre is past the wall and it has left the container, which Rapier's soft contacts did not hold against the load on the ball (the walls accelerate at {:.3e} m/s^2, gravity is {:.3e} m/s^2); the compliant model and, without friction, the reference run such scenes",
            ball + 1,
            depth,
            radius,
            frame_acceleration.abs(),
            contacts_dot(scene.space.gravity, scene.space.gravity).sqrt(),
        ),
    }
}

/// The impact of contact `c` at time `t`, named as the run lists its pairs: the left wall
/// before the ball, the right wall and the side walls after it.
pub(super) fn impact_record(t: f64, c: &Contact, approach: f64, lost: f64) -> Impact {
    let (a, b) = match c.other {
        Other::Ball(j) => (Body::Ball(c.ball), Body::Ball(j)),
        Other::Wall(Wall::Left) => (Body::LeftWall, Body::Ball(c.ball)),
        Other::Wall(wall) => (Body::Ball(c.ball), wall.body()),
    };
    Impact { t, a, b, approach_speed: approach, energy_lost: lost, impulses: 1, peak_force: None, contact_duration: None }
}

/// Takes the sample at `ts`: the frame at `frame` (displacement and velocity), or a
/// structure's floors from `carrier`, and each ball's centre and velocity from `ball(i)`.
pub(super) fn sample(
    recorder: &mut Recorder,
    scene: &Scene,
    carrier: &Carrier,
    ts: f64,
    frame: (f64, f64),
    ball: impl Fn(usize) -> ([f64; 3], [f64; 3]),
) {
    match carrier.floors(ts) {
        None => recorder.sample_in_space(scene, ts, frame.0, frame.1, ball),
        Some((z, ground)) => recorder.sample_floors_in_space(scene, ts, z.split_at(z.len() / 2), ground, ball),
    }
}
