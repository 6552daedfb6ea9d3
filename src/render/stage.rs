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

/// One damper's container as drawn: on its floor, beside the containers before it on the
/// same floor.
#[derive(Debug, Clone, PartialEq)]
pub struct BoxLayout {
    /// The floor that carries it, 0 at the bottom.
    pub floor: usize,
    /// Its balls, a run of the scene's.
    pub balls: std::ops::Range<usize>,
    /// Inner length, m.
    pub length: f32,
    /// Inner width (across the motion, drawn along the picture's depth), m.
    pub depth: f32,
    /// Inner height, m.
    pub height: f32,
    /// How far along the motion the picture moves it from where the physics has it: the
    /// containers of one floor occupy the same place in the models (their balls never meet)
    /// and are drawn side by side. 0 for the first container on its floor, m.
    pub shift: f32,
    /// Height of its middle (of its balls' centres on a line), m.
    pub ball_y: f32,
    /// Its chains' dividers, each at its place across the motion, m.
    pub dividers: Vec<f32>,
}

/// Where the parts of the structure are, from the scene's sizes: each floor's rest position
/// puts the left inner face of its first container at x = 0.
#[derive(Resource, Debug, Clone, PartialEq)]
pub struct Layout {
    /// Largest ball radius, m.
    pub radius: f32,
    /// Wall and floor thickness of the containers, m.
    pub wall: f32,
    /// Height of each storey's columns, m.
    pub column_height: f32,
    /// Platform (a floor's mass) thickness, m.
    pub platform: f32,
    /// Overhang of the platforms beyond the containers on each side, m.
    pub overhang: f32,
    /// Length of the widest floor's row of containers (gaps included), m.
    pub width: f32,
    /// Floors of the structure that carries the containers (1 for a frame).
    pub floors: usize,
    /// Every damper's container, in the scene's order.
    pub boxes: Vec<BoxLayout>,
}

impl Layout {
    /// The layout of `scene` (a chain without a frame gets a container around its balls).
    pub fn of(scene: &Scene) -> Layout {
        let radius = scene.balls.iter().map(|b| b.radius).fold(0.005, f64::max) as f32;
        let wall = 0.2 * radius;
        let platform = 0.5 * radius;
        let floors = scene.structure.as_ref().map_or(1, |s| s.floors());
        // A line of balls gets a box a little wider and higher than its balls; a scene with a
        // cross-section gets that. Its chains are divided at their channels' edges.
        let placed = |floor: usize, balls: std::ops::Range<usize>, length: f32, section: [f64; 2], channel: f64| {
            let (depth, height) = ((3.0 * radius).max(section[0] as f32), (2.4 * radius).max(section[1] as f32));
            let chains = balls.clone().map(|i| scene.space.chain_of(i)).collect::<std::collections::BTreeSet<_>>().len();
            let dividers = (1..chains).map(|k| k as f32 * channel as f32 - 0.5 * depth).collect();
            BoxLayout { floor, balls, length, depth, height, shift: 0.0, ball_y: 0.0, dividers }
        };
        let mut boxes: Vec<BoxLayout> =
            scene.damper_list().into_iter().map(|d| placed(d.floor, d.balls, d.container.length as f32, d.section, d.channel)).collect();
        if boxes.is_empty() {
            let (lo, hi) = scene.initial_positions.iter().fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
            // No balls at all: an empty stretch of a few radii, not `MIN - MAX`.
            let length = if lo <= hi { (hi - lo) as f32 + 4.0 * radius } else { 4.0 * radius };
            boxes.push(placed(0, 0..scene.balls.len(), length, scene.space.section, scene.space.channel));
        }
        // The containers of a floor stand in a row, a few radii apart.
        let gap = 2.0 * wall + 4.0 * radius;
        let mut row_ends = vec![0.0f32; floors];
        for b in &mut boxes {
            let end = &mut row_ends[b.floor];
            b.shift = if *end > 0.0 { *end + gap } else { 0.0 };
            *end = b.shift + b.length;
        }
        let width = row_ends.iter().copied().fold(0.0, f32::max);
        // A storey above a container is tall enough to clear it.
        let clear = boxes.iter().filter(|b| b.floor + 1 < floors).map(|b| 1.3 * (wall + b.height)).fold(0.0, f32::max);
        let column_height = (0.7 * width.max(6.0 * radius)).max(clear);
        for b in &mut boxes {
            b.ball_y = (b.floor + 1) as f32 * (column_height + platform) + wall + 0.5 * b.height;
        }
        Layout { radius, wall, column_height, platform, overhang: 0.25 * width.max(6.0 * radius), width, floors, boxes }
    }

    /// The height of floor `i`'s platform's centre (0 at the bottom): each storey is its
    /// columns with the platform on them.
    pub fn floor_y(&self, i: usize) -> f32 {
        (i + 1) as f32 * self.column_height + (i as f32 + 0.5) * self.platform
    }

    /// The container ball `i` is in (the last one for an index beyond the balls).
    pub fn box_of(&self, i: usize) -> &BoxLayout {
        self.boxes.iter().find(|b| b.balls.contains(&i)).unwrap_or(&self.boxes[self.boxes.len() - 1])
    }

    /// World position of ball `i`'s centre at `x` (the models' coordinate) and `[y, z]` across
    /// the motion (the scene's `y` is the picture's depth, its `z` the picture's up).
    pub fn ball(&self, i: usize, x: f64, across: [f64; 2]) -> Vec3 {
        let b = self.box_of(i);
        Vec3::new(x as f32 + b.shift, b.ball_y + across[1] as f32, across[0] as f32)
    }

    /// The lowest and the highest floor that carry a container.
    fn carrying(&self) -> (usize, usize) {
        self.boxes.iter().fold((usize::MAX, 0), |(lo, hi), b| (lo.min(b.floor), hi.max(b.floor)))
    }

    /// The height of the highest container's top.
    fn boxes_top(&self) -> f32 {
        self.boxes.iter().map(|b| b.ball_y + 0.5 * b.height).fold(0.0, f32::max)
    }

    /// The height of the structure's top above the ground: the highest container's top, or
    /// the top floor above it.
    fn top(&self) -> f32 {
        self.boxes_top().max(self.floor_y(self.floors - 1) + 0.5 * self.platform)
    }

    /// The heights the camera frames, bottom and top: the containers and the storeys around
    /// them, at most [`STOREYS_SHOWN_BELOW`] under the lowest (from the ground when it rides
    /// no higher) and one above the highest. A tall building shown whole would leave its
    /// damper a few pixels wide.
    pub fn shown(&self) -> (f32, f32) {
        let (lowest, highest) = self.carrying();
        let bottom = if lowest < STOREYS_SHOWN_BELOW { 0.0 } else { self.floor_y(lowest - STOREYS_SHOWN_BELOW) - 0.5 * self.platform };
        let above = self.floor_y((highest + 1).min(self.floors - 1)) + 0.5 * self.platform;
        (bottom, self.top().min(above.max(self.boxes_top())))
    }

    /// The point the camera looks at: mid-row, 0.6 of the way up what it frames
    /// ([`Layout::shown`]).
    pub fn camera_target(&self) -> Vec3 {
        let (bottom, top) = self.shown();
        Vec3::new(0.5 * self.width, bottom + 0.6 * (top - bottom), 0.0)
    }

    /// The camera: in front of the structure, a little above and to the right, framing what
    /// [`Layout::shown`] gives (from the ground to the containers' top on a low structure).
    pub fn camera(&self) -> Transform {
        let target = self.camera_target();
        let (bottom, top) = self.shown();
        let span = (self.width + 2.0 * self.overhang).max(top - bottom);
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

    /// The impacts within [`FLASH`] before the sample shown.
    fn recent_impacts(&self) -> impl Iterator<Item = &(f64, Body, Body)> {
        let t = self.time();
        let from = self.impacts.partition_point(|i| i.0 < t - FLASH);
        self.impacts[from..].iter().take_while(move |i| i.0 <= t + 1e-12)
    }

    /// Whether ball `i` was struck within [`FLASH`] before the sample shown.
    pub fn ball_flashing(&self, i: usize) -> bool {
        self.recent_impacts().any(|imp| imp.1 == Body::Ball(i) || imp.2 == Body::Ball(i))
    }

    /// Whether `wall` of the container holding `balls` was struck by one of them within
    /// [`FLASH`] before the sample shown: every container's walls share their names.
    pub fn wall_flashing(&self, wall: Body, balls: &std::ops::Range<usize>) -> bool {
        let ours = |b: Body| matches!(b, Body::Ball(j) if balls.contains(&j));
        self.recent_impacts().any(|imp| (imp.1 == wall && ours(imp.2)) || (imp.2 == wall && ours(imp.1)))
    }
}

/// A ball's mesh (index left to right) and its place across the motion on its line.
#[derive(Component, Debug, Clone, Copy)]
pub struct BallMesh(pub usize, pub [f64; 2]);
/// A part that moves with a floor (the frame's on a frame): the floor and its centre when
/// the floor is at rest.
#[derive(Component, Debug, Clone, Copy)]
pub struct FloorPart(pub usize, pub Vec3);
/// A container's end wall (for its flash) and the container's index among the layout's
/// boxes.
#[derive(Component, Debug, Clone, Copy)]
pub struct WallMesh(pub Body, pub usize);
/// A column of storey `.1` (0 at the bottom), leaning with its floor over the one below (the
/// ground under the first): its foot's position when the structure is at rest.
#[derive(Component, Debug, Clone, Copy)]
pub struct Column(pub Vec3, pub usize);

fn srgb(c: [u8; 3]) -> Color {
    Color::srgb_u8(c[0], c[1], c[2])
}

/// Spawns ground, columns, floors, containers, balls and light (not the camera).
pub fn spawn_stage(
    commands: &mut Commands,
    meshes: &mut Assets<Mesh>,
    materials: &mut Assets<StandardMaterial>,
    scene: &Scene,
    layout: &Layout,
) {
    let l = layout;
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
    let span = l.width + 2.0 * l.overhang;
    commands.spawn((
        Mesh3d(meshes.add(Plane3d::default().mesh().size(3.0 * span, 2.0 * span))),
        MeshMaterial3d(ground),
        Transform::from_xyz(0.5 * l.width, 0.0, 0.0),
    ));
    let depth = l.boxes.iter().map(|b| b.depth).fold(0.0, f32::max);
    // Columns stand under each platform's ends; their feet follow the floor below (the ground
    // stays), their tops the floor they hold.
    let col = 0.35 * l.radius;
    let column = meshes.add(Cuboid::new(col, l.column_height, col));
    for storey in 0..l.floors {
        let foot_y = if storey == 0 { 0.0 } else { l.floor_y(storey - 1) + 0.5 * l.platform };
        for foot_x in [-0.6 * l.overhang, l.width + 0.6 * l.overhang] {
            commands.spawn((
                Column(Vec3::new(foot_x, foot_y, 0.0), storey),
                Mesh3d(column.clone()),
                MeshMaterial3d(steel.clone()),
                Transform::from_xyz(foot_x, foot_y + 0.5 * l.column_height, 0.0),
            ));
        }
    }
    let floor_part = |commands: &mut Commands, floor: usize, mesh: Handle<Mesh>, material: Handle<StandardMaterial>, centre: Vec3| {
        commands.spawn((FloorPart(floor, centre), Mesh3d(mesh), MeshMaterial3d(material), Transform::from_translation(centre))).id()
    };
    let slab = meshes.add(Cuboid::new(span, l.platform, depth * 1.4));
    for i in 0..l.floors {
        floor_part(commands, i, slab.clone(), steel.clone(), Vec3::new(0.5 * l.width, l.floor_y(i), 0.0));
    }
    for (k, b) in l.boxes.iter().enumerate() {
        let (f, middle) = (b.floor, b.shift + 0.5 * b.length);
        let pane = |commands: &mut Commands, meshes: &mut Assets<Mesh>, size: Vec3, centre: Vec3| {
            floor_part(commands, f, meshes.add(Cuboid::from_size(size)), glass.clone(), centre);
        };
        let floor_y = l.floor_y(f) + 0.5 * l.platform + 0.5 * l.wall;
        floor_part(
            commands,
            f,
            meshes.add(Cuboid::new(b.length + 2.0 * l.wall, l.wall, b.depth)),
            steel.clone(),
            Vec3::new(middle, floor_y, 0.0),
        );
        for (body, x) in [(Body::LeftWall, b.shift - 0.5 * l.wall), (Body::RightWall, b.shift + b.length + 0.5 * l.wall)] {
            let m = materials.add(StandardMaterial { base_color: Color::srgb(0.5, 0.52, 0.56), ..default() });
            let id = floor_part(commands, f, meshes.add(Cuboid::new(l.wall, b.height, b.depth)), m, Vec3::new(x, b.ball_y, 0.0));
            commands.entity(id).insert(WallMesh(body, k));
        }
        // The see-through box: front, back and lid (the end walls are drawn opaque), and the
        // dividers between chains.
        let thin = 0.02 * l.radius;
        pane(commands, meshes, Vec3::new(b.length, b.height, thin), Vec3::new(middle, b.ball_y, 0.5 * b.depth));
        pane(commands, meshes, Vec3::new(b.length, b.height, thin), Vec3::new(middle, b.ball_y, -0.5 * b.depth));
        pane(commands, meshes, Vec3::new(b.length, thin, b.depth), Vec3::new(middle, b.ball_y + 0.5 * b.height, 0.0));
        for &z in &b.dividers {
            pane(commands, meshes, Vec3::new(b.length, b.height, thin), Vec3::new(middle, b.ball_y, z));
        }
    }
    let sphere = meshes.add(Sphere::new(1.0).mesh().uv(48, 24));
    for (i, b) in scene.balls.iter().enumerate() {
        let colour = if b.kind == BallKind::Small { SMALL_BALL } else { LARGE_BALL };
        let m = materials.add(StandardMaterial { base_color: srgb(colour), perceptual_roughness: 0.35, metallic: 0.1, ..default() });
        commands.spawn((
            BallMesh(i, scene.space.lateral_of(i)),
            Mesh3d(sphere.clone()),
            MeshMaterial3d(m),
            Transform::from_translation(l.ball(i, scene.initial_positions[i], scene.space.lateral_of(i)))
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
    (Without<FloorPart>, Without<Column>),
>;
/// The parts that move with a floor (platforms, containers), posed by [`pose`].
type FloorParts<'w, 's> = Query<
    'w,
    's,
    (&'static FloorPart, &'static mut Transform, Option<&'static WallMesh>, &'static MeshMaterial3d<StandardMaterial>),
    (Without<BallMesh>, Without<Column>),
>;
/// The columns the floors stand on, posed by [`pose`].
type Columns<'w, 's> = Query<'w, 's, (&'static Column, &'static mut Transform), (Without<BallMesh>, Without<FloorPart>)>;

/// Poses every part at the playback's sample and lights the flashes.
pub fn pose(
    playback: Res<Playback>,
    layout: Res<Layout>,
    mut balls: BallParts,
    mut parts: FloorParts,
    mut columns: Columns,
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
            t.translation = layout.ball(b.0, xi, across);
        }
        glow(m, playback.ball_flashing(b.0));
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
    for (p, mut t, wall, m) in &mut parts {
        t.translation = p.1 + Vec3::X * floor_x(p.0);
        if let Some(w) = wall {
            glow(m, playback.wall_flashing(w.0, &layout.boxes[w.1].balls));
        }
    }
    for (c, mut t) in &mut columns {
        // Lean so that the top follows the floor it holds while the foot follows the one below.
        let (foot, top) = (if c.1 == 0 { 0.0 } else { floor_x(c.1 - 1) }, floor_x(c.1));
        let lean = (top - foot).atan2(layout.column_height);
        t.rotation = Quat::from_rotation_z(-lean);
        t.translation = c.0 + Vec3::new(0.5 * (foot + top), 0.5 * layout.column_height, 0.0);
    }
}
