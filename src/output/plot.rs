//! Figures (plotters, SVG): error against cost for `lpc bench`.

use std::path::Path;

use plotters::prelude::*;

use crate::studies::bench::BenchRow;

/// Log-log plot of early error against computing cost per simulated second, one series per
/// scene and model/stepping, Pareto-optimal settings circled.
pub fn error_vs_cost(rows: &[BenchRow], path: &Path) -> Result<(), Box<dyn std::error::Error>> {
    let pts: Vec<(f64, f64)> = rows.iter().map(|r| (r.wall_s_per_sim_s.max(1e-9), (r.errors.max_xs_early * 1e3).max(1e-6))).collect();
    let (xmin, xmax) = pts.iter().fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let (ymin, ymax) = pts.iter().fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.1), b.max(p.1)));
    let root = SVGBackend::new(path, (900, 640)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption("Early error (first 0.5 s) against cost", ("sans-serif", 22))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d((xmin / 2.0..xmax * 2.0).log_scale(), (ymin / 2.0..ymax * 2.0).log_scale())?;
    chart.configure_mesh().x_desc("computing time per simulated second (s)").y_desc("max |xs - xs_ref| over 0.5 s (mm)").draw()?;
    let mut groups: Vec<(String, Vec<usize>)> = Vec::new();
    for (i, r) in rows.iter().enumerate() {
        let name = format!("{} {} {}", r.scene, r.model, r.settings.stepping);
        match groups.iter_mut().find(|g| g.0 == name) {
            Some(g) => g.1.push(i),
            None => groups.push((name, vec![i])),
        }
    }
    for (k, (name, idx)) in groups.iter().enumerate() {
        let color = Palette99::pick(k).to_rgba();
        let mut line: Vec<(f64, f64)> = idx.iter().map(|&i| pts[i]).collect();
        line.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart
            .draw_series(LineSeries::new(line.clone(), color.stroke_width(2)))?
            .label(name.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2)));
        chart.draw_series(line.iter().map(|&p| Circle::new(p, 3, color.filled())))?;
        chart.draw_series(idx.iter().filter(|&&i| rows[i].pareto).map(|&i| Circle::new(pts[i], 8, BLACK.stroke_width(1))))?;
    }
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;
    root.present()?;
    Ok(())
}
