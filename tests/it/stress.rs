//! Seeded stress run of the reference (what `lpc stress --models reference` does, smaller):
//! random valid scenes with 1-50 balls, mass ratios 1-1000, e in [0, 1], zero to large gaps
//! and clearances, frame periods 1 ms-10 s, xs0 up to ten times the clearance. Every run must
//! pass every check (no panic, finite, no energy gained, impact losses bounded, momentum kept
//! on free frames, balls inside, no stall). The full count is a documented command.

use lpc_damper::studies::stress::{stress, Draws, Outcome};
use lpc_damper::Model;

/// Every outcome passed; otherwise the count, the first failure and its shrunk scene.
fn assert_all_pass(outcomes: &[Outcome]) {
    let failed: Vec<_> = outcomes.iter().filter(|o| o.failure.is_some()).collect();
    assert!(
        failed.is_empty(),
        "{} failures, first: seed {} {:?}\n{}",
        failed.len(),
        failed[0].seed,
        failed[0].failure,
        failed[0].minimal_scene.as_deref().unwrap_or("")
    );
}

#[test]
fn three_hundred_random_scenes_pass_every_check() {
    assert_all_pass(&stress(Model::Reference, 1, 300, Draws::plausible(2.0), &|| {}));
    // The same scenes as 1 to 4 chains side by side.
    assert_all_pass(&stress(Model::Reference, 1, 100, Draws { chains: true, ..Draws::plausible(2.0) }, &|| {}));
}

/// The same scenes with their frames as floors of buildings of 1 to 5 storeys, a third of the
/// free ones shaken by random ground motion (`lpc stress --structures`), through all three
/// models: every check passes, with the storeys' loss and the ground's work in the balance.
/// Seed 40 of these is a stiff, heavily damped building whose reference scan took minutes as
/// its motion died away (`reference::storeys` has its test). The full count (200 scenes per
/// model, all pass) is a documented command.
#[test]
fn random_buildings_pass_every_check() {
    let draws = Draws { structures: true, ..Draws::plausible(2.0) };
    for (model, count) in [(Model::Reference, 40), (Model::Rapier, 20), (Model::Compliant, 10)] {
        assert_all_pass(&stress(model, 30, count, draws, &|| {}));
    }
}

/// Random beds on random buildings (`lpc stress --beds --structures`), a third shaken by random
/// ground motion: the contact and compliant models run them all (none refused), the reference
/// all but those with friction, and every run passes the checks; a run may stop at its budget
/// of computing, which bounds the test's time.
#[test]
fn random_beds_on_buildings_pass_every_check() {
    let draws = Draws { max_wall_s: Some(2.0), beds: true, structures: true, ..Draws::plausible(2.0) };
    run_and_pass(draws, &[(Model::Rapier, 12), (Model::Compliant, 4)]);
    let outcomes = stress(Model::Reference, 1, 40, draws, &|| {});
    assert_all_pass(&outcomes);
    let refused: Vec<&String> = outcomes.iter().filter_map(|o| o.refused.as_ref()).collect();
    assert!(refused.iter().all(|why| why.contains("friction")), "{refused:?}");
    assert!(refused.len() < outcomes.len(), "some draws are frictionless and run");
}

/// Beds drawn as two dampers on floors of their own draws (`lpc stress --beds --structures
/// --dampers`): every model runs them and passes every check on what it runs within its budget
/// (each damper's balls in their own box, energy never gained, the energy balance with each
/// damper's impulses or forces handed to its own floor); the reference refuses only those with
/// friction.
#[test]
fn random_dampers_on_buildings_pass_every_check() {
    let draws = Draws { max_wall_s: Some(3.0), beds: true, structures: true, dampers: true, ..Draws::plausible(1.0) };
    run_and_pass(draws, &[(Model::Rapier, 8), (Model::Compliant, 4)]);
    let outcomes = stress(Model::Reference, 1, 24, Draws { max_wall_s: Some(2.0), ..draws }, &|| {});
    assert_all_pass(&outcomes);
    let refused: Vec<&String> = outcomes.iter().filter_map(|o| o.refused.as_ref()).collect();
    assert!(refused.iter().all(|why| why.contains("friction")), "{refused:?}");
    assert!(refused.len() < outcomes.len(), "some draws are frictionless and run");
}

/// The same under a random harmonic force or base motion (`lpc stress --forced`): besides the
/// free checks, the energy balance against the forcing's work, and no ball inside a wall or
/// another ball beyond the contact tolerance (issue 17). The full count (2000 scenes, horizons
/// up to 10 s, all pass) is a documented command.
#[test]
fn forced_random_scenes_pass_every_check() {
    assert_all_pass(&stress(Model::Reference, 1, 100, Draws { forced: true, ..Draws::plausible(2.0) }, &|| {}));
}

#[test]
fn generated_scenes_are_reproducible_from_their_seed() {
    let a = toml::to_string(&lpc_damper::studies::stress::random_scene_file(42, 100.0, false)).unwrap();
    let b = toml::to_string(&lpc_damper::studies::stress::random_scene_file(42, 100.0, false)).unwrap();
    let c = toml::to_string(&lpc_damper::studies::stress::random_scene_file(43, 100.0, false)).unwrap();
    assert_eq!(a, b);
    assert_ne!(a, c);
}

/// The contact model on the first 25 scenes of the default seed (horizons up to 1 s); a scene
/// refused with a reason, before or during the run, is a pass (`lpc stress --models rapier
/// --count 1000` passes all 1000, 235 of them refused; docs/BENCHMARKS.md "Stress").
#[test]
fn contact_model_passes_the_first_seeded_scenes() {
    assert_all_pass(&stress(Model::Rapier, 1, 25, Draws::plausible(1.0), &|| {}));
}

#[test]
fn contact_model_passes_the_first_seeded_beds() {
    // Beds in boxes, under gravity and friction, some shaken by frames swinging at hundreds of
    // metres per second (seeds 1-10 of `lpc stress --beds`).
    assert_all_pass(&stress(Model::Rapier, 1, 10, Draws { beds: true, ..Draws::plausible(1.0) }, &|| {}));
}

#[test]
fn reference_passes_the_first_seeded_beds() {
    // Seeds 1-23 of the same draws for the reference: rough beds are refused up front; every
    // one of the eight smooth ones it finishes passes every check (the balance closed to
    // round-off with gravity's work, no overlap, no stall); a run may stop at its 3 s budget, a
    // typed stop (a pile costs a million events per contact and simulated second, docs/MODEL.md
    // §14).
    assert_all_pass(&stress(Model::Reference, 1, 23, Draws { max_wall_s: Some(3.0), beds: true, ..Draws::plausible(1.0) }, &|| {}));
}

#[test]
fn compliant_model_passes_the_first_seeded_beds() {
    // The same beds for the compliant model's spatial path: every run it finishes passes every
    // check (its energy balance to the integration error); a run may stop at its 3 s budget,
    // a typed stop (whether it does depends on the machine; what is asserted does not).
    assert_all_pass(&stress(Model::Compliant, 1, 10, Draws { max_wall_s: Some(3.0), beds: true, ..Draws::plausible(1.0) }, &|| {}));
}

/// Issue 19: scenes at the extremes a user can type (`lpc stress --extreme`: 1-10 000 balls,
/// frame periods 1 us-1000 s, mass ratios up to 1e9, densities 1e-3-1e6, gaps, clearances and
/// displacements far beyond the container) end in a pass, a typed refusal or a typed stop at
/// the time budget, never a panic; the reference passes every check on every one it finishes.
/// (Whether a run finishes within its budget depends on the machine; what is asserted does not.)
#[test]
fn extreme_scenes_pass_refuse_or_stop_never_panic() {
    let draws = |max_wall_s| Draws { extreme: true, max_wall_s: Some(max_wall_s), ..Draws::plausible(100.0) };
    assert_all_pass(&stress(Model::Reference, 1, 24, draws(1.0), &|| {}));
    for model in [Model::Rapier, Model::Compliant] {
        for o in stress(model, 1, 6, draws(0.5), &|| {}) {
            assert!(
                o.failure.as_ref().is_none_or(|f| f.check != "panic" && f.check != "non-finite"),
                "{model} seed {}: {:?}",
                o.seed,
                o.failure
            );
        }
    }
}

/// Each model of `counts` runs its count of scenes drawn from seed 30 on as `draws` says,
/// refuses none, and passes every check.
fn run_and_pass(draws: Draws, counts: &[(Model, u64)]) {
    for &(model, count) in counts {
        let outcomes = stress(model, 30, count, draws, &|| {});
        assert_all_pass(&outcomes);
        assert!(outcomes.iter().all(|o| o.refused.is_none()), "{model}: {:?}", outcomes.iter().find_map(|o| o.refused.as_ref()));
    }
}
