//! Issue 12 (found while writing `examples/bevy_app.rs`): in an app driven by `app.update()`,
//! as the user guide tells a Bevy user to drive the plug-in, bevy_rapier copies a changed
//! `Velocity` component back into its body before each step. It had written the step's
//! velocity there before the plug-in's feedback corrected the body (the bounce Rapier skipped),
//! so every correction was undone one step later and the run drifted millimetres from the
//! headless model within 0.2 s. The feedback now keeps the component equal to the body.

use lpc_damper::model::{Model, RunOptions};
use lpc_damper::rapier::{collect, settings, LpcDamperPlugins, StepClock};
use lpc_damper::scene::{load_scene, scenes_dir, Overrides};

use bevy::prelude::*;

#[test]
fn the_plugin_in_a_users_app_runs_the_headless_model() {
    let scene = load_scene(scenes_dir().join("lpc-lsl.toml")).unwrap();
    let scene = Overrides { horizon: Some(0.5), ..Overrides::default() }.apply(scene, "lpc-lsl").unwrap();
    let headless = Model::Rapier.simulate(&scene, &RunOptions::default()).unwrap();
    let mut app = App::new();
    app.init_resource::<Time>().add_plugins(LpcDamperPlugins {
        scene: scene.clone(),
        settings: settings(&scene),
        record: lpc_damper::run::Record::Series,
    });
    app.finish();
    app.cleanup();
    while app.world().get_resource::<StepClock>().is_none_or(|c| c.t < scene.horizon * (1.0 - 1e-12)) {
        app.update();
    }
    let steps = app.world().resource::<StepClock>().steps;
    let driven = collect(app.world_mut(), &scene, scene.horizon, steps);
    assert_eq!(driven.impacts.len(), headless.impacts.len());
    assert_eq!(driven.series.len(), headless.series.len());
    // The same steps on the same f32 bodies: the same numbers.
    for (k, (a, b)) in driven.series.xs().iter().zip(headless.series.xs()).enumerate() {
        assert_eq!(a, b, "xs at sample {k}");
    }
}
