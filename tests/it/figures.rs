//! `lpc plot`: every figure is written as PNG and SVG of the requested size, with real content
//! (curves, axes and text, not a blank canvas), from a scene, a run directory, a chain scene and
//! a compare directory; bad input gets an error naming what is wrong.

use crate::common::lpc;
use std::path::Path;

/// Width, height and RGBA pixels of a PNG.
fn decode(path: &Path) -> (u32, u32, Vec<[u8; 4]>) {
    let mut reader = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap())).read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = info.color_type.samples();
    let px = buf[..info.buffer_size()]
        .chunks(channels)
        .map(|c| match channels {
            3 => [c[0], c[1], c[2], 255],
            4 => [c[0], c[1], c[2], c[3]],
            _ => panic!("unexpected colour type {:?}", info.color_type),
        })
        .collect();
    (info.width, info.height, px)
}

/// The PNG and SVG of `name` in `dir` have size `w` x `h` and carry a drawing: some ink
/// (axes, text, curves) on a mostly white page, in several colours, and a curve in the SVG.
fn assert_figure(dir: &Path, name: &str, (w, h): (u32, u32), curves: usize) {
    let (pw, ph, px) = decode(&dir.join(format!("{name}.png")));
    assert_eq!((pw, ph), (w, h), "{name}.png size");
    let white = px.iter().filter(|p| p[0] > 245 && p[1] > 245 && p[2] > 245).count();
    let ink = 1.0 - white as f64 / px.len() as f64;
    assert!((0.01..0.6).contains(&ink), "{name}.png: {:.1} % of the page inked", 100.0 * ink);
    let mut colours: Vec<[u8; 4]> = px.clone();
    colours.sort();
    colours.dedup();
    assert!(colours.len() > curves + 2, "{name}.png: only {} colours", colours.len());
    let svg = std::fs::read_to_string(dir.join(format!("{name}.svg"))).unwrap();
    assert!(svg.contains(&format!("width=\"{w}\"")) && svg.contains(&format!("height=\"{h}\"")), "{name}.svg size");
    // Each curve is a polyline, and so is each legend sample.
    let polylines = svg.matches("<polyline").count();
    assert!(polylines >= curves, "{name}.svg: {polylines} polylines for {curves} curves");
}

#[test]
fn scene_gives_figs_8_to_12_with_and_without_the_damper() {
    let out = tempfile::tempdir().unwrap();
    let o = lpc(["plot", "scenes/lpc-lsl.toml", "--out", out.path().to_str().unwrap(), "--size", "640x400"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for (name, curves) in [("displacement", 2), ("acceleration", 2), ("positions", 5)] {
        assert_figure(out.path(), name, (640, 400), curves);
    }
    let svg = std::fs::read_to_string(out.path().join("displacement.svg")).unwrap();
    assert!(svg.contains("without damper") && svg.contains("with damper (reference)"), "legend");
}

#[test]
fn chain_scene_gives_the_ker_chart() {
    let out = tempfile::tempdir().unwrap();
    let o = lpc(["plot", "scenes/chain-ker.toml", "--out", out.path().to_str().unwrap(), "--size", "500x300"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_figure(out.path(), "ker", (500, 300), 2);
}

#[test]
fn sweep_scene_gives_one_curve_per_value() {
    let out = tempfile::tempdir().unwrap();
    let o = lpc(["plot", "scenes/sweep-cor.toml", "--out", out.path().to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_figure(out.path(), "sweep", (1000, 640), 3);
    let svg = std::fs::read_to_string(out.path().join("sweep.svg")).unwrap();
    for e in ["0.85", "0.9", "0.95"] {
        assert!(svg.contains(&format!("restitution = {e}")), "legend entry for e = {e}");
    }
}

#[test]
fn compare_and_run_directories_are_plotted() {
    let dir = tempfile::tempdir().unwrap();
    let cmp = dir.path().join("cmp");
    let o = lpc(["compare", "scenes/conventional.toml", "--out", cmp.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let figs = dir.path().join("figs");
    let o = lpc(["plot", cmp.to_str().unwrap(), "--out", figs.to_str().unwrap(), "--size", "320x200"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_figure(&figs, "overlay", (320, 200), 2);
    let svg = std::fs::read_to_string(figs.join("overlay.svg")).unwrap();
    assert!(svg.contains("reference") && svg.contains("rapier"), "one curve per model");

    let o = lpc(["plot", cmp.join("rapier").to_str().unwrap(), "--out", figs.to_str().unwrap(), "--size", "320x200"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_figure(&figs, "displacement", (320, 200), 1);
}

#[test]
fn bad_input_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("figs");
    let o = lpc(["plot", dir.path().to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("series.csv"), "{}", String::from_utf8_lossy(&o.stderr));
    let o = lpc(["plot", "scenes/lpc-lsl.toml", "--out", out.to_str().unwrap(), "--size", "10x10"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("WIDTHxHEIGHT"));
    assert!(!out.exists(), "nothing written on bad input");
}
