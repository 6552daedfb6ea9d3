//! A row of two touching balls flying into a wall at e = 1 lost half its energy at steps of 0.2
//! and 0.3 ms (issue 55, item 4): Rapier's plastic solve of the step stopped the row as one
//! block at the wall, and the impact law then gave the first ball its bounce but left the
//! second with what Rapier's solve left it, so the knock-on came at 0.77 of its speed. A
//! touching group that rested on no wall and of which a ball strikes a wall now has its step
//! undone, as a group in flight has (docs/MODEL.md §9, "Groups in flight").
//!
//! Rows of three and five then left 0.8 % and 2.5 % off their speed at 0.3 ms steps: Rapier's
//! stop had left the row pressed 0.02-0.03 mm into itself, and its next step pushed the
//! overlaps apart. An undone group's pressed pairs are now parted before that step
//! (docs/MODEL.md §9, "Touching rows struck into a wall").
//!
//! Rows lying on the floor under gravity kept 20-52 % of their energy at those steps: they
//! rested on a wall, so their step was not undone. A ball lying on the floor outside a pile
//! now counts as off the walls, and such a group has its motion along the floor undone.
//!
//! Rows on the floor then lost the knock-ons along the row at 0.5 and 1 ms steps from some
//! gaps (a row of three left at 0.11, 0.93 and 1.07 m/s): Rapier's solve of the impact's step
//! had opened the first pair by 0.03 mm, past the touching distance, and the knock-ons passed
//! only along pairs that touched at the step's end. A pair of an undone group that touched at
//! the step's start now takes the knock-ons too, as it does between hard spheres.

use lpc_damper::model::RunOptions;
use lpc_damper::rapier::spatial::simulate_spatial;

use crate::common::scene_from_toml;

/// Rapier keeps velocities in f32: a velocity's relative rounding over a run of a few hundred
/// steps, and the energy that rounding may make or lose, relative to the initial energy.
const F32_VELOCITY: f64 = 1e-6;
const F32_ENERGY: f64 = 1e-5;

#[test]
fn a_touching_row_struck_into_a_wall_leaves_at_its_speed() {
    for dt in [0.0002, 0.0003] {
        // Two touching balls fly at 1 m/s towards the left wall of a frame too heavy to move,
        // without gravity. The sequence of §3 at e = 1: the first bounces, passes its speed to
        // the second, bounces again; both leave at 1 m/s.
        let run = simulate_spatial(&scene_from_toml(&row_into_wall(2, 0.005, dt, Lying::Floating)), &RunOptions::default())
            .expect("the row keeps its energy");
        for (i, v) in run.final_velocities.iter().enumerate() {
            assert!((v - 1.0).abs() <= F32_VELOCITY, "dt {dt}: ball {i} leaves at {v} m/s");
        }
        let (lost, initial) = (run.energy.contact_loss, run.energy.initial);
        assert!(lost.abs() <= F32_ENERGY * initial, "dt {dt}: {lost} J lost of {initial} J at e = 1");
    }
}

/// Rows of three and five, whose balls Rapier's next step solves touching at every step
/// after the impacts: each step may add an `f32` rounding of the speed.
#[test]
fn longer_rows_struck_into_a_wall_leave_parted_at_their_speed() {
    for (balls, dt) in [(3, 0.0003), (5, 0.0003), (5, 0.0002)] {
        assert_leaves_at_its_speed(balls, 0.005, dt, Lying::Floating);
    }
}

/// Rows lying on the frictionless floor under gravity: the floor holds them across the row,
/// and along it they leave as floating rows do.
#[test]
fn rows_lying_on_the_floor_struck_into_a_wall_leave_at_their_speed() {
    for (balls, dt) in [(2, 0.0003), (2, 0.0002), (3, 0.0003), (5, 0.0003), (5, 0.0002)] {
        assert_leaves_at_its_speed(balls, 0.005, dt, Lying::OnFloor);
    }
}

/// A row of three on the floor whose first ball reaches the wall 0.19 mm into a step of
/// 0.5 ms: Rapier's solve of that step opened the first pair.
#[test]
fn a_row_whose_first_pair_the_step_opened_leaves_at_its_speed() {
    assert_leaves_at_its_speed(3, 0.006185, 0.0005, Lying::OnFloor);
}

/// Every ball of the row leaves at the 1 m/s of the sequence of §3 (for a row at `e = 1`, the
/// row's speed reversed), to the `f32` roundings of its impacts and of Rapier's solve of the
/// touching row at every step after them.
fn assert_leaves_at_its_speed(balls: usize, gap: f64, dt: f64, lying: Lying) {
    let run = simulate_spatial(&scene_from_toml(&row_into_wall(balls, gap, dt, lying)), &RunOptions::default())
        .expect("the row keeps its energy");
    let tolerance = 4.0 * F32_VELOCITY + (0.03 / dt) * f32::EPSILON as f64;
    for (i, v) in run.final_velocities.iter().enumerate() {
        assert!((v - 1.0).abs() <= tolerance, "{balls} balls {lying:?}, dt {dt}: ball {i} leaves at {v} m/s");
    }
}

/// Where a row lies.
#[derive(Debug, Clone, Copy)]
enum Lying {
    /// Without gravity, with friction (which a head-on row never calls on).
    Floating,
    /// On the box's frictionless floor under gravity.
    OnFloor,
}

/// A row of `balls` touching balls of 10 g flying at 1 m/s towards the left wall of a frame
/// too heavy to move, the first `gap` (m) from the wall, at steps of `dt`, for 30 ms at `e = 1`.
fn row_into_wall(balls: usize, gap: f64, dt: f64, lying: Lying) -> String {
    let (r, height) = (0.00675, 0.05);
    let (world, z) = match lying {
        Lying::Floating => ("friction = 0.1", 0.0),
        Lying::OnFloor => ("gravity = [0.0, 0.0, -9.81]\nfriction = 0.0", -0.5 * height + r),
    };
    let mut text = format!(
        "[frame]\nmass = 1e6\nstiffness = 1e6\ndamping = 0.0\ninitial_displacement = 0.0\n\
         [container]\nlength = 1.0\nwidth = 0.05\nheight = {height}\n\
         [world]\nrestitution = 1.0\n{world}\n\
         [rapier]\ndt = {dt}\n\
         [run]\nhorizon = 0.03\nsample_dt = 0.001\n"
    );
    for k in 0..balls {
        let x = r + gap + 2.0 * r * k as f64;
        text += &format!("[[ball]]\nposition = [{x}, 0.0, {z}]\nmass = 0.01\nradius = {r}\nvelocity = [-1.0, 0.0, 0.0]\n");
    }
    text
}
