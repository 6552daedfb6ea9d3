//! Structures of several storeys and ground-motion records (docs/MODEL.md §16-17): the
//! reference's floors against an independent solution, a one-storey structure against the
//! frame it is, and the rules a structure's scene keeps.

use lpc_damper::model::{Model, RunOptions};
use lpc_damper::run::Run;
use lpc_damper::scene::Scene;
use nalgebra::{DMatrix, DVector};

use crate::common::{lpc_command, LSL_TOML};

/// A three-storey building (Rayleigh damping) without a damper, shaken by `record`.
fn building_text(record: &str) -> String {
    format!(
        r#"
name = "building"
[structure]
masses = [2.0, 1.6, 1.35]
stiffnesses = [3000.0, 2400.0, 865.0]
rayleigh = [0.4, 0.002]
initial_displacements = [0.001, -0.002, 0.004]
initial_velocities = [0.0, 0.05, -0.02]
[forcing]
kind = "record"
file = "{record}"
scale = 2.0
[run]
horizon = 3.0
sample_dt = 0.01
"#
    )
}

/// Writes `text` as `scene.toml` beside a record of `points` and loads it.
fn scene_with_record(text: impl Fn(&str) -> String, points: &[(f64, f64)]) -> (tempfile::TempDir, Scene) {
    let dir = tempfile::tempdir().unwrap();
    let record: String = points.iter().map(|(t, a)| format!("{t} {a}\n")).collect();
    std::fs::write(dir.path().join("quake.txt"), record).unwrap();
    let file = dir.path().join("scene.toml");
    std::fs::write(&file, text("quake.txt")).unwrap();
    let scene = lpc_damper::scene::load_scene(&file).unwrap();
    (dir, scene)
}

fn reference(scene: &Scene) -> Run {
    Model::Reference.simulate(scene, &RunOptions::default()).unwrap()
}

/// The floor masses, `K` and `C` of the building of [`building_text`], written out by hand.
fn building_matrices() -> ([f64; 3], DMatrix<f64>, DMatrix<f64>) {
    let (m, k, a) = ([2.0, 1.6, 1.35], [3000.0, 2400.0, 865.0], [0.4, 0.002]);
    let n = 3;
    let kk = DMatrix::from_fn(n, n, |i, j| match (i, j) {
        _ if i == j => k[i] + if i + 1 < n { k[i + 1] } else { 0.0 },
        _ if j == i + 1 => -k[j],
        _ if i == j + 1 => -k[i],
        _ => 0.0,
    });
    let c = DMatrix::from_diagonal(&DVector::from_row_slice(&m)) * a[0] + &kk * a[1];
    (m, kk, c)
}

/// The building's state matrix for `[u; u']` in the top left of an `(2n + 2)`-square matrix
/// whose last two rows and columns the caller fills with its excitation.
fn bordered_state_matrix() -> DMatrix<f64> {
    let (m, kk, c) = building_matrices();
    let n = 3;
    let mut aug = DMatrix::<f64>::zeros(2 * n + 2, 2 * n + 2);
    for i in 0..n {
        aug[(i, n + i)] = 1.0;
        for j in 0..n {
            aug[(n + i, j)] = -kk[(i, j)] / m[i];
            aug[(n + i, n + j)] = -c[(i, j)] / m[i];
        }
    }
    aug
}

/// The state of the building of [`building_text`] advanced by the matrix exponential of the
/// state matrix bordered by the record's line (nalgebra's Pade approximant: nothing of the
/// modal closed form), record point to record point. The record acts on floor `i` as
/// `pattern[i]` times its value: `-1` on every floor for the ground's acceleration, `1 / m_j`
/// on floor `j` alone for a force on it.
fn by_matrix_exponential(points: &[(f64, f64)], scale: f64, samples: &[f64], pattern: [f64; 3]) -> Vec<Vec<f64>> {
    let n = 3;
    // Augmented state [u; u'; 1; s]: u'' = -M^-1 (C u' + K u) + pattern (g0 + g1 s).
    let step = |z: &DVector<f64>, g0: f64, g1: f64, h: f64| -> DVector<f64> {
        let mut aug = bordered_state_matrix();
        for i in 0..n {
            aug[(n + i, 2 * n)] = pattern[i] * g0;
            aug[(n + i, 2 * n + 1)] = pattern[i] * g1;
        }
        aug[(2 * n + 1, 2 * n)] = 1.0;
        let mut x = DVector::<f64>::zeros(2 * n + 2);
        x.rows_mut(0, 2 * n).copy_from(z);
        x[2 * n] = 1.0;
        ((aug * h).exp() * x).rows(0, 2 * n).into_owned()
    };
    let mut z = DVector::from_row_slice(&[0.001, -0.002, 0.004, 0.0, 0.05, -0.02]);
    let mut t = 0.0;
    let mut out = Vec::new();
    let mut j = 0;
    for &ts in samples {
        // Advance to each record point before `ts`, then to `ts`.
        loop {
            let (g0, g1, end) = if j + 1 < points.len() {
                let (t0, a0) = points[j];
                let (t1, a1) = points[j + 1];
                (scale * (a0 + (a1 - a0) / (t1 - t0) * (t - t0)), scale * (a1 - a0) / (t1 - t0), t1)
            } else {
                (0.0, 0.0, f64::INFINITY)
            };
            if end <= ts {
                z = step(&z, g0, g1, end - t);
                t = end;
                j += 1;
            } else {
                z = step(&z, g0, g1, ts - t);
                t = ts;
                break;
            }
        }
        out.push(z.iter().copied().collect());
    }
    out
}

/// Every floor of `run` (the building of [`building_text`] shaken by `points`) within
/// `relative` of the peak displacement and velocity of the matrix exponential's, at every sample.
fn assert_floors_follow(run: &Run, points: &[(f64, f64)], relative: f64) {
    assert_floors_follow_load(run, points, relative, [-1.0; 3]);
}

/// [`assert_floors_follow`] for a record that acts as `pattern` says
/// ([`by_matrix_exponential`]).
fn assert_floors_follow_load(run: &Run, points: &[(f64, f64)], relative: f64, pattern: [f64; 3]) {
    let s = &run.series;
    assert_eq!(s.floor_count(), 3);
    let times: Vec<f64> = s.t().to_vec();
    let exact = by_matrix_exponential(points, 2.0, &times, pattern);
    let peak_u = exact.iter().flat_map(|z| z[..3].to_vec()).fold(0.0, |m: f64, x| m.max(x.abs()));
    let peak_v = exact.iter().flat_map(|z| z[3..].to_vec()).fold(0.0, |m: f64, x| m.max(x.abs()));
    for (k, z) in exact.iter().enumerate() {
        for i in 0..3 {
            let (u, v, _) = s.floor(i, k).unwrap();
            assert!((u - z[i]).abs() <= relative * peak_u, "floor {} at {} s: u {u} vs {}", i + 1, times[k], z[i]);
            assert!((v - z[3 + i]).abs() <= relative * peak_v, "floor {} at {} s: v {v} vs {}", i + 1, times[k], z[3 + i]);
        }
    }
}

/// The reference's floors under a piecewise-linear record agree with the matrix exponential
/// to 1e-8 of the largest displacement and velocity (both are exact to round-off; what is left
/// is the round-off of two different evaluations over a few hundred stretches).
#[test]
fn a_three_storey_building_under_a_record_is_the_matrix_exponential() {
    let points: Vec<(f64, f64)> =
        (0..=200).map(|j| (j as f64 * 0.01, (j as f64 * 0.37).sin() * (1.0 + 0.5 * (j as f64 * 0.05).cos()))).collect();
    let (_dir, scene) = scene_with_record(building_text, &points);
    let run = reference(&scene);
    assert_floors_follow(&run, &points, 1e-8);
    // The energy balance closes with the ground's work.
    let e = &run.energy;
    assert!(e.balance_error.abs() <= 1e-9, "{e:?}");
}

/// A `[structure]` of one storey at rest is the `[frame]` it describes: the same scene, and the
/// same run to the bit.
#[test]
fn a_one_storey_structure_is_its_frame_to_the_bit() {
    let frame = crate::common::scene_from_toml(&LSL_TOML.replace("damping = 1.092", "damping = 1.35"));
    let storey = LSL_TOML.replace(
        "[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 1.092\ninitial_displacement = 0.0185",
        "[structure]\nmasses = [1.35]\nstiffnesses = [865.0]\nrayleigh = [1.0, 0.0]\ninitial_displacements = [0.0185]",
    );
    let structure = crate::common::scene_from_toml(&storey);
    assert_eq!(structure, frame);
    let (a, b) = (reference(&frame), reference(&structure));
    assert_eq!(a.series, b.series);
    assert_eq!(a.impacts, b.impacts);
}

/// The LSL damper on the top floor of a building whose lower storeys are far stiffer than the
/// top one moves as on the paper's frame: its early impacts come at the frame's times, to the
/// relative flexibility of the lower storeys.
#[test]
fn a_damper_on_a_floor_whose_storeys_below_are_stiff_moves_as_on_a_frame() {
    let frame = crate::common::scene_from_toml(&LSL_TOML.replace("horizon = 5.0", "horizon = 0.5"));
    let stiff = 865.0e4;
    // The top storey's stiffness-proportional damping is the frame's 1.092 N s/m.
    let storeys = LSL_TOML.replace("horizon = 5.0", "horizon = 0.5").replace(
        "[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 1.092\ninitial_displacement = 0.0185",
        &format!(
            "[structure]\nmasses = [1.35, 1.35]\nstiffnesses = [{stiff}, 865.0]\nrayleigh = [0.0, 0.0012624]\ninitial_displacements = [{}, 0.0185]",
            0.0185 * 865.0 / stiff
        ),
    );
    let building = crate::common::scene_from_toml(&storeys);
    let (a, b) = (reference(&frame), reference(&building));
    assert!(a.impacts.len() >= 10 && b.impacts.len() >= 10);
    // The lower storey stretches by 1e-4 of the top one: times agree to a few 1e-4 of the
    // frame's period over the first impacts.
    let period = frame.frame.unwrap().damped_period();
    for (x, y) in a.impacts.iter().zip(&b.impacts).take(10) {
        assert_eq!((x.a, x.b), (y.a, y.b));
        assert!((x.t - y.t).abs() <= 1e-3 * period, "{} vs {}", x.t, y.t);
    }
}

fn expect_error(text: &str, field: &str, words: &str) {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("scene.toml");
    std::fs::write(&file, text).unwrap();
    let out = dir.path().join("out");
    let o = lpc_command().arg("run").arg(&file).arg("--out").arg(&out).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{field}: {stderr}");
    assert!(stderr.contains(field) && stderr.to_lowercase().contains(words), "{field} / {words}: {stderr}");
    assert!(!out.exists());
}

/// A structure's bad input names the field, exits 2 and writes nothing.
#[test]
fn a_structure_or_record_that_cannot_exist_is_refused() {
    let base = building_text("missing.txt");
    expect_error(&base, "forcing.file", "cannot be read");
    let undamped = base
        .replace("kind = \"record\"\nfile = \"missing.txt\"\nscale = 2.0", "kind = \"force\"\namplitude = 1.0\nfrequency = 2.0")
        .replace("rayleigh = [0.4, 0.002]", "rayleigh = [0.0, 0.0]");
    // At the undamped building's first natural frequency.
    let first = lpc_damper::storeys::Building::new(
        vec![2.0, 1.6, 1.35],
        vec![3000.0, 2400.0, 865.0],
        &lpc_damper::storeys::StoreyDamping::Modal(vec![0.0; 3]),
    )
    .undamped_modes()
    .0[0];
    expect_error(
        &undamped.replace("frequency = 2.0", &format!("frequency = {}", first / (2.0 * std::f64::consts::PI))),
        "forcing.frequency",
        "natural frequency",
    );
    let free = base.replace("[forcing]\nkind = \"record\"\nfile = \"missing.txt\"\nscale = 2.0\n", "");
    expect_error(
        &free.replace("stiffnesses = [3000.0, 2400.0, 865.0]", "stiffnesses = [3000.0, 865.0]"),
        "structure.stiffnesses",
        "one per storey",
    );
    expect_error(&free.replace("masses = [2.0, 1.6, 1.35]", "masses = [2.0, -1.6, 1.35]"), "structure.masses[1]", "positive");
    expect_error(&free.replace("rayleigh = [0.4, 0.002]", "rayleigh = [0.4, 0.002]\ndamper_floor = 4"), "structure.damper_floor", "from 1");
    expect_error(
        &free.replace("rayleigh = [0.4, 0.002]", "rayleigh = [0.4, 0.002]\ndamping_ratios = [0.1, 0.1, 0.1]"),
        "structure.damping_ratios",
        "one way",
    );
    expect_error(&free.replace("rayleigh = [0.4, 0.002]", "damping_ratios = [0.1, 1.5, 0.1]"), "structure.damping_ratios[1]", "below 1");
    expect_error(
        &free.replace("initial_velocities = [0.0, 0.05, -0.02]", "initial_velocities = [0.0, nan, -0.02]"),
        "structure.initial_velocities[1]",
        "finite",
    );
    expect_error(&format!("{LSL_TOML}\n[structure]\nmasses = [1.0]\nstiffnesses = [1.0]\n"), "structure", "cannot be combined");
    // A record whose times go back.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("bad.txt"), "0 0\n0.1 1\n0.05 2\n").unwrap();
    let file = dir.path().join("scene.toml");
    std::fs::write(&file, building_text("bad.txt")).unwrap();
    let o = lpc_command().arg("run").arg(&file).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("forcing.file") && stderr.contains("must increase"), "{stderr}");
    // A force record on a floor the building lacks, one in a PEER file (a ground acceleration
    // in g), and a floor given to a ground record.
    std::fs::write(dir.path().join("push.txt"), "0 0\n0.1 1\n").unwrap();
    std::fs::write(dir.path().join("quake.at2"), "PEER\nquake\nACCELERATION TIME SERIES IN UNITS OF G\nNPTS= 2, DT= 0.01 SEC\n0.0 0.1\n")
        .unwrap();
    let force = |file: &str, extra: &str| {
        building_text(file).replace("kind = \"record\"", "kind = \"force_record\"").replace("scale = 2.0", &format!("scale = 2.0{extra}"))
    };
    for (text, field, words) in [
        (force("push.txt", "\nfloor = 4"), "forcing.floor", "from 1"),
        (force("quake.at2", ""), "forcing.file", "two columns"),
        (building_text("push.txt").replace("scale = 2.0", "scale = 2.0\nfloor = 1"), "forcing.floor", "does not belong"),
    ] {
        std::fs::write(&file, text).unwrap();
        let out = dir.path().join("out");
        let o = lpc_command().arg("run").arg(&file).arg("--out").arg(&out).output().unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(field) && stderr.contains(words), "{field}: {stderr}");
        assert!(!out.exists(), "nothing is written");
    }
}

/// Every model moves a building with its damper on one line, and carries a box of balls on it;
/// the reference refuses the box's friction up front, with the reason and what would make it
/// run.
#[test]
fn every_model_carries_a_box_on_a_building() {
    let text = std::fs::read_to_string(lpc_damper::scene::scenes_dir().join("mdof-3storey.toml")).unwrap();
    let scene = crate::common::scene_from_toml(&text);
    for model in [Model::Reference, Model::Compliant, Model::Rapier] {
        assert!(model.supports(&scene).is_ok(), "{}", model.name());
    }
    let building = &text[..text.find("[balls]").unwrap()];
    let boxed = crate::common::scene_from_toml(&format!(
        "{building}\n[container]\nlength = 0.06\nwidth = 0.04\nheight = 0.05\n\
         [world]\ngravity = [0.0, 0.0, -9.81]\nrestitution = 0.6\nfriction = 0.3\n\
         [bed]\ncount = 12\nradii = [0.005]\ndensity = 7800.0\nplacement = \"lattice\"\n"
    ));
    assert!(boxed.structure.is_some());
    for model in [Model::Compliant, Model::Rapier] {
        assert!(model.supports(&boxed).is_ok(), "{}: {:?}", model.name(), model.supports(&boxed));
    }
    let why = Model::Reference.supports(&boxed).unwrap_err();
    assert!(why.contains("friction") && why.contains("world.friction = 0"), "{why}");
    let mut smooth = boxed.clone();
    smooth.space.friction = 0.0;
    assert!(Model::Reference.supports(&smooth).is_ok(), "{:?}", Model::Reference.supports(&smooth));
}

fn rapier(scene: &Scene) -> Run {
    Model::Rapier.simulate(scene, &RunOptions::default()).unwrap()
}

/// The contact model moves the floors with the closed form, restarted at every step from the
/// floors' state: without a damper it is the matrix exponential to the round-off of its
/// restarts, a few ulps of the peaks each.
#[test]
fn the_contact_model_moves_a_building_as_the_matrix_exponential() {
    let points: Vec<(f64, f64)> =
        (0..=200).map(|j| (j as f64 * 0.01, (j as f64 * 0.37).sin() * (1.0 + 0.5 * (j as f64 * 0.05).cos()))).collect();
    let (_dir, scene) = scene_with_record(building_text, &points);
    let run = rapier(&scene);
    // Each of its steps restarts the closed form from the floors' state, rounding it by a
    // few ulps: 16 ulps of the peaks per step at most, added up.
    let bound = run.events as f64 * 16.0 * f64::EPSILON;
    assert_floors_follow(&run, &points, bound);
    assert!(run.energy.balance_error.abs() <= bound, "{:?}", run.energy);
}

fn compliant(scene: &Scene) -> Run {
    Model::Compliant.simulate(scene, &RunOptions::default()).unwrap()
}

/// The compliant model integrates the floors: without a damper they follow the matrix
/// exponential to its integration error. Each step errs by at most the tolerance of the
/// scene's scales (here below the peaks), and the errors add up at worst, so the bound is the
/// steps times the tolerance, relative to the peaks.
#[test]
fn the_compliant_model_moves_a_building_as_the_matrix_exponential() {
    let points: Vec<(f64, f64)> =
        (0..=200).map(|j| (j as f64 * 0.01, (j as f64 * 0.37).sin() * (1.0 + 0.5 * (j as f64 * 0.05).cos()))).collect();
    let (_dir, scene) = scene_with_record(building_text, &points);
    let run = compliant(&scene);
    let bound = run.events as f64 * scene.compliant.tolerance;
    assert_floors_follow(&run, &points, bound);
    assert!(run.energy.balance_error.abs() <= bound * run.energy.forcing_work.abs(), "{:?}", run.energy);
}

/// The LSL damper on the top floor of the three-storey building, the compliant model against
/// the reference: early on they differ by what the impacts' durations explain, as on the
/// paper's frame (see the compliant model's tests: some 0.1-0.2 mm over the first 0.5 s, bound
/// 0.25 mm), and that difference shrinks as the durations do (`t_c ~ E^(-2/5)`: balls 100
/// times stiffer, 4.5 to 9 times less). Shaken by the record, its balance closes with the
/// ground's work to the integration error.
#[test]
fn the_compliant_model_follows_the_reference_on_a_building() {
    let dir = lpc_damper::scene::scenes_dir();
    let mut early = lpc_damper::scene::load_scene(dir.join("mdof-3storey.toml")).unwrap();
    early.horizon = 0.5;
    let exact = reference(&early);
    let soft = lpc_damper::studies::compare::errors(&compliant(&early), &exact).max_xs_early;
    assert!(soft <= 0.25e-3, "max |xs - xs_ref| over 0.5 s: {soft:e} m");
    let mut stiff = early.clone();
    stiff.compliant.youngs_modulus *= 100.0;
    let stiff_err = lpc_damper::studies::compare::errors(&compliant(&stiff), &exact).max_xs_early;
    let ratio = soft / stiff_err;
    assert!((4.5..9.0).contains(&ratio), "error {soft:e} -> {stiff_err:e} (ratio {ratio})");
    let shaken = lpc_damper::scene::load_scene(dir.join("mdof-3storey-record.toml")).unwrap();
    let run = compliant(&shaken);
    assert_eq!(run.horizon, shaken.horizon);
    let e = &run.energy;
    assert!(e.forcing_work > 0.0 && e.impact_loss > 0.0, "{e:?}");
    assert!(e.balance_error.abs() <= run.events as f64 * shaken.compliant.tolerance, "{e:?} after {} steps", run.events);
    // No ball deeper in a wall or another ball than the model's own bound on its overlaps.
    let allowed = Model::Compliant.checks(&shaken, &run).wall_overlap;
    let gap = crate::common::min_gap(&shaken, &run);
    assert!(gap >= -allowed, "overlap {gap:e} m beyond {allowed:e} m");
}

/// The LSL damper on the top floor of the three-storey building, the contact model against
/// the reference: within the contact model's targets on the paper's scenes (early error 0.2
/// mm, impact loss within 2 % of E0, impact count within 10 %). Shaken by the record, its run
/// passes every check of the model (no energy gained, balls inside within Rapier's allowed
/// overlap), with the ground's work booked.
#[test]
fn the_contact_model_follows_the_reference_on_a_building() {
    let dir = lpc_damper::scene::scenes_dir();
    let free = lpc_damper::scene::load_scene(dir.join("mdof-3storey.toml")).unwrap();
    let e = lpc_damper::studies::compare::errors(&rapier(&free), &reference(&free));
    assert!(e.max_xs_early <= 0.2e-3, "early error {:e} m", e.max_xs_early);
    assert!(e.impact_loss_diff.abs() <= 0.02, "impact loss differs by {:.3} E0", e.impact_loss_diff);
    let exact = reference(&free).impacts.len() as f64;
    assert!(e.impact_count_diff.abs() as f64 <= 0.1 * exact, "{e:?}");
    let shaken = lpc_damper::scene::load_scene(dir.join("mdof-3storey-record.toml")).unwrap();
    let run = rapier(&shaken);
    assert_eq!(run.horizon, shaken.horizon);
    assert!(run.energy.forcing_work > 0.0 && run.energy.impact_loss > 0.0, "{:?}", run.energy);
    lpc_damper::studies::stress::judge(Model::Rapier, &shaken, &run).unwrap();
    assert_eq!(run.series.floor_count(), 3);
}

/// A random ground motion gives each ensemble member its own record, drawn from `(seed, k)`
/// alone (the same member whatever range is drawn), and each member's run balances its energy
/// with the ground's work.
#[test]
fn each_member_shakes_with_its_own_random_ground() {
    use lpc_damper::studies::ensemble::{draw, draw_range};
    let path = lpc_damper::scene::scenes_dir().join("mdof-3storey-random.toml");
    let text = std::fs::read_to_string(&path).unwrap().replace("horizon = 20.0", "horizon = 2.0");
    let loaded = lpc_damper::scene::parse(&text, path.to_str().unwrap(), "random").unwrap();
    let nominal = loaded.scene.clone().unwrap();
    let file = &loaded.file;
    let all = draw(file, path.to_str().unwrap(), &nominal, None, 4, Some(9)).unwrap();
    let ground = |s: &Scene| s.structure.as_ref().unwrap().ground.clone().unwrap();
    for (j, a) in all.members.iter().enumerate() {
        for b in &all.members[j + 1..] {
            assert_ne!(ground(&a.scene).accel, ground(&b.scene).accel);
        }
        let run = reference(&a.scene);
        assert!(run.energy.balance_error.abs() <= 1e-12, "{:?}", run.energy);
    }
    let third = draw_range(file, path.to_str().unwrap(), &nominal, None, 4, 2..3, Some(9)).unwrap();
    assert_eq!(third.members[0].scene, all.members[2].scene);
    assert_eq!(all.columns.last().map(String::as_str), Some("ground_seed"));
}

/// The largest interstorey drift, the roof's largest displacement and the largest floor
/// acceleration are tallied as the run goes, so a run without a series has them too: they are
/// the series' from one period on (the acceleration with the sine force on the top floor), and
/// a frame has none.
#[test]
fn the_peak_drift_is_the_largest_drift_of_the_floors() {
    let path = lpc_damper::scene::scenes_dir().join("mdof-3storey.toml");
    let forced = std::fs::read_to_string(&path).unwrap() + "\n[forcing]\nkind = \"force\"\namplitude = 2.0\nfrequency = 3.0\n";
    let scenes = [
        lpc_damper::scene::load_scene(&path).unwrap(),
        lpc_damper::scene::parse(&forced, path.to_str().unwrap(), "forced").unwrap().scene.unwrap(),
    ];
    for scene in scenes {
        for model in [Model::Reference, Model::Compliant] {
            let run = model.simulate(&scene, &RunOptions::default()).unwrap();
            let s = &run.series;
            let from = scene.frame.unwrap().damped_period();
            let (mut drift, mut roof, mut accel) = (0.0f64, 0.0f64, 0.0f64);
            for k in (0..s.len()).filter(|&k| s.t()[k] >= from) {
                let mut below = 0.0;
                for i in 0..3 {
                    let (u, _, a) = s.floor(i, k).unwrap();
                    drift = drift.max((u - below).abs());
                    accel = accel.max(a.abs());
                    below = u;
                }
                roof = roof.max(below.abs());
            }
            let quiet = model.simulate(&scene, &RunOptions::metrics_only()).unwrap();
            for m in [lpc_damper::metrics::metrics(&run), lpc_damper::metrics::metrics(&quiet)] {
                assert_eq!(m.peak_drift, Some(drift), "{model:?} {}", scene.name);
                assert_eq!(m.peak_roof_displacement, Some(roof), "{model:?} {}", scene.name);
                assert_eq!(m.peak_floor_acceleration, Some(accel), "{model:?} {}", scene.name);
            }
        }
    }
    let frame = lpc_damper::metrics::metrics(&reference(&crate::common::scene_from_toml(LSL_TOML)));
    assert_eq!((frame.peak_drift, frame.peak_roof_displacement, frame.peak_floor_acceleration), (None, None, None));
}

/// `lpc sweep` varies the floor that carries the damper, and refuses a floor the building has
/// not.
#[test]
fn a_sweep_moves_the_damper_from_floor_to_floor() {
    let o = lpc_command()
        .args(["sweep", "scenes/mdof-3storey-record.toml", "--x", "damper_floor=1,2,3", "--horizon", "2", "--format", "json"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let text = out.to_string();
    for name in ["damper_floor", "peak_drift", "peak_roof_displacement", "peak_floor_acceleration"] {
        assert!(text.contains(name), "{name}: {text}");
    }
    let o = lpc_command().args(["sweep", "scenes/mdof-3storey-record.toml", "--x", "damper_floor=1,4"]).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("damper_floor"), "{stderr}");
}

/// A structure's figures: every floor against time, and the drift profile with and without
/// the damper, one point per storey at its peak drift; a frame has neither.
#[test]
fn a_structure_plots_its_floors_and_drift_profile() {
    use lpc_damper::output::figures::floor_responses;
    let scene = lpc_damper::scene::load_scene(lpc_damper::scene::scenes_dir().join("mdof-3storey.toml")).unwrap();
    let (with, without) = (reference(&scene), reference(&scene.without_damper()));
    let figs = floor_responses(&with, Some(&lpc_damper::metrics::FloorSummary::of(&without.series)));
    assert_eq!(figs.iter().map(|f| f.name.as_str()).collect::<Vec<_>>(), ["floors", "drift-profile"]);
    assert_eq!(figs[0].curves.len(), 3);
    let profile = &figs[1].curves;
    assert_eq!(profile.len(), 2);
    let floors = lpc_damper::metrics::FloorSummary::of(&with.series);
    assert_eq!(profile[1].x, floors.iter().map(|f| f.peak_drift * 1e3).collect::<Vec<_>>());
    assert_eq!(profile[1].y, vec![1.0, 2.0, 3.0]);
    let frame = crate::common::scene_from_toml(LSL_TOML);
    assert!(floor_responses(&reference(&frame), None).is_empty());
    // From a run's directory: series.csv gives the floors back exactly, summary.json the bare
    // building's, and `lpc plot` draws both figures.
    let dir = tempfile::tempdir().unwrap();
    let (run_dir, figures) = (dir.path().join("run"), dir.path().join("figures"));
    let o = lpc_command().args(["run", "scenes/mdof-3storey.toml", "--out", run_dir.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let read = lpc_damper::output::figures::read_series_csv(&run_dir.join("series.csv")).unwrap();
    assert_eq!(read.floor_count(), 3);
    for k in [0, read.len() / 2, read.len() - 1] {
        for i in 0..3 {
            assert_eq!(read.floor(i, k), with.series.floor(i, k), "floor {} at sample {k}", i + 1);
        }
    }
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(run_dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["floors_without_damper"].as_array().map(|f| f.len()), Some(3));
    let o = lpc_command().args(["plot", run_dir.to_str().unwrap(), "--out", figures.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for name in ["floors.png", "drift-profile.svg"] {
        assert!(figures.join(name).is_file(), "{name}");
    }
}

/// Under a sine (the ground moving as `Y sin w t`, or a force on the top floor), the floors of
/// the three-storey building agree with the matrix exponential of the state matrix bordered by
/// the sine's own oscillator `[cos; sin]` to 1e-8 of the peak, and the energy balance closes
/// with the excitation's work.
#[test]
fn a_three_storey_building_under_a_sine_is_the_matrix_exponential() {
    let (m, _, _) = building_matrices();
    let n = 3;
    let omega = 2.0 * std::f64::consts::PI * 3.1;
    for (kind, amplitude) in [("base", 0.003), ("force", 2.0)] {
        let text = format!(
            "name = \"sine\"\n[structure]\nmasses = [2.0, 1.6, 1.35]\nstiffnesses = [3000.0, 2400.0, 865.0]\nrayleigh = [0.4, 0.002]\n\
             initial_displacements = [0.001, -0.002, 0.004]\ninitial_velocities = [0.0, 0.05, -0.02]\n\
             [forcing]\nkind = \"{kind}\"\namplitude = {amplitude}\nfrequency = 3.1\n[run]\nhorizon = 2.0\nsample_dt = 0.01\n"
        );
        let scene = crate::common::scene_from_toml(&text);
        let run = reference(&scene);
        assert!(run.energy.balance_error.abs() <= 1e-12, "{kind}: {:?}", run.energy);
        // [u; u'; cos; sin]: u'' = -M^-1 (C u' + K u) + load sin, (cos, sin)' = w (-sin, cos).
        let mut aug = bordered_state_matrix();
        for i in 0..n {
            aug[(n + i, 2 * n + 1)] = if kind == "base" {
                amplitude * omega * omega
            } else if i == 2 {
                amplitude / m[i]
            } else {
                0.0
            };
        }
        aug[(2 * n, 2 * n + 1)] = -omega;
        aug[(2 * n + 1, 2 * n)] = omega;
        let x0 = DVector::from_row_slice(&[0.001, -0.002, 0.004, 0.0, 0.05, -0.02, 1.0, 0.0]);
        let s = &run.series;
        let exact: Vec<DVector<f64>> = s.t().iter().map(|&t| (&aug * t).exp() * &x0).collect();
        let peak_u = exact.iter().flat_map(|z| z.rows(0, n).iter().copied().collect::<Vec<_>>()).fold(0.0, |m: f64, x| m.max(x.abs()));
        let peak_v = exact.iter().flat_map(|z| z.rows(n, n).iter().copied().collect::<Vec<_>>()).fold(0.0, |m: f64, x| m.max(x.abs()));
        for (kk, z) in exact.iter().enumerate() {
            for i in 0..n {
                let (u, v, _) = s.floor(i, kk).unwrap();
                assert!((u - z[i]).abs() <= 1e-8 * peak_u, "{kind}: floor {} at {} s: u {u} vs {}", i + 1, s.t()[kk], z[i]);
                assert!((v - z[n + i]).abs() <= 1e-8 * peak_v, "{kind}: floor {} at {} s: v {v} vs {}", i + 1, s.t()[kk], z[n + i]);
            }
        }
    }
}

/// The LSL damper on the top floor of the three-storey building driven by a sine, through the
/// ground or on the floor, at frequencies where the balls rattle and collect: every run reaches
/// its horizon with no ball through a wall and the energy balanced with the excitation's work.
#[test]
fn a_damper_on_a_building_under_a_sine_keeps_its_balls_inside() {
    let path = lpc_damper::scene::scenes_dir().join("mdof-3storey.toml");
    let base = std::fs::read_to_string(&path).unwrap().replace("horizon = 5.0", "horizon = 3.0");
    for (kind, amplitude) in [("base", 0.002), ("force", 2.0)] {
        for frequency in [3.0, 4.0, 8.0] {
            let text = format!("{base}\n[forcing]\nkind = \"{kind}\"\namplitude = {amplitude}\nfrequency = {frequency}\n");
            let scene = lpc_damper::scene::parse(&text, path.to_str().unwrap(), "sine").unwrap().scene.unwrap();
            let run = reference(&scene);
            assert_eq!(run.horizon, 3.0);
            assert!(run.energy.balance_error.abs() <= 1e-12, "{kind} {frequency} Hz: {:?}", run.energy);
            let gap = crate::common::min_gap(&scene, &run);
            assert!(gap >= -1e-12, "{kind} {frequency} Hz: overlap {gap:e} m");
        }
    }
}

/// `lpc frf` on a building gives every floor's steady amplitude. Without the damper each is the
/// closed form `|U_i|`, `(K - w^2 M + i w C) U = M 1 Y w^2` for the ground moving as
/// `Y sin w t`, to what the reading allows: its blocks agree to `STEADY_TOLERANCE`, and a sine
/// sampled 100 times a period peaks within 5e-4 of its amplitude. The carrying floor's column
/// is the curve's own, and both models give it. The command writes the floors' table.
#[test]
fn the_frequency_response_of_a_building_has_every_floor() {
    use lpc_damper::studies::frf;
    let path = lpc_damper::scene::scenes_dir().join("mdof-3storey.toml");
    let text = std::fs::read_to_string(&path).unwrap() + "\n[forcing]\nkind = \"base\"\namplitude = 0.002\nfrequency = 4.0\n";
    let scene = lpc_damper::scene::parse(&text, path.to_str().unwrap(), "sine").unwrap().scene.unwrap();
    let structure = scene.structure.as_deref().unwrap();
    let b = &structure.building;
    let frequencies = [3.0, 4.0, 6.0];
    let limits = lpc_damper::model::Limits::default();
    for model in [Model::Reference, Model::Compliant] {
        let points = frf::frf(&scene, &frequencies, model, limits, &|| {});
        for p in &points {
            let omega = 2.0 * std::f64::consts::PI * p.frequency;
            let loads: Vec<_> = b.masses.iter().map(|m| nalgebra::Complex::new(m * 0.002 * omega * omega, 0.0)).collect();
            let exact = b.harmonic_response(&b.masses, omega, &loads).unwrap();
            let (with, without) = (p.floors.as_ref().unwrap(), p.floors_no_damper.as_ref().unwrap());
            assert_eq!(with[structure.floor], p.amplitude.unwrap());
            assert!(p.steady_no_damper, "{model:?} at {} Hz", p.frequency);
            for (i, u) in exact.iter().enumerate() {
                let bound = (frf::STEADY_TOLERANCE + 5e-4) * u.norm();
                assert!(
                    (without[i] - u.norm()).abs() <= bound,
                    "{model:?} {} Hz floor {}: {} vs {}",
                    p.frequency,
                    i + 1,
                    without[i],
                    u.norm()
                );
            }
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("sine.toml");
    std::fs::write(&file, &text).unwrap();
    let out = dir.path().join("out");
    let o = lpc_command()
        .args(["frf", file.to_str().unwrap(), "--freq", "3..5", "--steps", "2", "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let table = std::fs::read_to_string(out.join("frf-floors.csv")).unwrap();
    assert_eq!(table.lines().next(), Some("frequency,floor,amplitude,amplitude_no_damper"));
    assert_eq!(table.lines().count(), 1 + 2 * 3);
}

/// A force recorded on the middle floor (`kind = "force_record"`, `floor = 2`): both models
/// against the matrix exponential with the force in the middle floor's row alone, the reference
/// to 1e-8 and the compliant model to its steps times its tolerance; the balance closes with the
/// force's work, and the ground stays still.
#[test]
fn a_force_recorded_on_a_floor_is_the_matrix_exponential() {
    let points: Vec<(f64, f64)> = (0..=200).map(|j| (j as f64 * 0.01, 3.0 * (j as f64 * 0.29).sin())).collect();
    let text = |record: &str| {
        building_text(record).replace("kind = \"record\"", "kind = \"force_record\"").replace("scale = 2.0", "scale = 2.0\nfloor = 2")
    };
    let (_dir, scene) = scene_with_record(text, &points);
    let pattern = [0.0, 1.0 / 1.6, 0.0];
    let exact = reference(&scene);
    assert_floors_follow_load(&exact, &points, 1e-8, pattern);
    assert!(exact.energy.balance_error.abs() <= 1e-9 * exact.energy.forcing_work.abs(), "{:?}", exact.energy);
    let soft = compliant(&scene);
    let bound = soft.events as f64 * scene.compliant.tolerance;
    assert_floors_follow_load(&soft, &points, bound, pattern);
    assert!(soft.energy.balance_error.abs() <= bound * soft.energy.forcing_work.abs(), "{:?}", soft.energy);
    // A force on the top floor (the damper's, by default), where the balls ride.
    let path = lpc_damper::scene::scenes_dir().join("mdof-3storey.toml");
    let damper = std::fs::read_to_string(&path).unwrap().replace("horizon = 5.0", "horizon = 2.0");
    let dir = tempfile::tempdir().unwrap();
    let record: String = points.iter().map(|(t, a)| format!("{t} {a}\n")).collect();
    std::fs::write(dir.path().join("push.txt"), record).unwrap();
    let file = dir.path().join("scene.toml");
    std::fs::write(&file, format!("{damper}\n[forcing]\nkind = \"force_record\"\nfile = \"push.txt\"\n")).unwrap();
    let scene = lpc_damper::scene::load_scene(&file).unwrap();
    assert_eq!(scene.structure.as_ref().unwrap().force.as_ref().unwrap().floor, 2, "the damper's floor by default");
    let run = reference(&scene);
    assert_eq!(run.horizon, 2.0);
    assert!(run.energy.forcing_work != 0.0 && run.energy.balance_error.abs() <= 1e-12, "{:?}", run.energy);
    assert!(crate::common::min_gap(&scene, &run) >= -1e-12);
}
