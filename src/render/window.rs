//! `lpc view`: the run in an interactive window. Drag with the left mouse button to orbit,
//! scroll to zoom; Space pauses, Right arrow (or `.`) steps one sample when paused, Up and Down
//! double and halve the speed, R restarts. The overlay shows simulated time, frame
//! displacement, impacts so far and the mechanical energy; a struck ball or wall flashes.

use bevy::input::mouse::{AccumulatedMouseMotion, AccumulatedMouseScroll};
use bevy::prelude::*;

use super::stage::{pose, spawn_stage, Layout, Playback, BACKGROUND};
use crate::run::Run;
use crate::scene::Scene;

/// Playback controls.
#[derive(Resource, Debug, Clone, Copy)]
struct Controls {
    /// Simulated seconds per real second.
    speed: f64,
    paused: bool,
    /// Simulated time on screen, s.
    t: f64,
}

/// Orbit camera: angles about the layout's target and distance.
#[derive(Component, Debug, Clone, Copy)]
struct Orbit {
    target: Vec3,
    yaw: f32,
    pitch: f32,
    distance: f32,
}

#[derive(Component)]
struct Overlay;

#[derive(Resource, Clone)]
struct ViewScene(Scene);

/// Opens a window showing `run` (a run of `scene`) until it is closed.
pub fn view(scene: &Scene, run: Run) {
    let layout = Layout::of(scene);
    App::new()
        .add_plugins(DefaultPlugins.set(WindowPlugin {
            primary_window: Some(Window { title: format!("lpc view: {} ({})", run.scene, run.model), ..default() }),
            ..default()
        }))
        .insert_resource(ClearColor(Color::srgb_u8(BACKGROUND[0], BACKGROUND[1], BACKGROUND[2])))
        .insert_resource(layout)
        .insert_resource(Playback::new(run))
        .insert_resource(ViewScene(scene.clone()))
        .insert_resource(Controls { speed: 0.25, paused: false, t: 0.0 })
        .add_systems(Startup, setup)
        .add_systems(Update, (keys, advance, orbit, overlay).chain())
        .add_systems(PostUpdate, pose.before(TransformSystems::Propagate))
        .run();
}

fn setup(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
    scene: Res<ViewScene>,
    layout: Res<Layout>,
) {
    spawn_stage(&mut commands, &mut meshes, &mut materials, &scene.0, &layout);
    let cam = layout.camera();
    let target = layout.camera_target();
    let offset = cam.translation - target;
    let distance = offset.length();
    commands.spawn((
        Camera3d::default(),
        bevy::core_pipeline::tonemapping::Tonemapping::AcesFitted,
        cam,
        Orbit { target, yaw: offset.x.atan2(offset.z), pitch: (offset.y / distance).asin(), distance },
    ));
    commands.spawn((
        Overlay,
        Text::new(""),
        TextFont::from_font_size(16.0),
        TextColor(Color::srgb(0.1, 0.1, 0.12)),
        Node { position_type: PositionType::Absolute, top: Val::Px(10.0), left: Val::Px(12.0), ..default() },
    ));
}

fn keys(input: Res<ButtonInput<KeyCode>>, mut controls: ResMut<Controls>, mut playback: ResMut<Playback>) {
    if input.just_pressed(KeyCode::Space) {
        controls.paused = !controls.paused;
    }
    if input.just_pressed(KeyCode::ArrowUp) {
        controls.speed = (controls.speed * 2.0).min(16.0);
    }
    if input.just_pressed(KeyCode::ArrowDown) {
        controls.speed = (controls.speed / 2.0).max(1.0 / 256.0);
    }
    if input.just_pressed(KeyCode::KeyR) {
        controls.t = 0.0;
        playback.sample = 0;
    }
    if controls.paused && (input.just_pressed(KeyCode::ArrowRight) || input.just_pressed(KeyCode::Period)) {
        playback.sample = (playback.sample + 1).min(playback.run.series.len().saturating_sub(1));
        controls.t = playback.time();
    }
}

fn advance(time: Res<Time>, mut controls: ResMut<Controls>, mut playback: ResMut<Playback>) {
    if controls.paused {
        return;
    }
    let horizon = playback.run.series.t().last().copied().unwrap_or(0.0);
    controls.t = (controls.t + time.delta_secs_f64() * controls.speed).min(horizon);
    // The sample at or just before the time on screen.
    let t = controls.t;
    playback.sample = playback.run.series.t().partition_point(|&s| s <= t + 1e-12).saturating_sub(1);
}

fn orbit(
    buttons: Res<ButtonInput<MouseButton>>,
    motion: Res<AccumulatedMouseMotion>,
    scroll: Res<AccumulatedMouseScroll>,
    mut cams: Query<(&mut Orbit, &mut Transform)>,
) {
    for (mut o, mut t) in &mut cams {
        if buttons.pressed(MouseButton::Left) {
            o.yaw -= 0.005 * motion.delta.x;
            o.pitch = (o.pitch + 0.005 * motion.delta.y).clamp(-1.4, 1.4);
        }
        o.distance = (o.distance * (1.0 - 0.1 * scroll.delta.y)).clamp(0.05, 20.0);
        let dir = Vec3::new(o.pitch.cos() * o.yaw.sin(), o.pitch.sin(), o.pitch.cos() * o.yaw.cos());
        *t = Transform::from_translation(o.target + o.distance * dir).looking_at(o.target, Vec3::Y);
    }
}

fn overlay(playback: Res<Playback>, controls: Res<Controls>, scene: Res<ViewScene>, mut text: Query<&mut Text, With<Overlay>>) {
    let s = &playback.run.series;
    let k = playback.sample.min(s.len().saturating_sub(1));
    if s.is_empty() {
        return;
    }
    let frame = scene.0.frame.map_or(0.0, |f| f.energy(s.xs()[k], s.vs()[k]));
    let balls: f64 = scene.0.balls.iter().enumerate().map(|(i, b)| 0.5 * b.mass * s.v(i)[k].powi(2)).sum();
    for mut t in &mut text {
        t.0 = format!(
            "{} ({})\nt = {:.3} s   xs = {:+.2} mm\nimpacts {}   energy {:.4} J\nspeed x{}{}\n[Space] pause  [Right] step  [Up/Down] speed  [R] restart  drag: orbit  wheel: zoom",
            playback.run.scene,
            playback.run.model,
            s.t()[k],
            1e3 * s.xs()[k],
            playback.impacts_so_far(),
            frame + balls,
            controls.speed,
            if controls.paused { "   PAUSED" } else { "" },
        );
    }
}
