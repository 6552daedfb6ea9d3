//! Beds settled under gravity (`placement = "settled"`, docs/MODEL.md §13): a pile at rest on
//! its supports, inside the box, without overlaps, the same for a seed, that stays where it
//! starts when the frame is still.

use crate::common::{compliant, lpc, scene_from_toml};
use lpc_damper::compliant::contact;
use lpc_damper::scene::Scene;

/// A box on the paper's frame holding `count` balls of radii 4 and 3 mm, placed by
/// `placement`, under gravity along -z with friction 0.3.
fn bed(count: usize, placement: &str, seed: u64, xs0: f64) -> String {
    format!(
        "[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 1.092\ninitial_displacement = {xs0}\n\
         [container]\nlength = 0.05\nwidth = 0.04\nheight = 0.06\n\
         [world]\ngravity = [0.0, 0.0, -9.81]\nfriction = 0.3\nrestitution = 0.6\n\
         [bed]\ncount = {count}\nradii = [0.004, 0.003]\nproportions = [1.0, 1.0]\ndensity = 7800.0\nplacement = \"{placement}\"\nseed = {seed}\n\
         [compliant]\nyoungs_modulus = 2e9\n[run]\nhorizon = 0.1\nsample_dt = 0.001\n"
    )
}

/// Each ball's centre in the container's frame.
fn centres(s: &Scene) -> Vec<[f64; 3]> {
    (0..s.balls.len())
        .map(|i| {
            let [y, z] = s.space.lateral_of(i);
            [s.initial_positions[i] - s.initial_displacement, y, z]
        })
        .collect()
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

#[test]
fn a_settled_bed_is_a_pile_resting_on_its_supports() {
    let settled = scene_from_toml(&bed(60, "settled", 3, 0.0));
    let lattice = scene_from_toml(&bed(60, "lattice", 3, 0.0));
    let (c, n) = (centres(&settled), settled.balls.len());
    let r = |i: usize| settled.balls[i].radius;
    // Touching within the round-off of coordinates of the container's size (the rule explicit
    // balls follow).
    let round_off = 8.0 * f64::EPSILON * 0.06;
    // The descent ends at steps of a thousandth of the smallest radius: a ball rests within a
    // few of them of what carries it.
    let resting = 1e-2 * 0.003;
    for i in 0..n {
        let [x, y, z] = c[i];
        assert!(x >= r(i) && x <= 0.05 - r(i) && y.abs() <= 0.02 - r(i) && z.abs() <= 0.03 - r(i), "ball {i} outside");
        let on_floor = z - r(i) + 0.03 <= resting;
        let mut on_balls = false;
        for j in 0..n {
            if j == i {
                continue;
            }
            let gap = distance(c[i], c[j]) - r(i) - r(j);
            assert!(gap >= -round_off, "balls {i} and {j} overlap by {:e} m", -gap);
            on_balls |= gap <= resting && c[j][2] < z;
        }
        assert!(on_floor || on_balls, "ball {i} at z = {z} rests on nothing");
    }
    // The balls sank into the hollows of the lattice's layers.
    let height = |s: &Scene| centres(s).iter().zip(&s.balls).map(|(c, b)| b.mass * c[2]).sum::<f64>();
    assert!(height(&settled) < height(&lattice), "{} >= {}", height(&settled), height(&lattice));
    // The seed settles the same bed; another seed nudges it into another.
    assert_eq!(scene_from_toml(&bed(60, "settled", 3, 0.0)), settled);
    assert_ne!(scene_from_toml(&bed(60, "settled", 4, 0.0)).space.lateral, settled.space.lateral);
}

#[test]
fn a_settled_bed_stays_at_rest_on_a_still_frame() {
    let scene = scene_from_toml(&bed(60, "settled", 3, 0.0));
    let run = compliant(&scene).expect("the compliant model runs the bed");
    let start = centres(&scene);
    let s = &run.series;
    let last = s.len() - 1;
    let moved: Vec<f64> = (0..scene.balls.len())
        .map(|i| {
            let [y, z] = s.across(i, last);
            distance([s.x(i)[last] - s.xs()[last], y, z], start[i])
        })
        .collect();
    let mean = moved.iter().sum::<f64>() / moved.len() as f64;
    // What the balls may move by at rest: the Hertz deflection of one contact carrying the whole
    // bed's weight (more than any contact carries), and the descent's resolution.
    let weight: f64 = scene.balls.iter().map(|b| b.mass * 9.81).sum();
    let k = contact::stiffness(contact::effective_modulus(&scene.compliant), contact::effective_radius(0.003, Some(0.003)));
    let bound = (weight / k).powf(2.0 / 3.0) + 2e-3 * 0.003;
    assert!(mean <= bound, "the balls moved {mean:e} m on average over 0.1 s (bound {bound:e} m)");
}

#[test]
fn beds_that_cannot_settle_are_refused_naming_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let weightless = bed(20, "settled", 1, 0.0).replace("gravity = [0.0, 0.0, -9.81]", "gravity = [0.0, 0.0, 0.0]");
    let huge = bed(20_000, "settled", 1, 0.0);
    for (text, fields) in [(weightless, ["bed.placement", "world.gravity"]), (huge, ["bed.count", "10000"])] {
        let path = dir.path().join("bed.toml");
        std::fs::write(&path, text).unwrap();
        let out = dir.path().join("out");
        let o = lpc(["run".as_ref(), path.as_os_str(), "--out".as_ref(), out.as_os_str()]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{stderr}");
        assert!(fields.iter().all(|f| stderr.contains(f)), "{stderr}");
        assert!(!out.exists());
    }
}
