//! Classifies contact-model stress outcomes by scene parameters (one JSON line per seed):
//! `cargo run --release -p lpc-tools --bin probe_stress -- 300` (docs/BENCHMARKS.md, "Stress").
use rayon::prelude::*;
fn main() {
    let n: u64 = std::env::args().nth(1).unwrap().parse().unwrap();
    let rows: Vec<String> = (1..=n).into_par_iter().map(|seed| {
        let file = lpc_damper::studies::stress::random_scene_file(seed, 1.0, false);
        let scene = lpc_damper::scene::from_file(file, "s", "s").unwrap().scene.unwrap();
        let r = lpc_damper::studies::stress::judge_run(lpc_damper::Model::Rapier, &scene, None);
        let f = scene.frame.unwrap();
        let w = (f.stiffness / f.mass).sqrt();
        let c = scene.container.unwrap();
        let rmin = scene.balls.iter().map(|b| b.radius).fold(1.0, f64::min);
        let mmax = scene.balls.iter().map(|b| b.mass).fold(0.0, f64::max);
        format!("{{\"seed\":{seed},\"n\":{},\"w\":{w},\"xs0\":{},\"gap\":{},\"clr\":{},\"e\":{},\"rmin\":{rmin},\"mmax\":{mmax},\"zeta\":{},\"out\":\"{}\",\"detail\":\"{}\"}}",
            scene.balls.len(), scene.initial_displacement.abs(), c.gap, c.clearance, scene.restitution,
            f.damping / (2.0 * (f.stiffness * f.mass).sqrt()).max(1e-300),
            match &r { Ok(lpc_damper::studies::stress::Passed::Refused { .. }) => "refused", Ok(_) => "ok", Err(f) => f.check },
            match &r { Err(f) => f.detail.replace('"', "'"), _ => String::new() })
    }).collect();
    for r in rows {
        println!("{r}");
    }
}
