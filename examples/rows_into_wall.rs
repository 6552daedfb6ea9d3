//! Rows of touching balls struck into a wall on the contact model's spatial path, scanned over
//! gaps, row lengths, steps and restitutions (docs/MODEL.md §9, "Touching rows struck into a
//! wall"). A row of 10 g balls (r 6.75 mm) flies at 1 m/s into the left wall of a long box on a
//! frame too heavy to move, floating or lying on the frictionless floor; each line counts the
//! cases that leave more than 1e-4 m/s off the velocities of §3's sequence, with the wall an
//! infinitely heavy partner, and the worst of them.
//!   cargo run --release --example rows_into_wall [E...]   (default: 1 0.9 0.6 0.3)

use anyhow::Context;
use lpc_damper::model::RunOptions;
use lpc_damper::rapier::spatial::simulate_spatial;

const RADIUS: f64 = 0.00675;
const SPEED: f64 = 1.0;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let restitutions: Vec<f64> =
        if args.is_empty() { vec![1.0, 0.9, 0.6, 0.3] } else { args.iter().map(|a| a.parse()).collect::<Result<_, _>>().context("E")? };
    for e in restitutions {
        for on_floor in [true, false] {
            for dt in [5e-5, 1e-4, 2e-4, 3e-4, 5e-4, 1e-3] {
                let (mut off, mut cases, mut worst) = (0, 0, (0.0f64, 0.0, 0));
                for row in 2..6 {
                    for k in 0..20 {
                        let gap = 0.01 * (k as f64 + 0.37) / 20.0;
                        let parsed = lpc_damper::scene::parse(&row_into_wall(gap, row, e, dt, on_floor), "row.toml", "row")?;
                        let scene = parsed.scene.context("a single-run scene")?;
                        let run = simulate_spatial(&scene, &RunOptions::default())?;
                        let expected = sequence_into_wall(vec![-SPEED; row], e, 1e-9 * SPEED);
                        let error = run.final_velocities.iter().zip(&expected).map(|(v, w)| (v - w).abs()).fold(0.0, f64::max);
                        cases += 1;
                        if error > 1e-4 {
                            off += 1;
                        }
                        if error > worst.0 {
                            worst = (error, gap, row);
                        }
                    }
                }
                let lying = if on_floor { "on the floor" } else { "floating" };
                println!(
                    "e {e}, {lying}, dt {dt}: {off} of {cases} off; worst {:.2e} m/s (gap {:.4} m, row of {})",
                    worst.0, worst.1, worst.2
                );
            }
        }
    }
    Ok(())
}

/// The scene: the row's first ball `gap` (m) from the wall, restitution `e`, steps of `dt`, the
/// horizon 20 ms after the row reaches the wall.
fn row_into_wall(gap: f64, row: usize, e: f64, dt: f64, on_floor: bool) -> String {
    let (height, horizon) = (0.05, gap / SPEED + 0.02);
    let (world, z) =
        if on_floor { ("gravity = [0.0, 0.0, -9.81]\nfriction = 0.0", -0.5 * height + RADIUS) } else { ("friction = 0.1", 0.0) };
    let mut text = format!(
        "[frame]\nmass = 1e6\nstiffness = 1e6\ndamping = 0.0\ninitial_displacement = 0.0\n\
         [container]\nlength = 1.0\nwidth = 0.05\nheight = {height}\n\
         [world]\nrestitution = {e}\n{world}\n[rapier]\ndt = {dt}\n\
         [run]\nhorizon = {horizon}\nsample_dt = {horizon}\n"
    );
    for k in 0..row {
        let x = RADIUS + gap + 2.0 * RADIUS * k as f64;
        text += &format!("[[ball]]\nposition = [{x}, 0.0, {z}]\nmass = 0.01\nradius = {RADIUS}\nvelocity = [{}, 0.0, 0.0]\n", -SPEED);
    }
    text
}

/// §3's sequence on a row of equal touching balls with a wall at rest touching the first: the
/// fastest-approaching pair (the wall's sends its ball back at `e` times its approach) strikes
/// first, until nothing approaches faster than `slowest`.
fn sequence_into_wall(mut v: Vec<f64>, e: f64, slowest: f64) -> Vec<f64> {
    loop {
        let pairs = (0..v.len() - 1).map(|i| (v[i] - v[i + 1], Some(i)));
        let fastest = pairs.chain([(-v[0], None)]).max_by(|a, b| a.0.total_cmp(&b.0));
        let Some((approach, pair)) = fastest.filter(|(approach, _)| *approach > slowest) else { return v };
        match pair {
            None => v[0] = e * approach,
            Some(i) => {
                let centre = 0.5 * (v[i] + v[i + 1]);
                v[i] = centre - 0.5 * e * approach;
                v[i + 1] = centre + 0.5 * e * approach;
            }
        }
    }
}
