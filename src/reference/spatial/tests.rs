//! The spatial reference against the one-line reference and its own bounds.

use super::*;
use crate::model::Simulator;
use crate::scene::Body;

/// The spatial run's impacts are the one-line run's, more than twenty of them: the same bodies,
/// times to 1e-12 s, approach speeds to 1e-9 of themselves.
fn assert_same_impacts(spatial: &Run, line: &Run) {
    assert!(line.impacts.len() > 20, "{} impacts", line.impacts.len());
    assert_eq!(spatial.impacts.len(), line.impacts.len());
    for (a, b) in spatial.impacts.iter().zip(&line.impacts) {
        assert_eq!((a.a, a.b), (b.a, b.b), "at {} s", b.t);
        assert!((a.t - b.t).abs() <= 1e-12, "{} s against {} s", a.t, b.t);
        assert!((a.approach_speed - b.approach_speed).abs() <= 1e-9 * b.approach_speed, "at {} s", b.t);
    }
}

/// Balls on one line with no gravity across it, run in a container with a cross-section,
/// meet at the one-line reference's impacts to round-off (the ball-ball times are roots of
/// the same distance, computed in three dimensions).
#[test]
fn balls_on_one_line_give_the_one_line_reference() {
    let mut scene = crate::scene::load(crate::scene::scenes_dir().join("lpc-lsl.toml")).unwrap().scene.unwrap();
    scene.horizon = 0.6;
    let line = super::super::Reference.simulate(&scene, &RunOptions::default()).unwrap();
    scene.space.section = [0.05, 0.05];
    assert!(refusal(&scene).is_none());
    let spatial = simulate(&scene, &RunOptions::default()).unwrap();
    assert_same_impacts(&spatial, &line);
    let (fa, fb) = (spatial.series.xs(), line.series.xs());
    assert!(fa.iter().zip(fb).all(|(a, b)| (a - b).abs() <= 1e-12), "the frame moves alike");
    assert!(spatial.energy.balance_error.abs() <= 1e-12, "{:?}", spatial.energy);
}

/// The same on a building shaken by a record (docs/MODEL.md §16-17): balls on one line on
/// the top floor, run in a container with a cross-section, meet the walls that move with the
/// floors' closed form at the one-line reference's impacts, and every floor moves alike.
#[test]
fn balls_on_one_line_on_a_building_give_the_one_line_reference() {
    let mut scene = crate::scene::load(crate::scene::scenes_dir().join("mdof-3storey-record.toml")).unwrap().scene.unwrap();
    scene.horizon = 4.0;
    let line = super::super::Reference.simulate(&scene, &RunOptions::default()).unwrap();
    scene.space.section = [0.05, 0.05];
    assert!(refusal(&scene).is_none());
    let spatial = simulate(&scene, &RunOptions::default()).unwrap();
    assert_same_impacts(&spatial, &line);
    assert_eq!(spatial.series.floor_count(), 3);
    let mut worst = 0.0f64;
    for k in 0..line.series.len() {
        for i in 0..3 {
            let (a, b) = (spatial.series.floor(i, k).unwrap(), line.series.floor(i, k).unwrap());
            worst = worst.max((a.0 - b.0).abs()).max((a.1 - b.1).abs() * 1e-2);
        }
    }
    assert!(worst <= 1e-12, "the floors differ by {worst:e}");
    let (xa, xb) = (spatial.series.x(0), line.series.x(0));
    assert!(xa.iter().zip(xb).all(|(a, b)| (a - b).abs() <= 1e-12), "the balls are written alike, in the ground's frame");
    assert!(spatial.energy.balance_error.abs() <= 1e-12, "{:?}", spatial.energy);
    assert!(spatial.energy.forcing_work != 0.0, "the ground does work");
}

/// Balls that wait before searching against the frame's walls, their waits kept across
/// the frame's segments, meet the walls where balls that search after every event and
/// every impact on the walls do: `planar-bed`'s first impacts, dozens of them on the end
/// walls, alike to round-off (the searches start at other instants, so roots differ in
/// their last bits, which the bed amplifies later).
#[test]
fn waiting_balls_meet_the_frames_walls_where_searching_ones_do() {
    let mut scene = crate::scene::load(crate::scene::scenes_dir().join("planar-bed.toml")).unwrap().scene.unwrap();
    scene.horizon = 0.1;
    let waiting = simulate_with(&scene, &RunOptions::default(), true, MAX_EVENTS).unwrap();
    let searching = simulate_with(&scene, &RunOptions::default(), false, MAX_EVENTS).unwrap();
    let walls = |impacts: &[Impact]| impacts.iter().filter(|i| matches!((i.a, i.b), (Body::LeftWall, _) | (_, Body::RightWall))).count();
    let alike =
        waiting.impacts.iter().zip(&searching.impacts).take_while(|(a, b)| (a.a, a.b) == (b.a, b.b) && (a.t - b.t).abs() <= 1e-12).count();
    let shared = &waiting.impacts[..alike];
    assert!(alike >= 1000 && walls(shared) >= 30, "{alike} impacts alike, {} on the end walls", walls(shared));
}

/// Balls that wait before searching against the frame's walls, with a bound on the frame's
/// reach that tightens twice as a gas of twenty balls with e = 0.5 loses its energy (from
/// 11.6 mm to 2.5 mm, every wait and search redone each time), meet the frame's walls where
/// balls that search after every event do: every impact of the first 0.4 s, twenty on the
/// end walls, alike to round-off.
#[test]
fn a_bound_tightened_as_the_balls_lose_energy_keeps_the_walls_impacts() {
    let mut text = String::from(
        "name = \"gas\"\n[frame]\nmass = 1.35\nstiffness = 865.0\ndamping = 0.0\ninitial_displacement = 0.0\n\
         [container]\nlength = 0.1\nwidth = 0.06\nheight = 0.1\n[world]\ngravity = [0.0, 0.0, 0.0]\nrestitution = 0.5\n[run]\nhorizon = 0.4\n",
    );
    for i in 0..20 {
        let (x, y, z) = (0.01 + 0.02 * (i % 4) as f64, -0.02 + 0.02 * ((i / 4) % 3) as f64, -0.04 + 0.02 * (i / 12) as f64);
        let v = [(i as f64 * 0.37).sin(), (i as f64 * 0.91).cos(), (i as f64 * 1.73).sin()];
        text += &format!("[[ball]]\nposition = [{x}, {y}, {z}]\nmass = 0.004\nradius = 0.005\nvelocity = [{}, {}, {}]\n", v[0], v[1], v[2]);
    }
    let scene = crate::scene::parse(&text, "gas.toml", "gas").unwrap().scene.unwrap();
    let options = RunOptions::default();
    let mut solver = Solver::new(&scene, ImpactRecord::Every).unwrap();
    let first = solver.frame_reach.as_ref().unwrap().reach;
    solver.run(&Meter::new(&options, BUDGET_EVENTS), &mut Recorder::new(&scene, options.record)).unwrap();
    let last = solver.frame_reach.as_ref().unwrap().reach;
    assert!(solver.reach_version == 2 && last < 0.25 * first, "{} bounds, from {first} m to {last} m", solver.reach_version);
    let waiting = simulate_with(&scene, &options, true, MAX_EVENTS).unwrap();
    let searching = simulate_with(&scene, &options, false, MAX_EVENTS).unwrap();
    assert_eq!(waiting.impacts.len(), searching.impacts.len());
    for (a, b) in waiting.impacts.iter().zip(&searching.impacts) {
        assert!((a.a, a.b) == (b.a, b.b) && (a.t - b.t).abs() <= 1e-12, "{a:?} against {b:?}");
    }
    let walls = waiting.impacts.iter().filter(|i| matches!((i.a, i.b), (Body::LeftWall, _) | (_, Body::RightWall))).count();
    assert!(walls >= 20, "{walls} impacts on the end walls");
}
/// A run past the events it may keep stops with the run so far, which is the unbounded
/// run's up to there, and says what the events cost and how to make them fewer: a bed's
/// events come at the rate the collapse rule allows, so this is a bound, not a stall.
#[test]
fn a_run_past_the_events_it_keeps_stops_with_the_run_so_far() {
    let mut scene = crate::scene::load(crate::scene::scenes_dir().join("planar-bed.toml")).unwrap().scene.unwrap();
    scene.horizon = 0.5;
    let whole = simulate(&scene, &RunOptions::default()).unwrap();
    let bound = whole.events / 2;
    let err = simulate_with(&scene, &RunOptions::default(), true, bound).unwrap_err();
    let message = err.to_string();
    let ModelError::OverBudget(stop) = err else { panic!("{message}") };
    assert_eq!((stop.budget, stop.limit, stop.steps), (Budget::Memory, bound as f64, bound + 1));
    assert!(message.contains("keeps in memory") && message.contains("`[reference] contact_duration`"), "{message}");
    let partial = &stop.partial;
    assert!(stop.t > 0.0 && stop.t < scene.horizon && partial.horizon == stop.t, "stopped at {}", stop.t);
    assert!(!partial.impacts.is_empty() && partial.impacts.len() < whole.impacts.len());
    assert_eq!(partial.impacts[..], whole.impacts[..partial.impacts.len()]);
    assert!(partial.energy.balance_error.abs() <= 1e-12, "{:?}", partial.energy);
    assert!(message.contains("`--impacts count`"), "{message}");
}

/// A run that counts its impacts instead of keeping them is not bounded by memory: past
/// the bound it goes on to the horizon, and it is the run that keeps them, less the list.
#[test]
fn a_run_that_counts_its_impacts_goes_past_the_bound_on_events_kept() {
    let mut scene = crate::scene::load(crate::scene::scenes_dir().join("planar-bed.toml")).unwrap().scene.unwrap();
    scene.horizon = 0.5;
    let whole = simulate(&scene, &RunOptions::default()).unwrap();
    let counting = RunOptions { impacts: ImpactRecord::Count, ..RunOptions::default() };
    let counted = simulate_with(&scene, &counting, true, whole.events / 2).unwrap();
    assert!(counted.impacts.is_empty());
    assert_eq!((counted.counted_impacts.count, counted.impact_count()), (whole.impacts.len(), whole.impact_count()));
    assert_eq!((counted.horizon, counted.events, counted.energy), (whole.horizon, whole.events, whole.energy));
    assert_eq!((counted.series.xs(), counted.final_velocities.as_slice()), (whole.series.xs(), whole.final_velocities.as_slice()));
}
