//! Beds and boxes of balls carried by a structure's floor, under ground-motion records
//! (docs/MODEL.md §16-17): every model runs them (the reference when they are frictionless),
//! the same box on a frame and on the one-storey structure that frame is gives the same run,
//! and every run passes the checks the stress study applies.

use lpc_damper::model::{Model, RunOptions};
use lpc_damper::run::Run;
use lpc_damper::scene::Scene;
use lpc_damper::studies::stress::judge;

/// A box of `count` balls (radius 5 mm, steel, frictionless or not) on `carrier`, text that
/// ends in a table of the carrier's own. The reference's contact duration is long enough that
/// the balls resting on the floor under gravity cost little (docs/MODEL.md §14).
fn box_on(carrier: &str, count: usize, friction: f64, horizon: f64) -> String {
    format!(
        "{carrier}\n\
         [container]\nlength = 0.06\nwidth = 0.04\nheight = 0.05\n\
         [world]\ngravity = [0.0, 0.0, -9.81]\nfriction = {friction}\nrestitution = 0.6\n\
         [bed]\ncount = {count}\nradii = [0.005]\ndensity = 7800.0\nplacement = \"lattice\"\n\
         [compliant]\nyoungs_modulus = 2e9\n\
         [rapier]\ndt = 0.0005\n\
         [reference]\ncontact_duration = 1e-4\n\
         [run]\nhorizon = {horizon}\nsample_dt = 0.001\n"
    )
}

fn record() -> String {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/records/synthetic-kt.csv").display().to_string()
}

fn scene(text: &str) -> Scene {
    lpc_damper::scene::parse(text, "bed-on-structure.toml", "bed-on-structure").unwrap().scene.unwrap()
}

fn run(model: Model, scene: &Scene) -> Run {
    let run = model.simulate(scene, &RunOptions::default()).unwrap_or_else(|e| panic!("{model}: {e}"));
    judge(model, scene, &run).unwrap_or_else(|f| panic!("{model}: {} {}", f.check, f.detail));
    run
}

/// The three-storey building of scenes/mdof-3storey-record.toml, the box on its top floor.
fn building(scale: f64) -> String {
    format!(
        "[structure]\nmasses = [1.35, 1.35, 1.35]\nstiffnesses = [4364.0, 4364.0, 4364.0]\n\
         damping_ratios = [0.016, 0.016, 0.016]\ndamper_floor = 3\n\
         [forcing]\nkind = \"record\"\nfile = \"{}\"\nscale = {scale}\n",
        record()
    )
}

/// The reference runs the frictionless copy: its friction is the only thing it refuses.
#[test]
fn a_box_on_a_building_under_a_record_runs_in_every_model_and_passes_the_checks() {
    let s = scene(&box_on(&building(2.0), 12, 0.3, 2.5));
    assert!(Model::Reference.supports(&s).unwrap_err().contains("friction"));
    let smooth = scene(&box_on(&building(2.0), 12, 0.0, 2.5));
    for (model, s) in [(Model::Rapier, &s), (Model::Compliant, &s), (Model::Reference, &smooth)] {
        let r = run(model, s);
        assert_eq!(r.series.floor_count(), 3, "{model}: every floor is written");
        assert!(r.impact_count() > 0, "{model}: the record throws the balls about");
        assert!(r.energy.forcing_work != 0.0, "{model}: the ground does work");
    }
}

/// A frame under a record of a still ground is a one-storey structure (the floors' closed form
/// in the contact model and the reference, the floors' own Verlet step in the compliant model)
/// with the frame's motion: the same run as on the frame, to round-off.
#[test]
fn a_box_on_a_frame_under_a_still_record_is_the_box_on_the_frame() {
    let dir = tempfile::tempdir().unwrap();
    let still = dir.path().join("still.csv");
    std::fs::write(&still, "time_s,accel_m_s2\n0.0,0.0\n1.0,0.0\n").unwrap();
    let frame = "[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 1.092\ninitial_displacement = 0.01\n";
    let on_frame = scene(&box_on(frame, 8, 0.0, 0.1));
    let on_record = scene(&box_on(&format!("{frame}[forcing]\nkind = \"record\"\nfile = \"{}\"\n", still.display()), 8, 0.0, 0.1));
    assert!(on_frame.structure.is_none() && on_record.structure.is_some());
    for model in [Model::Rapier, Model::Compliant, Model::Reference] {
        let (a, b) = (run(model, &on_frame), run(model, &on_record));
        let worst = a.series.xs().iter().zip(b.series.xs()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(worst <= 1e-9, "{model}: the frame's displacement differs by {worst:e} m");
        assert_eq!(a.impact_count(), b.impact_count(), "{model}");
    }
}

/// The shipped particle box on a building loads, the contact and compliant models accept it,
/// and the reference accepts its frictionless copy only.
#[test]
fn the_shipped_particle_box_on_a_building_loads_and_every_model_accepts_it() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/particle-box-building.toml");
    let mut s = lpc_damper::scene::load_scene(&path).unwrap();
    assert_eq!(s.balls.len(), 300);
    assert_eq!(s.structure.as_ref().map(|st| st.floors()), Some(3));
    assert!(Model::Reference.supports(&s).unwrap_err().contains("friction"));
    let mut smooth = s.clone();
    smooth.space.friction = 0.0;
    assert!(Model::Reference.supports(&smooth).is_ok(), "{:?}", Model::Reference.supports(&smooth));
    // Its first 20 ms in the contact model pass the stress checks.
    s.horizon = 0.02;
    let r = run(Model::Rapier, &s);
    assert_eq!(r.series.floor_count(), 3);
    assert!(Model::Compliant.supports(&s).is_ok());
}

/// `lpc compare` on a box with friction refuses to put the reference beside it unless asked,
/// naming the flag; with `--frictionless-reference` the reference's run is its run of the
/// frictionless copy, and the JSON says which friction each side ran with.
#[test]
fn compare_puts_the_reference_on_the_frictionless_copy_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("box.toml");
    std::fs::write(&path, format!("name = \"box\"\n{}", box_on(&building(2.0), 12, 0.3, 0.5))).unwrap();
    let p = path.to_str().unwrap();
    let refused = crate::common::lpc(["compare", p, "--models", "rapier", "--format", "json"]);
    assert_eq!(refused.status.code(), Some(1));
    assert!(refused.stdout.is_empty());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("--frictionless-reference"));
    let out = crate::common::lpc(["compare", p, "--models", "rapier", "--format", "json", "--frictionless-reference"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!((v["friction"].as_f64(), v["reference_friction"].as_f64()), (Some(0.3), Some(0.0)));
    let smooth = scene(&box_on(&building(2.0), 12, 0.0, 0.5));
    let direct = Model::Reference.simulate(&smooth, &RunOptions::default()).unwrap();
    assert_eq!(v["reference"]["impact_count"].as_u64(), Some(direct.impact_count() as u64));
    assert!(v["models"]["rapier"]["errors"]["rms_xs"].as_f64().is_some());
}

/// An ensemble of a box placed at random on a building shaken at random: every member draws its
/// own bed and its own ground motion (from the seed and its index), and every model runs them.
#[test]
fn an_ensemble_draws_a_bed_and_a_ground_motion_per_member() {
    let shaken = building(1.0).replace(
        &format!("kind = \"record\"\nfile = \"{}\"\nscale = 1\n", record()),
        "kind = \"random\"\nground_frequency = 2.5\nground_damping = 0.6\nintensity = 4.0e-4\nduration = 5.0\nstep = 0.01\nseed = 1\n",
    );
    let text = box_on(&shaken, 12, 0.0, 0.3).replace("\"lattice\"", "\"random\"");
    let loaded = lpc_damper::scene::parse(&text, "box.toml", "box").unwrap();
    let nominal = loaded.scene.as_ref().unwrap();
    let members = lpc_damper::studies::ensemble::draw(&loaded.file, &loaded.path, nominal, None, 3, Some(7)).unwrap();
    let (a, b) = (&members.members[0].scene, &members.members[1].scene);
    assert_ne!(a.initial_positions, b.initial_positions, "each member places its own bed");
    let ground = |s: &Scene| s.structure.as_ref().and_then(|st| st.ground.as_ref()).map(|g| g.accel.clone()).unwrap();
    assert_ne!(ground(a), ground(b), "each member draws its own ground motion");
    for model in [Model::Reference, Model::Rapier, Model::Compliant] {
        for m in &members.members {
            run(model, &m.scene);
        }
    }
}

/// The damper's size is a design variable of sweeps and optimize: `ball_count` sets a bed's
/// number of balls (a whole number) and `ball_radius` its largest radius, every size scaled
/// alike; a count that is not whole is refused with the field.
#[test]
fn sweeps_size_a_bed_by_its_count_and_radius() {
    use lpc_damper::scene::{format::Length, Parameter};
    let text = box_on(&building(2.0), 12, 0.3, 0.5).replace("radii = [0.005]", "radii = [0.005, 0.0025]");
    let loaded = lpc_damper::scene::parse(&text, "box.toml", "box").unwrap();
    let nominal = loaded.scene.as_ref().unwrap();
    assert_eq!(Parameter::BallCount.value(&loaded.file, nominal), Some(12.0));
    assert_eq!(Parameter::BallRadius.value(&loaded.file, nominal), Some(0.005));
    let file = Parameter::BallCount.apply(&loaded.file, Length::Metres(6.0)).unwrap();
    let file = Parameter::BallRadius.apply(&file, Length::Metres(0.004)).unwrap();
    let sized = lpc_damper::scene::from_file(file.clone(), "box", "box").unwrap().scene.unwrap();
    assert_eq!(sized.balls.len(), 6);
    let radii: Vec<f64> = sized.balls.iter().map(|b| b.radius).collect();
    let (largest, smallest) = (radii.iter().copied().fold(0.0, f64::max), radii.iter().copied().fold(1.0, f64::min));
    assert!((largest - 0.004).abs() <= 1e-15 && (smallest - 0.002).abs() <= 1e-15, "{radii:?}");
    assert_eq!(Parameter::BallCount.value(&file, &sized), Some(6.0));
    assert!(Parameter::BallCount.is_count());
    let err = Parameter::BallCount.apply(&loaded.file, Length::Metres(2.5)).unwrap_err();
    assert!(err.contains("ball_count") && err.contains("whole number"), "{err}");
}
