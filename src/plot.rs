//! SVG plots of benchmark tables (plotters' SVG backend: no fonts or system libraries needed).

use crate::bench::BenchRow;
use crate::error::Error;
use crate::output::write_atomic;
use plotters::prelude::*;
use std::path::Path;

/// Plots throughput (particle-substeps/s) against particle count on log–log axes, one line per
/// backend and device, and writes it atomically to `path`.
pub fn throughput_svg(rows: &[BenchRow], title: &str, path: &Path) -> Result<(), Error> {
    let mut series: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for r in rows {
        let name = format!("{}: {}", r.backend, r.device);
        let point = (r.particles as f64, r.particle_substeps_per_second);
        match series.iter_mut().find(|(n, _)| *n == name) {
            Some((_, points)) => points.push(point),
            None => series.push((name, vec![point])),
        }
    }
    let (x_lo, x_hi) = range(rows.iter().map(|r| r.particles as f64));
    let (y_lo, y_hi) = range(rows.iter().map(|r| r.particle_substeps_per_second));
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 560)).into_drawing_area();
        let draw = |e: DrawingAreaErrorKind<std::io::Error>| {
            Error::io(path, std::io::Error::other(format!("plotting failed: {e}")))
        };
        root.fill(&WHITE).map_err(draw)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(80)
            .build_cartesian_2d(
                (x_lo / 1.5..x_hi * 1.5).log_scale(),
                (y_lo / 2.0..y_hi * 2.0).log_scale(),
            )
            .map_err(draw)?;
        chart
            .configure_mesh()
            .x_desc("particles")
            .y_desc("particle-substeps / s")
            .y_label_formatter(&|y| format!("{y:.1e}"))
            .draw()
            .map_err(draw)?;
        for (k, (name, points)) in series.iter().enumerate() {
            let color = Palette99::pick(k).to_rgba();
            chart
                .draw_series(LineSeries::new(points.clone(), color.stroke_width(2)))
                .map_err(draw)?
                .label(name.clone())
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], color));
            chart
                .draw_series(points.iter().map(|&p| Circle::new(p, 4, color.filled())))
                .map_err(draw)?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(draw)?;
        root.present().map_err(draw)?;
    }
    write_atomic(path, svg.as_bytes())
}

fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    if lo.is_finite() && lo > 0.0 {
        (lo, hi)
    } else {
        (1.0, 10.0)
    }
}
