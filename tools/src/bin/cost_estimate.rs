//! How good the compliant model's cost estimates are (issue 18): runs the compliant model on
//! each scene given (a scene file, or a seed of `lpc stress --max-horizon 2`), watched as
//! `lpc run` watches it ([`lpc_damper::model::cost::watch`]), and prints what it said and
//! when, against what the run took.
//!
//! `cargo run --release -p lpc-tools --bin cost_estimate -- examples/scenes/packed-column.toml 31338 80056 ...`
use lpc_damper::model::{cost, Limits, Model, Progress, RunOptions};

fn main() {
    println!("| scene | balls | first said at | said steps | said s | revisions | last said s | steps | s | said / took |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for arg in std::env::args().skip(1) {
        let scene = if arg.ends_with(".toml") {
            lpc_damper::scene::load_scene(&arg).expect("a valid scene file")
        } else {
            let seed: u64 = arg.parse().expect("a scene file or a stress seed");
            let file = lpc_damper::studies::stress::random_scene_file(seed, 2.0, false);
            lpc_damper::scene::from_file(file, "stress", &format!("seed-{seed}")).expect("a valid stress scene").scene.expect("a scene")
        };
        let progress = Progress::default();
        let done = std::sync::atomic::AtomicBool::new(false);
        let mut said = Vec::new();
        let start = std::time::Instant::now();
        let options = RunOptions {
            limits: Limits { max_wall_s: Some(60.0), ..Limits::NONE },
            progress: Some(&progress),
            ..RunOptions::metrics_only()
        };
        let run = std::thread::scope(|s| {
            let watcher = s.spawn(|| {
                let mut said = Vec::new();
                cost::watch(&progress, scene.horizon, &done, |e| said.push(e), |_, _, _| {});
                said
            });
            let run = Model::Compliant.simulate(&scene, &options);
            done.store(true, std::sync::atomic::Ordering::Relaxed);
            watcher.thread().unpark();
            said = watcher.join().expect("the watcher ends");
            run
        });
        let took = start.elapsed().as_secs_f64();
        if let Err(e) = &run {
            println!("| {} | {} | stopped: {e} |", scene.name, scene.balls.len());
            continue;
        }
        // Every step taken, accepted or rejected, as the estimates count them.
        let steps_taken = progress.steps() as f64;
        match (said.first(), said.last()) {
            (Some(first), Some(last)) => println!(
                "| {} | {} | {:.2} s | {:.3e} | {:.1} | {} | {:.1} | {:.3e} | {:.1} | {:.2} |",
                scene.name,
                scene.balls.len(),
                first.elapsed_s,
                first.estimate.steps,
                first.estimate.seconds,
                said.len() - 1,
                last.estimate.seconds,
                steps_taken,
                took,
                first.estimate.seconds / took
            ),
            _ => println!("| {} | {} | not said | - | - | - | - | {:.3e} | {:.2} | - |", scene.name, scene.balls.len(), steps_taken, took),
        }
    }
}
