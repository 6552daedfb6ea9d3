//! Runs the reference on a scene many times (with its series), for profilers:
//! `cargo run --release -p lpc-tools --bin profile_reference -- scenes/lpc-lsl.toml 2000`.
use lpc_damper::model::{Model, RunOptions};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene = lpc_damper::scene::load_scene(args.get(1).map_or("scenes/lpc-lsl.toml", |s| s)).unwrap();
    let n: usize = args.get(2).map_or(1000, |s| s.parse().unwrap());
    let mut events = 0;
    for _ in 0..n {
        events += Model::Reference.simulate(&scene, &RunOptions::default()).unwrap().events;
    }
    println!("{events} events");
}
