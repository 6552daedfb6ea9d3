//! Off-screen rendering (`--features render`; on CPU-only machines through Mesa's lavapipe):
//! frames of the requested size in which each ball is drawn where the physics puts it, with
//! background between balls, and a rendered run whose physics equals the headless run's to
//! the byte.
#![cfg(feature = "render")]

use crate::common::{lpc, lpc_command};
use std::path::Path;

use lpc_damper::output::figures::read_series_csv;
use lpc_damper::render::stage::{Layout, BACKGROUND, STOREYS_SHOWN_BELOW};
use lpc_damper::scene::{load_scene, BallKind};

fn decode(path: &Path) -> (u32, u32, Vec<u8>, usize) {
    let mut reader = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap())).read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf, info.color_type.samples())
}

/// The colour at pixel `p` of frame `k`, decoded as `(width, height, bytes, channels)`.
fn pixel((w, h, px, channels): (u32, u32, &[u8], usize), p: bevy::math::Vec2, k: usize) -> [u8; 3] {
    assert!(p.x >= 0.0 && p.y >= 0.0 && p.x < w as f32 && p.y < h as f32, "frame {k}: pixel {p} is out of the picture");
    let i = ((p.y.round() as usize) * w as usize + p.x.round() as usize) * channels;
    [px[i], px[i + 1], px[i + 2]]
}

/// Large balls are drawn red, small ones blue (see `render::stage`); lighting changes the
/// shade, not which channel leads.
fn is_large(p: [u8; 3]) -> bool {
    p[0] > 90 && p[0] as i32 > p[1] as i32 + 50 && p[0] as i32 > p[2] as i32 + 50
}
fn is_small(p: [u8; 3]) -> bool {
    p[2] > 90 && p[2] as i32 > p[0] as i32 + 50 && p[2] as i32 > p[1] as i32 + 20
}
/// A large ball deep in a pile, in the shade of the balls around it: darker, red still leads
/// by far more than the grey walls, the floor or the sky let it.
fn is_shaded_large(p: [u8; 3]) -> bool {
    p[0] as i32 > p[1].max(p[2]) as i32 + 25
}

/// The structure's grey steel: cool (blue at least red) and darker than the sky; the ground
/// is warm (red over blue).
fn is_steel(p: [u8; 3]) -> bool {
    p[2] >= p[0] && p != BACKGROUND && p[0] < 200
}

const FPS: f64 = 20.0;
const SIZE: (u32, u32) = (480, 270);

/// Renders the first 0.1 s of the scene at `path` with the contact model at 20 fps into `out`
/// (frames of 640x480), and returns the scene, its layout and the run's series.
fn render_tenth_of_a_second(path: &str, out: &Path) -> (lpc_damper::scene::Scene, Layout, lpc_damper::run::Series) {
    let o =
        lpc(["render", path, "--model", "rapier", "--out", out.to_str().unwrap(), "--horizon", "0.1", "--fps", "20", "--size", "640x480"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let scene = load_scene(path).unwrap();
    let layout = Layout::of(&scene);
    let series = read_series_csv(&out.join("series.csv")).unwrap();
    (scene, layout, series)
}

/// Asserts that ball `i` shows a ball's colour at its centre's pixel in frame `k` (its own, or
/// that of a ball in front of it), `at` reading that frame's pixels.
fn assert_ball_drawn(
    (scene, layout, series): (&lpc_damper::scene::Scene, &Layout, &lpc_damper::run::Series),
    i: usize,
    (k, sample): (usize, usize),
    at: impl Fn(bevy::math::Vec2) -> [u8; 3],
) {
    let size = (640, 480);
    let centre = layout.ball(i, series.x(i)[sample], series.across(i, sample));
    let p = layout.project(size, centre);
    let r_px = layout.projected_radius(size, centre, scene.balls[i].radius as f32);
    assert!(r_px > 3.0, "ball{} is {r_px} px across: too small to check", i + 1);
    // The light's highlight may sit on the centre's pixel (near white there): the ball is drawn
    // when a ball's colour shows there or a third of its radius from it.
    let drawn = |c: [u8; 3]| is_shaded_large(c) || is_small(c) || is_large(c);
    let c = at(p);
    let around = (0..8).map(|q| {
        let angle = q as f32 * std::f32::consts::FRAC_PI_4;
        at(p + r_px / 3.0 * bevy::math::Vec2::new(angle.cos(), angle.sin()))
    });
    assert!(
        drawn(c) || around.clone().any(drawn),
        "frame {k}: ball{} at pixel {p} is not drawn ({c:?}, around it {:?})",
        i + 1,
        around.collect::<Vec<_>>()
    );
}

#[test]
fn balls_are_drawn_where_the_physics_puts_them() {
    let out = tempfile::tempdir().unwrap();
    let dir = out.path().to_str().unwrap();
    let o = lpc(["render", "scenes/lpc-lsl.toml", "--out", dir, "--horizon", "0.4", "--fps", "20", "--size", "480x270"]);
    assert!(o.status.success(), "{}\n{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    // Off-screen on a machine without a Wayland session, nothing but the summary is printed.
    assert!(String::from_utf8_lossy(&o.stderr).trim().is_empty(), "{}", String::from_utf8_lossy(&o.stderr));
    // The animation beside the frames: a GIF of the frames' size, one image per frame, each
    // shown 100/fps hundredths of a second (one simulated second per second).
    let gif = std::fs::read(out.path().join("animation.gif")).unwrap();
    assert_eq!(&gif[..6], b"GIF89a");
    assert_eq!((u16::from_le_bytes([gif[6], gif[7]]), u16::from_le_bytes([gif[8], gif[9]])), (SIZE.0 as u16, SIZE.1 as u16));
    let delays: Vec<u16> = gif.windows(6).filter(|w| w[..3] == [0x21, 0xF9, 0x04]).map(|w| u16::from_le_bytes([w[4], w[5]])).collect();
    assert_eq!(delays.len(), (0.4 * FPS).round() as usize + 1, "one graphic control block per frame");
    assert!(delays.iter().all(|&d| d == (100.0 / FPS) as u16), "{delays:?}");
    let scene = load_scene("scenes/lpc-lsl.toml").unwrap();
    let layout = Layout::of(&scene);
    let series = read_series_csv(&out.path().join("series.csv")).unwrap();
    let (_, per_frame) = lpc_damper::run::frame_sampling(FPS, scene.sample_dt);
    let frames = (0.4 * FPS).round() as usize + 1;
    for k in 0..frames {
        let path = out.path().join(format!("frame_{k:05}.png"));
        let (w, h, px, channels) = decode(&path);
        assert_eq!((w, h), SIZE, "{}", path.display());
        let at = |p: bevy::math::Vec2| {
            let i = (p.y.round() as usize * w as usize + p.x.round() as usize) * channels;
            [px[i], px[i + 1], px[i + 2]]
        };
        let sample = k * per_frame;
        assert!((series.t()[sample] - k as f64 / FPS).abs() < 1e-9, "frame {k} falls on a sample");
        let mut centres = vec![];
        for (i, ball) in scene.balls.iter().enumerate() {
            let centre = layout.ball(i, series.x(i)[sample], scene.space.lateral_of(i));
            let p = layout.project(SIZE, centre);
            let r_px = layout.projected_radius(SIZE, centre, ball.radius as f32);
            assert!(r_px > 3.0, "ball{} is {r_px} px across: too small to check", i + 1);
            let colour = at(p);
            let ok = if ball.kind == BallKind::Small { is_small(colour) } else { is_large(colour) };
            assert!(ok, "frame {k}: ball{} ({:?}) at pixel {p} shows {colour:?}", i + 1, ball.kind);
            // Just above the ball (inside the see-through box) the ball's colour has ended: the
            // ball is drawn at its size, not larger.
            let above = at(p - bevy::math::Vec2::new(0.0, 1.3 * r_px + 1.0));
            assert!(!is_large(above) && !is_small(above), "frame {k}: ball{} colour {above:?} above it", i + 1);
            centres.push((p, r_px));
        }
        for i in 1..centres.len() {
            // Midway between two balls' facing surfaces, when there is room for a pixel.
            let ((a, ra), (b, rb)) = (centres[i - 1], centres[i]);
            if (b.x - rb) - (a.x + ra) >= 3.0 {
                let mid = bevy::math::Vec2::new(0.5 * ((a.x + ra) + (b.x - rb)), 0.5 * (a.y + b.y));
                let c = at(mid);
                assert!(!is_large(c) && !is_small(c), "frame {k}: ball colour {c:?} between ball{i} and ball{}", i + 1);
            }
        }
        // The top-left corner is sky: the clear colour.
        let corner = at(bevy::math::Vec2::new(2.0, 2.0));
        for ch in 0..3 {
            assert!((corner[ch] as i32 - BACKGROUND[ch] as i32).abs() <= 12, "frame {k}: background {corner:?}");
        }
    }
    assert!(!out.path().join(format!("frame_{frames:05}.png")).exists(), "one frame per 1/fps of simulated time");
}

#[test]
fn a_missing_graphics_driver_is_an_error_not_a_panic() {
    let out = tempfile::tempdir().unwrap();
    let o = lpc_command()
        .args(["render", "scenes/conventional.toml", "--out", out.path().to_str().unwrap(), "--horizon", "0.1"])
        .env("VK_ICD_FILENAMES", "/nonexistent/icd.json")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("no graphics adapter") && !stderr.contains("panicked"), "{stderr}");
}

#[test]
fn rendering_never_changes_the_physics() {
    for model in ["reference", "rapier"] {
        let out = tempfile::tempdir().unwrap();
        let (rendered, headless) = (out.path().join("rendered"), out.path().join("headless"));
        let o = lpc([
            "render",
            "scenes/lpc-lsl.toml",
            "--model",
            model,
            "--out",
            rendered.to_str().unwrap(),
            "--horizon",
            "0.3",
            "--fps",
            "20",
            "--size",
            "160x100",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let (sample_dt, _) = lpc_damper::run::frame_sampling(FPS, 0.001);
        let o = lpc([
            "run",
            "scenes/lpc-lsl.toml",
            "--model",
            model,
            "--out",
            headless.to_str().unwrap(),
            "--horizon",
            "0.3",
            "--sample-dt",
            &format!("{sample_dt}"),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        for file in ["series.csv", "impacts.csv"] {
            assert!(
                std::fs::read(rendered.join(file)).unwrap() == std::fs::read(headless.join(file)).unwrap(),
                "{model}: {file} differs between rendered and headless runs"
            );
        }
        let strip = |p: &Path| -> String {
            std::fs::read_to_string(p.join("summary.json")).unwrap().lines().filter(|l| !l.contains("wall_time_s")).collect()
        };
        assert_eq!(strip(&rendered), strip(&headless), "{model}: summary.json");
    }
}

#[test]
fn view_without_a_display_is_an_error_not_a_panic() {
    let o = lpc_command()
        .args(["view", "scenes/conventional.toml", "--horizon", "0.1"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("no display") && !stderr.contains("panicked"), "{stderr}");
}

/// A box of three hundred balls (issue 30): every frame of the animation draws every ball, each
/// ball's centre showing a ball's colour (its own, or that of a ball in front of it).
#[test]
fn a_box_of_balls_is_drawn_ball_by_ball() {
    let out = tempfile::tempdir().unwrap();
    let dir = out.path().to_str().unwrap();
    let size = (640, 360);
    let o = lpc([
        "render",
        "scenes/particle-box.toml",
        "--model",
        "rapier",
        "--out",
        dir,
        "--horizon",
        "0.1",
        "--fps",
        "20",
        "--size",
        "640x360",
    ]);
    assert!(o.status.success(), "{}\n{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    let scene = load_scene("scenes/particle-box.toml").unwrap();
    assert!(scene.balls.len() >= 300);
    let layout = Layout::of(&scene);
    let series = read_series_csv(&out.path().join("series.csv")).unwrap();
    assert!(series.has_across(), "a box's series holds the balls' places across the motion");
    let (_, per_frame) = lpc_damper::run::frame_sampling(FPS, scene.sample_dt);
    for k in 0..=2 {
        let (w, h, px, channels) = decode(&out.path().join(format!("frame_{k:05}.png")));
        assert_eq!((w, h), size);
        let sample = k * per_frame;
        let at = |p: bevy::math::Vec2| pixel((w, h, &px, channels), p, k);
        for i in 0..scene.balls.len() {
            let centre = layout.ball(i, series.x(i)[sample], series.across(i, sample));
            let p = layout.project(size, centre);
            let r_px = layout.projected_radius(size, centre, scene.balls[i].radius as f32);
            assert!(r_px > 3.0, "ball{} is {r_px} px across: too small to check", i + 1);
            // The light's highlight may whiten one spot of a ball: most of a ball's middle is
            // its colour (or that of a ball in front of it).
            let offsets = [(0.0, 0.0), (0.4, 0.0), (-0.4, 0.0), (0.0, 0.4), (0.0, -0.4)];
            let coloured = offsets
                .iter()
                .filter(|(dx, dy)| {
                    let c = at(p + bevy::math::Vec2::new(dx * r_px, dy * r_px));
                    is_shaded_large(c) || is_small(c)
                })
                .count();
            assert!(coloured >= 3, "frame {k}: ball{} at pixel {p} ({r_px} px) is not drawn", i + 1);
        }
    }
}

/// A building's damper renders (issue 32): the contact model moves the container with the
/// carrying floor, and the rendered run's physics is the headless run's.
#[test]
fn a_damper_on_a_building_renders() {
    let out = tempfile::tempdir().unwrap();
    let (rendered, headless) = (out.path().join("rendered"), out.path().join("headless"));
    let o = lpc([
        "render",
        "scenes/mdof-3storey.toml",
        "--model",
        "rapier",
        "--out",
        rendered.to_str().unwrap(),
        "--horizon",
        "0.2",
        "--fps",
        "20",
        "--size",
        "160x100",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(rendered.join("frame_00004.png").exists());
    let (sample_dt, _) = lpc_damper::run::frame_sampling(FPS, 0.001);
    let o = lpc([
        "run",
        "scenes/mdof-3storey.toml",
        "--model",
        "rapier",
        "--out",
        headless.to_str().unwrap(),
        "--horizon",
        "0.2",
        "--sample-dt",
        &format!("{sample_dt}"),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(std::fs::read(rendered.join("series.csv")).unwrap() == std::fs::read(headless.join("series.csv")).unwrap());
}

/// A box of balls on a building (issue 54): every floor is drawn, moving with its own
/// displacement from the series, the lower ones under the box and the box on the carrying
/// floor, and each ball where the physics puts it.
#[test]
fn a_box_on_a_building_is_drawn_on_its_floor() {
    let out = tempfile::tempdir().unwrap();
    let (scene, layout, series) = render_tenth_of_a_second("examples/scenes/small-box-building.toml", out.path());
    let container = &layout.boxes[0];
    assert_eq!((layout.floors, layout.boxes.len(), container.floor), (3, 1, 2));
    assert!(layout.floor_y(1) + layout.platform < container.ball_y - 0.5 * container.height, "the box rides above the floors under it");
    assert_eq!(series.floor_count(), 3);
    let (_, per_frame) = lpc_damper::run::frame_sampling(FPS, scene.sample_dt);
    let size = (640, 480);
    for k in 0..=2 {
        let (w, h, px, channels) = decode(&out.path().join(format!("frame_{k:05}.png")));
        assert_eq!((w, h), size);
        let sample = k * per_frame;
        let at = |p: bevy::math::Vec2| pixel((w, h, &px, channels), p, k);
        for i in 0..3 {
            // The slab's end beyond the columns, where nothing else is drawn in front of it.
            let (u, _, _) = series.floor(i, sample).unwrap();
            let end = bevy::math::Vec3::new(-0.8 * layout.overhang + u as f32, layout.floor_y(i), 0.0);
            let slab = at(layout.project(size, end));
            assert!(is_steel(slab), "frame {k}: floor {} is not drawn ({slab:?})", i + 1);
            // Half a storey above it, beside the columns: the sky or the ground behind.
            let above = at(layout.project(size, end + bevy::math::Vec3::Y * (0.5 * layout.column_height)));
            assert!(!is_steel(above), "frame {k}: something is drawn between floors {} and {} ({above:?})", i + 1, i + 2);
        }
        for i in 0..scene.balls.len() {
            assert_ball_drawn((&scene, &layout, &series), i, (k, sample), at);
        }
    }
}

/// A box on the top floor of a tall building is framed with the storeys under it, not the
/// whole building: shown whole, twenty storeys left the box a twentieth of the picture.
#[test]
fn a_tall_buildings_damper_fills_the_picture() {
    let text = std::fs::read_to_string("examples/scenes/small-box-building.toml").unwrap();
    let storeys = |n: usize, floor: usize| {
        let list = |x: f64| format!("[{}]", vec![x.to_string(); n].join(", "));
        let structure = format!(
            "[structure]\nmasses = {}\nstiffnesses = {}\ndamping_ratios = {}\ndamper_floor = {floor}\n",
            list(1.35),
            list(4364.0 * n as f64),
            list(0.016)
        );
        let start = text.find("[structure]").unwrap();
        let end = text.find("[forcing]").unwrap();
        let file = format!("{}{structure}\n{}", &text[..start], &text[end..]);
        Layout::of(&lpc_damper::scene::parse(&file, "examples/scenes/tall.toml", "tall").unwrap().scene.unwrap())
    };
    let size = (640, 480);
    let low = storeys(3, 3);
    let box_width = |l: &Layout| {
        let (y, length) = (l.boxes[0].ball_y, l.boxes[0].length);
        l.project(size, bevy::math::Vec3::new(length, y, 0.0)).x - l.project(size, bevy::math::Vec3::new(0.0, y, 0.0)).x
    };
    for (n, floor) in [(10, 10), (20, 20), (20, 12)] {
        let tall = storeys(n, floor);
        assert_eq!((tall.floors, tall.boxes[0].floor), (n, floor - 1));
        // On the top floor the box is about as wide as on the three-storey building (its
        // framing reaches a little higher); below the top, the storey above is framed too and
        // the box is narrower, by less than half. Shown whole, twenty storeys leave it a
        // twentieth of the picture's width (34 px here).
        let (wide, low_wide) = (box_width(&tall), box_width(&low));
        let least = if floor == n { 0.95 } else { 0.5 };
        assert!(wide >= least * low_wide, "{n} storeys, box on floor {floor}: {wide} px wide, {low_wide} px on three");
        // The floors under it in view, the lowest framed cut at the picture's edge as the
        // ground is on three storeys.
        for i in floor - STOREYS_SHOWN_BELOW..floor {
            let p = tall.project(size, bevy::math::Vec3::new(0.0, tall.floor_y(i), 0.0));
            assert!((0.0..size.1 as f32).contains(&p.y), "{n} storeys: floor {} is out of the picture at {p}", i + 1);
        }
    }
}

/// Several dampers (issue 54): each container is drawn on its own floor, moving with it, and
/// each ball inside its own container where the physics puts it.
#[test]
fn several_dampers_are_drawn_each_on_its_floor() {
    let out = tempfile::tempdir().unwrap();
    let (scene, layout, series) = render_tenth_of_a_second("examples/scenes/dampers-two-floors.toml", out.path());
    let floors: Vec<usize> = layout.boxes.iter().map(|b| b.floor).collect();
    assert_eq!(floors, [1, 2]);
    let (lower, upper) = (&layout.boxes[0], &layout.boxes[1]);
    assert!(lower.ball_y + 0.5 * lower.height < layout.floor_y(2) - 0.5 * layout.platform, "the lower box stands under the top floor");
    assert!(upper.ball_y - 0.5 * upper.height > layout.floor_y(2), "the upper box stands on the top floor");
    let (_, per_frame) = lpc_damper::run::frame_sampling(FPS, scene.sample_dt);
    for k in 0..=2 {
        let (w, h, px, channels) = decode(&out.path().join(format!("frame_{k:05}.png")));
        assert_eq!((w, h), (640, 480));
        let sample = k * per_frame;
        let at = |p: bevy::math::Vec2| pixel((w, h, &px, channels), p, k);
        for (d, container) in layout.boxes.iter().enumerate() {
            // The container's left wall moves with its floor.
            let (u, _, _) = series.floor(container.floor, sample).unwrap();
            for i in container.balls.clone() {
                let x = series.x(i)[sample];
                assert!(x >= u - 1e-9 && x <= u + f64::from(container.length) + 1e-9, "ball{} is in damper {}'s container", i + 1, d + 1);
                assert_ball_drawn((&scene, &layout, &series), i, (k, sample), at);
            }
        }
    }
}

/// Containers on one floor occupy the same place in the models (their balls never meet); the
/// picture stands them side by side on that floor, all in view.
#[test]
fn dampers_on_one_floor_stand_side_by_side() {
    let text = std::fs::read_to_string("examples/scenes/dampers-two-floors.toml").unwrap().replace("floor = 2 ", "floor = 3 ");
    let scene = lpc_damper::scene::parse(&text, "examples/scenes/one-floor.toml", "one-floor").unwrap().scene.unwrap();
    assert_eq!(scene.dampers.iter().map(|d| d.floor).collect::<Vec<_>>(), [2, 2]);
    let layout = Layout::of(&scene);
    let (first, second) = (&layout.boxes[0], &layout.boxes[1]);
    assert_eq!((first.floor, second.floor, first.ball_y), (2, 2, second.ball_y));
    assert!(second.shift >= first.shift + first.length + 2.0 * layout.wall, "the containers overlap: {first:?}, {second:?}");
    assert!(layout.width >= second.shift + second.length);
    let size = (640, 480);
    for b in &layout.boxes {
        for x in [b.shift - layout.wall, b.shift + b.length + layout.wall] {
            for y in [b.ball_y - 0.5 * b.height, b.ball_y + 0.5 * b.height] {
                let p = layout.project(size, bevy::math::Vec3::new(x, y, 0.0));
                assert!(
                    p.x > 0.0 && p.x < size.0 as f32 && p.y > 0.0 && p.y < size.1 as f32,
                    "a corner of a container is out of the picture at {p}"
                );
            }
        }
        // Each ball is drawn inside its own container.
        for i in b.balls.clone() {
            let c = layout.ball(i, scene.initial_positions[i], scene.space.lateral_of(i));
            let r = scene.balls[i].radius as f32;
            assert!(c.x - r >= b.shift - 1e-6 && c.x + r <= b.shift + b.length + 1e-6, "ball{} is drawn outside its container", i + 1);
        }
    }
}
