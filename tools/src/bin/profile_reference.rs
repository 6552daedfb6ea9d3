//! Runs the reference on a scene many times (with its series), for profilers:
//! `cargo run --release -p lpc-tools --bin profile_reference -- scenes/lpc-lsl.toml 2000`.
use lpc_damper::model::{Model, RunOptions};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let loaded = lpc_damper::scene::load(args.get(1).map_or("scenes/lpc-lsl.toml", |s| s)).unwrap();
    // A damper scene, or every case of a chain experiment.
    let scenes: Vec<_> = match (loaded.scene, loaded.chain) {
        (Some(s), _) => vec![s],
        (None, Some(cases)) => cases.into_iter().map(|c| c.scene).collect(),
        _ => panic!("a damper or chain scene"),
    };
    let n: usize = args.get(2).map_or(1000, |s| s.parse().unwrap());
    let mut events = 0;
    for _ in 0..n {
        for scene in &scenes {
            events += Model::Reference.simulate(scene, &RunOptions::default()).unwrap().events;
        }
    }
    println!("{events} events");
}
