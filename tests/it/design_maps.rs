//! Design maps and design search: grids of two parameters (`lpc sweep --x --y`), the heat map,
//! `lpc optimize` against an exhaustive evaluation, `lpc frf` files, and the noise proxy.

use crate::common::{self, reference};

use lpc_damper::metrics::{metrics, noise};
use lpc_damper::scene::{self, Length};
use lpc_damper::studies::optimize::{optimize, Judging, Objective};
use lpc_damper::studies::sweep::{grid_scenes, parse_axis};

fn paper(name: &str) -> scene::Loaded {
    scene::load(scene::scenes_dir().join(name)).unwrap()
}

/// `lpc ARGS...`: its exit code, standard output and standard error.
fn lpc(args: &[&str]) -> (i32, String, String) {
    let o = common::lpc(args);
    (o.status.code().unwrap_or(-1), String::from_utf8_lossy(&o.stdout).into_owned(), String::from_utf8_lossy(&o.stderr).into_owned())
}

#[test]
fn a_grid_varies_the_first_axis_fastest_and_applies_both_values() {
    let loaded = paper("lpc-lsl.toml");
    let axes = [parse_axis("clearance=0.5Rr..1.5Rr:3").unwrap(), parse_axis("mass_ratio=2,10").unwrap()];
    let grid = grid_scenes(&loaded, &axes).unwrap();
    assert_eq!(grid.len(), 6);
    let rr = loaded.scene.as_ref().unwrap().reference_radius;
    for (k, g) in grid.iter().enumerate() {
        let (cx, my) = ([0.5, 1.0, 1.5][k % 3], [2.0, 10.0][k / 3]);
        assert_eq!(g.values, vec![cx, my]);
        let c = g.scene.container.unwrap();
        assert!((c.clearance - cx * rr).abs() <= 1e-15, "{}", g.scene.name);
        let (l, s) = (g.scene.balls[0].mass, g.scene.balls[1].mass);
        assert!((l / s - my).abs() <= 1e-12);
    }
}

#[test]
fn axes_parse_lists_and_ranges_and_reject_the_rest() {
    let a = parse_axis("gap=0.1Rr..0.5Rr:5").unwrap();
    assert_eq!(a.values.len(), 5);
    assert!(matches!(a.values[4], Length::Rr(x) if (x - 0.5).abs() < 1e-15));
    assert_eq!(parse_axis("restitution=0.5, 0.9").unwrap().values, vec![Length::Metres(0.5), Length::Metres(0.9)]);
    // Evenly spaced values read as written.
    let g = parse_axis("gap=0.1..0.7:5").unwrap();
    assert_eq!(g.values.iter().map(|v| v.raw()).collect::<Vec<_>>(), vec![0.1, 0.25, 0.4, 0.55, 0.7]);
    for bad in ["colour=1,2", "gap", "gap=1..2", "gap=1Rr..2:3", "gap=a,b", "gap=1..2:1"] {
        assert!(parse_axis(bad).is_err(), "{bad}");
    }
}

#[test]
fn the_sweep_command_writes_a_grid_and_its_heat_map() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("map");
    let scene = scene::scenes_dir().join("lpc-lsl.toml");
    let (code, stdout, stderr) = lpc(&[
        "sweep",
        scene.to_str().unwrap(),
        "--x",
        "clearance=0.5Rr,1Rr,2Rr",
        "--y",
        "mass_ratio=2,10",
        "--metric",
        "energy_remaining",
        "--format",
        "json",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    let points: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let points = points.as_array().unwrap();
    assert_eq!(points.len(), 6);
    assert_eq!(points[4]["parameter_y"], "mass_ratio");
    assert_eq!(points[4]["value_y"], 10.0);
    assert_eq!(points[4]["value"], 1.0);
    let png = std::fs::File::open(out.join("sweep-map.png")).unwrap();
    let info = png::Decoder::new(std::io::BufReader::new(png)).read_info().unwrap();
    assert_eq!((info.info().width, info.info().height), (900, 640));
    assert!(std::fs::read_to_string(out.join("sweep-map.svg")).unwrap().contains("energy_remaining"));
    // Bad axes and metrics are bad input (exit 2) naming the flag.
    for (flag, args) in [("--x", vec!["--x", "colour=1,2"]), ("--metric", vec!["--x", "gap=0.1Rr,0.2Rr", "--metric", "loudness"])] {
        let mut all = vec!["sweep", scene.to_str().unwrap()];
        all.extend(args);
        let (code, _, stderr) = lpc(&all);
        assert_eq!(code, 2, "{stderr}");
        assert!(stderr.contains(flag) && !stderr.contains("panicked"), "{stderr}");
    }
}

#[test]
fn optimize_finds_the_best_of_an_exhaustive_evaluation() {
    let loaded = paper("lpc-lsl.toml");
    let length = loaded.scene.as_ref().unwrap().container.unwrap().length;
    let axes = [parse_axis("gap=0.1Rr,0.25Rr,0.5Rr,0.75Rr").unwrap()];
    let arrangements = ["LSL".to_string(), "LLLLLLLL".to_string()];
    let search = optimize(
        &loaded,
        &axes,
        &arrangements,
        Length::Metres(length),
        Judging {
            objective: Objective::SettlingTime,
            model: lpc_damper::Model::Reference,
            limits: lpc_damper::model::Limits::NONE,
            refinements: 0,
            robust: None,
        },
        &|| {},
    )
    .unwrap();
    // Eight large balls (8 x 29.7 mm) do not fit a 114 mm container.
    assert_eq!(search.infeasible, 4);
    // Exhaustive evaluation, built independently from scene text.
    let mut best = (f64::INFINITY, 0.0);
    for gap in [0.1, 0.25, 0.5, 0.75] {
        let text = std::fs::read_to_string(scene::scenes_dir().join("lpc-lsl.toml"))
            .unwrap()
            .replace("gap = \"0.25 Rr\"", &format!("gap = \"{gap} Rr\""))
            .replace("clearance = \"2 Rr\"", &format!("container_length = {length:?}"));
        let s = scene::parse(&text, "t", "t").unwrap().scene.unwrap();
        let settle = metrics(&reference(&s).unwrap()).settling_time.unwrap_or(f64::INFINITY);
        if settle < best.0 {
            best = (settle, gap);
        }
    }
    let found = search.best.unwrap();
    assert_eq!(found.values, vec![("gap".to_string(), best.1)]);
    assert_eq!(found.objective, Some(best.0));
    assert_eq!(search.ranking.len(), 4);
}

#[test]
fn the_noise_proxy_summarises_the_impact_list() {
    let s = paper("lpc-lsl.toml").scene.unwrap();
    let run = reference(&s).unwrap();
    let n = noise(&run);
    assert_eq!(n.impact_rate, run.impacts.len() as f64 / s.horizon);
    let e = n.energy_lost.unwrap();
    let max = run.impacts.iter().map(|i| i.energy_lost).fold(0.0, f64::max);
    assert_eq!(e.max, max);
    assert!(e.mean <= e.p95 && e.p95 <= e.max);
    assert!(n.wall_energy_lost.unwrap().max <= e.max);
    assert!(n.peak_force.is_none(), "impulse models have no contact force");
    assert!((e.mean * run.impacts.len() as f64 / run.energy.impact_loss - 1.0).abs() < 1e-12);
}

#[test]
fn the_frf_command_writes_its_table_and_plot() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("frf");
    let scene = scene::scenes_dir().join("forced-lsl.toml");
    let (code, stdout, stderr) =
        lpc(&["frf", scene.to_str().unwrap(), "--freq", "3..5", "--steps", "3", "--format", "json", "--out", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{stderr}");
    let points: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let points = points.as_array().unwrap();
    assert_eq!(points.len(), 3);
    for (p, f) in points.iter().zip([3.0, 4.0, 5.0]) {
        assert_eq!(p["frequency"], f);
        assert!(p["amplitude"].as_f64().unwrap() > 0.0 && p["amplitude_no_damper"].as_f64().unwrap() > 0.0);
    }
    for f in ["frf.json", "frf.csv", "frf.png", "frf.svg"] {
        assert!(out.join(f).exists(), "{f}");
    }
    // A scene without forcing needs --amplitude: bad input naming the table.
    let bare = scene::scenes_dir().join("lpc-lsl.toml");
    let (code, _, stderr) = lpc(&["frf", bare.to_str().unwrap(), "--freq", "3..5"]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("forcing"), "{stderr}");
    let (code, _, stderr) = lpc(&["frf", bare.to_str().unwrap(), "--freq", "5..3", "--amplitude", "1"]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("--freq"), "{stderr}");
    // An undamped frame has no steady state at its natural frequency (4.0 Hz): a sweep over
    // it is refused by the same rule as a scene forced there.
    let dir = tempfile::tempdir().unwrap();
    let undamped = dir.path().join("undamped.toml");
    std::fs::write(&undamped, std::fs::read_to_string(&bare).unwrap().replace("damping = 1.092", "damping = 0.0")).unwrap();
    let (code, _, stderr) = lpc(&["frf", undamped.to_str().unwrap(), "--freq", "3..5", "--amplitude", "1"]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("--freq") && stderr.contains("resonance"), "{stderr}");
}
