//! Bad input: every impossible scene gets an error naming the file, the field and the rule,
//! with exit status 2, no panic and nothing written.

use crate::common::lpc_command;
use std::path::Path;

const GOOD: &str = crate::common::LSL_TOML;

/// Runs `lpc run` on `text` written to a file; returns (status, stderr, out dir existed).
fn run_lpc(text: &str, extra: &[&str]) -> (i32, String, bool) {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("scene.toml");
    std::fs::write(&file, text).unwrap();
    let out = dir.path().join("out");
    let o = lpc_command().arg("run").arg(&file).arg("--out").arg(&out).args(extra).output().unwrap();
    (o.status.code().unwrap_or(-1), String::from_utf8_lossy(&o.stderr).into_owned(), out.exists())
}

fn expect_error(text: &str, extra: &[&str], field: &str, rule_words: &str) {
    let (code, stderr, wrote) = run_lpc(text, extra);
    assert_eq!(code, 2, "exit status for `{field}`: {stderr}");
    assert!(stderr.contains("scene.toml"), "file not named: {stderr}");
    assert!(stderr.contains(field), "field `{field}` not named: {stderr}");
    assert!(stderr.to_lowercase().contains(rule_words), "rule `{rule_words}` not stated: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(!wrote, "an output directory was written for `{field}`");
}

fn with(key: &str, value: &str) -> String {
    let mut done = false;
    let out: Vec<String> = GOOD
        .lines()
        .map(|l| {
            if !done && l.split('=').next().map(str::trim) == Some(key) {
                done = true;
                format!("{key} = {value}")
            } else {
                l.to_string()
            }
        })
        .collect();
    assert!(done, "no key {key}");
    out.join("\n")
}

#[test]
fn the_good_scene_runs() {
    let (code, stderr, wrote) = run_lpc(GOOD, &[]);
    assert_eq!(code, 0, "{stderr}");
    assert!(wrote);
}

#[test]
fn restitution_outside_0_1() {
    expect_error(&with("restitution", "1.5"), &[], "balls.restitution", "[0, 1]");
    expect_error(&with("restitution", "-0.1"), &[], "balls.restitution", "[0, 1]");
}

#[test]
fn non_positive_mass_density_horizon() {
    expect_error(&with("large_mass", "-0.11"), &[], "balls.large_mass", "positive");
    expect_error(&with("mass", "0.0"), &[], "frame.mass", "positive");
    expect_error(&with("density", "0"), &[], "balls.density", "positive");
    expect_error(&with("horizon", "-5.0"), &[], "run.horizon", "positive");
    expect_error(GOOD, &["--horizon", "0"], "--horizon", "positive");
    // Issue 19: numbers for people, not a 300-digit sample count.
    expect_error(GOOD, &["--horizon", "1e300"], "run.sample_dt", "would write 1e303 samples over 1e300 s");
}

#[test]
fn negative_stiffness_damping_gap_clearance() {
    expect_error(&with("stiffness", "-865.0"), &[], "frame.stiffness", "negative");
    expect_error(&with("damping", "-1.0"), &[], "frame.damping", "negative");
    expect_error(&with("gap", "\"-0.25 Rr\""), &[], "balls.gap", "overlap");
    expect_error(&with("clearance", "-0.001"), &[], "balls.clearance", "negative");
}

#[test]
fn nan_and_infinity() {
    expect_error(&with("damping", "nan"), &[], "frame.damping", "finite");
    expect_error(&with("initial_displacement", "inf"), &[], "frame.initial_displacement", "finite");
    expect_error(&with("mass_ratio", "-inf"), &[], "balls.mass_ratio", "finite");
}

#[test]
fn unknown_letters_and_keys() {
    expect_error(&with("arrangement", "\"LXL\""), &[], "balls.arrangement", "unknown letter");
    let extra = GOOD.replace("[run]", "[run]\nhorizn = 3.0");
    expect_error(&extra, &[], "horizn", "unknown field");
}

#[test]
fn balls_that_cannot_fit() {
    let text = with("clearance", "0.0").replace("clearance = 0.0", "container_length = 0.05");
    expect_error(&text, &[], "balls.container_length", "cannot fit");
}

#[test]
fn absurd_output_step() {
    expect_error(&with("sample_dt", "10.0"), &[], "run.sample_dt", "longer than the horizon");
    expect_error(&with("sample_dt", "1e-9"), &[], "run.sample_dt", "samples");
    expect_error(GOOD, &["--sample-dt=-1"], "--sample-dt", "positive");
}

#[test]
fn not_toml_at_all() {
    let (code, stderr, wrote) = run_lpc("this is [not toml", &[]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("scene.toml") && !wrote);
}

#[test]
fn missing_file() {
    let o = lpc_command().args(["run", "no/such/scene.toml"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("no/such/scene.toml") && stderr.contains("cannot read"), "{stderr}");
}

#[test]
fn every_shipped_scene_is_valid() {
    for entry in std::fs::read_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")).unwrap() {
        let p = entry.unwrap().path();
        if p.extension().is_none_or(|x| x != "toml") {
            continue; // records/ and other companions of the scenes
        }
        lpc_damper::scene::load(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    }
}

#[test]
fn impossible_forcing_and_material() {
    let forced = |body: &str| format!("{GOOD}\n[forcing]\n{body}\n");
    expect_error(&forced("kind = \"force\"\namplitude = -1.0\nfrequency = 4.0"), &[], "forcing.amplitude", "negative");
    expect_error(&forced("kind = \"force\"\namplitude = 1.0\nfrequency = 0.0"), &[], "forcing.frequency", "positive");
    expect_error(&forced("kind = \"force\"\namplitude = nan\nfrequency = 4.0"), &[], "forcing.amplitude", "finite");
    expect_error(&forced("kind = \"shake\"\namplitude = 1.0\nfrequency = 4.0"), &[], "kind", "unknown variant");
    // An undamped frame driven exactly at its natural frequency sqrt(865/1.35)/2pi.
    let undamped = with("damping", "0.0");
    let f0 = (865.0f64 / 1.35).sqrt() / (2.0 * std::f64::consts::PI);
    let resonant = format!("{undamped}\n[forcing]\nkind = \"force\"\namplitude = 1.0\nfrequency = {f0:?}\n");
    expect_error(&resonant, &[], "forcing.frequency", "resonance");
    expect_error(&format!("{GOOD}\n[compliant]\npoisson_ratio = 0.5\n"), &[], "compliant.poisson_ratio", "(-1, 0.5)");
    expect_error(&format!("{GOOD}\n[compliant]\nyoungs_modulus = -2e11\n"), &[], "compliant.youngs_modulus", "positive");
    for (duration, rule) in [("0.0", "positive"), ("nan", "finite"), ("-1e-6", "positive"), ("0.5", "no impact")] {
        expect_error(&format!("{GOOD}\n[reference]\ncontact_duration = {duration}\n"), &[], "reference.contact_duration", rule);
    }
}

#[test]
fn model_errors_print_times_for_people() {
    // Issue 19: a stall at t = 1.916e-6 s printed `0.000001916413341752815 s`.
    use lpc_damper::model::{Budget, ModelError, OverBudget};
    use lpc_damper::Model;
    let e = ModelError::Stalled { scene: "s".into(), model: Model::Reference, steps: 7, t: 1.916413341752815e-6, why: "w".into() };
    assert!(e.to_string().contains("at t = 1.916e-6 s"), "{e}");
    let e = OverBudget {
        scene: "s".into(),
        model: Model::Compliant,
        t: 0.30000000000000004,
        horizon: 5.0,
        steps: 7,
        wall_s: 600.0000001,
        budget: Budget::WallTime,
        limit: 600.0,
        cost: "d".into(),
        partial: lpc_damper::run::Run::empty("s", Model::Compliant),
    };
    assert!(e.to_string().contains("at t = 0.3 s of 5 s after 7 steps and 600.0 s of computing"), "{e}");
}

/// A scene of explicit balls or a bed in a 0.1 x 0.04 x 0.03 m box, `body` its balls' tables.
fn boxed(body: &str) -> String {
    format!(
        "[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 1.092\ninitial_displacement = 0.01\n\
         [container]\nlength = 0.1\nwidth = 0.04\nheight = 0.03\n[world]\nrestitution = 0.6\n{body}\n"
    )
}

const BALL: &str = "[[ball]]\nposition = [0.05, 0.0, 0.0]\nmass = 0.01\nradius = 0.007\n";

#[test]
fn chains_containers_beds_and_explicit_balls() {
    let chains = |n: &str| GOOD.replace("arrangement = \"LSL\"", &format!("arrangement = \"LSL\"\nchains = {n}"));
    expect_error(&chains("0"), &[], "balls.chains", "1..=10000");
    expect_error(&format!("{}\n[container]\nwidth = \"2.5 Rr\"\n", chains("2")), &[], "container.width", "narrower");
    expect_error(&format!("{}\n[container]\nlength = 0.2\n", chains("2")), &[], "container.length", "eq. 11");
    expect_error(&format!("{GOOD}\n[world]\nrestitution = 0.5\n"), &[], "world.restitution", "give one");
    expect_error(&format!("{GOOD}\n[world]\nfriction = -0.1\n"), &[], "world.friction", "negative");
    expect_error(&format!("{GOOD}\n[world]\ngravity = [0.0, nan, 0.0]\n"), &[], "world.gravity[1]", "finite");
    expect_error(&format!("{}\n{BALL}", GOOD), &[], "ball", "cannot be combined with [balls]");
    expect_error(&boxed(BALL).replace("[world]\nrestitution = 0.6\n", ""), &[], "world.restitution", "missing");
    expect_error(&boxed(BALL).replace("width = 0.04\n", ""), &[], "container.width", "missing");
    expect_error(&boxed(&BALL.replace("0.05, 0.0, 0.0", "0.05, 0.0, 0.01")), &[], "ball[0].position", "outside the container along z");
    expect_error(&boxed(&format!("{BALL}{}", BALL.replace("0.05, 0.0", "0.06, 0.0"))), &[], "ball[1].position", "overlap ball[0]");
    expect_error(&boxed(&BALL.replace("mass = 0.01", "mass = -1.0")), &[], "ball[0].mass", "positive");
    expect_error(&boxed(&format!("{BALL}density = 7800.0\n")), &[], "ball[0].radius", "give one");
    let bed = "[bed]\ncount = 100\nradii = [0.005]\ndensity = 7800.0\n";
    expect_error(&boxed(&bed.replace("100", "1000")), &[], "bed", "holds at most");
    expect_error(&boxed(&bed.replace("count = 100", "fill_fraction = 0.6")), &[], "bed.fill_fraction", "pi/6");
    expect_error(&boxed(&format!("{bed}fill_fraction = 0.1\n")), &[], "bed.fill_fraction", "give one");
    expect_error(&boxed(&format!("{bed}proportions = [1.0, 2.0]\n")), &[], "bed.proportions", "one per size");
    expect_error(&boxed(&bed.replace("[0.005]", "[0.02]")), &[], "bed", "cannot be placed");
    expect_error(&boxed(&format!("{}placement = \"random\"\n", bed.replace("count = 100", "fill_fraction = 0.5"))), &[], "bed", "random");
}
