//! Several chains side by side, explicit balls and generated beds: the scene format's rules,
//! the one-dimensional models on several chains, and the refusal of what they cannot represent.

use crate::common::{compliant, lpc, reference, scene_from_toml, LSL_TOML};
use lpc_damper::model::Model;
use lpc_damper::scene::Scene;

/// The paper's LSL damper as `chains` chains side by side.
fn chains(count: u32, frame_mass: f64) -> Scene {
    let text = LSL_TOML
        .replace("mass = 1.35\nstiffness = 865.0", &format!("mass = {frame_mass}\nstiffness = {}", 865.0 / 1.35 * frame_mass))
        .replace("arrangement = \"LSL\"", &format!("arrangement = \"LSL\"\nchains = {count}"));
    scene_from_toml(&text)
}

#[test]
fn chains_of_a_heavy_frame_each_move_as_the_chain_alone() {
    // A frame a million times heavier than the balls moves as if they were not there, so each
    // chain sees the same wall motion as a single chain does and must move as it does. What
    // couples them is the frame's response to the impulses, (1 + e) m u / ms ~ 2e-7 m/s a wall
    // impact, which over the run moves an impact by ~ that speed over the balls' speed
    // (~0.8 m/s) times the time to the next (~0.1 s): ~3e-8 m, then carried by the balls.
    let mut single = chains(1, 1e6);
    let mut three = chains(3, 1e6);
    single.horizon = 1.0;
    three.horizon = 1.0;
    let one = reference(&single).unwrap();
    let all = reference(&three).unwrap();
    assert_eq!(three.space.chain_starts, vec![0, 3, 6]);
    let mut worst = 0.0f64;
    for k in 0..3 {
        for i in 0..3 {
            let (a, b) = (one.series.x(i), all.series.x(3 * k + i));
            worst = a.iter().zip(b).fold(worst, |m, (a, b)| m.max((a - b).abs()));
        }
    }
    assert!(worst <= 1e-6, "a chain of three departs from the chain alone by {worst:e} m");
    // Three chains lose three times the energy a single chain loses in its impacts, up to the
    // frame's response: each wall impact's loss, (1 - e^2) mu u^2 / 2, moves by the relative
    // change of u that a chain's wall impulse makes in the frame's velocity,
    // (1 + e) m_L u / ms over u, twice (u squared), at each of the run's wall impacts.
    let ratio = all.energy.impact_loss / one.energy.impact_loss;
    let wall_impacts =
        one.impacts.iter().filter(|i| i.a == lpc_damper::scene::Body::LeftWall || i.b == lpc_damper::scene::Body::RightWall).count();
    let bound = wall_impacts as f64 * 2.0 * (1.0 + 0.9) * 0.11 / 1e6 * 3.0;
    assert!((ratio - 3.0).abs() <= bound, "impact losses of three chains / one: {ratio} (bound {bound:e} off 3)");
}

#[test]
fn three_chains_damp_the_frame_exactly() {
    let scene = chains(3, 1.35);
    let run = reference(&scene).unwrap();
    assert!(run.energy.balance_error.abs() <= 1e-12, "balance {:e}", run.energy.balance_error);
    assert!(crate::common::min_gap(&scene, &run) >= -1e-12);
    // Impacts happen in every chain.
    for k in 0..3 {
        let chain = scene.space.chain(k, scene.balls.len());
        let hits = |b: lpc_damper::scene::Body| matches!(b, lpc_damper::scene::Body::Ball(i) if chain.contains(&i));
        assert!(run.impacts.iter().any(|i| hits(i.a) || hits(i.b)), "chain {k} never struck");
    }
}

#[test]
fn identical_chains_in_the_compliant_model_are_one_chain_three_times_as_heavy() {
    // Three identical chains stay identical, so each ball's contact force with the wall is the
    // same in all three: the frame feels three times one chain's force. That is one chain whose
    // balls are three times as heavy (same radii: density times three) with contacts three
    // times as stiff (Young's modulus times three scales every Hertz constant, and with it the
    // Hunt-Crossley force, by three), whose ball-ball contacts move exactly as before. The two
    // systems are the same equations, integrated to the same tolerance: they agree to what
    // the error control allows (its tolerance times the steps, relative to xs0) over the first
    // half second: later the chaotic motion amplifies the round-off by which they differ (they
    // part by microns after 0.7 s), so that is the well-conditioned window.
    let three = chains(3, 1.35);
    let heavy = scene_from_toml(
        &LSL_TOML
            .replace("large_mass = 0.11", "large_mass = 0.33")
            .replace("density = 8000.0", "density = 24000.0")
            .replace("[run]", "[compliant]\nyoungs_modulus = 600e9\n[run]"),
    );
    let (mut a, mut b) = (three.clone(), heavy.clone());
    a.horizon = 0.5;
    b.horizon = 0.5;
    let (ra, rb) = (compliant(&a).unwrap(), compliant(&b).unwrap());
    let err = ra.series.xs().iter().zip(rb.series.xs()).fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
    let steps = ra.events.max(rb.events) as f64;
    let bound = steps * three.compliant.tolerance * three.initial_displacement;
    assert!(err <= bound, "three chains vs one heavy chain: max |dxs| {err:e} m > {bound:e} m");
    // The chains stay identical.
    for k in 1..3 {
        for i in 0..3 {
            let same = ra.series.x(i).iter().zip(ra.series.x(3 * k + i)).all(|(p, q)| (p - q).abs() <= bound);
            assert!(same, "chain {k} ball {i} departs from chain 0");
        }
    }
}

/// A bed scene: `body` holds the balls' tables.
fn bed_scene(body: &str) -> String {
    format!(
        "[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 1.092\ninitial_displacement = 0.01\n\
         [container]\nlength = 0.1\nwidth = 0.04\nheight = 0.03\n[world]\nrestitution = 0.6\n{body}\n[run]\nhorizon = 0.1\n"
    )
}

#[test]
fn beds_fill_their_box_without_overlaps() {
    let lattice = scene_from_toml(&bed_scene(
        "gravity = [0.0, 0.0, -9.81]\n[bed]\ncount = 100\nradii = [0.004, 0.003]\nproportions = [1.0, 3.0]\ndensity = 7800.0\n",
    ));
    assert_eq!(lattice.balls.len(), 100);
    assert_eq!(lattice.balls.iter().filter(|b| b.radius == 0.004).count(), 25);
    // The first layer rests on the floor.
    let floor = -0.015;
    assert!((lattice.space.lateral_of(0)[1] - lattice.balls[0].radius - floor).abs() <= 1e-5);
    let random_text = bed_scene("[bed]\nfill_fraction = 0.2\nradii = [0.004]\ndensity = 7800.0\nplacement = \"random\"\nseed = 7\n");
    let random = scene_from_toml(&random_text);
    let expect = (0.2f64 * 0.1 * 0.04 * 0.03 / (4.0 / 3.0 * std::f64::consts::PI * 0.004f64.powi(3))).round() as usize;
    assert_eq!(random.balls.len(), expect);
    // The same seed places the same bed; another seed another.
    assert_eq!(scene_from_toml(&random_text), random);
    assert_ne!(scene_from_toml(&random_text.replace("seed = 7", "seed = 8")).space.lateral, random.space.lateral);
    for s in [&lattice, &random] {
        let n = s.balls.len();
        for i in 0..n {
            let (r, [y, z]) = (s.balls[i].radius, s.space.lateral_of(i));
            let x = s.initial_positions[i] - s.initial_displacement;
            assert!(x >= r && x <= 0.1 - r && y.abs() <= 0.02 - r && z.abs() <= 0.015 - r, "ball {i} outside");
            for j in 0..i {
                let [yj, zj] = s.space.lateral_of(j);
                let xj = s.initial_positions[j] - s.initial_displacement;
                let d = ((x - xj).powi(2) + (y - yj).powi(2) + (z - zj).powi(2)).sqrt();
                assert!(d >= r + s.balls[j].radius, "balls {j} and {i} overlap");
            }
        }
    }
}

#[test]
fn models_run_beds_or_refuse_what_they_cannot_represent() {
    let dir = tempfile::tempdir().unwrap();
    let bed = dir.path().join("bed.toml");
    // The compliant model runs a bed under gravity on its spatial path (tests/it/compliant_space.rs).
    std::fs::write(&bed, bed_scene("gravity = [0.0, 0.0, -9.81]\n[bed]\ncount = 10\nradii = [0.004]\ndensity = 7800.0\n")).unwrap();
    let o = lpc(["run".as_ref(), bed.as_os_str(), "--model".as_ref(), "compliant".as_ref()]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    // The reference runs a smooth bed in space (tests/it/spatial_reference.rs), not a rough one.
    std::fs::write(&bed, bed_scene("gravity = [0.0, 0.0, -9.81]\nfriction = 0.3\n[bed]\ncount = 10\nradii = [0.004]\ndensity = 7800.0\n"))
        .unwrap();
    let o = lpc(["run".as_ref(), bed.as_os_str(), "--model".as_ref(), "reference".as_ref()]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("friction"), "{stderr}");
    // Explicit balls on one line, listed left to right, are a chain the one-line models run.
    let line = bed_scene(
        "[[ball]]\nposition = [0.02, 0.0, 0.0]\nmass = 0.1\ndensity = 8000.0\nvelocity = [1.0, 0.0, 0.0]\n\
         [[ball]]\nposition = [0.07, 0.0, 0.0]\nmass = 0.1\ndensity = 8000.0\n",
    );
    let scene = scene_from_toml(&line);
    assert!(Model::Reference.supports(&scene).is_ok());
    let run = reference(&scene).unwrap();
    assert!(!run.impacts.is_empty());
    // Listed out of order they are not a chain: the models' spatial paths run them, and the
    // same bodies meet at the same instants (the compliant model's within a contact's duration).
    let swapped = scene_from_toml(&bed_scene(
        "[[ball]]\nposition = [0.07, 0.0, 0.0]\nmass = 0.1\ndensity = 8000.0\n\
         [[ball]]\nposition = [0.02, 0.0, 0.0]\nmass = 0.1\ndensity = 8000.0\nvelocity = [1.0, 0.0, 0.0]\n",
    ));
    assert!(Model::Compliant.supports(&swapped).is_ok());
    let compliant_line = compliant(&scene).unwrap();
    let compliant_spatial = compliant(&swapped).unwrap();
    assert_eq!(compliant_spatial.impacts.len(), compliant_line.impacts.len());
    for (a, b) in compliant_spatial.impacts.iter().zip(&compliant_line.impacts) {
        assert!((a.t - b.t).abs() <= b.contact_duration.unwrap(), "{} s against {} s", a.t, b.t);
    }
    let spatial = reference(&swapped).unwrap();
    assert_eq!(spatial.impacts.len(), run.impacts.len());
    for (a, b) in spatial.impacts.iter().zip(&run.impacts) {
        assert!((a.t - b.t).abs() <= 1e-12, "{} s against {} s", a.t, b.t);
    }
}

#[test]
fn optimize_chooses_the_number_of_chains_among_whole_numbers() {
    // Refinement between 1 and 3 chains visits 2, never 1.5 (which is no scene).
    let o = lpc(["optimize", "scenes/lpc-lsl.toml", "--vary", "chains=1,3", "--format", "json"]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let chains: Vec<f64> = report["ranking"].as_array().unwrap().iter().map(|d| d["values"][0][1].as_f64().unwrap()).collect();
    assert!(chains.iter().all(|c| c.fract() == 0.0), "{chains:?}");
    let mut seen = chains.clone();
    seen.sort_by(f64::total_cmp);
    assert_eq!(seen, vec![1.0, 2.0, 3.0]);
}

#[test]
fn plots_show_each_chain_on_its_own() {
    let dir = tempfile::tempdir().unwrap();
    let o = lpc(["plot".as_ref(), "scenes/lpc-lsl-3chains.toml".as_ref(), "--out".as_ref(), dir.path().as_os_str()]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    for k in 1..=3 {
        assert!(dir.path().join(format!("positions-chain{k}.png")).is_file(), "no figure of chain {k}");
    }
    assert!(!dir.path().join("positions.png").exists());
}

#[test]
fn balls_moving_across_the_motion_write_where_they_are() {
    // A ball dropped in a box: the series carries its height, falling as gravity says until
    // it first meets the floor, and series.csv writes it after every ball's x and v.
    let text = bed_scene(
        "gravity = [0.0, 0.0, -9.81]\n[[ball]]\nposition = [0.05, 0.005, 0.008]\nmass = 0.004\nradius = 0.005\n[rapier]\ndt = 0.0001\n",
    );
    let scene = scene_from_toml(&text);
    let run = Model::Rapier.simulate(&scene, &lpc_damper::model::RunOptions::default()).unwrap();
    let s = &run.series;
    assert!(s.has_across());
    // Free fall from z0 = 8 mm to the floor's contact at z = -15 + 5 = -10 mm takes
    // sqrt(2 x 0.018 / 9.81) = 60.6 ms; at 40 ms the ball has fallen g t^2 / 2 = 7.85 mm.
    let k = s.t().iter().position(|t| (t - 0.04).abs() < 1e-9).unwrap();
    let [y, z] = s.across(0, k);
    assert!((y - 0.005).abs() <= 1e-6, "y {y}");
    // Rapier integrates gravity with symplectic Euler: the position lags by g h t / 2 at most.
    let expect = 0.008 - 0.5 * 9.81 * 0.04f64.powi(2);
    assert!((z - expect).abs() <= 0.5 * 9.81 * 1e-4 * 0.04 + 1e-6, "z {z} vs {expect}");
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("drop.toml");
    std::fs::write(&file, text.replace("horizon = 0.1", "horizon = 0.01")).unwrap();
    let out = dir.path().join("out");
    let o = lpc(["run".as_ref(), file.as_os_str(), "--model".as_ref(), "rapier".as_ref(), "--out".as_ref(), out.as_os_str()]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(out.join("series.csv")).unwrap();
    assert!(csv.lines().next().unwrap().ends_with("x1,v1,y1,z1"), "{}", csv.lines().next().unwrap());
}
