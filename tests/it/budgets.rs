//! Every model reports where it stands as it runs, and stops at a step budget with the run so
//! far: what a user's script or batch job sees of a long run (the cost announced from the
//! progress, a budget that bounds it).

use lpc_damper::model::{Budget, Limits, Model, ModelError, Progress, RunOptions};
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
