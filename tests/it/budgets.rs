//! Every model reports where it stands as it runs, and stops at a step budget with the run so
//! far: what a user's script or batch job sees of a long run (the cost announced from the
//! progress, a budget that bounds it).

use lpc_damper::model::{Budget, Model, ModelError, Progress, RunOptions};
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
        let err = model.simulate(&scene, &RunOptions { max_steps: Some(budget), ..RunOptions::default() }).unwrap_err();
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
