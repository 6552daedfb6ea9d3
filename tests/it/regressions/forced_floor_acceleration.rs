//! Issue 32: a building driven by a sine force on its carrying floor reported that floor's
//! acceleration without the force. The recorder took the floors' accelerations from the
//! storeys' springs and dampers alone; it now takes them from the scene's one rule,
//! `Scene::floor_accelerations`, which adds the force. Checked against the derivative of the
//! floor's own velocity, for both models that move floors.

use lpc_damper::model::{Model, RunOptions};

#[test]
fn a_forced_floor_reports_the_force_in_its_acceleration() {
    let text = "name = \"forced\"\n[structure]\nmasses = [2.0, 1.6, 1.35]\nstiffnesses = [3000.0, 2400.0, 865.0]\n\
                rayleigh = [0.4, 0.002]\n[forcing]\nkind = \"force\"\namplitude = 2.0\nfrequency = 3.1\n\
                [run]\nhorizon = 1.0\nsample_dt = 0.001\n";
    let scene = crate::common::scene_from_toml(text);
    let structure = scene.structure.as_deref().unwrap();
    let (omegas, _) = structure.building.undamped_modes();
    let fastest = omegas.iter().fold(0.0f64, |m, w| m.max(*w));
    let dt = scene.sample_dt;
    for model in [Model::Reference, Model::Compliant] {
        let run = model.simulate(&scene, &RunOptions::default()).unwrap();
        let s = &run.series;
        let (v, a) = (s.vs(), s.a());
        let peak = a.iter().fold(0.0f64, |m, a| m.max(a.abs()));
        // The central difference errs by `dt^2 / 6` of the acceleration's second derivative,
        // at most `fastest^2` times its peak; the force alone is 2 N / 1.35 kg = 1.5 m/s^2.
        let truncation = dt * dt / 6.0 * fastest * fastest * peak;
        for k in 1..s.len() - 1 {
            let slope = (v[k + 1] - v[k - 1]) / (2.0 * dt);
            assert!((a[k] - slope).abs() <= truncation, "{model:?} at {} s: a {} vs dv/dt {slope}", s.t()[k], a[k]);
            assert_eq!(s.floor(2, k).unwrap().2, a[k]);
        }
    }
}
