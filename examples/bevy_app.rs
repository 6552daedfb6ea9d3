//! The contact model's plug-in in your own Bevy app: `LpcDamperPlugins` next to a system of
//! the app's own that watches the frame, one physics step per `app.update()`, and the
//! reference model's answer beside it.
//!
//! `cargo run --release --example bevy_app [SCENE]` (default `scenes/lpc-lsl.toml`).

use bevy::prelude::*;
use lpc_damper::rapier::{settings, DamperSet, FrameState, LpcDamperPlugins, StepClock};

/// What the app's own system collects: the frame's displacement every tenth of a second.
#[derive(Resource, Default)]
struct Watch {
    next: f64,
    xs: Vec<(f64, f64)>,
}

/// The app's own system, ordered after the plug-in has fed the step's impacts to the frame.
fn watch_frame(clock: Res<StepClock>, frame: Res<FrameState>, mut watch: ResMut<Watch>) {
    if clock.t >= watch.next {
        watch.xs.push((clock.t, frame.now.0));
        watch.next += 0.1;
    }
}

fn main() -> anyhow::Result<()> {
    let path = std::env::args().nth(1).unwrap_or_else(|| "scenes/lpc-lsl.toml".into());
    let scene = lpc_damper::scene::load_scene(&path)?;
    let horizon = scene.horizon.min(1.0);
    let mut app = App::new();
    // Rapier reads `Time` although the plug-in's fixed steps never use its value.
    app.init_resource::<Time>()
        .init_resource::<Watch>()
        .add_plugins(LpcDamperPlugins { scene: scene.clone(), settings: settings(&scene), record: lpc_damper::run::Record::Series })
        .add_systems(PostUpdate, watch_frame.after(DamperSet::Feedback));
    app.finish();
    app.cleanup();
    while app.world().get_resource::<StepClock>().is_none_or(|c| c.t < horizon) {
        app.update();
    }
    let reference = lpc_damper::Model::Reference.simulate(&scene, &lpc_damper::model::RunOptions::default())?;
    let at = |t: f64| reference.series.xs()[((t / reference.sample_dt).round() as usize).min(reference.series.len() - 1)];
    println!("{:>8} {:>14} {:>14}", "t s", "rapier xs mm", "reference mm");
    for &(t, xs) in &app.world().resource::<Watch>().xs {
        println!("{t:>8.4} {:>14.4} {:>14.4}", xs * 1e3, at(t) * 1e3);
    }
    Ok(())
}
