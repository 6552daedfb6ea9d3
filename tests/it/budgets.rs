//! Every model reports where it stands as it runs, and stops at a step budget with the run so
//! far: what a user's script or batch job sees of a long run (the cost announced from the
//! progress, a budget that bounds it).

use lpc_damper::model::{Budget, Limits, Model, ModelError, Progress, RunOptions};
use lpc_damper::run::ImpactRecord;
use lpc_damper::scene::{load_scene, scenes_dir};

/// A finished run has reported its end: the horizon reached, and as many steps as it took
/// (the reference: its events; the contact model: its steps).
#[test]
fn every_model_reports_its_progress() {
    let scene = load_scene(scenes_dir().join("lpc-lsl.toml")).unwrap();
    for &model in Model::ALL {
        let progress = Progress::default();
        let run = model.simulate(&scene, &RunOptions { progress: Some(&progress), ..RunOptions::default() }).unwrap();
        assert_eq!(progress.time(), run.horizon, "{model}");
        assert!(progress.steps() >= run.events && progress.steps() > 0, "{model}: {} steps, {} events", progress.steps(), run.events);
    }
}

/// A step budget stops every model part way with the run so far: its samples end by the time
/// reached, its impacts happened before it, and the impulse models' energy balance closes.
#[test]
fn a_step_budget_stops_every_model_with_the_run_so_far() {
    let scene = load_scene(scenes_dir().join("lpc-lsl.toml")).unwrap();
    for (model, budget) in [(Model::Reference, 40), (Model::Rapier, 300), (Model::Compliant, 3000)] {
        let err = model.simulate(&scene, &RunOptions::limited(Limits { max_steps: Some(budget), ..Limits::NONE })).unwrap_err();
        let message = err.to_string();
        let ModelError::OverBudget(stop) = err else { panic!("{model}: {message}") };
        assert_eq!(stop.budget, Budget::Steps);
        assert!(message.contains(&format!("more than {budget} {}", model.step_unit())) && message.contains("--max-steps"), "{message}");
        let partial = &stop.partial;
        assert!(stop.t > 0.0 && stop.t < scene.horizon && partial.horizon == stop.t, "{model}: stopped at {}", stop.t);
        assert!(!partial.series.is_empty() && *partial.series.t().last().unwrap() <= stop.t, "{model}");
        assert!(partial.impacts.iter().all(|i| i.t <= stop.t), "{model}");
        assert!(!partial.impacts.is_empty(), "{model}: the budget leaves some impacts");
        if model == Model::Reference {
            assert!(partial.energy.balance_error.abs() < 1e-12, "{:?}", partial.energy);
        }
    }
}

/// Every command that runs a model takes the budgets, checks them before any work (exit 2,
/// the flag named, nothing written), and gives each run of a study the same budget: a frequency
/// response whose runs all exceed it reports each frequency's stop and exits 1.
#[test]
fn every_command_takes_the_budgets() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let out = out.to_str().unwrap();
    for args in [
        vec!["sweep", "scenes/sweep-gap.toml", "--max-steps", "0", "--out", out],
        vec!["compare", "scenes/lpc-lsl.toml", "--max-wall-time=-1", "--out", out],
        vec!["frf", "scenes/forced-lsl.toml", "--freq", "3..4", "--max-wall-time", "nan", "--out", out],
        vec!["chain", "scenes/chain-ker.toml", "--max-steps", "0", "--out", out],
        vec!["plot", "scenes/lpc-lsl.toml", "--max-steps", "0", "--out", out],
        vec!["optimize", "scenes/lpc-lsl.toml", "--max-steps", "0", "--out", out],
    ] {
        let output = crate::common::lpc(&args);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
        let flag = args.iter().find(|a| a.starts_with("--max")).unwrap().split('=').next().unwrap();
        assert!(stderr.contains(flag), "{args:?}: {stderr}");
        assert!(!dir.path().join("out").exists(), "{args:?} wrote its outputs");
    }
    let output =
        crate::common::lpc(["frf", "scenes/forced-lsl.toml", "--freq", "3..4", "--steps", "2", "--max-steps", "5", "--format", "json"]);
    assert_eq!(output.status.code(), Some(1), "{}", String::from_utf8_lossy(&output.stderr));
    let points: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let points = points.as_array().unwrap();
    assert_eq!(points.len(), 2);
    for p in points {
        assert!(p["amplitude"].is_null(), "{p}");
        assert!(p["error"].as_str().unwrap().contains("--max-steps"), "{p}");
    }
}

/// A run that counts its impacts instead of keeping them (what a long run of a pile needs)
/// is the run that keeps them, less the list: every model gives the same count, energy
/// account and peak contact force either way, and so does its run so far at a budget.
#[test]
fn every_model_counts_its_impacts_when_asked() {
    let scene = load_scene(scenes_dir().join("lpc-lsl.toml")).unwrap();
    let counting = RunOptions { impacts: ImpactRecord::Count, ..RunOptions::default() };
    for (model, budget) in [(Model::Reference, 40), (Model::Rapier, 300), (Model::Compliant, 3000)] {
        let every = model.simulate(&scene, &RunOptions::default()).unwrap();
        let counted = model.simulate(&scene, &counting).unwrap();
        assert!(counted.impacts.is_empty() && every.impacts.len() > 10, "{model}: {} impacts", every.impacts.len());
        assert_eq!(counted.impact_count(), every.impacts.len(), "{model}");
        assert_eq!((counted.energy, counted.peak_contact_force()), (every.energy, every.peak_contact_force()), "{model}");
        let limits = Limits { max_steps: Some(budget), ..Limits::NONE };
        let stopped = |options: RunOptions| match model.simulate(&scene, &RunOptions { limits, ..options }) {
            Err(ModelError::OverBudget(stop)) => stop.partial,
            other => panic!("{model}: {:?}", other.map(|r| r.horizon)),
        };
        let (every, counted) = (stopped(RunOptions::default()), stopped(counting));
        assert!(counted.impacts.is_empty() && !every.impacts.is_empty(), "{model}");
        assert_eq!((counted.impact_count(), counted.energy), (every.impacts.len(), every.energy), "{model}");
    }
}

/// `lpc run --impacts count --out` writes the series and a summary that says the list was not
/// kept, with the count of the run that keeps it; it writes no `impacts.csv`, and removes an
/// older one, which would be read as this run's. With `--ensemble`, the nominal run it writes
/// beside the members counts its impacts too.
#[test]
fn a_run_that_counts_its_impacts_writes_no_list() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("impacts.csv"), "t,body_a,body_b\n").unwrap();
    let out = dir.path().to_str().unwrap();
    let args = ["run", "scenes/planar-bed.toml", "--horizon", "0.05", "--format", "json"];
    let every = crate::common::lpc(args);
    assert_eq!(every.status.code(), Some(0), "{}", String::from_utf8_lossy(&every.stderr));
    let every: serde_json::Value = serde_json::from_slice(&every.stdout).unwrap();
    let counted = crate::common::lpc(args.iter().chain(&["--impacts", "count", "--out", out]));
    assert_eq!(counted.status.code(), Some(0), "{}", String::from_utf8_lossy(&counted.stderr));
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.path().join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["impacts_not_kept"], true);
    assert!(every.get("impacts_not_kept").is_none());
    assert_eq!(summary["impact_count"], every["impact_count"]);
    assert!(every["impact_count"].as_u64().unwrap() > 100 && summary["impacts"].as_array().unwrap().is_empty());
    assert_eq!(summary["energy"], every["energy"]);
    assert!(dir.path().join("series.csv").exists() && !dir.path().join("impacts.csv").exists());
    // An ensemble's nominal run, which --out writes beside the members, counts them too.
    let ensemble = dir.path().join("ensemble");
    let args = ["run", "scenes/planar-bed.toml", "--horizon", "0.05", "--ensemble", "2", "--impacts", "count", "--out"];
    let counted = crate::common::lpc(args.iter().map(std::ffi::OsStr::new).chain([ensemble.as_os_str()]));
    assert_eq!(counted.status.code(), Some(0), "{}", String::from_utf8_lossy(&counted.stderr));
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(ensemble.join("summary.json")).unwrap()).unwrap();
    assert_eq!((&summary["impacts_not_kept"], &summary["impact_count"]), (&serde_json::json!(true), &every["impact_count"]));
    assert!(ensemble.join("members.csv").exists() && !ensemble.join("impacts.csv").exists());
    let bad = crate::common::lpc(["run", "scenes/planar-bed.toml", "--impacts", "some"]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--impacts"), "{}", String::from_utf8_lossy(&bad.stderr));
}
