//! The driven box at a 15 mm drive stopped at 0.011 s in the contact model with a ball sunk into
//! its right wall, once strikes on touching groups were kept out of Rapier's solve: a ball that
//! the accelerating end wall pressed was taken for a striker in flight and set back along its
//! path among the walls, into the wall. A ball an end wall touches is driven by the frame, not
//! in flight: it is no striker.

use crate::common::scene_from_toml;
use lpc_damper::model::RunOptions;
use lpc_damper::rapier::spatial::simulate_spatial;

#[test]
fn a_ball_pressed_by_an_end_wall_is_no_striker() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("benches/driven-box.toml")).unwrap();
    // The bug showed on the scene's former lattice, whose rows the ring-down drives into the walls.
    let text = text
        .replace("amplitude = 0.00955", "amplitude = 0.015")
        .replace("horizon = 2.0", "horizon = 0.05")
        .replace("placement = \"random\"", "placement = \"lattice\"");
    assert!(text.contains("placement = \"lattice\""), "the scene names its placement");
    let scene = scene_from_toml(&text);
    let run = simulate_spatial(&scene, &RunOptions::default()).unwrap();
    assert!(run.impacts.len() > 10, "the walls strike the bed: {} impacts", run.impacts.len());
}
