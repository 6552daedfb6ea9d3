//! Issue 19's audit: inputs that pass every rule of the scene file and of clap, yet reached a
//! panic (exit 101), an overflow (in debug builds, which the tests are) or an endless run.
//! Each now runs, or stops with the field or the physical reason:
//! - `lpc stress --max-horizon inf` panicked in the random draw (`random_range` on an infinite
//!   range); `--seed` near `u64::MAX` overflowed `seed + count`;
//! - `lpc optimize --steps 2^64-1` and `lpc bench --repeat 2^64-1` allocated without limit;
//! - the contact model on a container without balls subtracted 1 from 0 (`n - 1`);
//! - `large_mass / mass_ratio` underflowing to 0 made an infinite neighbour mass ratio, whose
//!   solver iterations overflowed;
//! - `lpc frf` lengthened a scene past the 2e7-sample rule without checking it
//!   (`sample_count` overflowed at a frequency of 1e-16 Hz);
//! - `lpc merge` sliced a `members.csv` without its metrics columns out of bounds;
//! - `lpc frf --ensemble 1000000 --steps 10000` allocated 2e10 runs' results (an abort).

use std::process::Output;

use crate::common::lpc;

/// The run neither panicked nor overflowed: exit status `code`, and a message if it failed.
fn ends_with(o: &Output, code: i32, words: &[&str]) {
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(o.status.code(), Some(code), "{stderr}");
    for w in words {
        assert!(stderr.contains(w), "`{w}` not in: {stderr}");
    }
}

fn scene_file(dir: &tempfile::TempDir, text: &str) -> String {
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, text).unwrap();
    path.to_str().unwrap().to_string()
}

const FRAME: &str = "[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 1.092\ninitial_displacement = \"-2 Rr\"\n";

#[test]
fn command_line_counts_and_ranges_are_bounded() {
    ends_with(&lpc(["stress", "--max-horizon", "inf", "--count", "1"]), 2, &["--max-horizon"]);
    ends_with(&lpc(["stress", "--extreme", "--max-horizon", "NaN", "--count", "1"]), 2, &["--max-horizon"]);
    ends_with(&lpc(["stress", "--seed", "18446744073709551615", "--count", "2"]), 2, &["--seed"]);
    let forced = lpc_damper::scene::scenes_dir().join("forced-lsl.toml");
    let max = u64::MAX.to_string();
    ends_with(
        &lpc(["optimize", forced.to_str().unwrap(), "--objective", "resonant-amplitude", "--freq", "1..2", "--steps", &max]),
        2,
        &["--steps", "10000"],
    );
    let lsl = lpc_damper::scene::scenes_dir().join("lpc-lsl.toml");
    ends_with(&lpc(["bench", lsl.to_str().unwrap(), "--repeat", &max]), 2, &["--repeat"]);
    ends_with(
        &lpc(["frf", forced.to_str().unwrap(), "--freq", "3..5", "--steps", "10000", "--ensemble", "1000000"]),
        2,
        &["--ensemble", "2e10 runs", "of memory"],
    );
}

#[test]
fn a_container_without_balls_runs_in_every_model() {
    let dir = tempfile::tempdir().unwrap();
    let path = scene_file(
        &dir,
        &format!("name = \"empty\"\n{FRAME}[balls]\narrangement = \"\"\nlarge_mass = 0.11\ndensity = 8000.0\nrestitution = 0.9\ngap = 0.0\nclearance = \"1 Rr\"\n[run]\nhorizon = 0.2\n"),
    );
    for model in ["reference", "rapier", "compliant"] {
        ends_with(&lpc(["run", &path, "--model", model]), 0, &[]);
    }
}

#[test]
fn masses_no_number_can_hold_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let underflow = format!(
        "name = \"tiny\"\n{FRAME}[balls]\narrangement = \"LS\"\nlarge_mass = 1e-300\nmass_ratio = 1e30\ndensity = 8000.0\nrestitution = 0.9\ngap = 0.0\nclearance = \"1 Rr\"\n[run]\nhorizon = 0.2\n"
    );
    ends_with(&lpc(["run", &scene_file(&dir, &underflow), "--model", "rapier"]), 2, &["balls.mass_ratio"]);
    let subnormal = format!(
        "name = \"subnormal\"\n{FRAME}[balls]\narrangement = [{{mass = 0.11}}, {{mass = 1e-320}}]\nlarge_mass = 0.11\ndensity = 8000.0\nrestitution = 0.9\ngap = 0.0\nclearance = \"1 Rr\"\n[run]\nhorizon = 0.2\n"
    );
    ends_with(&lpc(["run", &scene_file(&dir, &subnormal)]), 2, &["balls.arrangement"]);
}

#[test]
fn a_response_curve_past_the_sample_rule_is_refused_with_the_reason() {
    let forced = lpc_damper::scene::scenes_dir().join("forced-lsl.toml");
    // 40 periods of 1e-16 Hz: 4e17 s, sampled a hundred times a period.
    let o = lpc(["frf", forced.to_str().unwrap(), "--freq", "1e-16..2e-16", "--steps", "2"]);
    let (stdout, stderr) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stdout.contains("1e-16 Hz failed") && stdout.contains("4e20 samples over 4e17 s"), "{stdout}");
}

#[test]
fn merge_refuses_a_table_without_its_metrics() {
    let dir = tempfile::tempdir().unwrap();
    let lsl = lpc_damper::scene::scenes_dir().join("lpc-lsl.toml");
    let shard = dir.path().join("shard");
    // A real shard, then its table cut to one column.
    let o = lpc(["run", lsl.to_str().unwrap(), "--ensemble", "4", "--shard", "0/1", "--out", shard.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::write(shard.join("members.csv"), "member\n0\n1\n2\n3\n").unwrap();
    let out = dir.path().join("merged");
    ends_with(&lpc(["merge", shard.to_str().unwrap(), "--out", out.to_str().unwrap()]), 2, &["members.csv", "metrics columns"]);
    assert!(!out.exists());
}
