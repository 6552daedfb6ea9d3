//! Energy balance (initial = mechanical now + damping dissipation + impact losses) to 1e-12 on
//! every paper scene, every sweep value and every chain; no ball ever leaves the container.

use crate::common;

use crate::common::reference;

#[test]
fn every_paper_scene_balances_energy_and_keeps_balls_inside() {
    let scenes = common::all_paper_scenes();
    assert!(scenes.len() >= 5 + 14 + 10, "expected every paper scene, got {}", scenes.len());
    // Rough beds are the contact model's: the reference refuses them.
    for scene in scenes.into_iter().filter(|s| lpc_damper::model::Model::Reference.supports(s).is_ok()) {
        let run = reference(&scene).unwrap();
        assert!(run.energy.balance_error.abs() <= 1e-12, "{}: balance error {:e}", scene.name, run.energy.balance_error);
        // Impacts lose energy, except that the collapse rule in space gives a contact pressed
        // shut at `a` the separation speed `a t_c / 2` (docs/MODEL.md §14): at most
        // `m (a t_c / 2)^2 / 2` gained, `a` at most gravity and the frame's largest acceleration.
        let frame_accel = scene.frame.map_or(0.0, |f| {
            let w = (f.stiffness / f.mass).sqrt();
            (f.stiffness + f.damping * w) * scene.initial_displacement.abs() / f.mass
        });
        let pressing = scene.space.gravity.iter().map(|g| g * g).sum::<f64>().sqrt() + frame_accel;
        let heaviest = scene.balls.iter().map(|b| b.mass).fold(0.0, f64::max);
        let gain = 0.5 * heaviest * (0.5 * pressing * scene.reference.contact_duration).powi(2);
        assert!(run.impacts.iter().all(|i| i.energy_lost >= -gain), "{}", scene.name);
        // Contact tolerance is 1e-12 of the container length (< 1e-13 m).
        let min_gap = common::min_gap(&scene, &run);
        assert!(min_gap >= -1e-12, "{}: overlap {min_gap:e} m", scene.name);
    }
}

#[test]
fn runs_are_bitwise_repeatable() {
    let scene = lpc_damper::scene::load_scene(lpc_damper::scene::scenes_dir().join("lpc-lslsl.toml")).unwrap();
    let a = reference(&scene).unwrap();
    let b = reference(&scene).unwrap();
    assert_eq!(a.series, b.series);
    assert_eq!(a.impacts, b.impacts);
}

#[test]
fn damper_beats_no_damper_on_the_paper_scene() {
    // Qualitative result of the paper (Figs. 8-9): with the LPC damper the frame settles much
    // sooner than with the conventional damper, and both beat the bare frame.
    let load = |n: &str| lpc_damper::scene::load_scene(lpc_damper::scene::scenes_dir().join(n)).unwrap();
    let metrics = |n: &str| lpc_damper::metrics::metrics(&reference(&load(n)).unwrap());
    let bare = metrics("no-damper.toml");
    let conventional = metrics("conventional.toml");
    let lsl = metrics("lpc-lsl.toml");
    assert!(bare.settling_time.is_none());
    assert!(lsl.settling_time.unwrap() < conventional.settling_time.unwrap());
    assert!(lsl.peak_displacement < conventional.peak_displacement);
    assert!(conventional.peak_displacement < bare.peak_displacement);
}
