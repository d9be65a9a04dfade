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
        let x_range = (x_lo / 1.5, x_hi * 1.5);
        let (corner, y_range) = legend_place(series, x_range, (y_lo / 2.0, y_hi * 2.0));
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(80)
            .build_cartesian_2d(
                (x_range.0..x_range.1)
                    .log_scale()
                    .with_key_points(ticks(x_range.0, x_range.1)),
                (y_range.0..y_range.1)
                    .log_scale()
                    .with_key_points(ticks(y_range.0, y_range.1)),
            )
            .map_err(draw)?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .x_label_formatter(&|x| format!("{x:.0e}"))
            .y_label_formatter(&|y| format!("{y:.0e}"))
            // Log axes over less than a decade crowd the minor lines into grey bands.
            .light_line_style(TRANSPARENT)
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
            .position(corner)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(draw)?;
        root.present().map_err(draw)?;
    }
    write_atomic(path, svg.as_bytes())
}

/// The share of the plotting area's width and height that the legend of `series` takes
/// (about 16 px a row and 6.5 px a character of the 900 × 560 plot's area of about 790 × 440).
fn legend_size(series: &[Series]) -> (f64, f64) {
    let longest = series
        .iter()
        .map(|s| s.name.chars().count())
        .max()
        .unwrap_or(0);
    let width = (40.0 + 6.5 * longest as f64) / 790.0;
    let height = (10.0 + 16.0 * series.len() as f64) / 440.0;
    (width.min(1.0), height.min(0.9))
}

/// Where the legend goes, and the y range that leaves it room: the corner of the log–log plot
/// with the fewest points under the legend (lines sampled between their points; lower right
/// on a tie), and, where every corner has some, the y range `y` grown on that corner's side
/// until the data clears the legend's height (many series make a legend taller than any
/// free corner).
fn legend_place(
    series: &[Series],
    x: (f64, f64),
    y: (f64, f64),
) -> (SeriesLabelPosition, (f64, f64)) {
    let unit = |v: f64, (lo, hi): (f64, f64)| (v / lo).ln() / (hi / lo).ln();
    let mut at = Vec::new();
    for s in series {
        for pair in s.points.windows(2) {
            for k in 0..8 {
                let f = k as f64 / 8.0;
                let (a, b) = (pair[0], pair[1]);
                at.push((
                    a.0.powf(1.0 - f) * b.0.powf(f),
                    a.1.powf(1.0 - f) * b.1.powf(f),
                ));
            }
        }
        at.extend(s.points.last().copied());
    }
    let (width, height) = legend_size(series);
    let corners = [
        (SeriesLabelPosition::LowerRight, (true, false)),
        (SeriesLabelPosition::UpperLeft, (false, true)),
        (SeriesLabelPosition::UpperRight, (true, true)),
        (SeriesLabelPosition::LowerLeft, (false, false)),
    ];
    let under = |(right, top): (bool, bool)| {
        (at.iter()).filter(move |&&(px, py)| {
            let (u, v) = (unit(px, x), unit(py, y));
            (if right { u > 1.0 - width } else { u < width })
                && (if top { v > 1.0 - height } else { v < height })
        })
    };
    let (corner, (right, top)) = (corners.into_iter())
        .min_by_key(|&(_, c)| under(c).count())
        .unwrap_or((SeriesLabelPosition::LowerRight, (true, false)));
    let (ln_lo, ln_hi) = (y.0.ln(), y.1.ln());
    // The data under the legend, in ln y: the axis grows until it clears the legend's height.
    let mut y = y;
    for (_, py) in under((right, top)) {
        let v = py.ln();
        if top {
            // (ln y_hi' − v) / (ln y_hi' − ln y_lo) = height.
            let hi = (v - height * ln_lo) / (1.0 - height);
            y.1 = y.1.max(hi.exp());
        } else {
            let lo = (v - height * ln_hi) / (1.0 - height);
            y.0 = y.0.min(lo.exp());
        }
    }
    (corner, y)
}

/// 1, 2 and 5 times the powers of ten between `lo` and `hi`: tick marks for log axes.
fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    let mut ticks = Vec::new();
    let mut decade = 10f64.powf(lo.log10().floor());
    while decade <= hi {
        for m in [1.0, 2.0, 5.0] {
            let v = m * decade;
            if v >= lo && v <= hi {
                ticks.push(v);
            }
        }
        decade *= 10.0;
    }
    ticks
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

/// A labelled point of a scatter plot.
#[derive(Clone, Debug, PartialEq)]
pub struct Labelled {
    /// Position, both positive (log axes).
    pub at: (f64, f64),
    /// Text drawn beside it.
    pub label: String,
}

/// A named group of labelled points, drawn in one colour.
#[derive(Clone, Debug, PartialEq)]
pub struct Group {
    /// Legend text.
    pub name: String,
    /// Its points.
    pub points: Vec<Labelled>,
}

/// What a trade-off plot shows beyond its groups.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TradeOff {
    /// Points joined by a dashed line, in order (e.g. a Pareto front).
    pub front: Vec<(f64, f64)>,
    /// The front's legend text.
    pub front_name: String,
    /// Points with an x but no y (e.g. runs that failed): crosses along the top edge.
    pub top: Vec<Labelled>,
    /// A vertical line at this x with its label (e.g. a reference with no y of its own).
    pub vertical: Option<Labelled>,
    /// A horizontal dotted line at this y with its label (e.g. a noise floor).
    pub horizontal: Option<Labelled>,
}

/// Each group's points as labelled markers on log–log axes, the front as a dashed line, `top`
/// as crosses along the top edge and `vertical` as a line, written as SVG atomically.
pub fn trade_off_svg(
    groups: &[Group],
    extra: &TradeOff,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    path: &Path,
) -> Result<(), Error> {
    let xs = || {
        (groups.iter().flat_map(|g| g.points.iter().map(|p| p.at.0)))
            .chain(extra.top.iter().map(|p| p.at.0))
            .chain(extra.vertical.iter().map(|p| p.at.0))
    };
    let (x_lo, x_hi) = range(xs());
    let (y_lo, y_hi) = range(
        (groups.iter().flat_map(|g| g.points.iter().map(|p| p.at.1)))
            .chain(extra.horizontal.iter().map(|p| p.at.1)),
    );
    let (y_min, y_max) = (y_lo / 2.0, y_hi * 4.0);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1000, 680)).into_drawing_area();
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
                (x_lo / 1.5..x_hi * 2.5)
                    .log_scale()
                    .with_key_points(ticks(x_lo / 1.5, x_hi * 2.5)),
                (y_min..y_max)
                    .log_scale()
                    .with_key_points(ticks(y_min, y_max)),
            )
            .map_err(draw)?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .x_label_formatter(&|x| format!("{x:.0e}"))
            .y_label_formatter(&|y| format!("{y:.0e}"))
            // Log axes over less than a decade crowd the minor lines into grey bands.
            .light_line_style(TRANSPARENT)
            .draw()
            .map_err(draw)?;
        if let Some(v) = &extra.vertical {
            let grey = RGBColor(120, 120, 120);
            chart
                .draw_series(LineSeries::new(
                    [(v.at.0, y_min), (v.at.0, y_max)],
                    grey.stroke_width(1),
                ))
                .map_err(draw)?;
            // Left of the line, so that it stays inside the plot (about 6 px per character).
            let width = 6 * v.label.chars().count() as i32;
            chart
                .draw_series([EmptyElement::at((v.at.0, y_min * 1.3))
                    + Text::new(
                        v.label.clone(),
                        (-width - 6, -12),
                        ("sans-serif", 12).into_font().color(&grey),
                    )])
                .map_err(draw)?;
        }
        if let Some(h) = &extra.horizontal {
            let grey = RGBColor(90, 90, 160);
            let (x0, x1) = (x_lo / 1.5, x_hi * 2.5);
            chart
                .draw_series(DashedLineSeries::new(
                    [(x0, h.at.1), (x1, h.at.1)],
                    2,
                    4,
                    grey.stroke_width(1),
                ))
                .map_err(draw)?;
            // At the left end (cheap and accurate: usually empty); the legend sits upper right.
            chart
                .draw_series([EmptyElement::at((x0, h.at.1))
                    + Text::new(
                        h.label.clone(),
                        (6, 3),
                        ("sans-serif", 11).into_font().color(&grey),
                    )])
                .map_err(draw)?;
        }
        if extra.front.len() > 1 {
            let front = extra.front.clone();
            chart
                .draw_series(DashedLineSeries::new(front, 6, 4, BLACK.stroke_width(1)))
                .map_err(draw)?
                .label(extra.front_name.clone())
                .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLACK));
        }
        for (k, g) in groups.iter().enumerate() {
            let color = Palette99::pick(k).to_rgba();
            chart
                .draw_series(
                    g.points
                        .iter()
                        .map(|p| Circle::new(p.at, 5, color.filled())),
                )
                .map_err(draw)?
                .label(g.name.clone())
                .legend(move |(x, y)| Circle::new((x + 10, y), 5, color.filled()));
        }
        // Labels go where they cover no marker and no other label, tried nearest first.
        let points: Vec<&Labelled> = groups.iter().flat_map(|g| &g.points).collect();
        let mut taken: Vec<[i32; 4]> = points
            .iter()
            .map(|p| {
                let (x, y) = chart.backend_coord(&p.at);
                [x - 6, y - 6, x + 6, y + 6]
            })
            .collect();
        for p in points {
            let (x, y) = chart.backend_coord(&p.at);
            let (w, h) = (6 * p.label.chars().count() as i32, 12);
            let offsets = [
                (7, -14),
                (7, 2),
                (-w - 7, -14),
                (-w - 7, 2),
                (-w / 2, -22),
                (-w / 2, 8),
                (7, -28),
                (7, 16),
                (-w - 7, -28),
                (-w - 7, 16),
                (-w / 2, -36),
                (-w / 2, 22),
            ];
            let free = |o: &(i32, i32)| {
                let b = [x + o.0, y + o.1, x + o.0 + w, y + o.1 + h];
                !taken
                    .iter()
                    .any(|t| b[0] < t[2] && t[0] < b[2] && b[1] < t[3] && t[1] < b[3])
            };
            let o = offsets.iter().copied().find(free).unwrap_or(offsets[0]);
            taken.push([x + o.0, y + o.1, x + o.0 + w, y + o.1 + h]);
            chart
                .draw_series([EmptyElement::at(p.at)
                    + Text::new(p.label.clone(), o, ("sans-serif", 11).into_font())])
                .map_err(draw)?;
        }
        let red = RGBColor(200, 30, 30);
        chart
            .draw_series(extra.top.iter().map(|p| {
                EmptyElement::at((p.at.0, y_max / 1.4))
                    + Cross::new((0, 0), 5, red.stroke_width(2))
                    + Text::new(
                        p.label.clone(),
                        (7, 2),
                        ("sans-serif", 11).into_font().color(&red),
                    )
            }))
            .map_err(draw)?;
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(draw)?;
        root.present().map_err(draw)?;
    }
    write_atomic(path, svg.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_legend_taller_than_any_free_corner_gets_room_below_the_data() {
        // Twelve series, each round the square of the data's four corners: every corner of the
        // plot holds as many points, and the legend (12 rows, about 45% of the height) fits
        // none.
        let corners = vec![
            (1.0, 1.0),
            (100.0, 1.0),
            (100.0, 100.0),
            (1.0, 100.0),
            (1.0, 1.0),
        ];
        let series: Vec<Series> = (0..12)
            .map(|k| Series {
                name: format!("series {k}"),
                points: corners.clone(),
            })
            .collect();
        let (x, y) = ((1.0 / 1.5, 150.0), (0.5, 200.0));
        let (corner, grown) = legend_place(&series, x, y);
        assert_eq!(
            corner,
            SeriesLabelPosition::LowerRight,
            "a tie goes lower right"
        );
        // The data's lowest point, 1.0, now sits above the legend's height on the grown axis.
        let (_, height) = legend_size(&series);
        let v = (1.0f64 / grown.0).ln() / (grown.1 / grown.0).ln();
        assert!(grown.1 == y.1 && grown.0 < y.0, "{grown:?}");
        assert!(
            (v - height).abs() < 1e-9,
            "the lowest point at {v}, the legend {height}"
        );
    }

    #[test]
    fn a_legend_that_fits_a_free_corner_leaves_the_axes_alone() {
        // One falling line and a one-row legend: some corner is free, and the axes stay.
        let series = vec![Series {
            name: "falling".into(),
            points: vec![(1.0, 100.0), (10.0, 10.0), (100.0, 1.0)],
        }];
        let y = (0.5, 200.0);
        assert_eq!(legend_place(&series, (1.0 / 1.5, 150.0), y).1, y);
    }
}
