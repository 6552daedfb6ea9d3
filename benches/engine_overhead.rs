//! What the Bevy plug-in costs per physics step against a bare Rapier pipeline stepping the
//! same scene (lpc-lsl, fixed 0.5 ms steps, same integration parameters, plastic contacts as the
//! plug-in's Rapier sees them, same exact kinematic frame). `cargo bench --bench engine_overhead`.

use bevy_rapier3d::rapier::prelude::*;
use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use lpc_damper::oscillator::Oscillator;
use lpc_damper::rapier::integration_parameters;
use lpc_damper::rapier::DamperStep;
use lpc_damper::rapier::{headless_app, StepSettings};
use lpc_damper::scene::{load_scene, scenes_dir, Scene};

const STEPS: usize = 2000;
const DT: f64 = 5e-4;

/// The plug-in's scene in a bare Rapier world, with the same exact frame drive and m dv
/// feedback as the plug-in, stepped `STEPS` times.
struct Bare {
    pipeline: PhysicsPipeline,
    params: IntegrationParameters,
    islands: IslandManager,
    broad: DefaultBroadPhase,
    narrow: NarrowPhase,
    bodies: RigidBodySet,
    colliders: ColliderSet,
    joints: ImpulseJointSet,
    multibody: MultibodyJointSet,
    ccd: CCDSolver,
    frame: RigidBodyHandle,
    balls: Vec<RigidBodyHandle>,
    masses: Vec<f64>,
    osc: Oscillator,
    state: (f64, f64),
    v: Vec<f64>,
}

fn bare(scene: &Scene) -> Bare {
    let f = scene.frame.unwrap();
    let c = scene.container.unwrap();
    let mut bodies = RigidBodySet::new();
    let mut colliders = ColliderSet::new();
    let frame = bodies.insert(
        RigidBodyBuilder::kinematic_position_based().translation(Vector::new(scene.initial_displacement as f32, 0.0, 0.0)).can_sleep(false),
    );
    let half = (0.5 * c.length as f32).max(0.06);
    for centre in [-half, c.length as f32 + half] {
        colliders.insert_with_parent(
            ColliderBuilder::cuboid(half, 0.03, 0.03).translation(Vector::new(centre, 0.0, 0.0)).friction(0.0).user_data(0),
            frame,
            &mut bodies,
        );
    }
    let mut balls = vec![];
    for (i, (b, &x)) in scene.balls.iter().zip(&scene.initial_positions).enumerate() {
        let h = bodies.insert(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(x as f32, 0.0, 0.0))
                .locked_axes(LockedAxes::ROTATION_LOCKED | LockedAxes::TRANSLATION_LOCKED_Y | LockedAxes::TRANSLATION_LOCKED_Z)
                .can_sleep(false),
        );
        colliders.insert_with_parent(
            ColliderBuilder::ball(b.radius as f32).mass(b.mass as f32).friction(0.0).user_data(i as u128 + 1),
            h,
            &mut bodies,
        );
        balls.push(h);
    }
    let params = integration_parameters(scene, StepSettings::fixed(DT, 4));
    Bare {
        pipeline: PhysicsPipeline::new(),
        params,
        islands: IslandManager::new(),
        broad: DefaultBroadPhase::new(),
        narrow: NarrowPhase::new(),
        bodies,
        colliders,
        joints: ImpulseJointSet::new(),
        multibody: MultibodyJointSet::new(),
        ccd: CCDSolver::new(),
        frame,
        balls,
        masses: scene.balls.iter().map(|b| b.mass).collect(),
        osc: Oscillator::new(f.mass, f.damping, f.stiffness),
        state: (scene.initial_displacement, 0.0),
        v: vec![0.0; scene.balls.len()],
    }
}

impl Bare {
    fn step(&mut self) {
        let (x, v) = self.osc.state(self.state.0, self.state.1, DT);
        self.bodies[self.frame].set_next_kinematic_translation(Vector::new(x as f32, 0.0, 0.0));
        self.pipeline.step(
            Vector::ZERO,
            &self.params,
            &mut self.islands,
            &mut self.broad,
            &mut self.narrow,
            &mut self.bodies,
            &mut self.colliders,
            &mut self.joints,
            &mut self.multibody,
            &mut self.ccd,
            &(),
            &(),
        );
        let mut dp = 0.0;
        for (i, h) in self.balls.iter().enumerate() {
            let vn = self.bodies[*h].linvel().x as f64;
            dp += self.masses[i] * (vn - self.v[i]);
            self.v[i] = vn;
        }
        self.state = (x, v - dp / self.osc.mass);
    }
}

fn overhead(c: &mut Criterion) {
    let scene = load_scene(scenes_dir().join("lpc-lsl.toml")).unwrap();
    let mut group = c.benchmark_group(format!("lpc-lsl, {STEPS} fixed steps of {DT} s"));
    group.sample_size(20);
    group.bench_function("bare rapier pipeline", |b| {
        b.iter_batched(
            || bare(&scene),
            |mut w| {
                for _ in 0..STEPS {
                    w.step();
                }
                w
            },
            BatchSize::LargeInput,
        )
    });
    let settings = StepSettings::fixed(DT, 4);
    group.bench_function("bevy plug-in, lean step schedule (headless default)", |b| {
        b.iter_batched(
            || {
                let mut app = headless_app(&scene, settings);
                app.update();
                app
            },
            |mut app| {
                for _ in 1..STEPS {
                    app.world_mut().run_schedule(DamperStep);
                }
                app
            },
            BatchSize::LargeInput,
        )
    });
    group.bench_function("bevy plug-in, app.update per step (as when rendering)", |b| {
        b.iter_batched(
            || headless_app(&scene, settings),
            |mut app| {
                for _ in 0..STEPS {
                    app.update();
                }
                app
            },
            BatchSize::LargeInput,
        )
    });
    group.finish();
}

criterion_group!(benches, overhead);
criterion_main!(benches);
