//! Figures: a small description (panels of series) drawn twice, to SVG and to PNG, with the
//! same code. Logarithmic axes are drawn as log10 of the data on a linear axis with labels
//! `1e-15`, …, which keeps one coordinate type for every panel.

use crate::error::Error;
use crate::output::{Outputs, Stability};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// A polyline.
    Line,
    /// Markers only.
    Points,
    /// A polyline with markers.
    LinePoints,
}

/// One named data series.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend text.
    pub name: String,
    /// Data points (for log axes: the values, not their logarithms).
    pub points: Vec<(f64, f64)>,
    /// Drawing style.
    pub kind: Kind,
    /// Index into the palette.
    pub color: usize,
}

/// One chart.
#[derive(Debug, Clone, Default)]
pub struct Panel {
    /// Caption above the chart.
    pub title: String,
    /// x axis label.
    pub x_label: String,
    /// y axis label.
    pub y_label: String,
    /// Logarithmic x axis.
    pub x_log: bool,
    /// Logarithmic y axis.
    pub y_log: bool,
    /// Fixed y range (data units); automatic when `None`.
    pub y_range: Option<(f64, f64)>,
    /// Fixed x range (data units); automatic when `None`.
    pub x_range: Option<(f64, f64)>,
    /// Names of the integer y positions 0, 1, … (a category axis).
    pub y_categories: Vec<String>,
    /// The data.
    pub series: Vec<Series>,
    /// Vertical reference lines (x position, legend text).
    pub vlines: Vec<(f64, String)>,
    /// Horizontal reference lines (y position, legend text).
    pub hlines: Vec<(f64, String)>,
    /// Where the legend goes (a corner the data leave empty).
    pub legend: Corner,
}

/// A corner of a chart.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Corner {
    /// Upper right (the default).
    #[default]
    UpperRight,
    /// Upper left.
    UpperLeft,
    /// Lower right.
    LowerRight,
    /// Lower left.
    LowerLeft,
}

/// A figure: panels stacked in one column.
#[derive(Debug, Clone)]
pub struct Figure {
    /// The panels, top to bottom.
    pub panels: Vec<Panel>,
    /// Height of each panel in pixels (width is 1024).
    pub panel_height: u32,
}

const WIDTH: u32 = 1024;
const FONT_NAME: &str = "sans-serif";
/// Smallest errors are drawn at this floor on log axes (an exact 0 has no logarithm); the
/// figure text says so.
pub const LOG_FLOOR: f64 = 1e-18;

static FONT: OnceLock<bool> = OnceLock::new();

/// Registers the embedded DejaVu Sans once. The bitmap backend has no system font lookup in
/// this build (ab_glyph only): without a registered font every text draw panics, so a failed
/// registration is an error before any drawing starts.
fn register_font(path: &Path) -> Result<(), Error> {
    let ok = *FONT.get_or_init(|| {
        let bytes: &'static [u8] =
            include_bytes!("../../crates/ellipack/assets/fonts/DejaVuSans.ttf");
        plotters::style::register_font(FONT_NAME, FontStyle::Normal, bytes).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(Error::Plot {
            path: path.to_path_buf(),
            message: "the embedded font crates/ellipack/assets/fonts/DejaVuSans.ttf could not be registered".into(),
        })
    }
}

fn palette(k: usize) -> RGBColor {
    const COLORS: [RGBColor; 8] = [
        RGBColor(31, 119, 180),
        RGBColor(214, 39, 40),
        RGBColor(44, 160, 44),
        RGBColor(148, 103, 189),
        RGBColor(255, 127, 14),
        RGBColor(23, 190, 207),
        RGBColor(140, 86, 75),
        RGBColor(0, 0, 0),
    ];
    COLORS[k % COLORS.len()]
}

fn transform(v: f64, log: bool) -> Option<f64> {
    if log {
        if v.is_nan() {
            None
        } else {
            Some(v.max(LOG_FLOOR).log10())
        }
    } else if v.is_finite() {
        Some(v)
    } else {
        None
    }
}

fn range(values: impl Iterator<Item = f64>, pad_log: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if pad_log {
        ((lo - 0.3).floor(), (hi + 0.3).ceil())
    } else {
        let pad = if hi > lo { 0.05 * (hi - lo) } else { 0.5 };
        (lo - pad, hi + pad)
    }
}

/// A tick label: `1e-15` on log axes (integer exponents only), and on linear axes the value
/// with as many decimals as the axis span needs (plotters' tick values carry rounding noise
/// such as 0.30000000000000004 that must not reach the picture).
fn tick(v: f64, log: bool, span: f64) -> String {
    if log {
        if (v - v.round()).abs() < 1e-6 {
            format!("1e{}", v.round() as i64)
        } else {
            String::new()
        }
    } else {
        let decimals = (2.0 - span.log10().floor()).clamp(0.0, 12.0) as usize;
        let v = if v.abs() < 1e-9 * span { 0.0 } else { v };
        let s = format!("{v:.decimals$}");
        let s = if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        };
        if s == "-0" { "0".into() } else { s }
    }
}

type DrawResult<DB> = Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

fn draw_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &Panel) -> DrawResult<DB> {
    let xs = p
        .series
        .iter()
        .flat_map(|s| s.points.iter().filter_map(|q| transform(q.0, p.x_log)))
        .chain(p.vlines.iter().filter_map(|v| transform(v.0, p.x_log)));
    let (x0, x1) = match p.x_range {
        Some((a, b)) => (
            transform(a, p.x_log).unwrap_or(0.0),
            transform(b, p.x_log).unwrap_or(1.0),
        ),
        None => range(xs, p.x_log),
    };
    let (y0, y1) = match p.y_range {
        Some((a, b)) => (
            transform(a, p.y_log).unwrap_or(0.0),
            transform(b, p.y_log).unwrap_or(1.0),
        ),
        None if !p.y_categories.is_empty() => (-0.6, p.y_categories.len() as f64 - 0.4),
        None => {
            let ys = p
                .series
                .iter()
                .flat_map(|s| s.points.iter().filter_map(|q| transform(q.1, p.y_log)))
                .chain(p.hlines.iter().filter_map(|h| transform(h.0, p.y_log)));
            range(ys, p.y_log)
        }
    };
    // Wide enough for the longest tick label (about 10 px per character at 18 px) and the
    // rotated axis description.
    let longest = if p.y_categories.is_empty() {
        [y0, y1, 0.5 * (y0 + y1)]
            .iter()
            .map(|v| tick(*v, p.y_log, y1 - y0).chars().count() + 2)
            .max()
            .unwrap_or(6)
    } else {
        p.y_categories
            .iter()
            .map(|c| c.chars().count())
            .max()
            .unwrap_or(6)
    };
    let y_area = (40 + 10 * longest as u32).max(110);
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, (FONT_NAME, 24))
        .margin(12)
        .margin_right(36)
        .x_label_area_size(60)
        .y_label_area_size(y_area)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    let x_log = p.x_log;
    let y_log = p.y_log;
    let cats = &p.y_categories;
    let y_fmt = |v: &f64| -> String {
        if cats.is_empty() {
            tick(*v, y_log, y1 - y0)
        } else {
            let k = v.round();
            if (v - k).abs() < 1e-6 && k >= 0.0 && (k as usize) < cats.len() {
                cats[k as usize].clone()
            } else {
                String::new()
            }
        }
    };
    let x_fmt = |v: &f64| tick(*v, x_log, x1 - x0);
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(&p.x_label)
        .y_desc(&p.y_label)
        .label_style((FONT_NAME, 18))
        .axis_desc_style((FONT_NAME, 20))
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .light_line_style(RGBColor(235, 235, 235));
    if x_log {
        mesh.x_labels(((x1 - x0) as usize + 1).min(20));
    }
    if y_log {
        mesh.y_labels(((y1 - y0) as usize + 1).min(20));
    }
    if !cats.is_empty() {
        mesh.y_labels(cats.len() * 2 + 1);
    }
    mesh.draw()?;

    for (k, (x, name)) in p.vlines.iter().enumerate() {
        if let Some(x) = transform(*x, x_log) {
            let style = ShapeStyle::from(&palette(7 - k % 2)).stroke_width(1);
            let s = chart.draw_series(LineSeries::new(vec![(x, y0), (x, y1)], style))?;
            if !name.is_empty() {
                s.label(name.clone())
                    .legend(move |(a, b)| PathElement::new(vec![(a, b), (a + 24, b)], style));
            }
        }
    }
    for (y, name) in &p.hlines {
        if let Some(y) = transform(*y, y_log) {
            let style = ShapeStyle::from(&RGBColor(60, 60, 60)).stroke_width(2);
            let s = chart.draw_series(LineSeries::new(vec![(x0, y), (x1, y)], style))?;
            if !name.is_empty() {
                s.label(name.clone())
                    .legend(move |(a, b)| PathElement::new(vec![(a, b), (a + 24, b)], style));
            }
        }
    }
    for s in &p.series {
        let color = palette(s.color);
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .filter_map(|q| Some((transform(q.0, x_log)?, transform(q.1, y_log)?)))
            .collect();
        let line = ShapeStyle::from(&color).stroke_width(2);
        let fill = ShapeStyle::from(&color).filled();
        let name = s.name.clone();
        // A series without a name stays out of the legend (the outlines of a packing).
        let labelled = !name.is_empty();
        match s.kind {
            // Segment by segment: plotters' bitmap polyline joins with widths above 1 can shoot
            // past the last point at sharp turns (plotters issue #549).
            Kind::Line => {
                let a = chart.draw_series(
                    pts.windows(2)
                        .map(|w| PathElement::new(vec![w[0], w[1]], line)),
                )?;
                if labelled {
                    a.label(name)
                        .legend(move |(a, b)| PathElement::new(vec![(a, b), (a + 24, b)], line));
                }
            }
            Kind::Points => {
                let a = chart.draw_series(pts.iter().map(|&q| Circle::new(q, 5, fill)))?;
                if labelled {
                    a.label(name)
                        .legend(move |(a, b)| Circle::new((a + 12, b), 5, fill));
                }
            }
            Kind::LinePoints => {
                chart.draw_series(
                    pts.windows(2)
                        .map(|w| PathElement::new(vec![w[0], w[1]], line)),
                )?;
                let a = chart.draw_series(pts.iter().map(|&q| Circle::new(q, 4, fill)))?;
                if labelled {
                    a.label(name).legend(move |(a, b)| {
                        EmptyElement::at((a, b))
                            + PathElement::new(vec![(0, 0), (24, 0)], line)
                            + Circle::new((12, 0), 4, fill)
                    });
                }
            }
        }
    }
    let any_label = p.series.iter().any(|s| !s.name.is_empty())
        || p.vlines.iter().any(|v| !v.1.is_empty())
        || p.hlines.iter().any(|h| !h.1.is_empty());
    if !any_label {
        return Ok(());
    }
    chart
        .configure_series_labels()
        .position(match p.legend {
            Corner::UpperRight => SeriesLabelPosition::UpperRight,
            Corner::UpperLeft => SeriesLabelPosition::UpperLeft,
            Corner::LowerRight => SeriesLabelPosition::LowerRight,
            Corner::LowerLeft => SeriesLabelPosition::LowerLeft,
        })
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FONT_NAME, 18))
        .draw()?;
    Ok(())
}

fn draw_figure<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, fig: &Figure) -> DrawResult<DB> {
    root.fill(&WHITE)?;
    let areas = root.split_evenly((fig.panels.len().max(1), 1));
    for (area, panel) in areas.iter().zip(&fig.panels) {
        draw_panel(area, panel)?;
    }
    root.present()
}

/// One panel of certified packing fraction against wall time (logarithmic), as the random
/// and peer studies draw their runs.
pub fn density_against_time(title: &str, series: Vec<Series>) -> Figure {
    Figure {
        panels: vec![Panel {
            title: title.into(),
            x_label: "wall time (s), logarithmic".into(),
            x_log: true,
            y_label: "certified packing fraction".into(),
            series,
            legend: Corner::LowerRight,
            ..Panel::default()
        }],
        panel_height: 640,
    }
}

/// Draws `fig` to `dir/base.svg` and `dir/base.png`.
pub fn render(fig: &Figure, dir: &Path, base: &str, outputs: &mut Outputs) -> Result<(), Error> {
    register_font(&dir.join(base))?;
    let height = fig.panel_height * fig.panels.len().max(1) as u32;
    std::fs::create_dir_all(dir).map_err(crate::error::io(dir))?;
    let svg = dir.join(format!("{base}.svg"));
    let png = dir.join(format!("{base}.png"));
    let size = (WIDTH, height);
    let tmp = Outputs::scratch(&svg);
    draw_file(SVGBackend::new(&tmp, size), fig, (&tmp, &svg), outputs)?;
    let tmp = Outputs::scratch(&png);
    draw_file(BitMapBackend::new(&tmp, size), fig, (&tmp, &png), outputs)?;
    Ok(())
}

/// Draws `fig` through `backend`, which writes the scratch file `tmp`, then adopts it as `path`.
fn draw_file<DB: DrawingBackend>(
    backend: DB,
    fig: &Figure,
    (tmp, path): (&Path, &Path),
    outputs: &mut Outputs,
) -> Result<(), Error> {
    // The backend is consumed (and so has flushed `tmp`) before the file is adopted.
    draw_figure(backend.into_drawing_area(), fig).map_err(|e| Error::Plot {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    outputs.adopt(tmp, path, Stability::Volatile)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn render_writes_both_pictures() {
        let dir = std::env::temp_dir().join(format!("xtask-plot-{}", std::process::id()));
        let fig = Figure {
            panels: Vec::new(),
            panel_height: 40,
        };
        let mut outputs = Outputs::new(false);
        render(&fig, &dir, "empty", &mut outputs).unwrap();
        for name in ["empty.svg", "empty.png"] {
            let len = std::fs::metadata(dir.join(name)).map_or(0, |m| m.len());
            assert!(len > 0, "{name} missing or empty");
        }
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().flatten().collect();
        assert_eq!(left.len(), 2, "no scratch file stays: {left:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
