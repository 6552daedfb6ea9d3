//! Ensembles (`--ensemble N`): members drawn under a scene's `[tolerances]`. Zero tolerances
//! reproduce the single run exactly; a stiffness tolerance gives the analytic distribution of
//! the frame's period; the draws depend only on (seed, k), never on threads; a metrics-only
//! member has exactly the metrics of a full run; bad tolerances are refused with the field.

use lpc_damper::model::{Limits, RunOptions};
use std::f64::consts::PI;

use lpc_damper::metrics::Headline;
use lpc_damper::scene::{self, Loaded};
use lpc_damper::studies::ensemble::{self, quantile};
use lpc_damper::Model;

use crate::common::lpc;

const LSL: &str = crate::common::LSL_TOML;

fn loaded(text: &str) -> Loaded {
    scene::parse(text, "test.toml", "test").expect("the scene parses")
}

fn draw(l: &Loaded, count: usize, seed: Option<u64>) -> ensemble::Ensemble {
    let nominal = l.scene.as_ref().expect("a damper scene");
    ensemble::draw(&l.file, &l.path, nominal, l.tolerances.as_ref(), count, seed).expect("the members draw")
}

#[test]
fn zero_tolerances_reproduce_the_single_run_exactly() {
    // Both kinds of draw: the gaps moved on the built scene, the stiffness rebuilt from the file.
    let l = loaded(&format!("{LSL}[tolerances]\ngap = 0.0\nstiffness = 0.0\nrestitution = 0.0\n"));
    let members = draw(&l, 4, None);
    assert_eq!(members.redraws, 0);
    for model in Model::ALL {
        let single = model.simulate(l.scene.as_ref().unwrap(), &RunOptions::default()).unwrap();
        let expected = Headline::of_run(&single).values();
        let runs = ensemble::run_members(&members, *model, Limits::NONE, true, &|| {}).unwrap();
        for (k, m) in runs.metrics.iter().enumerate() {
            assert_eq!(m, &expected, "{model}: member {k}'s metrics differ from the single run's");
            assert_eq!(runs.xs[k], single.series.xs(), "{model}: member {k}'s displacement differs from the single run's");
        }
    }
}

#[test]
fn metrics_only_runs_have_exactly_the_metrics_of_full_runs() {
    // Forced too: the tally must not depend on the series being kept in any model.
    let forced = format!("{LSL}[forcing]\nkind = \"force\"\namplitude = 2.0\nfrequency = 4.0\n");
    for text in [LSL.to_string(), forced] {
        let s = loaded(&text).scene.unwrap();
        for model in Model::ALL {
            let full = model.simulate(&s, &RunOptions::default()).unwrap();
            let lean = model.simulate(&s, &RunOptions::metrics_only()).unwrap();
            assert!(lean.series.is_empty(), "{model}: a metrics-only run kept its series");
            assert!(!full.series.is_empty());
            assert_eq!(Headline::of_run(&lean), Headline::of_run(&full), "{model} on {}", s.name);
        }
    }
}

#[test]
fn dissipation_times_are_where_the_energy_falls_to_each_level() {
    // A bare damped frame: energy at each sample in closed form,
    // x = xs0 e^{-st} (cos wt + s/w sin wt), v = -xs0 (w^2 + s^2)/w e^{-st} sin wt.
    let text = "[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 1.092\ninitial_displacement = 0.0185\n\
                [balls]\narrangement = \"L\"\nlarge_mass = 0.11\ndensity = 8000.0\nrestitution = 0.9\ngap = 0.2\nclearance = 0.2\n\
                [run]\nhorizon = 8.0\n";
    let s = loaded(text).scene.unwrap();
    let run = Model::Reference.simulate(&s, &RunOptions::default()).unwrap();
    assert!(run.impacts.is_empty(), "the ball was meant to stay clear of the walls");
    let (m, k, c, x0): (f64, f64, f64, f64) = (1.35, 865.0, 1.092, 0.0185);
    let sigma = c / (2.0 * m);
    let w = (k / m - sigma * sigma).sqrt();
    let energy = |t: f64| {
        let decay = (-sigma * t).exp();
        let x = x0 * decay * ((w * t).cos() + sigma / w * (w * t).sin());
        let v = -x0 * (w * w + sigma * sigma) / w * decay * (w * t).sin();
        0.5 * m * v * v + 0.5 * k * x * x
    };
    let e0 = 0.5 * k * x0 * x0;
    let first_below = |level: f64| (0..=8000).map(|i| i as f64 * 1e-3).find(|&t| energy(t) <= level * e0);
    let metrics = lpc_damper::metrics::metrics(&run);
    for (got, level) in [(metrics.dissipation_time_90, 0.1), (metrics.dissipation_time_99, 0.01)] {
        // The reference's is exact: the energy is at the level there (to the round-off of the
        // closed form), and the first sample below it comes within one step after.
        let t = got.expect("reached within the horizon");
        assert!((energy(t) - level * e0).abs() < 1e-9 * e0, "E({t}) = {} vs {}", energy(t), level * e0);
        let sample = first_below(level).unwrap();
        assert!(t <= sample && sample - t < 1e-3, "{t} vs first sample below {sample}");
    }
    // Forced runs have none: energy need not fall.
    let forced = loaded(&format!("{text}[forcing]\nkind = \"force\"\namplitude = 1.0\nfrequency = 3.0\n")).scene.unwrap();
    let m = lpc_damper::metrics::metrics(&Model::Reference.simulate(&forced, &RunOptions::default()).unwrap());
    assert_eq!((m.dissipation_time_90, m.dissipation_time_99), (None, None));
}

#[test]
fn a_uniform_stiffness_tolerance_gives_the_analytic_distribution_of_the_period() {
    // An undamped frame whose ball never reaches a wall: period 2 pi sqrt(m / k) with k uniform
    // on [k0 - w, k0 + w], so P(T <= tau) = (k0 + w - 4 pi^2 m / tau^2) / (2 w).
    let (m, k0, w): (f64, f64, f64) = (1.35, 865.0, 200.0);
    let text = format!(
        "[frame]\nmass = {m}\nstiffness = {k0}\ndamping = 0.0\ninitial_displacement = 0.001\n\
         [balls]\narrangement = \"L\"\nlarge_mass = 0.11\ndensity = 8000.0\nrestitution = 0.9\ngap = 0.05\nclearance = 0.05\n\
         [run]\nhorizon = 0.6\nsample_dt = 1e-4\n[tolerances]\nstiffness = {w}\n"
    );
    let l = loaded(&text);
    let n = 400;
    let members = draw(&l, n, Some(7));
    let periods: Vec<f64> = ensemble::map_members(
        &members.members,
        |member| {
            let run = Model::Reference.simulate(&member.scene, &RunOptions::default())?;
            assert!(run.impacts.is_empty());
            // Two upward zero crossings of xs (linearly interpolated) one period apart.
            let (t, x) = (&run.series.t(), &run.series.xs());
            let ups: Vec<f64> = (1..x.len())
                .filter(|&i| x[i - 1] < 0.0 && x[i] >= 0.0)
                .map(|i| t[i - 1] + (t[i] - t[i - 1]) * -x[i - 1] / (x[i] - x[i - 1]))
                .collect();
            Ok::<_, lpc_damper::model::ModelError>(ups[1] - ups[0])
        },
        &|| {},
    )
    .unwrap();
    let cdf = |tau: f64| ((k0 + w - 4.0 * PI * PI * m / (tau * tau)) / (2.0 * w)).clamp(0.0, 1.0);
    let mut sorted = periods.clone();
    sorted.sort_by(f64::total_cmp);
    let ks = sorted
        .iter()
        .enumerate()
        .map(|(i, &tau)| (cdf(tau) - i as f64 / n as f64).abs().max(((i + 1) as f64 / n as f64 - cdf(tau)).abs()))
        .fold(0.0, f64::max);
    // One-sample Kolmogorov-Smirnov test at 1 % significance: critical value 1.628 / sqrt(n).
    // The measured periods err by far less (interpolated crossings of 0.1 ms samples) than
    // the spread (+-12 % in k, +-6 % in T).
    assert!(ks < 1.628 / (n as f64).sqrt(), "KS statistic {ks} rejects the analytic distribution");
    // And the draws span the range: the extremes of k lie within a few 1/n of its ends.
    let t_of = |k: f64| 2.0 * PI * (m / k).sqrt();
    assert!(quantile(&sorted, 0.0) < t_of(k0 + w * (1.0 - 10.0 / n as f64)));
    assert!(quantile(&sorted, 1.0) > t_of(k0 - w * (1.0 - 10.0 / n as f64)));
}

#[test]
fn members_draw_uniform_numbers_across_indices() {
    // The first number of each of 20000 members, against the uniform distribution (one-sample
    // Kolmogorov-Smirnov at 1 % significance, critical value 1.628 / sqrt(n)): members whose
    // generators were seeded alike would share their numbers and fail it by far.
    use rand::Rng;
    let n = 20_000;
    for seed in [0, 1, 7] {
        let mut u: Vec<f64> = (0..n).map(|k| ensemble::member_rng(seed, k).random::<f64>()).collect();
        u.sort_by(f64::total_cmp);
        let ks = u
            .iter()
            .enumerate()
            .map(|(i, &x)| (x - i as f64 / n as f64).abs().max(((i + 1) as f64 / n as f64 - x).abs()))
            .fold(0.0, f64::max);
        assert!(ks < 1.628 / (n as f64).sqrt(), "seed {seed}: KS statistic {ks}");
    }
}

#[test]
fn members_depend_on_seed_and_index_only() {
    let l = loaded(&format!("{LSL}[tolerances]\ngap = \"0.02 Rr\"\nrestitution = 0.02\nseed = 5\n"));
    let (a, b) = (draw(&l, 8, None), draw(&l, 3, None));
    for (x, y) in a.members.iter().zip(&b.members) {
        assert_eq!(x.drawn, y.drawn, "member {} depends on the ensemble's size", x.index);
    }
    assert_eq!(a.seed, 5);
    let c = draw(&l, 3, Some(6));
    assert_ne!(c.members[0].drawn, a.members[0].drawn, "--seed is ignored");
    // The gaps move with the container held: the clearance takes up their sum.
    let nominal = l.scene.as_ref().unwrap();
    for m in &a.members {
        let gaps: f64 = m.drawn[..3].iter().sum();
        let c = m.scene.container.unwrap();
        let sum_d: f64 = m.scene.balls.iter().map(|b| 2.0 * b.radius).sum();
        approx::assert_relative_eq!(gaps + sum_d + c.clearance, nominal.container.unwrap().length, max_relative = 1e-12);
    }
}

#[test]
fn the_same_seed_gives_the_same_bytes_at_any_thread_count() {
    // The paper scene's own tolerance: each gap within 0.02 Rr.
    let tmp = tempfile::tempdir().unwrap();
    let path = scene::scenes_dir().join("lpc-lsl.toml");
    let run = |threads: &str, out: &str| {
        let o = crate::common::lpc_command()
            .env("RAYON_NUM_THREADS", threads)
            .args(["run", "--horizon", "1", "--ensemble", "24", "--seed", "3", "--out"])
            .arg(tmp.path().join(out))
            .arg(&path)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        ["members.csv", "band.csv"].map(|f| std::fs::read(tmp.path().join(out).join(f)).unwrap())
    };
    let (one, two) = (run("1", "one"), run("2", "two"));
    assert_eq!(one, two, "members.csv or band.csv differ between 1 and 2 threads");
    let members = String::from_utf8(one[0].clone()).unwrap();
    assert_eq!(members.lines().count(), 25);
    assert!(members.starts_with("member,gap1,gap2,gap3,peak_displacement,"));
}

#[test]
fn run_ensemble_json_has_every_metric_distribution() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("lsl.toml");
    std::fs::write(&path, format!("{LSL}[tolerances]\ngap = \"0.02 Rr\"\n")).unwrap();
    let out = lpc(["run".as_ref(), path.as_os_str(), "--ensemble".as_ref(), "16".as_ref(), "--format".as_ref(), "json".as_ref()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["members"], 16);
    assert_eq!(v["redraws"], 0);
    for name in lpc_damper::metrics::Metric::ALL.iter().map(|m| m.name()) {
        let s = &v["metrics"][name];
        assert!(s.is_object(), "{name} missing");
        if let (Some(lo), Some(med), Some(hi)) = (s["p05"].as_f64(), s["median"].as_f64(), s["p95"].as_f64()) {
            assert!(s["min"].as_f64().unwrap() <= lo && lo <= med && med <= hi && hi <= s["max"].as_f64().unwrap(), "{name}: {s}");
        }
    }
    // Impulse models have no contact force: every member reports it undefined.
    assert_eq!(v["metrics"]["peak_contact_force"]["undefined"], 16);
    assert!(v["metrics"]["dissipation_time_90"]["median"].as_f64().is_some());
}

#[test]
fn studies_answer_with_distributions() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("lsl.toml");
    std::fs::write(&path, format!("{LSL}[tolerances]\ngap = \"0.02 Rr\"\n")).unwrap();
    let p = path.to_str().unwrap();
    let json = |args: &[&str]| -> serde_json::Value {
        let out = lpc(args.iter().copied().chain(["--format", "json"]));
        assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
        serde_json::from_slice(&out.stdout).unwrap()
    };
    // compare: every model against the reference's distribution.
    let v = json(&["compare", p, "--models", "rapier", "--ensemble", "6"]);
    let d = &v["models"]["rapier"]["agreement"]["dissipation_time_90"];
    assert!(d["ks"].as_f64().is_some_and(|k| (0.0..=1.0).contains(&k)), "{d}");
    assert!(d["median_inside_reference_band"].is_boolean());
    assert_eq!(v["reference"]["agreement"]["impact_count"]["ks"], 0.0);
    assert_eq!(v["reference"]["agreement"]["impact_count"]["differ_at_5_percent"], false);
    // sweep: every point a distribution, read at the chosen quantile.
    let v = json(&["sweep", p, "--x", "clearance=1Rr,2Rr", "--ensemble", "6", "--quantile", "0.9", "--metric", "impact_loss"]);
    let points = v.as_array().unwrap();
    assert_eq!(points.len(), 2);
    for point in points {
        let (q, s) = (point["at_quantile"]["impact_loss"].as_f64().unwrap(), &point["metrics"]["impact_loss"]);
        assert!(s["median"].as_f64().unwrap() <= q && q <= s["max"].as_f64().unwrap(), "{point}");
    }
    // optimize: ranked by the quantile, the best's band against the runner-up's.
    let v = json(&["optimize", p, "--vary", "gap=0.2Rr,0.3Rr", "--refinements", "0", "--ensemble", "8", "--quantile", "0.5"]);
    assert!(v["distinguishable"].is_boolean(), "{v}");
    let best = &v["ranking"][0];
    let (lo, hi) = (best["band"][0].as_f64().unwrap(), best["band"][1].as_f64().unwrap());
    assert!(lo <= hi);
    // frf: per frequency the distribution of per-period peaks, with and without the damper.
    let text = format!("{LSL}[forcing]\nkind = \"force\"\namplitude = 2.0\nfrequency = 4.0\n[tolerances]\ngap = \"0.02 Rr\"\n");
    std::fs::write(&path, text).unwrap();
    let v = json(&["frf", p, "--freq", "3..5", "--steps", "2", "--ensemble", "3"]);
    for band in v.as_array().unwrap() {
        assert_eq!(band["members"], 3);
        let (a, b) = (&band["amplitude"], &band["amplitude_no_damper"]);
        assert!(a["p05"].as_f64().unwrap() <= a["p95"].as_f64().unwrap() && b["median"].as_f64().unwrap() > 0.0, "{band}");
    }
}

#[test]
fn bad_tolerances_name_the_field_and_write_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let cases = [
        ("gap = -0.001", "tolerances.gap"),
        ("stiffness = nan", "tolerances.stiffness"),
        ("stifness = 1.0", "stifness"),
        ("mass_ratio = \"0.1 Rr\"", "tolerances.mass_ratio"),
        ("distribution = \"cauchy\"", "distribution"),
        // Every draw puts a ball through its neighbour: the gap is 0.25 Rr, the spread 5 Rr.
        ("gap = \"5 Rr\"", "tolerances.gap"),
        // A restitution drawn from [0.9 - 2, 0.9 + 2] leaves [0, 1] far more often than not.
        ("restitution = 2.0", "tolerances.restitution"),
        ("forcing_amplitude = 0.1", "tolerances.forcing_amplitude"),
    ];
    for (line, field) in cases {
        let path = tmp.path().join("bad.toml");
        std::fs::write(&path, format!("{LSL}[tolerances]\n{line}\n")).unwrap();
        let out_dir = tmp.path().join("out");
        let out = lpc(["run".as_ref(), path.as_os_str(), "--ensemble".as_ref(), "20".as_ref(), "--out".as_ref(), out_dir.as_os_str()]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{line}: {stderr}");
        assert!(stderr.contains(field), "{line}: the error does not name `{field}`: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(!out_dir.exists(), "{line}: something was written");
    }
    // An ensemble whose members cannot all be held (a million members of 10 000 balls: about
    // 500 GB) is refused before any is drawn, with the numbers.
    let path = tmp.path().join("many.toml");
    std::fs::write(&path, LSL.replace("arrangement = \"LSL\"", &format!("arrangement = \"{}\"", "L".repeat(10_000)))).unwrap();
    let out = lpc(["run".as_ref(), path.as_os_str(), "--ensemble".as_ref(), "1000000".as_ref()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("--ensemble") && stderr.contains("GB of memory") && stderr.contains("10000 balls"), "{stderr}");
    // And the ensemble's own bounds.
    let out = lpc(["run", "scenes/lpc-lsl.toml", "--ensemble", "0"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--ensemble"));
    let out = lpc(["sweep", "scenes/sweep-gap.toml", "--ensemble", "2", "--quantile", "1.5"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--quantile"));
}

#[test]
fn exact_reference_metrics_bound_the_sampled_ones_within_one_sample() {
    // The reference computes its free-vibration metrics from the closed form; read at its own
    // samples they can only miss a peak, a crossing or an energy level by one sample's motion.
    for name in ["lpc-lsl", "lpc-lslsl", "conventional", "no-damper"] {
        let s = scene::load_scene(scene::scenes_dir().join(format!("{name}.toml"))).unwrap();
        let run = Model::Reference.simulate(&s, &RunOptions::default()).unwrap();
        let exact = run.motion;
        let series = &run.series;
        let mut tally = lpc_damper::run::SampleTally::new(&s);
        for k in 0..series.len() {
            let kinetic: f64 = s.balls.iter().enumerate().map(|(i, b)| 0.5 * b.mass * series.v(i)[k].powi(2)).sum();
            let energy = s.frame_energy(series.t()[k], series.xs()[k], series.vs()[k]) + kinetic;
            tally.add(series.t()[k], series.xs()[k], series.a()[k], energy);
        }
        let sampled = tally.finish();
        let step = |v: &[f64]| v.windows(2).map(|w| (w[1] - w[0]).abs()).fold(0.0, f64::max);
        let dt = s.sample_dt;
        let (dx, da) = (exact.peak_displacement - sampled.peak_displacement, exact.peak_acceleration - sampled.peak_acceleration);
        assert!((0.0..=step(series.xs())).contains(&dx), "{name}: peak xs exact - sampled = {dx}");
        assert!((0.0..=step(series.a())).contains(&da), "{name}: peak a exact - sampled = {da}");
        match (exact.settling_time, sampled.settling_time) {
            (Some(e), Some(t)) => assert!(e >= t && e < t + dt, "{name}: settling {e} vs sampled {t}"),
            (e, t) => assert_eq!(e, t, "{name}: settled in one and not the other"),
        }
        for (e, t) in exact.dissipation_times.iter().zip(sampled.dissipation_times) {
            match (e, t) {
                (Some(e), Some(t)) => assert!(*e <= t && *e > t - dt, "{name}: dissipation {e} vs sampled {t}"),
                (e, t) => assert!(e.is_some() && t.is_none() || e.is_none() && t.is_none(), "{name}: {e:?} vs {t:?}"),
            }
        }
        // RMS: the trapezoid rule over the samples against the exact integral, within the
        // trapezoid rule's error: dt^2 T / 12 max |(x^2)''| on smooth stretches, plus dt |x| |dv|
        // at each kink (an impact on the frame).
        let n = series.len();
        let sum: f64 = series.xs().iter().map(|x| x * x).sum::<f64>() - 0.5 * (series.xs()[0].powi(2) + series.xs()[n - 1].powi(2));
        let trapezoid = sum * dt;
        let (vmax, xmax, amax) = [series.vs(), series.xs(), series.a()].map(|v| v.iter().fold(0.0f64, |m, x| m.max(x.abs()))).into();
        let kinks: f64 = run.impacts.len() as f64 * dt * xmax * 2.0 * vmax;
        let bound = dt * dt * s.horizon / 12.0 * (2.0 * vmax * vmax + 2.0 * xmax * amax) + kinks;
        let integral = exact.rms_displacement.powi(2) * s.horizon;
        assert!((trapezoid - integral).abs() <= bound, "{name}: trapezoid {trapezoid} vs exact {integral} (bound {bound})");
    }
}

/// Shards (`--shard I/K`) merged by `lpc merge` give the unsharded run's `members.csv` and
/// `members.parquet` byte for byte, and the Parquet table holds the CSV's numbers.
#[test]
fn shards_merge_into_the_unsharded_table() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("lsl.toml");
    std::fs::write(&path, format!("{LSL}[tolerances]\ngap = \"0.02 Rr\"\nrestitution = 0.05\n")).unwrap();
    let dir = |name: &str| tmp.path().join(name);
    let run = |args: &[&str], out: &std::path::Path| {
        let mut all: Vec<&std::ffi::OsStr> =
            vec!["run".as_ref(), path.as_os_str(), "--ensemble".as_ref(), "23".as_ref(), "--seed".as_ref(), "5".as_ref()];
        all.extend(args.iter().map(std::ffi::OsStr::new));
        all.extend(["--out".as_ref(), out.as_os_str()]);
        let o = lpc(all);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    run(&[], &dir("whole"));
    for i in 0..4 {
        run(&["--shard", &format!("{i}/4")], &dir(&format!("shard{i}")));
    }
    let o = lpc([
        "merge".as_ref(),
        dir("shard3").as_os_str(),
        dir("shard1").as_os_str(),
        dir("shard0").as_os_str(),
        dir("shard2").as_os_str(),
        "--out".as_ref(),
        dir("merged").as_os_str(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for file in ["members.csv", "members.parquet"] {
        assert_eq!(std::fs::read(dir("whole").join(file)).unwrap(), std::fs::read(dir("merged").join(file)).unwrap(), "{file}");
    }
    let whole: serde_json::Value = serde_json::from_slice(&std::fs::read(dir("whole").join("ensemble.json")).unwrap()).unwrap();
    let merged: serde_json::Value = serde_json::from_slice(&std::fs::read(dir("merged").join("ensemble.json")).unwrap()).unwrap();
    assert_eq!(whole["metrics"], merged["metrics"]);
    assert_eq!(whole["redraws"], merged["redraws"]);

    // The Parquet table reads back to the CSV's numbers.
    use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
    let file = std::fs::File::open(dir("whole").join("members.parquet")).unwrap();
    let batches: Vec<_> = ParquetRecordBatchReaderBuilder::try_new(file).unwrap().build().unwrap().collect::<Result<_, _>>().unwrap();
    let csv_text = std::fs::read_to_string(dir("whole").join("members.csv")).unwrap();
    let mut csv = csv::Reader::from_reader(csv_text.as_bytes());
    let header: Vec<String> = csv.headers().unwrap().iter().map(String::from).collect();
    let rows: Vec<csv::StringRecord> = csv.records().map(Result::unwrap).collect();
    let batch = &batches[0];
    assert_eq!(batches.len(), 1);
    assert_eq!(batch.num_rows(), 23);
    for (c, name) in header.iter().enumerate() {
        let col = batch.column_by_name(name).unwrap_or_else(|| panic!("{name} missing from the Parquet table"));
        for (r, row) in rows.iter().enumerate() {
            let cell = &row[c];
            let got = if col.is_null(r) {
                None
            } else if let Some(a) = col.as_any().downcast_ref::<arrow_array::Float64Array>() {
                Some(a.value(r))
            } else {
                Some(col.as_any().downcast_ref::<arrow_array::Int64Array>().unwrap().value(r) as f64)
            };
            assert_eq!(got, (!cell.is_empty()).then(|| cell.parse::<f64>().unwrap()), "{name} row {r}");
        }
    }
    let model = batch.column_by_name("model").unwrap().as_any().downcast_ref::<arrow_array::StringArray>().unwrap();
    assert_eq!(model.value(0), "reference");

    // Shards of different ensembles, or missing ones, are refused with the directory.
    let o = lpc(["merge".as_ref(), dir("shard0").as_os_str(), dir("shard2").as_os_str(), "--out".as_ref(), dir("bad").as_os_str()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("shard2"));
    assert!(!dir("bad").exists());
    let o = lpc(["run".as_ref(), path.as_os_str(), "--ensemble".as_ref(), "3".as_ref(), "--shard".as_ref(), "3/3".as_ref()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--shard"));
}

/// A bed placed at random is placed anew in each member, from a seed of the member's own drawn
/// from `(seed, k)`: the members differ, the same seed gives the same members, and each member
/// is the scene file with that bed seed.
#[test]
fn members_of_a_random_bed_place_their_own_beds() {
    let text = "[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 1.092\ninitial_displacement = 0.01\n\
                [container]\nlength = 0.1\nwidth = 0.04\nheight = 0.03\n[world]\nrestitution = 0.6\n\
                [bed]\ncount = 12\nradii = [0.004]\ndensity = 7800.0\nplacement = \"random\"\n";
    let l = lpc_damper::scene::parse(text, "bed.toml", "bed").unwrap();
    let nominal = l.scene.as_ref().unwrap();
    let members = ensemble::draw(&l.file, &l.path, nominal, None, 3, Some(5)).unwrap();
    assert_eq!(members.columns, vec!["bed_seed".to_string()]);
    let again = ensemble::draw(&l.file, &l.path, nominal, None, 3, Some(5)).unwrap();
    for (a, b) in members.members.iter().zip(&again.members) {
        assert_eq!(a.scene, b.scene);
    }
    for (i, a) in members.members.iter().enumerate() {
        for b in &members.members[i + 1..] {
            assert_ne!(a.scene.space.lateral, b.scene.space.lateral);
        }
        let seed = a.drawn[0];
        assert_eq!(seed, seed.trunc());
        let placed = lpc_damper::scene::parse(&format!("{text}seed = {}\n", seed as u64), "bed.toml", "bed").unwrap();
        let placed = placed.scene.unwrap();
        assert_eq!((&placed.space, &placed.initial_positions), (&a.scene.space, &a.scene.initial_positions));
    }
}

/// Nine balls in the middle of a box, 20 mm apart on a square grid, under `gravity`,
/// their positions toleranced by `spread` (uniform).
fn grid_of_balls(gravity: &str, spread: f64) -> String {
    let mut text = format!(
        "[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 1.092\ninitial_displacement = 0.01\n\
         [container]\nlength = 0.08\nwidth = 0.06\nheight = 0.03\n\
         [world]\nrestitution = 0.6\ngravity = {gravity}\n[tolerances]\nposition = {spread}\n"
    );
    for i in 0..9 {
        let (x, y) = (0.02 + 0.02 * (i % 3) as f64, -0.02 + 0.02 * (i / 3) as f64);
        text += &format!("[[ball]]\nposition = [{x}, {y}, 0.0]\nmass = 0.002\nradius = 0.004\n");
    }
    text
}

#[test]
fn ball_positions_scatter_uniformly_across_gravity() {
    let w = 1e-3;
    // Under gravity along -z the balls keep their heights; each moves in x and y by its own
    // uniform draw on [-w, w), which never brings two balls (12 mm apart) or a wall
    // (6 mm off) into reach, so no draw is thrown away and the draws are exactly uniform.
    let l = loaded(&grid_of_balls("[0.0, 0.0, -9.81]", w));
    let nominal = l.scene.as_ref().unwrap();
    let members = draw(&l, 200, Some(7));
    assert_eq!(members.redraws, 0);
    assert_eq!(members.columns, vec!["position_rms".to_string()]);
    let mut draws = vec![];
    for m in &members.members {
        let mut squares = 0.0;
        for i in 0..9 {
            let [y, z] = m.scene.space.lateral[i];
            let [y0, z0] = nominal.space.lateral[i];
            assert_eq!(z, z0, "member {}: ball {} left the floor", m.index, i + 1);
            let d = [m.scene.initial_positions[i] - nominal.initial_positions[i], y - y0];
            assert!(d.iter().all(|d| d.abs() <= w * (1.0 + 1e-9)), "member {}: {d:?}", m.index);
            squares += d[0] * d[0] + d[1] * d[1];
            draws.extend(d);
        }
        let rms = (squares / 9.0).sqrt();
        assert!((m.drawn[0] - rms).abs() <= 1e-9 * w, "member {}: position_rms {} against {rms}", m.index, m.drawn[0]);
    }
    // Kolmogorov-Smirnov against the uniform law on [-w, w] at the 1 % level (the critical
    // distance 1.63 / sqrt(n) for n draws; the positions' rounding, 1e-17 m, is far below it).
    draws.sort_by(f64::total_cmp);
    let n = draws.len() as f64;
    let distance = draws
        .iter()
        .enumerate()
        .map(|(k, d)| {
            let cdf = (d + w) / (2.0 * w);
            (cdf - k as f64 / n).abs().max((cdf - (k + 1) as f64 / n).abs())
        })
        .fold(0.0, f64::max);
    assert!(distance < 1.63 / n.sqrt(), "KS distance {distance} over {n} draws");
    // Members differ, and each runs.
    assert_ne!(members.members[0].scene.space.lateral, members.members[1].scene.space.lateral);
    let mut member = members.members[0].scene.clone();
    member.horizon = 0.05;
    Model::Reference.simulate(&member, &RunOptions::default()).expect("a moved bed runs");
}

#[test]
fn ball_positions_move_along_every_axis_but_gravity() {
    // Without gravity the balls move along all three axes; under a tilted gravity only across
    // it, to the rounding of the projection (a few ulps of the spread).
    let w = 1e-3;
    for (gravity, across_only) in [("[0.0, 0.0, 0.0]", false), ("[0.0, -3.0, -9.0]", true)] {
        let l = loaded(&grid_of_balls(gravity, w));
        let nominal = l.scene.as_ref().unwrap();
        let members = draw(&l, 20, Some(3));
        let down = nominal.space.gravity.map(|g| g / 90f64.sqrt());
        let mut moved_along_z = false;
        for m in &members.members {
            for i in 0..9 {
                let d = [
                    m.scene.initial_positions[i] - nominal.initial_positions[i],
                    m.scene.space.lateral[i][0] - nominal.space.lateral[i][0],
                    m.scene.space.lateral[i][1] - nominal.space.lateral[i][1],
                ];
                let along: f64 = (0..3).map(|a| d[a] * down[a]).sum();
                if across_only {
                    assert!(along.abs() <= 8.0 * f64::EPSILON * w, "{gravity}: ball {} moved {along} m along gravity", i + 1);
                }
                moved_along_z |= d[2] != 0.0;
            }
        }
        assert!(moved_along_z, "{gravity}: no ball moved in z");
    }
}

#[test]
fn position_tolerances_need_room_and_a_bed() {
    let tmp = tempfile::tempdir().unwrap();
    let box_scene = std::fs::read_to_string("scenes/particle-box.toml").unwrap();
    let cases = [
        // A chain's balls take gaps, not positions.
        (format!("{LSL}[tolerances]\nposition = 0.001\n"), "needs balls placed in a box"),
        (grid_of_balls("[0.0, 0.0, -9.81]", -1e-3), "must not be negative"),
        (grid_of_balls("[0.0, 0.0, -9.81]", 1e-3).replace("position = 0.001", "position = \"0.1 Rr\""), "give metres"),
        // The particle box's lattice leaves 10 um between neighbours: a millimetre's spread
        // almost always makes two balls overlap.
        (format!("{box_scene}[tolerances]\nposition = 0.001\n"), "is too wide"),
    ];
    for (text, rule) in cases {
        let path = tmp.path().join("bad.toml");
        std::fs::write(&path, text).unwrap();
        let out_dir = tmp.path().join("out");
        let out = lpc(["run".as_ref(), path.as_os_str(), "--ensemble".as_ref(), "4".as_ref(), "--out".as_ref(), out_dir.as_os_str()]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains("tolerances.position") && stderr.contains(rule), "{stderr}");
        assert!(!out_dir.exists(), "something was written: {stderr}");
    }
}
