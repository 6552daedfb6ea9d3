//! Forced vibration: the bare frame against the textbook solution of
//! `m x'' + c x' + k x = P sin wt + Q cos wt`, for a force and for base motion, in both models;
//! the energy balance with the excitation's work; the frequency response against `|H(w)|`.

use crate::common;
use lpc_damper::model::RunOptions;

use crate::common::reference;
use lpc_damper::run::Series;
use lpc_damper::scene::{Forcing, ForcingKind, Scene};
use lpc_damper::studies::frf;
use lpc_damper::Model;

const FRAME: lpc_damper::scene::Frame = common::PAPER_FRAME;

fn bare(kind: ForcingKind, amplitude: f64, frequency: f64, xs0: f64) -> Scene {
    let mut s = common::damper(FRAME, xs0, &[], 0.9, 0.0, 0.0, 3.0).without_damper();
    s.forcing = Some(Forcing { kind, amplitude, frequency });
    s
}

/// The textbook solution, written independently of `oscillator`: steady part by complex
/// amplitude, transient `e^{-sigma t}(A cos wd t + B sin wd t)` fitted to `x(0) = x0`, `x'(0) = 0`.
fn textbook(kind: ForcingKind, amplitude: f64, frequency: f64, x0: f64, t: f64) -> f64 {
    let (m, c, k) = (FRAME.mass, FRAME.damping, FRAME.stiffness);
    let w = 2.0 * std::f64::consts::PI * frequency;
    // Load as the real part of F e^{i w t} with F = Q - i P (P sin + Q cos).
    let (p, q) = match kind {
        ForcingKind::Force => (amplitude, 0.0),
        ForcingKind::Base => (k * amplitude, c * w * amplitude),
    };
    // X_complex = F / (k - m w^2 + i c w).
    let (re_d, im_d) = (k - m * w * w, c * w);
    let den = re_d * re_d + im_d * im_d;
    let (fr, fi) = (q, -p);
    let (xr, xi) = ((fr * re_d + fi * im_d) / den, (fi * re_d - fr * im_d) / den);
    // x_p = Re(X e^{iwt}) = xr cos wt - xi sin wt.
    let xp = |t: f64| xr * (w * t).cos() - xi * (w * t).sin();
    let vp0 = -xi * w;
    let sigma = c / (2.0 * m);
    let wd = (k / m - sigma * sigma).sqrt();
    let a = x0 - xp(0.0);
    let b = (0.0 - vp0 + sigma * a) / wd;
    (-sigma * t).exp() * (a * (wd * t).cos() + b * (wd * t).sin()) + xp(t)
}

#[test]
fn bare_forced_frame_follows_the_textbook_solution_in_both_models() {
    for (kind, amp) in [(ForcingKind::Force, 2.0), (ForcingKind::Base, 0.003)] {
        for f in [1.5, 4.0, 9.0] {
            let scene = bare(kind, amp, f, 0.01);
            let scale = 0.01 + textbook(kind, amp, f, 0.0, 100.0).abs().max(amp / FRAME.stiffness);
            for model in [Model::Reference, Model::Rapier] {
                let run = model.simulate(&scene, &RunOptions::default()).unwrap();
                let worst = run
                    .series
                    .t()
                    .iter()
                    .zip(run.series.xs())
                    .map(|(t, x)| (x - textbook(kind, amp, f, 0.01, *t)).abs())
                    .fold(0.0, f64::max);
                // Both models move the frame in closed form: agreement to round-off, which
                // grows with the ~3000 samples' phase arguments (w t up to 170 rad).
                assert!(worst <= 1e-12 * scale * 1e3, "{kind:?} {f} Hz {}: {worst:e} m", model.name());
                // Each model balances the excitation's work to round-off (the Rapier model's
                // frame is exact and nothing else moves).
                assert!(run.energy.balance_error.abs() <= 1e-12, "{kind:?} {f} Hz {}: {:e}", model.name(), run.energy.balance_error);
                assert!(run.energy.forcing_work != 0.0);
            }
        }
    }
}

#[test]
fn forced_damper_balances_energy_with_the_forcing_work() {
    let scene = lpc_damper::scene::load_scene(lpc_damper::scene::scenes_dir().join("forced-lsl.toml")).unwrap();
    for kind in [ForcingKind::Force, ForcingKind::Base] {
        let mut s = scene.clone();
        let g = s.forcing.as_mut().unwrap();
        g.kind = kind;
        if kind == ForcingKind::Base {
            g.amplitude = 2.0 / FRAME.stiffness; // the same load amplitude as the force
        }
        let run = reference(&s).unwrap();
        assert!(run.impacts.len() > 50, "{kind:?}: the balls must be set moving");
        // Closed form between impacts, Gauss-Legendre for the work: round-off only.
        assert!(run.energy.balance_error.abs() <= 1e-12, "{kind:?}: {:e}", run.energy.balance_error);
        assert!(run.energy.forcing_work > 0.0);
        assert!(common::min_gap(&s, &run) >= -1e-12);
        // The series' acceleration is the smooth force over ms, forcing included.
        let k = run.series.len() / 2;
        let (t, x, v) = (run.series.t()[k], run.series.xs()[k], run.series.vs()[k]);
        assert_eq!(run.series.a()[k], s.frame_force(t, x, v) / FRAME.mass);
    }
}

#[test]
fn frequency_response_of_the_bare_frame_is_its_receptance() {
    let (m, c, k) = (FRAME.mass, FRAME.damping, FRAME.stiffness);
    for kind in [ForcingKind::Force, ForcingKind::Base] {
        let amp = if kind == ForcingKind::Force { 1.0 } else { 1e-3 };
        let scene = {
            let mut s = common::damper(FRAME, 0.0, &[0.11], 0.9, 0.004, 0.03, 5.0);
            s.forcing = Some(Forcing { kind, amplitude: amp, frequency: 1.0 });
            s
        };
        let freqs = frf::frequencies(3.0, 5.0, 5);
        let points = frf::frf(&scene, &freqs, Model::Reference, lpc_damper::model::Limits::NONE, &|| {});
        assert_eq!(points.len(), 5);
        for p in points {
            let w = 2.0 * std::f64::consts::PI * p.frequency;
            let load = match kind {
                ForcingKind::Force => amp,
                ForcingKind::Base => amp * (k * k + c * c * w * w).sqrt(),
            };
            let exact = load / ((k - m * w * w).powi(2) + (c * w).powi(2)).sqrt();
            assert!(p.steady_no_damper, "{kind:?} {} Hz", p.frequency);
            // Steady means the last blocks agree within STEADY_TOLERANCE; the sampled peak of
            // a sine is low by at most 1 - cos(pi / SAMPLES_PER_PERIOD).
            let tol = frf::STEADY_TOLERANCE + 1.0 - (std::f64::consts::PI / frf::SAMPLES_PER_PERIOD).cos();
            let amplitude = p.amplitude_no_damper.expect("the bare frame's run succeeds");
            assert!((amplitude / exact - 1.0).abs() <= tol, "{kind:?} {} Hz: {amplitude} vs {exact}", p.frequency);
        }
    }
}

#[test]
fn a_steady_reading_needs_agreeing_blocks() {
    // A decaying response is not steady; a constant sine is, with its amplitude.
    let mut run = lpc_damper::run::Run::empty("t", lpc_damper::Model::Reference);
    let period = 0.1;
    run.horizon = 40.0 * period;
    let t: Vec<f64> = (0..=4000).map(|k| k as f64 * run.horizon / 4000.0).collect();
    let xs: Vec<f64> = t.iter().map(|t| 0.002 * (2.0 * std::f64::consts::PI * t / period).sin()).collect();
    let zeros = vec![0.0; t.len()];
    run.series = Series::from_columns(t.clone(), xs.clone(), zeros.clone(), zeros.clone(), vec![], vec![]);
    let r = frf::steady_state(&run, period);
    assert!(r.steady && (r.amplitude - 0.002).abs() < 1e-9, "{r:?}");
    let decaying = xs.iter().enumerate().map(|(k, x)| x * (-(k as f64) / 1000.0).exp()).collect();
    run.series = Series::from_columns(t, decaying, zeros.clone(), zeros, vec![], vec![]);
    assert!(!frf::steady_state(&run, period).steady);
}
