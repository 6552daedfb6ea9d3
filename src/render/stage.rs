//! The 3D stage shared by off-screen frames and the window: where everything goes (the
//! [`Layout`], in metres, x along the motion, y up, z towards the viewer), how it is spawned,
//! and the [`Playback`] that poses it at a sample of a run.

use bevy::prelude::*;

use crate::run::Run;
use crate::scene::{BallKind, Body, Scene};

/// Storeys the camera frames under the container at most: the floors moving under the box,
/// close enough to see its balls.
pub const STOREYS_SHOWN_BELOW: usize = 3;
/// Vertical field of view of the camera, rad (Bevy's default perspective).
pub const FOV: f32 = std::f32::consts::FRAC_PI_4;
/// Large balls' colour (sRGB).
pub const LARGE_BALL: [u8; 3] = [205, 45, 40];
/// Small balls' colour (sRGB).
pub const SMALL_BALL: [u8; 3] = [35, 95, 225];
/// Clear colour behind the structure (sRGB).
pub const BACKGROUND: [u8; 3] = [232, 234, 238];
/// How long an impact flash lasts, in simulated seconds.
pub const FLASH: f64 = 0.03;

/// Where the parts of the structure are, from the scene's sizes: the frame's rest position
/// puts the container's left inner face at x = 0.
#[derive(Resource, Debug, Clone, Copy, PartialEq)]
pub struct Layout {
    /// Container inner length, m.
    pub length: f32,
    /// Largest ball radius, m.
    pub radius: f32,
    /// Wall and floor thickness of the container, m.
    pub wall: f32,
    /// Height of the columns from the ground to the platform, m.
    pub column_height: f32,
    /// Platform (the frame's mass) thickness, m.
    pub platform: f32,
    /// Height of the balls' centres, m.
    pub ball_y: f32,
    /// Overhang of the platform beyond the container on each side, m.
    pub overhang: f32,
    /// The container's inner width (across the motion, drawn along the picture's depth), m.
    pub depth: f32,
    /// The container's inner height, m.
    pub height: f32,
    /// Floors of the structure that carries the container (1 for a frame).
    pub floors: usize,
    /// The floor that carries the container, 0 at the bottom.
    pub carrying: usize,
}

impl Layout {
    /// The layout of `scene` (a chain without a frame gets a container around its balls).
    pub fn of(scene: &Scene) -> Layout {
        let radius = scene.balls.iter().map(|b| b.radius).fold(0.005, f64::max) as f32;
        let length = scene.container.map_or_else(
            || {
                let (lo, hi) = scene.initial_positions.iter().fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
                // No balls at all: an empty stretch of a few radii, not `MIN - MAX`.
                if lo <= hi {
                    (hi - lo) as f32 + 4.0 * radius
                } else {
                    4.0 * radius
                }
            },
            |c| c.length as f32,
        );
        let wall = 0.2 * radius;
        let platform = 0.5 * radius;
        // A line of balls gets a box a little wider and higher than its balls; a scene with a
        // cross-section gets that.
        let [width, high] = scene.space.section.map(|a| a as f32);
        let depth = (3.0 * radius).max(width);
        let height = (2.4 * radius).max(high);
        let (floors, carrying) = scene.structure.as_ref().map_or((1, 0), |s| (s.floors(), s.floor));
        // A storey above the container is tall enough to clear it.
        let clear = if carrying + 1 < floors { 1.3 * (wall + height) } else { 0.0 };
        let column_height = (0.7 * length.max(6.0 * radius)).max(clear);
        let base = (carrying + 1) as f32 * (column_height + platform);
        Layout {
            length,
            radius,
            wall,
            column_height,
            platform,
            ball_y: base + wall + 0.5 * height,
            overhang: 0.25 * length.max(6.0 * radius),
            depth,
            height,
            floors,
            carrying,
        }
    }

    /// The height of floor `i`'s platform's centre (0 at the bottom): each storey is its
    /// columns with the platform on them.
    pub fn floor_y(&self, i: usize) -> f32 {
        (i + 1) as f32 * self.column_height + (i as f32 + 0.5) * self.platform
    }

    /// World position of a ball centre at `x` (the models' coordinate) and `[y, z]` across
    /// the motion (the scene's `y` is the picture's depth, its `z` the picture's up).
    pub fn ball(&self, x: f64, across: [f64; 2]) -> Vec3 {
        Vec3::new(x as f32, self.ball_y + across[1] as f32, across[0] as f32)
    }

    /// The height of the structure's top above the ground: the container's top, or the top
    /// floor above it.
    fn top(&self) -> f32 {
        (self.ball_y + 0.5 * self.height).max(self.floor_y(self.floors - 1) + 0.5 * self.platform)
    }

    /// The heights the camera frames, bottom and top: the container and the storeys around it,
    /// at most [`STOREYS_SHOWN_BELOW`] under it (from the ground when it rides no higher) and one
    /// above it. A tall building shown whole would leave its damper a few pixels wide.
    pub fn shown(&self) -> (f32, f32) {
        let bottom =
            if self.carrying < STOREYS_SHOWN_BELOW { 0.0 } else { self.floor_y(self.carrying - STOREYS_SHOWN_BELOW) - 0.5 * self.platform };
        let above = self.floor_y((self.carrying + 1).min(self.floors - 1)) + 0.5 * self.platform;
        (bottom, self.top().min(above.max(self.ball_y + 0.5 * self.height)))
    }

    /// The point the camera looks at: mid-container, a little below the balls (below the
    /// middle of a tall box's inside), or 0.6 of the way up what it frames ([`Layout::shown`]).
    pub fn camera_target(&self) -> Vec3 {
        let (bottom, top) = self.shown();
        Vec3::new(0.5 * self.length, bottom + 0.6 * (top - bottom), 0.0)
    }

    /// The camera: in front of the structure, a little above and to the right, framing what
    /// [`Layout::shown`] gives (from the ground to the container's top on a low structure).
    pub fn camera(&self) -> Transform {
        let target = self.camera_target();
        let (bottom, top) = self.shown();
        let span = (self.length + 2.0 * self.overhang).max(top - bottom);
        let eye = target + Vec3::new(0.1 * span, 0.3 * span, 1.1 * span);
        Transform::from_translation(eye).looking_at(target, Vec3::Y)
    }

    /// Pixel (from the top-left corner) at which the camera of [`Layout::camera`] sees world
    /// point `p` in an image of `size` (width, height); computed by hand, independently of
    /// Bevy's camera, so that a test can check what Bevy drew.
    pub fn project(&self, size: (u32, u32), p: Vec3) -> Vec2 {
        let view = self.camera().compute_affine().inverse().transform_point3(p);
        let f = 1.0 / (FOV / 2.0).tan();
        let (w, h) = (size.0 as f32, size.1 as f32);
        let ndc = Vec2::new(f / (w / h) * view.x / -view.z, f * view.y / -view.z);
        Vec2::new((ndc.x + 1.0) * 0.5 * w, (1.0 - ndc.y) * 0.5 * h)
    }

    /// Apparent radius in pixels of a sphere of `radius` at `p`.
    pub fn projected_radius(&self, size: (u32, u32), p: Vec3, radius: f32) -> f32 {
        let depth = -self.camera().compute_affine().inverse().transform_point3(p).z;
        radius / depth * (1.0 / (FOV / 2.0).tan()) * 0.5 * size.1 as f32
    }
}

/// The run being shown and which sample is on screen.
#[derive(Resource, Debug, Clone)]
pub struct Playback {
    /// The finished run.
    pub run: Run,
    /// Sample shown.
    pub sample: usize,
    /// Impact times and bodies, for the flashes.
    pub impacts: Vec<(f64, Body, Body)>,
}

impl Playback {
    /// A playback of `run` from its first sample.
    pub fn new(run: Run) -> Self {
        let impacts = run.impacts.iter().map(|i| (i.t, i.a, i.b)).collect();
        Playback { run, sample: 0, impacts }
    }

    /// Simulated time of the sample shown, s.
    pub fn time(&self) -> f64 {
        self.run.series.t().get(self.sample).copied().unwrap_or(0.0)
    }

    /// Impacts up to the sample shown.
    pub fn impacts_so_far(&self) -> usize {
        let t = self.time();
        self.impacts.partition_point(|i| i.0 <= t + 1e-12)
    }

    /// Whether `body` was struck within [`FLASH`] before the sample shown.
    pub fn flashing(&self, body: Body) -> bool {
        let t = self.time();
        let from = self.impacts.partition_point(|i| i.0 < t - FLASH);
        self.impacts[from..].iter().take_while(|i| i.0 <= t + 1e-12).any(|i| i.1 == body || i.2 == body)
    }
}

/// A ball's mesh (index left to right).
#[derive(Component, Debug, Clone, Copy)]
pub struct BallMesh(pub usize, pub [f64; 2]);
/// A part that moves with the frame: offset of its centre from the frame's displacement.
#[derive(Component, Debug, Clone, Copy)]
pub struct FramePart(pub Vec3);
/// A container wall (for its flash).
#[derive(Component, Debug, Clone, Copy)]
pub struct WallMesh(pub Body);
/// A column of storey `.1` (0 at the bottom), leaning with its floor over the one below (the
/// ground under the first): its foot's position when the structure is at rest.
#[derive(Component, Debug, Clone, Copy)]
pub struct Column(pub Vec3, pub usize);
/// A floor of a structure other than the carrying one (which is the frame's platform): its
/// index and its centre at rest.
#[derive(Component, Debug, Clone, Copy)]
pub struct FloorSlab(pub usize, pub Vec3);

fn srgb(c: [u8; 3]) -> Color {
    Color::srgb_u8(c[0], c[1], c[2])
}

/// Spawns ground, columns, platform, container, balls and light (not the camera).
pub fn spawn_stage(
    commands: &mut Commands,
    meshes: &mut Assets<Mesh>,
    materials: &mut Assets<StandardMaterial>,
    scene: &Scene,
    layout: &Layout,
) {
    let l = *layout;
    let steel = materials.add(StandardMaterial {
        base_color: Color::srgb(0.42, 0.44, 0.48),
        metallic: 0.3,
        perceptual_roughness: 0.5,
        ..default()
    });
    let ground = materials.add(StandardMaterial { base_color: Color::srgb(0.62, 0.6, 0.56), perceptual_roughness: 0.95, ..default() });
    let glass = materials.add(StandardMaterial {
        base_color: Color::srgba(0.75, 0.88, 1.0, 0.16),
        alpha_mode: AlphaMode::Blend,
        perceptual_roughness: 0.1,
        ..default()
    });
    let span = l.length + 2.0 * l.overhang;
    commands.spawn((
        Mesh3d(meshes.add(Plane3d::default().mesh().size(3.0 * span, 2.0 * span))),
        MeshMaterial3d(ground),
        Transform::from_xyz(0.5 * l.length, 0.0, 0.0),
    ));
    let depth = l.depth;
    // Columns stand under each platform's ends; their feet follow the floor below (the ground
    // stays), their tops the floor they hold.
    let col = 0.35 * l.radius;
    let column = meshes.add(Cuboid::new(col, l.column_height, col));
    for storey in 0..l.floors {
        let foot_y = if storey == 0 { 0.0 } else { l.floor_y(storey - 1) + 0.5 * l.platform };
        for foot_x in [-0.6 * l.overhang, l.length + 0.6 * l.overhang] {
            commands.spawn((
                Column(Vec3::new(foot_x, foot_y, 0.0), storey),
                Mesh3d(column.clone()),
                MeshMaterial3d(steel.clone()),
                Transform::from_xyz(foot_x, foot_y + 0.5 * l.column_height, 0.0),
            ));
        }
    }
    let frame_part = |commands: &mut Commands, mesh: Handle<Mesh>, material: Handle<StandardMaterial>, centre: Vec3| {
        commands.spawn((FramePart(centre), Mesh3d(mesh), MeshMaterial3d(material), Transform::from_translation(centre))).id()
    };
    let slab = meshes.add(Cuboid::new(span, l.platform, depth * 1.4));
    frame_part(commands, slab.clone(), steel.clone(), Vec3::new(0.5 * l.length, l.floor_y(l.carrying), 0.0));
    for i in (0..l.floors).filter(|&i| i != l.carrying) {
        let centre = Vec3::new(0.5 * l.length, l.floor_y(i), 0.0);
        commands.spawn((FloorSlab(i, centre), Mesh3d(slab.clone()), MeshMaterial3d(steel.clone()), Transform::from_translation(centre)));
    }
    let floor_y = l.floor_y(l.carrying) + 0.5 * l.platform + 0.5 * l.wall;
    frame_part(
        commands,
        meshes.add(Cuboid::new(l.length + 2.0 * l.wall, l.wall, depth)),
        steel.clone(),
        Vec3::new(0.5 * l.length, floor_y, 0.0),
    );
    let height = l.height;
    let wall_y = l.ball_y;
    for (body, x) in [(Body::LeftWall, -0.5 * l.wall), (Body::RightWall, l.length + 0.5 * l.wall)] {
        let m = materials.add(StandardMaterial { base_color: Color::srgb(0.5, 0.52, 0.56), ..default() });
        let id = frame_part(commands, meshes.add(Cuboid::new(l.wall, height, depth)), m, Vec3::new(x, wall_y, 0.0));
        commands.entity(id).insert(WallMesh(body));
    }
    // The see-through box: front, back and lid (the end walls are drawn opaque).
    frame_part(
        commands,
        meshes.add(Cuboid::new(l.length, height, 0.02 * l.radius)),
        glass.clone(),
        Vec3::new(0.5 * l.length, wall_y, 0.5 * depth),
    );
    frame_part(
        commands,
        meshes.add(Cuboid::new(l.length, height, 0.02 * l.radius)),
        glass.clone(),
        Vec3::new(0.5 * l.length, wall_y, -0.5 * depth),
    );
    frame_part(
        commands,
        meshes.add(Cuboid::new(l.length, 0.02 * l.radius, depth)),
        glass.clone(),
        Vec3::new(0.5 * l.length, wall_y + 0.5 * height, 0.0),
    );

    // The dividers between chains.
    for k in 1..scene.space.chains() {
        let y = k as f32 * scene.space.channel as f32 - 0.5 * depth;
        frame_part(
            commands,
            meshes.add(Cuboid::new(l.length, height, 0.02 * l.radius)),
            glass.clone(),
            Vec3::new(0.5 * l.length, wall_y, y),
        );
    }
    let sphere = meshes.add(Sphere::new(1.0).mesh().uv(48, 24));
    for (i, b) in scene.balls.iter().enumerate() {
        let colour = if b.kind == BallKind::Small { SMALL_BALL } else { LARGE_BALL };
        let m = materials.add(StandardMaterial { base_color: srgb(colour), perceptual_roughness: 0.35, metallic: 0.1, ..default() });
        commands.spawn((
            BallMesh(i, scene.space.lateral_of(i)),
            Mesh3d(sphere.clone()),
            MeshMaterial3d(m),
            Transform::from_translation(l.ball(scene.initial_positions[i], scene.space.lateral_of(i)))
                .with_scale(Vec3::splat(b.radius as f32)),
        ));
    }
    commands.spawn((
        DirectionalLight { illuminance: 9_000.0, ..default() },
        Transform::from_xyz(0.3, 1.0, 0.8).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    commands.insert_resource(GlobalAmbientLight { brightness: 900.0, ..default() });
}

/// The balls' meshes, posed by [`pose`].
type BallParts<'w, 's> = Query<
    'w,
    's,
    (&'static BallMesh, &'static mut Transform, &'static MeshMaterial3d<StandardMaterial>),
    (Without<FramePart>, Without<Column>, Without<FloorSlab>),
>;
/// The frame's parts (walls, floor), posed by [`pose`].
type FrameParts<'w, 's> = Query<
    'w,
    's,
    (&'static FramePart, &'static mut Transform, Option<&'static WallMesh>, &'static MeshMaterial3d<StandardMaterial>),
    (Without<BallMesh>, Without<Column>, Without<FloorSlab>),
>;
/// The columns the frame stands on, posed by [`pose`].
type Columns<'w, 's> =
    Query<'w, 's, (&'static Column, &'static mut Transform), (Without<BallMesh>, Without<FramePart>, Without<FloorSlab>)>;
/// A structure's floors other than the carrying one, posed by [`pose`].
type FloorSlabs<'w, 's> =
    Query<'w, 's, (&'static FloorSlab, &'static mut Transform), (Without<BallMesh>, Without<FramePart>, Without<Column>)>;

/// Poses every part at the playback's sample and lights the flashes.
pub fn pose(
    playback: Res<Playback>,
    layout: Res<Layout>,
    mut balls: BallParts,
    mut parts: FrameParts,
    mut columns: Columns,
    mut slabs: FloorSlabs,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    let (xs, x) = super::state_at_sample(&playback.run, playback.sample);
    let mut glow = |m: &MeshMaterial3d<StandardMaterial>, on: bool| {
        // `get_mut` marks the material modified (re-uploaded), so only when the flash changes.
        let Some(mat) = materials.get(&m.0) else { return };
        let base = mat.base_color.to_linear();
        let want = if on { LinearRgba::rgb(base.red * 1.5, base.green * 1.5, base.blue * 1.5) } else { LinearRgba::BLACK };
        if mat.emissive != want {
            if let Some(mut mat) = materials.get_mut(&m.0) {
                mat.emissive = want;
            }
        }
    };
    let series = &playback.run.series;
    let k = playback.sample.min(series.len().saturating_sub(1));
    for (b, mut t, m) in &mut balls {
        if let Some(&xi) = x.get(b.0) {
            // Balls that move across the motion are where the series has them; balls on lines
            // stay at their place across.
            let across = if series.has_across() { series.across(b.0, k) } else { b.1 };
            t.translation = layout.ball(xi, across);
        }
        glow(m, playback.flashing(Body::Ball(b.0)));
    }
    for (p, mut t, wall, m) in &mut parts {
        t.translation = p.0 + Vec3::X * xs as f32;
        if let Some(w) = wall {
            glow(m, playback.flashing(w.0));
        }
    }
    // Each floor's displacement relative to the ground: a structure's from its series, a
    // frame's (one floor) its own.
    let floor_x = |i: usize| -> f32 {
        if series.floor_count() > 0 {
            series.floor(i, k).map_or(0.0, |f| f.0) as f32
        } else {
            xs as f32
        }
    };
    for (slab, mut t) in &mut slabs {
        t.translation = slab.1 + Vec3::X * floor_x(slab.0);
    }
    for (c, mut t) in &mut columns {
        // Lean so that the top follows the floor it holds while the foot follows the one below.
        let (foot, top) = (if c.1 == 0 { 0.0 } else { floor_x(c.1 - 1) }, floor_x(c.1));
        let lean = (top - foot).atan2(layout.column_height);
        t.rotation = Quat::from_rotation_z(-lean);
        t.translation = c.0 + Vec3::new(0.5 * (foot + top), 0.5 * layout.column_height, 0.0);
    }
}
