//! Issue 17: the reference under forcing let a ball through a wall, and the forced stress
//! scenes written to find such misses found three more ways for it to go wrong. One test per
//! bug, each on the scene that showed it.

use crate::common::{lpc_command, min_gap, scene_from_toml as scene};
use lpc_damper::model::RunOptions;

use crate::common::reference;
use lpc_damper::Model;

/// The sign-change scan of the forced frame's acceleration cleared a sub-interval whose end
/// values differed in sign (a bound compared with a value smaller than its own round-off), so
/// a convex and a concave stretch of the gap were searched as one: the ball went 7 mm into the
/// right wall at t = 6.447 s before the run went on.
#[test]
fn a_forced_ball_never_enters_a_wall() {
    let s = scene(
        "[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 1.092\ninitial_displacement = 0.03\n\
         [balls]\narrangement = \"L\"\nlarge_mass = 0.11\nmass_ratio = 10.0\ndensity = 8000.0\nrestitution = 0.9\n\
         gap = 0.025\nclearance = 0.025\n[forcing]\nkind = \"force\"\namplitude = 2.0\nfrequency = 3.3\n\
         [run]\nhorizon = 10.0\nsample_dt = 0.0005\n",
    );
    let run = reference(&s).unwrap();
    // The contact tolerance: 1e-12 of the container (round-off is far below it here).
    let gap = min_gap(&s, &run);
    assert!(gap >= -1e-12 * s.container.unwrap().length, "a ball is {:e} m inside a wall", -gap);
}

/// Balls released by a forced frame got its velocity, which the new segment's closed form
/// then re-evaluated an ulp off: the first ball drifted onto the wall at 4e-16 m/s, was held
/// again, released again, forever at t = 1.486 ms (a hang).
#[test]
fn released_balls_do_not_fall_back_onto_their_wall() {
    let s = scene(
        "[frame]\nmass = 1.35\nstiffness = 1580639.1894490267\ndamping = 526.7879675906153\n\
         initial_displacement = \"0.06668821871335018 Rr\"\n[balls]\narrangement = \"LSSLLLSSLSSLLLSSLSSLLSSSSSLS\"\n\
         large_mass = 0.11\nmass_ratio = 32.64874767625856\ndensity = 8000.0\nrestitution = 1.0\n\
         gap = \"0.0020663638766694266 Rr\"\nclearance = \"0.058979211036339844 Rr\"\n\
         [run]\nhorizon = 0.002\nsample_dt = 0.0001\n\
         [forcing]\nkind = \"base\"\namplitude = 0.005611764237531015\nfrequency = 215.40240833243777\n",
    );
    let run = reference(&s).unwrap();
    assert!(run.energy.balance_error.abs() < 1e-9, "{:e}", run.energy.balance_error);
}

/// Balls at 3 km/s closed a 1.6e-13 m gap in 5e-17 s, less than an ulp of t = 0.51 s: the
/// contact's time rounded to now, the gap stayed open by the resolving judgement, and the same
/// event fired a thousand times (a stall). Touching is now judged within the contact
/// tolerance, which includes two ulps of time at the pair's speed.
#[test]
fn a_contact_closer_than_a_tick_of_time_is_taken() {
    let s = scene(
        "[frame]\nmass = 1.35\nstiffness = 25139924.696604464\ndamping = 866.8917902950009\n\
         initial_displacement = \"-10.468211305858551 Rr\"\n[balls]\narrangement = \"LSS\"\nlarge_mass = 0.11\n\
         mass_ratio = 1.1778454663323934\ndensity = 8000.0\nrestitution = 0.892821675675421\n\
         gap = \"0.0038709224456708008 Rr\"\nclearance = \"3.152509525258354 Rr\"\n\
         [run]\nhorizon = 0.51\nsample_dt = 0.001\n\
         [forcing]\nkind = \"force\"\namplitude = 162195261.029805\nfrequency = 1179.1740839169877\n",
    );
    let run = reference(&s).unwrap();
    assert!(run.energy.balance_error.abs() < 1e-9, "{:e}", run.energy.balance_error);
}

/// Two balls whose contact was accepted within the tolerance of a held ball (which carries
/// the frame's round-off) were later released into a free pair with a smaller tolerance: the
/// postcondition reported the overlap they had been accepted with as a missed contact.
#[test]
fn an_accepted_overlap_stays_accepted() {
    let s = scene(
        "[frame]\nmass = 1.35\nstiffness = 1843664.309791128\ndamping = 216.51388847668068\n\
         initial_displacement = \"-0.9189586049881052 Rr\"\n[balls]\narrangement = \"SLSLSLLLLSSSLLLLSLSSSSSLLS\"\n\
         large_mass = 0.11\nmass_ratio = 6.375734266214517\ndensity = 8000.0\nrestitution = 0.8580111716359315\n\
         gap = \"1.347024149363073 Rr\"\nclearance = \"0.11894698922702122 Rr\"\n\
         [run]\nhorizon = 0.59\nsample_dt = 0.0005\n\
         [forcing]\nkind = \"force\"\namplitude = 86213055.98482168\nfrequency = 50.55983129038648\n",
    );
    let run = Model::Reference.simulate(&s, &RunOptions::default());
    assert!(run.is_ok(), "{}", run.unwrap_err());
}

/// `lpc frf` reads no run as steady when a run failed: the frequency carries the error and no
/// amplitude (here a packed chain whose simultaneous contact solve gains energy, and the
/// contact model stops).
#[test]
fn frf_never_calls_a_failed_run_steady() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("gaining.toml");
    let scene = super::squeezed_ball_stops::GAINING_CHAIN
        .replace("[run]", "[forcing]\nkind = \"force\"\namplitude = 1.0\nfrequency = 100.0\n[run]");
    // The frequency response chooses its own horizon and sampling.
    let scene: String = scene
        .lines()
        .filter(|l| !l.starts_with("horizon") && !l.starts_with("sample_dt") && *l != "[run]")
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(&path, scene).unwrap();
    let out = lpc_command()
        .arg("frf")
        .arg(&path)
        .args(["--freq", "100..120", "--steps", "2", "--model", "rapier", "--format", "json"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1), "{}", String::from_utf8_lossy(&out.stderr));
    let points: Vec<lpc_damper::studies::frf::FrfPoint> = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(points.len(), 2);
    for p in points {
        assert!(!p.steady && p.amplitude.is_none() && p.error.is_some(), "{p:?}");
        // The bare frame has no ball to refuse: its reading stands.
        assert!(p.amplitude_no_damper.is_some());
    }
}
