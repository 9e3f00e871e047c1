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

fn range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = vals
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(1e-12 * (1.0 + hi.abs()));
    (lo - pad, hi + pad)
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
            .caption(title, ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
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
            .caption(format!("{title}  [{lo:.4} … {hi:.4}]"), ("sans-serif", 16))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
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
            .caption(title, ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(-0.5..n - 0.5, lo..hi)
            .map_err(err)?;
        let cats = categories.to_vec();
        chart
            .configure_mesh()
            .y_desc(y_label)
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
            .caption(title, ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
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
}
