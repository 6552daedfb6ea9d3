//! Several dampers on one structure (docs/MODEL.md §18): each container's balls push their own
//! floor in every model, a damper that touches nothing leaves the others'
//! run as it was, one `[[damper]]` is the scene of today's format, and the reference carries
//! several beyond one line and refuses them on lines with the reason.

use lpc_damper::metrics::DamperSummary;
use lpc_damper::model::{Model, RunOptions};
use lpc_damper::run::Run;
use lpc_damper::scene::{parse, Scene, SceneError};
use lpc_damper::studies::stress::judge;

use crate::common::lpc;

/// The three-storey building of scenes/mdof-3storey-record.toml swinging freely from a
/// displaced start, with `more` after it (the damper tables, or a damper floor). Friction has
/// nothing to act on between balls on one axis; it sends one damper down the spatial path that
/// carries several, so that the two are the same arithmetic.
fn building(more: &str) -> String {
    format!(
        "[structure]\nmasses = [1.35, 1.35, 1.35]\nstiffnesses = [4364.0, 4364.0, 4364.0]\n\
         damping_ratios = [0.016, 0.016, 0.016]\ninitial_displacements = [0.005, 0.01, 0.015]\n{more}\
         [world]\nrestitution = 0.6\nfriction = 0.1\n\
         [compliant]\nyoungs_modulus = 2e9\n\
         [run]\nhorizon = 0.5\nsample_dt = 0.001\n"
    )
}

/// Three 4 g balls of 5 mm in a 6 cm box, on its axis, the middle one moving: the box's walls
/// and the balls strike each other as the floor swings. `prefix` is `""` for the scene's one
/// damper and `"damper."` inside a `[[damper]]`.
fn three_balls(prefix: &str) -> String {
    let ball = |x: f64, vx: f64| {
        format!("[[{prefix}ball]]\nposition = [{x}, 0.0, 0.0]\nmass = 0.004\nradius = 0.005\nvelocity = [{vx}, 0.0, 0.0]\n")
    };
    format!("[{prefix}container]\nlength = 0.06\nwidth = 0.04\nheight = 0.04\n{}{}{}", ball(0.01, 0.0), ball(0.03, 0.3), ball(0.05, 0.0))
}

/// One ball at rest in the middle of a half-metre box: the floor's swing of centimetres never
/// brings a wall to it, and nothing else acts on it.
const IDLE_DAMPER: &str = "[damper.container]\nlength = 0.5\nwidth = 0.04\nheight = 0.04\n\
                           [[damper.ball]]\nposition = [0.25, 0.0, 0.0]\nmass = 0.004\nradius = 0.005\n";

fn scene(text: &str) -> Scene {
    parse(text, "dampers.toml", "dampers").unwrap_or_else(|e| panic!("{e}")).scene.unwrap()
}

fn invalid(text: &str) -> (String, String) {
    match parse(text, "dampers.toml", "dampers") {
        Err(SceneError::Invalid { field, rule, .. }) => (field, rule),
        other => panic!("expected an invalid field, got {:?}", other.map(|l| l.scene.map(|s| s.name))),
    }
}

fn compliant(scene: &Scene) -> Run {
    let run = Model::Compliant.simulate(scene, &RunOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    judge(Model::Compliant, scene, &run).unwrap_or_else(|f| panic!("{} {}", f.check, f.detail));
    run
}

/// A damper whose balls touch nothing exchanges nothing with its floor: the other damper's run
/// on floor 2 is the run of that damper alone on floor 2, every floor and ball to round-off,
/// with the idle damper listed first. (On another floor the idle damper's floor would set the
/// step too: the step is fit for every wall's speed.)
#[test]
fn an_idle_damper_leaves_the_other_dampers_run_as_it_was() {
    let alone = scene(&building(&format!("damper_floor = 2\n{}", three_balls(""))));
    let with_idle = scene(&building(&format!("[[damper]]\nfloor = 2\n{IDLE_DAMPER}[[damper]]\nfloor = 2\n{}", three_balls("damper."))));
    assert!(with_idle.has_several_dampers() && with_idle.balls.len() == 4);
    let (a, b) = (compliant(&alone), compliant(&with_idle));
    assert_eq!(a.series.len(), b.series.len());
    // The floors' sums take the same forces in the same order; only the cells' grid differs.
    let mut worst = 0.0f64;
    for k in 0..a.series.len() {
        for j in 0..3 {
            let (fa, fb) = (a.series.floor(j, k).unwrap(), b.series.floor(j, k).unwrap());
            worst = worst.max((fa.0 - fb.0).abs());
        }
        for i in 0..3 {
            worst = worst.max((a.series.x(i)[k] - b.series.x(i + 1)[k]).abs());
        }
        assert_eq!(b.series.x(0)[k], 0.25 + 0.01, "the idle ball never moves (sample {k})");
    }
    assert!(worst <= 1e-12, "the floors and balls differ by {worst:e} m");
    let dampers = DamperSummary::of(&with_idle, &b);
    assert_eq!((dampers[0].floor, dampers[0].impacts, dampers[1].floor), (2, 0, 2));
    assert_eq!(dampers[1].impacts, b.impact_count(), "every impact is the active damper's");
    assert!(dampers[1].wall_impacts > 0 && dampers[1].impact_loss > 0.0);
}

/// Two dampers on two floors each push their own: the same box on floor 2 and on floor 3 of the
/// building swinging in its first mode moves the floors as neither box alone does, and the
/// run passes the checks the stress study applies (energy balance, balls inside their boxes).
#[test]
fn two_dampers_on_two_floors_each_push_their_own() {
    let two = scene(&building(&format!("[[damper]]\nfloor = 2\n{0}[[damper]]\nfloor = 3\n{0}", three_balls("damper."))));
    let run = compliant(&two);
    let dampers = DamperSummary::of(&two, &run);
    assert_eq!(dampers.iter().map(|d| d.floor).collect::<Vec<_>>(), [2, 3]);
    assert!(dampers.iter().all(|d| d.wall_impacts > 0), "{dampers:?}");
    assert_eq!(dampers.iter().map(|d| d.impacts).sum::<usize>(), run.impact_count());
    for floor in [2, 3] {
        let alone = compliant(&scene(&building(&format!("damper_floor = {floor}\n{}", three_balls("")))));
        let gap = (0..run.series.len()).map(|k| (run.series.floor(1, k).unwrap().0 - alone.series.floor(1, k).unwrap().0).abs());
        assert!(gap.fold(0.0, f64::max) > 1e-6, "the other box moves floor 2 too");
    }
}

/// One `[[damper]]` is the scene the one damper of today's format describes.
#[test]
fn one_damper_table_is_todays_scene() {
    let today = scene(&building(&format!("damper_floor = 2\n{}", three_balls(""))));
    let listed = scene(&building(&format!("[[damper]]\nfloor = 2\n{}", three_balls("damper."))));
    assert_eq!(today, listed);
    assert!(!listed.has_several_dampers());
}

/// [`building`] without friction and under gravity: the reference's spatial path runs it.
fn smooth(text: &str) -> String {
    text.replace("friction = 0.1\n", "friction = 0.0\ngravity = [0.0, 0.0, -9.81]\n")
}

fn reference(scene: &Scene) -> Run {
    let run = Model::Reference.simulate(scene, &RunOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    judge(Model::Reference, scene, &run).unwrap_or_else(|f| panic!("{} {}", f.check, f.detail));
    run
}

/// The impacts of `run` on the end walls of the container of the balls in `balls`.
fn end_wall_impacts(run: &Run, balls: std::ops::Range<usize>) -> usize {
    use lpc_damper::scene::Body;
    run.impacts
        .iter()
        .filter(|i| match (i.a, i.b) {
            (Body::LeftWall, Body::Ball(k)) | (Body::Ball(k), Body::RightWall) => balls.contains(&k),
            _ => false,
        })
        .count()
}

/// The reference on lines holds one container: it refuses several dampers there with the
/// reason, and friction as ever; the contact and compliant models take them.
#[test]
fn the_reference_refuses_several_dampers_on_lines_with_the_reason() {
    let two = format!("[[damper]]\nfloor = 2\n{0}[[damper]]\nfloor = 3\n{0}", three_balls("damper."));
    let on_lines = scene(&building(&two).replace("friction = 0.1", "friction = 0.0"));
    let why = Model::Reference.supports(&on_lines).unwrap_err();
    assert!(why.contains("2 dampers") && why.contains("on their lines") && why.contains("compliant"), "{why}");
    let rough = scene(&building(&two));
    assert!(Model::Reference.supports(&rough).unwrap_err().contains("friction"));
    assert!(Model::Compliant.supports(&rough).is_ok() && Model::Rapier.supports(&rough).is_ok());
}

/// The reference hands each damper's impulses to its own floor: an idle damper on floor 2
/// listed before the active one on floor 3 leaves the run that of the active one alone there,
/// floors and balls, to round-off (the idle ball falls and rests in its own box).
#[test]
fn the_reference_hands_impulses_to_each_dampers_floor() {
    let alone = scene(&smooth(&building(&format!("damper_floor = 3\n{}", three_balls("")))));
    let with_idle =
        scene(&smooth(&building(&format!("[[damper]]\nfloor = 2\n{IDLE_DAMPER}[[damper]]\nfloor = 3\n{}", three_balls("damper.")))));
    let (a, b) = (reference(&alone), reference(&with_idle));
    assert!(end_wall_impacts(&a, 0..3) > 0, "the active box's balls strike its end walls");
    assert_eq!(end_wall_impacts(&b, 1..4), end_wall_impacts(&a, 0..3));
    let mut worst = 0.0f64;
    for k in 0..a.series.len() {
        for j in 0..3 {
            worst = worst.max((a.series.floor(j, k).unwrap().0 - b.series.floor(j, k).unwrap().0).abs());
        }
        for i in 0..3 {
            worst = worst.max((a.series.x(i)[k] - b.series.x(i + 1)[k]).abs());
        }
    }
    assert!(worst <= 1e-12, "the floors and balls differ by {worst:e} m");
}

/// The reference carries two dampers on two floors: the run passes the stress checks (its
/// energy balance closes only if each impulse moves the floor whose mass it was weighed with)
/// and each box's balls strike its own end walls.
#[test]
fn the_reference_carries_two_dampers_on_two_floors() {
    let two = scene(&smooth(&building(&format!("[[damper]]\nfloor = 2\n{0}[[damper]]\nfloor = 3\n{0}", three_balls("damper.")))));
    let run = reference(&two);
    assert!(end_wall_impacts(&run, 0..3) > 0 && end_wall_impacts(&run, 3..6) > 0);
    let dampers = DamperSummary::of(&two, &run);
    assert_eq!(dampers.iter().map(|d| d.impacts).sum::<usize>(), run.impact_count());
    assert!(run.energy.balance_error.abs() <= 1e-12, "{:?}", run.energy);
}

/// The contact model: an idle damper on the active one's floor, listed after it, leaves its run
/// as it was.
#[test]
fn an_idle_damper_leaves_the_contact_models_run_as_it_was() {
    let alone = scene(&building(&format!("damper_floor = 2\n{}", three_balls(""))));
    let with_idle = scene(&building(&format!("[[damper]]\nfloor = 2\n{}[[damper]]\nfloor = 2\n{IDLE_DAMPER}", three_balls("damper."))));
    let run = |s: &Scene| {
        let r = Model::Rapier.simulate(s, &RunOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        judge(Model::Rapier, s, &r).unwrap_or_else(|f| panic!("{} {}", f.check, f.detail));
        r
    };
    let (a, b) = (run(&alone), run(&with_idle));
    let mut worst = 0.0f64;
    for k in 0..a.series.len() {
        for j in 0..3 {
            worst = worst.max((a.series.floor(j, k).unwrap().0 - b.series.floor(j, k).unwrap().0).abs());
        }
        for i in 0..3 {
            worst = worst.max((a.series.x(i)[k] - b.series.x(i)[k]).abs());
        }
    }
    assert!(worst <= 1e-12, "the floors and balls differ by {worst:e} m");
}

/// The contact model hands each damper's impulses to its own floor: an idle damper on floor 2
/// listed before the active one on floor 3 leaves the floors' run as it was with the active one
/// alone there.
#[test]
fn the_contact_model_hands_impulses_to_each_dampers_floor() {
    let alone = scene(&building(&format!("damper_floor = 3\n{}", three_balls(""))));
    let with_idle = scene(&building(&format!("[[damper]]\nfloor = 2\n{IDLE_DAMPER}[[damper]]\nfloor = 3\n{}", three_balls("damper."))));
    let run = |s: &Scene| Model::Rapier.simulate(s, &RunOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let (a, b) = (run(&alone), run(&with_idle));
    let mut worst = 0.0f64;
    for k in 0..a.series.len() {
        for j in 0..3 {
            worst = worst.max((a.series.floor(j, k).unwrap().0 - b.series.floor(j, k).unwrap().0).abs());
        }
    }
    // One damper's floor comes from the closed form of that floor alone, several floors' from
    // the whole state: the same motion to round-off (1e-16 m here; a misrouted impulse moves
    // the floors by tens of micrometres).
    assert!(worst <= 1e-12, "the floors differ by {worst:e} m");
}

/// The contact model carries two dampers on two floors: the run passes the stress checks and
/// each damper strikes its own walls.
#[test]
fn the_contact_model_carries_two_dampers_on_two_floors() {
    let two = scene(&building(&format!("[[damper]]\nfloor = 2\n{0}[[damper]]\nfloor = 3\n{0}", three_balls("damper."))));
    let run = Model::Rapier.simulate(&two, &RunOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    judge(Model::Rapier, &two, &run).unwrap_or_else(|f| panic!("{} {}", f.check, f.detail));
    let dampers = DamperSummary::of(&two, &run);
    assert!(dampers.iter().all(|d| d.wall_impacts > 0), "{dampers:?}");
}

#[test]
fn bad_damper_tables_name_the_field() {
    let table = |floor: u32| format!("[[damper]]\nfloor = {floor}\n{}", three_balls("damper."));
    let cases = [
        (building(&format!("{}{}", table(2), table(4))), "damper[1].floor", "floors 1 to 3"),
        (building(&format!("{}[[damper]]\nfloor = 1\n", table(2))), "damper[1]", "has no balls"),
        (building(&format!("{}{}", three_balls(""), table(2))), "container", "cannot be combined with [[damper]]"),
        (building(&format!("damper_floor = 2\n{}", table(2))), "structure.damper_floor", "each damper its `floor`"),
        (
            building(&format!("{}{}", table(2), table(3).replace("radius = 0.005", "radius = -0.005"))),
            "damper[1].ball[0].radius",
            "positive",
        ),
    ];
    for (text, field, rule) in cases {
        let (got_field, got_rule) = invalid(&text);
        assert_eq!(got_field, field, "{got_rule}");
        assert!(got_rule.contains(rule), "{field}: {got_rule}");
    }
}

/// On the command line a damper on a floor that does not exist exits 2 naming the file and
/// field, and writes nothing.
#[test]
fn a_damper_on_a_missing_floor_exits_2_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("two.toml");
    std::fs::write(&path, building(&format!("[[damper]]\nfloor = 7\n{}", three_balls("damper.")))).unwrap();
    let out = dir.path().join("out");
    let o = lpc(["run".as_ref(), path.as_os_str(), "--model".as_ref(), "compliant".as_ref(), "--out".as_ref(), out.as_os_str()]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("two.toml") && stderr.contains("damper[0].floor"), "{stderr}");
    assert!(!out.exists());
}

/// The shipped two-damper scene loads as two boxes of 40 balls on floors 2 and 3, and its first
/// 20 ms in the compliant model pass the stress checks.
#[test]
fn the_shipped_two_dampers_load_and_run() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/dampers-two-floors.toml");
    let mut s = lpc_damper::scene::load_scene(&path).unwrap();
    let floors: Vec<(usize, usize)> = s.damper_list().iter().map(|d| (d.floor + 1, d.balls.len())).collect();
    assert_eq!(floors, [(2, 40), (3, 40)]);
    s.horizon = 0.02;
    let run = compliant(&s);
    assert_eq!(run.series.floor_count(), 3);
}

/// Two beds of `count` balls in boxes of different lengths on floors 2 and 3.
fn two_beds(count: u32) -> String {
    let bed = |floor: u32, length: f64| {
        format!(
            "[[damper]]\nfloor = {floor}\n[damper.container]\nlength = {length}\nwidth = 0.04\nheight = 0.04\n\
             [damper.bed]\ncount = {count}\nradii = [0.005]\ndensity = 7800.0\n"
        )
    };
    building(&format!("{}{}", bed(2, 0.1), bed(3, 0.04)))
}

/// A study's bed parameters set every damper's bed, and `dampers` keeps the first so many.
#[test]
fn study_parameters_reach_every_damper() {
    use lpc_damper::scene::{Length, Parameter};
    let file: lpc_damper::scene::SceneFile = toml::from_str(&two_beds(4)).unwrap();
    let build = |f: &lpc_damper::scene::SceneFile| lpc_damper::scene::from_file(f.clone(), "t.toml", "t").unwrap().scene.unwrap();
    let counted = build(&Parameter::BallCount.apply(&file, Length::Metres(6.0)).unwrap());
    assert_eq!(counted.damper_list().iter().map(|d| d.balls.len()).collect::<Vec<_>>(), [6, 6]);
    assert_eq!(Parameter::BallCount.value(&file, &build(&file)), Some(4.0));
    let first = build(&Parameter::Dampers.apply(&file, Length::Metres(1.0)).unwrap());
    let mut alone = file.clone();
    alone.dampers.as_mut().unwrap().truncate(1);
    assert_eq!(first, build(&alone));
    assert!(!first.has_several_dampers() && first.structure.as_ref().unwrap().floor == 1);
    assert_eq!(Parameter::Dampers.value(&file, &build(&file)), Some(2.0));
    assert!(Parameter::Dampers.apply(&file, Length::Metres(3.0)).unwrap_err().contains("from 1 to the 2"));
}

/// An ensemble's moves keep each ball in its own box: a shift the first, longer box would hold
/// takes a ball of the second out of its own.
#[test]
fn moved_balls_stay_in_their_own_box() {
    let s = scene(&two_beds(1));
    let mut by = vec![[0.0; 3]; 2];
    by[0][0] = 0.05;
    let mut moved = s.clone();
    lpc_damper::scene::move_placed_balls(&mut moved, &by).unwrap();
    assert_eq!(moved.initial_positions[0], s.initial_positions[0] + 0.05);
    by = vec![[0.0, 0.0, 0.0], [0.05, 0.0, 0.0]];
    let why = lpc_damper::scene::move_placed_balls(&mut s.clone(), &by).unwrap_err();
    assert!(why.contains("ball2") && why.contains("outside the container along x"), "{why}");
}
