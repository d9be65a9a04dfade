//! SVG plots of benchmark tables (plotters' SVG backend: no fonts or system libraries needed).

use crate::atomic_file::write_atomic;
use crate::error::Error;
use plotters::prelude::*;
use std::path::Path;

/// One named line of points.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend text.
    pub name: String,
    /// (x, y) points, both positive (log axes).
    pub points: Vec<(f64, f64)>,
}

/// Plots each series as a line with markers on log–log axes and writes the SVG atomically.
pub fn log_log_svg(
    series: &[Series],
    title: &str,
    x_desc: &str,
    y_desc: &str,
    path: &Path,
) -> Result<(), Error> {
    let all = || series.iter().flat_map(|s| s.points.iter());
    let (x_lo, x_hi) = range(all().map(|p| p.0));
    let (y_lo, y_hi) = range(all().map(|p| p.1));
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
            .x_desc(x_desc)
            .y_desc(y_desc)
            .y_label_formatter(&|y| format!("{y:.1e}"))
            .draw()
            .map_err(draw)?;
        for (k, s) in series.iter().enumerate() {
            let color = Palette99::pick(k).to_rgba();
            chart
                .draw_series(LineSeries::new(s.points.clone(), color.stroke_width(2)))
                .map_err(draw)?
                .label(s.name.clone())
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], color));
            chart
                .draw_series(s.points.iter().map(|&p| Circle::new(p, 4, color.filled())))
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
