//! The paper's figures as PNG and SVG (plotters): time histories with and without the damper
//! (Figs. 8-11), ball positions inside the moving container (Fig. 12), a sweep's curves
//! (Figs. 13-16), the KER chart (Fig. 5) and an overlay of models. Every figure is written
//! twice, `NAME.png` and `NAME.svg`, of the same size.

use std::path::{Path, PathBuf};
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::run::{Run, Series};
use crate::studies::chain::KerRow;

/// The font every bitmap figure is drawn with (DejaVu Sans, bundled so that figures look the
/// same on every machine and need no system font library). SVG files name `sans-serif`.
const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// A figure could not be drawn or written.
#[derive(Debug, thiserror::Error)]
#[error("figure {path}: {reason}")]
pub struct FigureError {
    /// The file being written.
    pub path: String,
    /// What went wrong.
    pub reason: String,
}

/// One curve of a figure.
#[derive(Debug, Clone)]
pub struct Curve {
    /// Legend entry.
    pub label: String,
    /// Abscissae.
    pub x: Vec<f64>,
    /// Ordinates.
    pub y: Vec<f64>,
}

/// One figure: axes, titles and curves.
#[derive(Debug, Clone)]
pub struct Figure {
    /// File stem (`displacement` gives `displacement.png` and `displacement.svg`).
    pub name: String,
    /// Caption.
    pub title: String,
    /// Abscissa label.
    pub x_desc: String,
    /// Ordinate label.
    pub y_desc: String,
    /// Curves, drawn in order.
    pub curves: Vec<Curve>,
    /// Mark each point (for charts of few points).
    pub points: bool,
}

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        for style in [FontStyle::Normal, FontStyle::Bold] {
            let registered = plotters::style::register_font("sans-serif", style, FONT);
            assert!(registered.is_ok(), "the bundled font is a valid TrueType font");
        }
    });
}

/// Writes `figure` as PNG and SVG of `size` (width, height) into `dir`; returns the paths.
pub fn write(figure: &Figure, dir: &Path, size: (u32, u32)) -> Result<Vec<PathBuf>, FigureError> {
    write_both(&figure.name, dir, size, |root| draw(root, figure), |root| draw(root, figure))
}

/// Writes `map` as PNG and SVG of `size` into `dir`; returns the paths.
pub fn write_heat_map(map: &HeatMap, dir: &Path, size: (u32, u32)) -> Result<Vec<PathBuf>, FigureError> {
    write_both(&map.name, dir, size, |root| draw_heat_map(root, map), |root| draw_heat_map(root, map))
}

type Png<'a> = DrawingArea<BitMapBackend<'a>, Shift>;
type Svg<'a> = DrawingArea<SVGBackend<'a>, Shift>;

fn write_both(
    name: &str,
    dir: &Path,
    size: (u32, u32),
    png: impl FnOnce(Png) -> Result<(), String>,
    svg: impl FnOnce(Svg) -> Result<(), String>,
) -> Result<Vec<PathBuf>, FigureError> {
    register_font();
    std::fs::create_dir_all(dir).map_err(|e| FigureError { path: dir.display().to_string(), reason: e.to_string() })?;
    let mut written = vec![];
    let (mut png, mut svg) = (Some(png), Some(svg));
    for ext in ["png", "svg"] {
        let path = dir.join(format!("{name}.{ext}"));
        // Drawn beside the target and renamed, so an interrupted run leaves no half figure.
        let tmp = dir.join(format!(".{name}.tmp.{ext}"));
        let fail = |reason: String| FigureError { path: path.display().to_string(), reason };
        let drawn = if ext == "png" {
            let mut rgb = vec![0u8; 3 * size.0 as usize * size.1 as usize];
            let drawn = (png.take().expect("once"))(BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area());
            drawn.and_then(|()| encode_png(&tmp, size, &rgb))
        } else {
            (svg.take().expect("once"))(SVGBackend::new(&tmp, size).into_drawing_area())
        };
        drawn.map_err(fail)?;
        std::fs::rename(&tmp, &path).map_err(|e| fail(e.to_string()))?;
        written.push(path);
    }
    Ok(written)
}

/// Writes 8-bit RGB pixels, row by row, as a PNG file of `size` (width, height).
fn encode_png(path: &Path, size: (u32, u32), rgb: &[u8]) -> Result<(), String> {
    let file = std::fs::File::create(path).map_err(|e| e.to_string())?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), size.0, size.1);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
    writer.write_image_data(rgb).map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())
}

/// A design map: one metric over a grid of two parameters.
#[derive(Debug, Clone)]
pub struct HeatMap {
    /// File stem.
    pub name: String,
    /// Title.
    pub title: String,
    /// First parameter (columns) and its values.
    pub x: (String, Vec<f64>),
    /// Second parameter (rows) and its values.
    pub y: (String, Vec<f64>),
    /// `z[row][column]`; `None` where the metric has no value (e.g. not settled).
    pub z: Vec<Vec<Option<f64>>>,
    /// The metric's name and unit.
    pub z_desc: String,
}

fn draw_heat_map<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, m: &HeatMap) -> Result<(), String> {
    use plotters::style::colors::colormaps::{ColorMap, ViridisRGB};
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(err)?;
    let (w, h) = root.dim_in_pixel();
    let text = (h / 40).clamp(10, 22);
    let (plot, bar) = root.split_horizontally(w.saturating_sub((w / 5).max(110)));
    let (nx, ny) = (m.x.1.len(), m.y.1.len());
    let values = m.z.iter().flatten().flatten().copied().filter(|v| v.is_finite());
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    let (lo, hi) = if lo.is_finite() { (lo, if hi > lo { hi } else { lo + 1.0 }) } else { (0.0, 1.0) };
    let colour = |v: f64| ViridisRGB.get_color_normalized(v as f32, lo as f32, hi as f32);
    let label = |values: &[f64], i: f64| {
        let k = i.round();
        if (i - k).abs() < 1e-9 && k >= 0.0 && (k as usize) < values.len() {
            format!("{}", values[k as usize])
        } else {
            String::new()
        }
    };
    let mut chart = ChartBuilder::on(&plot)
        .caption(&m.title, ("sans-serif", text + 4))
        .margin(text)
        .x_label_area_size(text * 3)
        .y_label_area_size((w / 10).clamp(40, 90))
        .build_cartesian_2d(-0.5..nx as f64 - 0.5, -0.5..ny as f64 - 0.5)
        .map_err(err)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_labels(nx.min(12))
        .y_labels(ny.min(12))
        .x_label_formatter(&|i| label(&m.x.1, *i))
        .y_label_formatter(&|i| label(&m.y.1, *i))
        .x_desc(&m.x.0)
        .y_desc(&m.y.0)
        .label_style(("sans-serif", text))
        .draw()
        .map_err(err)?;
    let cells = (0..ny).flat_map(|r| (0..nx).map(move |c| (r, c)));
    chart
        .draw_series(cells.map(|(r, c)| {
            let (x, y) = (c as f64, r as f64);
            let style = match m.z[r][c] {
                Some(v) if v.is_finite() => colour(v).filled(),
                _ => RGBColor(200, 200, 200).filled(),
            };
            Rectangle::new([(x - 0.5, y - 0.5), (x + 0.5, y + 0.5)], style)
        }))
        .map_err(err)?;
    // Colour bar: the metric's range, bottom to top; grey means no value.
    let mut scale = ChartBuilder::on(&bar)
        .margin(text)
        .margin_top(text * 3)
        .y_label_area_size((w / 14).clamp(40, 70))
        .caption(&m.z_desc, ("sans-serif", text))
        .build_cartesian_2d(0.0..1.0, lo..hi)
        .map_err(err)?;
    scale.configure_mesh().disable_mesh().disable_x_axis().label_style(("sans-serif", text)).draw().map_err(err)?;
    let steps = 100;
    scale
        .draw_series((0..steps).map(|k| {
            let a = lo + (hi - lo) * k as f64 / steps as f64;
            let b = lo + (hi - lo) * (k + 1) as f64 / steps as f64;
            Rectangle::new([(0.0, a), (1.0, b)], colour(0.5 * (a + b)).filled())
        }))
        .map_err(err)?;
    root.present().map_err(|e| e.to_string())
}

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, f: &Figure) -> Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(err)?;
    let finite = |v: &f64| v.is_finite();
    let xs = f.curves.iter().flat_map(|c| c.x.iter().copied()).filter(finite);
    let ys = f.curves.iter().flat_map(|c| c.y.iter().copied()).filter(finite);
    let (x0, x1) = padded(xs, 0.0);
    let (y0, y1) = padded(ys, 0.05);
    let (w, h) = root.dim_in_pixel();
    let text = (h / 40).clamp(10, 22);
    let mut chart = ChartBuilder::on(&root)
        .caption(&f.title, ("sans-serif", text + 4))
        .margin(text)
        .x_label_area_size(text * 3)
        .y_label_area_size((w / 12).clamp(40, 90))
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(&f.x_desc)
        .y_desc(&f.y_desc)
        .label_style(("sans-serif", text))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(err)?;
    for (k, c) in f.curves.iter().enumerate() {
        let color = Palette99::pick(k).to_rgba();
        let pts: Vec<(f64, f64)> = c.x.iter().copied().zip(c.y.iter().copied()).filter(|p| p.0.is_finite() && p.1.is_finite()).collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
            .map_err(err)?
            .label(c.label.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2)));
        if f.points {
            chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.filled()))).map_err(err)?;
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font(("sans-serif", text))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(err)?;
    root.present().map_err(|e| e.to_string())
}

/// The range of `values`, widened by `pad` of its span (and never empty).
fn padded(values: impl Iterator<Item = f64>, pad: f64) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let span = hi - lo;
    if span <= 1e-12 * lo.abs().max(1e-300) {
        let d = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        return (lo - d, hi + d);
    }
    (lo - pad * span, hi + pad * span)
}

fn scaled(v: &[f64], k: f64) -> Vec<f64> {
    v.iter().map(|x| x * k).collect()
}

/// Figs. 8-11: frame displacement and acceleration against time, with the damper (`with`) and,
/// when given, without it (the bare frame).
pub fn time_histories(with: &Run, without: Option<&Run>) -> Vec<Figure> {
    let label = |r: &Run, what: &str| format!("{what} ({})", r.model);
    let mut disp = vec![Curve { label: label(with, "with damper"), x: with.series.t().to_vec(), y: scaled(with.series.xs(), 1e3) }];
    let mut acc = vec![Curve { label: label(with, "with damper"), x: with.series.t().to_vec(), y: with.series.a().to_vec() }];
    if let Some(w) = without {
        disp.insert(0, Curve { label: "without damper".into(), x: w.series.t().to_vec(), y: scaled(w.series.xs(), 1e3) });
        acc.insert(0, Curve { label: "without damper".into(), x: w.series.t().to_vec(), y: w.series.a().to_vec() });
    }
    vec![
        Figure {
            name: "displacement".into(),
            title: format!("{}: frame displacement", with.scene),
            x_desc: "t (s)".into(),
            y_desc: "xs (mm)".into(),
            curves: disp,
            points: false,
        },
        Figure {
            name: "acceleration".into(),
            title: format!("{}: frame acceleration", with.scene),
            x_desc: "t (s)".into(),
            y_desc: "a (m/s^2)".into(),
            curves: acc,
            points: false,
        },
    ]
}

/// A structure's floors: each floor's displacement relative to the ground against time (with
/// the damper), and the drift profile, each storey's peak interstorey drift against its
/// height, with the damper and, when given, without it (`without`, each floor's summary).
/// None without floors.
pub fn floor_responses(with: &Run, without: Option<&[crate::metrics::FloorSummary]>) -> Vec<Figure> {
    let s = &with.series;
    let n = s.floor_count();
    if n == 0 {
        return vec![];
    }
    let floors = (0..n)
        .map(|i| Curve {
            label: format!("floor {}", i + 1),
            x: s.t().to_vec(),
            y: (0..s.len()).map(|k| s.floor(i, k).map_or(f64::NAN, |f| f.0 * 1e3)).collect(),
        })
        .collect();
    let profile = |storeys: &[crate::metrics::FloorSummary], label: &str| Curve {
        label: label.into(),
        x: storeys.iter().map(|f| f.peak_drift * 1e3).collect(),
        y: storeys.iter().map(|f| f.floor as f64).collect(),
    };
    let mut drift = vec![profile(&crate::metrics::FloorSummary::of(s), &format!("with damper ({})", with.model))];
    if let Some(w) = without.filter(|w| w.len() == n) {
        drift.insert(0, profile(w, "without damper"));
    }
    vec![
        Figure {
            name: "floors".into(),
            title: format!("{}: floor displacements relative to the ground", with.scene),
            x_desc: "t (s)".into(),
            y_desc: "u (mm)".into(),
            curves: floors,
            points: false,
        },
        Figure {
            name: "drift-profile".into(),
            title: format!("{}: peak interstorey drift over height", with.scene),
            x_desc: "peak drift (mm)".into(),
            y_desc: "storey".into(),
            curves: drift,
            points: true,
        },
    ]
}

/// Fig. 12: each ball's centre relative to the container's left wall, with the walls' inner
/// faces when the container length is known; one figure per chain (`chains` the balls of each,
/// in order), named `positions` for one chain and `positions-chainK` for several.
pub fn ball_positions(run: &Run, container_length: Option<f64>, chains: &[std::ops::Range<usize>]) -> Vec<Figure> {
    let s = &run.series;
    // Without several chains, every ball in one figure.
    let all: Vec<std::ops::Range<usize>> = std::iter::once(0..s.balls()).collect();
    let chains = if chains.len() > 1 { chains } else { &all[..] };
    chains
        .iter()
        .enumerate()
        .map(|(k, chain)| {
            let mut curves: Vec<Curve> = chain
                .clone()
                .map(|i| Curve {
                    label: format!("ball{}", i + 1),
                    x: s.t().to_vec(),
                    y: s.x(i).iter().zip(s.xs()).map(|(x, xs)| (x - xs) * 1e3).collect(),
                })
                .collect();
            if let Some(l) = container_length {
                let ends = vec![s.t().first().copied().unwrap_or(0.0), s.t().last().copied().unwrap_or(0.0)];
                curves.push(Curve { label: "left wall".into(), x: ends.clone(), y: vec![0.0, 0.0] });
                curves.push(Curve { label: "right wall".into(), x: ends, y: vec![l * 1e3, l * 1e3] });
            }
            let several = chains.len() > 1;
            Figure {
                name: if several { format!("positions-chain{}", k + 1) } else { "positions".into() },
                title: if several {
                    format!("{}: chain {}'s ball centres in the container ({})", run.scene, k + 1, run.model)
                } else {
                    format!("{}: ball centres in the container ({})", run.scene, run.model)
                },
                x_desc: "t (s)".into(),
                y_desc: "x - xs (mm)".into(),
                curves,
                points: false,
            }
        })
        .collect()
}

/// Figs. 13-16: the frame displacement for each value of a swept parameter.
pub fn sweep_curves(parameter: &str, runs: &[(String, Run)]) -> Figure {
    let scene = runs.first().map_or(String::new(), |r| r.1.scene.clone());
    Figure {
        name: "sweep".into(),
        title: format!("{scene}: frame displacement for each {parameter}"),
        x_desc: "t (s)".into(),
        y_desc: "xs (mm)".into(),
        curves: runs
            .iter()
            .map(|(value, r)| Curve { label: format!("{parameter} = {value}"), x: r.series.t().to_vec(), y: scaled(r.series.xs(), 1e3) })
            .collect(),
        points: false,
    }
}

/// Frequency response: steady amplitude of `xs` against forcing frequency, with and without
/// the damper.
pub fn frf_chart(points: &[crate::studies::frf::FrfPoint], scene: &str, model: &str) -> Figure {
    // Frequencies whose run failed have no amplitude to draw.
    let curve = |label: &str, amplitude: fn(&crate::studies::frf::FrfPoint) -> Option<f64>| {
        let known: Vec<(f64, f64)> = points.iter().filter_map(|p| amplitude(p).map(|a| (p.frequency, a * 1e3))).collect();
        Curve { label: label.into(), x: known.iter().map(|k| k.0).collect(), y: known.iter().map(|k| k.1).collect() }
    };
    Figure {
        name: "frf".into(),
        title: format!("{scene}: steady amplitude ({model})"),
        x_desc: "forcing frequency (Hz)".into(),
        y_desc: "amplitude of xs (mm)".into(),
        curves: vec![curve("with damper", |p| p.amplitude), curve("without damper", |p| p.amplitude_no_damper)],
        points: true,
    }
}

/// Frequency response over an ensemble: the median and 5-95 % band of the per-period peaks,
/// with and without the damper.
pub fn frf_band_chart(bands: &[crate::studies::frf::FrfBand], scene: &str, model: &str) -> Figure {
    use crate::studies::ensemble::Stats;
    let curve = |label: String, stats: fn(&crate::studies::frf::FrfBand) -> &Stats, pick: fn(&Stats) -> Option<f64>| {
        let known: Vec<(f64, f64)> = bands.iter().filter_map(|b| pick(stats(b)).map(|a| (b.frequency, a * 1e3))).collect();
        Curve { label, x: known.iter().map(|k| k.0).collect(), y: known.iter().map(|k| k.1).collect() }
    };
    let mut curves = vec![];
    type Pick = fn(&crate::studies::frf::FrfBand) -> &Stats;
    let sides: [(&str, Pick); 2] = [("with damper", |b| &b.amplitude), ("without damper", |b| &b.amplitude_no_damper)];
    for (what, stats) in sides {
        curves.push(curve(format!("{what}: median"), stats, |s| s.median));
        curves.push(curve(format!("{what}: 5 %"), stats, |s| s.p05));
        curves.push(curve(format!("{what}: 95 %"), stats, |s| s.p95));
    }
    let members = bands.first().map_or(0, |b| b.members);
    Figure {
        name: "frf".into(),
        title: format!("{scene}: per-period peaks over {members} members ({model})"),
        x_desc: "forcing frequency (Hz)".into(),
        y_desc: "peak of |xs| per period (mm)".into(),
        curves,
        points: true,
    }
}

/// An ensemble's band of the frame displacement (5 %, median, 95 % of the members at each
/// sample) over the nominal run.
pub fn band_chart(nominal: &Run, band: &[[f64; 5]]) -> Figure {
    let column = |j: usize| band.iter().map(|r| r[j] * if j == 0 { 1.0 } else { 1e3 }).collect::<Vec<f64>>();
    let t = column(0);
    Figure {
        name: "band".into(),
        title: format!("{}: frame displacement, nominal and the members' 5-95 % band ({})", nominal.scene, nominal.model),
        x_desc: "t (s)".into(),
        y_desc: "xs (mm)".into(),
        curves: vec![
            Curve { label: "nominal".into(), x: nominal.series.t().to_vec(), y: nominal.series.xs().iter().map(|x| x * 1e3).collect() },
            Curve { label: "members: 5 %".into(), x: t.clone(), y: column(1) },
            Curve { label: "members: median".into(), x: t.clone(), y: column(2) },
            Curve { label: "members: 95 %".into(), x: t, y: column(3) },
        ],
        points: false,
    }
}

/// Fig. 5: kinetic energy ratio against the number of large balls, with and without small
/// balls between them.
pub fn ker_chart(rows: &[KerRow], model: &str) -> Figure {
    let curve = |with_small: bool, label: &str| {
        let sel: Vec<&KerRow> = rows.iter().filter(|r| (r.small > 0) == with_small).collect();
        Curve { label: label.into(), x: sel.iter().map(|r| r.large as f64).collect(), y: sel.iter().map(|r| r.ker).collect() }
    };
    Figure {
        name: "ker".into(),
        title: format!("Chain experiment: kinetic energy ratio ({model})"),
        x_desc: "large balls N_L".into(),
        y_desc: "KER".into(),
        curves: [curve(false, "large balls only"), curve(true, "small ball between each two")]
            .into_iter()
            .filter(|c| !c.x.is_empty())
            .collect(),
        points: true,
    }
}

/// The models' frame displacements over each other (from `lpc compare --out`).
pub fn overlay(runs: &[(String, Series)], scene: &str) -> Figure {
    Figure {
        name: "overlay".into(),
        title: format!("{scene}: frame displacement, every model"),
        x_desc: "t (s)".into(),
        y_desc: "xs (mm)".into(),
        curves: runs.iter().map(|(m, s)| Curve { label: m.clone(), x: s.t().to_vec(), y: scaled(s.xs(), 1e3) }).collect(),
        points: false,
    }
}

/// Reads a `series.csv` written by [`super::series_csv`].
pub fn read_series_csv(path: &Path) -> Result<Series, FigureError> {
    let fail = |reason: String| FigureError { path: path.display().to_string(), reason };
    let mut r = csv::Reader::from_path(path).map_err(|e| fail(e.to_string()))?;
    let header = r.headers().map_err(|e| fail(e.to_string()))?.clone();
    // The balls' places across the motion (`y1, z1, ...`) and then a structure's floors
    // (`xs1, vs1, ...`, then `as1, ...`) come after the balls'.
    let cols = header.iter().position(|h| h == "y1" || h == "xs1").unwrap_or(header.len());
    if cols < 4 || &header[0] != "t" || &header[1] != "xs" || (cols - 4) % 2 != 0 {
        return Err(fail("is not a series.csv (expected columns t, xs, vs, a, x1, v1, ...)".into()));
    }
    let balls = (cols - 4) / 2;
    // Each floor's `xs<i>, vs<i>` and `as<i>`, found by name.
    let floor_count = (1..).take_while(|i| header.iter().any(|h| h == format!("as{i}"))).count();
    let find = |name: String| header.iter().position(|h| h == name).ok_or_else(|| fail(format!("has no column `{name}`")));
    let across_columns: Vec<usize> = if header.iter().any(|h| h == "y1") {
        (1..=balls).flat_map(|i| [find(format!("y{i}")), find(format!("z{i}"))]).collect::<Result<_, _>>()?
    } else {
        vec![]
    };
    let mut floor_columns = Vec::with_capacity(3 * floor_count);
    for prefix in ["xs", "vs", "as"] {
        for i in 1..=floor_count {
            floor_columns.push(find(format!("{prefix}{i}"))?);
        }
    }
    let mut columns: Vec<Vec<f64>> = vec![vec![]; cols];
    let mut floors = Vec::new();
    let mut across = Vec::new();
    let number = |rec: &csv::StringRecord, k: usize, line: usize| {
        rec.get(k)
            .and_then(|v| v.parse::<f64>().ok())
            .ok_or_else(|| fail(format!("row {}: column `{}` is not a number", line + 2, &header[k])))
    };
    for (line, rec) in r.records().enumerate() {
        let rec = rec.map_err(|e| fail(e.to_string()))?;
        for (k, column) in columns.iter_mut().enumerate() {
            column.push(number(&rec, k, line)?);
        }
        for &k in &across_columns {
            across.push(number(&rec, k, line)?);
        }
        for &k in &floor_columns {
            floors.push(number(&rec, k, line)?);
        }
    }
    let mut columns = columns.into_iter();
    let mut next = || columns.next().unwrap_or_default();
    let (t, xs, vs, a) = (next(), next(), next(), next());
    let (mut x, mut v) = (Vec::with_capacity(balls), Vec::with_capacity(balls));
    for _ in 0..balls {
        x.push(next());
        v.push(next());
    }
    let s = Series::from_columns(t, xs, vs, a, x, v);
    let s = if across_columns.is_empty() { s } else { s.with_across(across) };
    Ok(if floor_count > 0 { s.with_floors(floor_count, floors) } else { s })
}

/// Reads the `band.csv` of `lpc run --ensemble --out` (`t, xs_p05, xs_median, xs_p95, env_p95`).
pub fn read_band_csv(path: &Path) -> Result<Vec<[f64; 5]>, FigureError> {
    let fail = |reason: String| FigureError { path: path.display().to_string(), reason };
    let mut r = csv::Reader::from_path(path).map_err(|e| fail(e.to_string()))?;
    let header = r.headers().map_err(|e| fail(e.to_string()))?.clone();
    if header.iter().collect::<Vec<_>>() != ["t", "xs_p05", "xs_median", "xs_p95", "env_p95"] {
        return Err(fail("is not a band.csv (expected columns t, xs_p05, xs_median, xs_p95, env_p95)".into()));
    }
    let mut rows = vec![];
    for (line, rec) in r.records().enumerate() {
        let rec = rec.map_err(|e| fail(e.to_string()))?;
        let mut row = [0.0; 5];
        for (k, x) in row.iter_mut().enumerate() {
            *x = rec
                .get(k)
                .and_then(|v| v.parse::<f64>().ok())
                .ok_or_else(|| fail(format!("row {}: column `{}` is not a number", line + 2, &header[k])))?;
        }
        rows.push(row);
    }
    Ok(rows)
}
