//! SVG plots with `plotters` (chosen over hand-written SVG for axes, ticks
//! and legends done right). Every function returns the SVG document as a
//! string so the report can both save and inline it.

use anyhow::{Result, anyhow};
use plotters::prelude::*;

/// One curve: a name for the legend, x values, y values.
pub struct Series<'a> {
    /// Legend entry.
    pub name: String,
    /// Abscissae.
    pub x: &'a [f64],
    /// Ordinates.
    pub y: &'a [f64],
}

const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(127, 127, 127),
];

/// The axis range of `vals` (non-finite values ignored): the data's span
/// with a 5 % margin on either side, so a change of 97.9 → 98.2 fills the
/// axis instead of hiding in a range drawn from zero. A constant series
/// gets a margin of 1 ‰ of its magnitude (at least 10⁻¹²); no data gives
/// `0 … 1`.
pub fn axis_range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = vals
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = if hi > lo {
        (hi - lo) * 0.05
    } else {
        (1e-3 * hi.abs()).max(1e-12)
    };
    (lo - pad, hi + pad)
}

fn range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    axis_range(vals)
}

/// Decimals that tell apart ticks about `span / 8` apart on an axis of
/// width `span` (0 for steps of 1 and more, at most 6).
pub fn tick_decimals(span: f64) -> usize {
    let step = span.abs() / 8.0;
    if !step.is_finite() || step <= 0.0 || step >= 1.0 {
        return 0;
    }
    ((-step.log10()).ceil() as usize).min(6)
}

/// A tick label of `v` on an axis spanning `(lo, hi)`: the decimals the
/// span needs ([`tick_decimals`]), scientific notation for magnitudes of
/// 10⁵ and more or below 10⁻³ (zero excepted), and never `-0`: a value
/// that rounds to zero is written without a sign.
pub fn tick(v: f64, (lo, hi): (f64, f64)) -> String {
    let big = lo.abs().max(hi.abs());
    let s = if big >= 1e5 || (big > 0.0 && big < 1e-3) {
        format!("{v:.2e}")
    } else {
        let d = tick_decimals(hi - lo);
        format!("{v:.d$}")
    };
    // `-0.00` (a small negative value rounded away) reads as zero.
    match s.strip_prefix('-') {
        Some(rest) if s.parse::<f64>() == Ok(0.0) => rest.to_string(),
        _ => s,
    }
}

/// A plot or page title without Markdown markup: backticks and the
/// asterisks of emphasis are dropped, so `` `val.csv` joint 1 `` reads
/// "val.csv joint 1" in an SVG caption or an HTML `<title>`. Every plot
/// title goes through it.
pub fn plain_title(t: &str) -> String {
    t.chars().filter(|c| !matches!(c, '`' | '*')).collect()
}

fn err<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow!("plotting failed: {e}")
}

/// A line chart of several series sharing axes. Long series are thinned
/// to at most `max_points` points per series to keep SVGs small.
pub fn lines(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    max_points: usize,
) -> Result<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 360)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let xr = range(series.iter().flat_map(|s| s.x.iter().copied()));
        let yr = range(series.iter().flat_map(|s| s.y.iter().copied()));
        let mut chart = ChartBuilder::on(&root)
            .caption(plain_title(title), ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
            .x_label_formatter(&|v| tick(*v, xr))
            .y_label_formatter(&|v| tick(*v, yr))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(err)?;
        for (i, s) in series.iter().enumerate() {
            let color = PALETTE[i % PALETTE.len()];
            let n = s.x.len().min(s.y.len());
            let step = n.div_ceil(max_points.max(2)).max(1);
            let pts = (0..n)
                .step_by(step)
                .map(|k| (s.x[k], s.y[k]))
                .filter(|p| p.0.is_finite() && p.1.is_finite());
            chart
                .draw_series(LineSeries::new(pts, color.stroke_width(1)))
                .map_err(err)?
                .label(s.name.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
                });
        }
        if series.len() > 1 {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK.mix(0.3))
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(err)?;
        }
        root.present().map_err(err)?;
    }
    Ok(svg)
}

/// A heat map of `values[i][j]` at (`xs[i]`, `ys[j]`) with a colour bar legend
/// given as text in the caption (min and max).
pub fn heatmap(
    title: &str,
    x_label: &str,
    y_label: &str,
    xs: &[f64],
    ys: &[f64],
    values: &[Vec<f64>],
) -> Result<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (700, 480)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let (lo, hi) = range(values.iter().flatten().copied());
        let dx = if xs.len() > 1 {
            (xs[1] - xs[0]).abs()
        } else {
            1.0
        };
        let dy = if ys.len() > 1 {
            (ys[1] - ys[0]).abs()
        } else {
            1.0
        };
        let xr = range(xs.iter().copied());
        let yr = range(ys.iter().copied());
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!(
                    "{}  [{} … {}]",
                    plain_title(title),
                    tick(lo, (lo, hi)),
                    tick(hi, (lo, hi))
                ),
                ("sans-serif", 16),
            )
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
            .x_label_formatter(&|v| tick(*v, xr))
            .y_label_formatter(&|v| tick(*v, yr))
            .disable_mesh()
            .draw()
            .map_err(err)?;
        let cells = xs
            .iter()
            .enumerate()
            .flat_map(|(i, &x)| ys.iter().enumerate().map(move |(j, &y)| (i, j, x, y)));
        chart
            .draw_series(cells.filter_map(|(i, j, x, y)| {
                let v = *values.get(i)?.get(j)?;
                let t = if hi > lo {
                    ((v - lo) / (hi - lo)).clamp(0.0, 1.0)
                } else {
                    0.5
                };
                let c = ViridisRGB::get_color(t);
                Some(Rectangle::new(
                    [(x - dx / 2.0, y - dy / 2.0), (x + dx / 2.0, y + dy / 2.0)],
                    c.filled(),
                ))
            }))
            .map_err(err)?;
        root.present().map_err(err)?;
    }
    Ok(svg)
}

/// Grouped bars: one group per category, one bar per series (e.g. fitness
/// per joint after each diagnosis step).
pub fn bars(
    title: &str,
    y_label: &str,
    categories: &[String],
    series: &[(String, Vec<f64>)],
) -> Result<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (800, 360)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let (lo, hi) = range(series.iter().flat_map(|s| s.1.iter().copied()).chain([0.0]));
        let n = categories.len().max(1) as f64;
        let mut chart = ChartBuilder::on(&root)
            .caption(plain_title(title), ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(-0.5..n - 0.5, lo..hi)
            .map_err(err)?;
        let cats = categories.to_vec();
        chart
            .configure_mesh()
            .y_desc(y_label)
            .y_label_formatter(&|v| tick(*v, (lo, hi)))
            .x_labels(categories.len().max(1))
            .x_label_formatter(&move |v| {
                let i = v.round();
                if (v - i).abs() < 1e-6 && i >= 0.0 {
                    cats.get(i as usize).cloned().unwrap_or_default()
                } else {
                    String::new()
                }
            })
            .draw()
            .map_err(err)?;
        let m = series.len().max(1) as f64;
        let w = 0.8 / m;
        for (k, (name, vals)) in series.iter().enumerate() {
            let color = PALETTE[k % PALETTE.len()];
            chart
                .draw_series(vals.iter().enumerate().map(|(i, &v)| {
                    let x0 = i as f64 - 0.4 + k as f64 * w;
                    Rectangle::new([(x0, 0.0f64.max(lo)), (x0 + w * 0.9, v)], color.filled())
                }))
                .map_err(err)?
                .label(name.clone())
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 5), (x + 12, y + 5)], color.filled())
                });
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.3))
            .position(SeriesLabelPosition::LowerRight)
            .draw()
            .map_err(err)?;
        root.present().map_err(err)?;
    }
    Ok(svg)
}

/// Points (e.g. measurements) under lines (e.g. model curves) on shared axes.
/// Point sets are thinned to at most `max_points` points each (evenly over
/// the samples) to keep SVGs small; lines are drawn in full order.
pub fn scatter(
    title: &str,
    x_label: &str,
    y_label: &str,
    points: &[Series],
    curves: &[Series],
    max_points: usize,
) -> Result<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 420)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let all = || points.iter().chain(curves);
        let xr = range(all().flat_map(|s| s.x.iter().copied()));
        let yr = range(all().flat_map(|s| s.y.iter().copied()));
        let mut chart = ChartBuilder::on(&root)
            .caption(plain_title(title), ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
            .x_label_formatter(&|v| tick(*v, xr))
            .y_label_formatter(&|v| tick(*v, yr))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(err)?;
        let greys = [RGBColor(150, 150, 150), RGBColor(120, 170, 210)];
        for (i, s) in points.iter().enumerate() {
            let color = greys[i % greys.len()];
            let n = s.x.len().min(s.y.len());
            let step = n.div_ceil(max_points.max(2)).max(1);
            let pts: Vec<(f64, f64)> = (0..n)
                .step_by(step)
                .map(|k| (s.x[k], s.y[k]))
                .filter(|p| p.0.is_finite() && p.1.is_finite())
                .collect();
            chart
                .draw_series(pts.into_iter().map(|p| Circle::new(p, 1, color.filled())))
                .map_err(err)?
                .label(s.name.clone())
                .legend(move |(x, y)| Circle::new((x + 9, y), 3, color.filled()));
        }
        for (i, s) in curves.iter().enumerate() {
            let color = PALETTE[i % PALETTE.len()];
            let n = s.x.len().min(s.y.len());
            let pts = (0..n)
                .map(|k| (s.x[k], s.y[k]))
                .filter(|p| p.0.is_finite() && p.1.is_finite());
            chart
                .draw_series(LineSeries::new(pts, color.stroke_width(2)))
                .map_err(err)?
                .label(s.name.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.3))
            .position(SeriesLabelPosition::UpperLeft)
            .draw()
            .map_err(err)?;
        root.present().map_err(err)?;
    }
    Ok(svg)
}

/// One panel of [`steps`]: a quantity after each step (e.g. one validation
/// set's fitness of one joint), with the best value it can reach if known.
pub struct StepPanel {
    /// Panel title.
    pub title: String,
    /// Value after each step, one per step name.
    pub values: Vec<f64>,
    /// The noise ceiling, drawn as a dashed line when known.
    pub ceiling: Option<f64>,
}

/// The y range of a [`StepPanel`]: its values and ceiling
/// ([`axis_range`]), zoomed to the data rather than drawn from zero.
pub fn step_range(p: &StepPanel) -> (f64, f64) {
    axis_range(p.values.iter().copied().chain(p.ceiling))
}

/// A quantity per step as points, one panel per quantity (small multiples,
/// each with its own zoomed y axis so a change of a few tenths shows):
/// one marker per step at integer x labelled with the step's name, the
/// ceiling as a dashed line.
pub fn steps(
    title: &str,
    y_label: &str,
    step_names: &[String],
    panels: &[StepPanel],
) -> Result<String> {
    let mut svg = String::new();
    {
        let rows = panels.len().max(1);
        let height = 40 + 230 * rows as u32;
        let root = SVGBackend::with_string(&mut svg, (900, height)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let body = root
            .titled(&plain_title(title), ("sans-serif", 18))
            .map_err(err)?;
        let n = step_names.len().max(1) as f64;
        for (area, p) in body.split_evenly((rows, 1)).iter().zip(panels) {
            let yr = step_range(p);
            let mut chart = ChartBuilder::on(area)
                .caption(plain_title(&p.title), ("sans-serif", 14))
                .margin(8)
                .x_label_area_size(30)
                .y_label_area_size(70)
                .build_cartesian_2d(-0.5..n - 0.5, yr.0..yr.1)
                .map_err(err)?;
            let names = step_names.to_vec();
            chart
                .configure_mesh()
                .y_desc(y_label)
                .x_labels(step_names.len().max(1))
                .x_label_formatter(&move |v| {
                    let i = v.round();
                    if (v - i).abs() < 1e-6 && i >= 0.0 {
                        names.get(i as usize).cloned().unwrap_or_default()
                    } else {
                        String::new()
                    }
                })
                .y_label_formatter(&|v| tick(*v, yr))
                .light_line_style(RGBColor(235, 235, 235))
                .draw()
                .map_err(err)?;
            if let Some(c) = p.ceiling.filter(|c| c.is_finite()) {
                let dashes = (0..(4.0 * n) as usize).map(|k| {
                    let x0 = -0.5 + k as f64 * 0.25;
                    PathElement::new(vec![(x0, c), (x0 + 0.15, c)], PALETTE[1].stroke_width(2))
                });
                chart.draw_series(dashes).map_err(err)?;
            }
            let pts: Vec<(f64, f64)> = p
                .values
                .iter()
                .enumerate()
                .filter(|(_, v)| v.is_finite())
                .map(|(i, &v)| (i as f64, v))
                .collect();
            chart
                .draw_series(LineSeries::new(
                    pts.clone(),
                    RGBColor(200, 200, 200).stroke_width(1),
                ))
                .map_err(err)?;
            chart
                .draw_series(
                    pts.into_iter()
                        .map(|p| Circle::new(p, 5, PALETTE[0].filled())),
                )
                .map_err(err)?;
        }
        root.present().map_err(err)?;
    }
    Ok(svg)
}

/// A cloud of points with its binned means (± spread) over it, e.g. the
/// residual of a bounded sample of rows against velocity.
pub struct Binned {
    /// Legend entry.
    pub name: String,
    /// The points `(x, y)` (already bounded in number).
    pub points: Vec<(f64, f64)>,
    /// Bins `(centre, mean, spread)`, the spread drawn as `mean ± spread`.
    pub bins: Vec<(f64, f64, f64)>,
}

/// Mean and standard deviation of `y` in `n` bins of equal count over `x`
/// (`aras_ident::stats::equal_count_bins`) as `(centre, mean, std)`, the
/// centre the mean `x` of the bin; bins of fewer than 3 points are left
/// out.
pub fn binned_means(points: &[(f64, f64)], n: usize) -> Vec<(f64, f64, f64)> {
    let (x, y): (Vec<f64>, Vec<f64>) = points.iter().copied().unzip();
    aras_ident::stats::equal_count_bins(&x, &y, n)
        .into_iter()
        .filter(|b| b.count >= 3)
        .map(|b| (b.x_mean, b.mean, b.std_dev))
        .collect()
}

/// Points (light) under their binned means (dark, joined, with ± spread
/// bars), one colour per group, on shared axes zoomed to the means and
/// spreads (points beyond are clipped) so the systematic part shows
/// above the noise.
pub fn scatter_binned(
    title: &str,
    x_label: &str,
    y_label: &str,
    groups: &[Binned],
) -> Result<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 420)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let xr = range(groups.iter().flat_map(|g| g.points.iter().map(|p| p.0)));
        // The y axis shows the means with their spread (and the points
        // when there are no bins): a few outliers do not flatten it.
        let with_bins = groups.iter().any(|g| !g.bins.is_empty());
        let yr = if with_bins {
            range(groups.iter().flat_map(|g| {
                g.bins
                    .iter()
                    .flat_map(|b| [b.1 - 1.5 * b.2, b.1 + 1.5 * b.2])
            }))
        } else {
            range(groups.iter().flat_map(|g| g.points.iter().map(|p| p.1)))
        };
        let mut chart = ChartBuilder::on(&root)
            .caption(plain_title(title), ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
            .x_label_formatter(&|v| tick(*v, xr))
            .y_label_formatter(&|v| tick(*v, yr))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(err)?;
        let inside = |p: &(f64, f64)| p.1 >= yr.0 && p.1 <= yr.1;
        for (i, g) in groups.iter().enumerate() {
            let color = PALETTE[i % PALETTE.len()];
            chart
                .draw_series(
                    g.points
                        .iter()
                        .filter(|p| p.0.is_finite() && inside(p))
                        .map(|&p| Circle::new(p, 1, color.mix(0.25).filled())),
                )
                .map_err(err)?;
        }
        for (i, g) in groups.iter().enumerate() {
            let color = PALETTE[i % PALETTE.len()];
            chart
                .draw_series(g.bins.iter().map(|&(x, m, s)| {
                    PathElement::new(vec![(x, m - s), (x, m + s)], color.stroke_width(1))
                }))
                .map_err(err)?;
            chart
                .draw_series(LineSeries::new(
                    g.bins.iter().map(|&(x, m, _)| (x, m)),
                    color.stroke_width(2),
                ))
                .map_err(err)?
                .label(g.name.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.3))
            .position(SeriesLabelPosition::UpperLeft)
            .draw()
            .map_err(err)?;
        root.present().map_err(err)?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plots_render_svg() {
        let x: Vec<f64> = (0..100).map(|i| i as f64 * 0.1).collect();
        let y: Vec<f64> = x.iter().map(|v| v.sin()).collect();
        let s = lines(
            "t",
            "x",
            "y",
            &[Series {
                name: "sin".into(),
                x: &x,
                y: &y,
            }],
            50,
        )
        .unwrap();
        assert!(s.contains("<svg") && s.contains("</svg>"));
        let h = heatmap(
            "h",
            "x",
            "y",
            &[0.0, 1.0],
            &[0.0, 1.0],
            &[vec![1.0, 2.0], vec![3.0, 4.0]],
        )
        .unwrap();
        assert!(h.contains("<rect"));
        let b = bars(
            "b",
            "%",
            &["j1".into(), "j2".into()],
            &[("s0".into(), vec![80.0, 90.0])],
        )
        .unwrap();
        assert!(b.contains("<rect"));
    }

    #[test]
    fn ticks_never_show_minus_zero_and_fit_the_range() {
        assert_eq!(tick(-0.0, (-1.0, 1.0)), "0.0");
        assert_eq!(tick(-0.004, (-1.0, 1.0)), "0.0");
        assert_eq!(tick(-1e-17, (-2.0, 100.0)), "0");
        assert_eq!(tick(-0.5, (-1.0, 1.0)), "-0.5");
        // 97.9 → 98.2: ticks ≈ 0.04 apart need two decimals.
        assert_eq!(tick(98.0, (97.88, 98.22)), "98.00");
        assert_eq!(tick(97.95, (97.88, 98.22)), "97.95");
        assert_eq!(tick(50.0, (0.0, 100.0)), "50");
        assert_eq!(tick(2.5e-4, (0.0, 5e-4)), "2.50e-4");
        assert_eq!(tick(-1e-9, (-5e-4, 5e-4)), "-1.00e-9");
        assert_eq!(tick(-0.0, (-5e-4, 5e-4)), "0.00e0");
        assert_eq!(tick_decimals(0.34), 2);
        assert_eq!(tick_decimals(8.0), 0);
        assert_eq!(tick_decimals(0.0), 0);
    }

    #[test]
    fn titles_lose_markdown_markup() {
        assert_eq!(
            plain_title("`val.csv` joint 1: **residual** *vs* velocity"),
            "val.csv joint 1: residual vs velocity"
        );
        let s = lines("`a.csv` **b**", "x", "y", &[], 10).unwrap();
        assert!(s.contains("a.csv b"), "{s}");
        assert!(!s.contains('`') && !s.contains("**"));
    }

    #[test]
    fn axis_range_is_the_data_with_a_margin() {
        let (lo, hi) = axis_range([97.9, 98.2, 98.05].into_iter());
        assert!(
            (lo - 97.885).abs() < 1e-9 && (hi - 98.215).abs() < 1e-9,
            "{lo} {hi}"
        );
        let (lo, hi) = axis_range([5.0, 5.0].into_iter());
        assert!(lo < 5.0 && hi > 5.0 && hi - lo < 0.011, "{lo} {hi}");
        assert_eq!(axis_range([f64::NAN].into_iter()), (0.0, 1.0));
    }

    /// The contents of the SVG's text elements.
    fn texts(svg: &str) -> Vec<String> {
        svg.split("</text>")
            .filter_map(|t| Some(t.rsplit('>').next()?.trim().to_string()))
            .collect()
    }

    /// The numbers among the SVG's text elements (the tick labels).
    fn numbers(svg: &str) -> Vec<f64> {
        texts(svg).iter().filter_map(|t| t.parse().ok()).collect()
    }

    #[test]
    fn step_plot_has_one_marker_per_step_and_a_tight_axis() {
        let names: Vec<String> = ["start", "+offset", "+viscous"].map(String::from).into();
        let panels = [StepPanel {
            title: "`val.csv` τ1".into(),
            values: vec![97.9, 98.1, 98.2],
            ceiling: None,
        }];
        let svg = steps("Fitness per step", "%", &names, &panels).unwrap();
        assert_eq!(svg.matches("<circle").count(), 3, "one marker per step");
        for n in &names {
            assert!(texts(&svg).contains(n), "step name {n} as x label");
        }
        let (lo, hi) = step_range(&panels[0]);
        assert!(
            lo > 97.8 && hi < 98.3 && lo < 97.9 && hi > 98.2,
            "{lo} … {hi}"
        );
        let ticks = numbers(&svg);
        assert!(ticks.len() >= 3, "{ticks:?}");
        assert!(ticks.iter().all(|t| (lo..=hi).contains(t)), "{ticks:?}");
        assert!(!svg.contains('`'));
        // A known ceiling widens the axis to include it and is drawn.
        let with = StepPanel {
            ceiling: Some(99.0),
            ..StepPanel {
                title: "t".into(),
                values: vec![97.9, 98.2],
                ceiling: None,
            }
        };
        let (_, hi) = step_range(&with);
        assert!(hi > 99.0 && hi < 99.1);
        let svg = steps("f", "%", &names[..2], &[with]).unwrap();
        assert_eq!(svg.matches("<circle").count(), 2);
        assert!(svg.matches("<polyline").count() > 3, "dashed ceiling drawn");
    }

    #[test]
    fn binned_means_over_a_cloud() {
        let pts: Vec<(f64, f64)> = (0..300)
            .map(|i| {
                let x = i as f64 / 100.0;
                (x, 2.0 * x + if i % 2 == 0 { 0.1 } else { -0.1 })
            })
            .collect();
        let b = binned_means(&pts, 3);
        assert_eq!(b.len(), 3);
        for (c, m, s) in &b {
            assert!((m - 2.0 * c).abs() < 1e-9, "{c} {m}");
            assert!(*s > 0.1 && *s < 0.6, "{s}");
        }
        let svg = scatter_binned(
            "r",
            "v",
            "r",
            &[Binned {
                name: "after".into(),
                points: pts,
                bins: b,
            }],
        )
        .unwrap();
        assert!(svg.matches("<circle").count() > 250);
    }
}
