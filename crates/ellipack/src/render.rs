//! Pictures of a packing, `packing.svg` and `packing.png`, drawn with plotters.
//!
//! * 2D: the ellipses and the container to scale (equal scales on both axes), the ellipses
//!   filled with a light colour and outlined, the container outlined over them.
//! * 3D: three orthographic projections side by side — onto the x–y plane seen from +z, the
//!   x–z plane seen from −y, the y–z plane seen from +x (a right-handed frame in each). The
//!   projection of the ellipsoid {x : (x − c)ᵀ M⁻¹ (x − c) ≤ 1} onto two coordinate axes is the
//!   ellipse whose matrix is the 2×2 sub-block of M = R diag(l²) Rᵀ on those rows and columns,
//!   so each ellipsoid is drawn as its exact outline. Ellipsoids are painted back to front and
//!   shaded by depth (nearer is lighter), so the front layer reads as in a photograph.
//!
//! Every picture has a title line (count, container, density) and a scale bar. Ellipses are
//! polygons of 12 to 48 vertices depending on their size on screen, which keeps 10 000 items
//! fast. An empty packing draws its container alone.

use crate::Error;
use crate::packing::{Container, Items, Packing};
use implicit_packing::ContainerShape;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::{Path, PathBuf};

pub use crate::folder::{PNG_FILE, SVG_FILE};

/// The font of every label (DejaVu Sans, embedded: plotters has no system font loader in this
/// build, and text without a registered font panics).
const FONT_BYTES: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");
pub(crate) const FONT: &str = "sans-serif";

/// What to draw besides the packing.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Width in pixels (the height follows from the container's shape).
    pub width: u32,
    /// Put before the title line, e.g. the scene's or instance's name. The title itself, "N
    /// ellipses in a circle (radius r) — density d", is always drawn.
    pub label: Option<String>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            width: 1200,
            label: None,
        }
    }
}

/// The size in pixels of the pictures of `packing`: `options.width` wide (at least 200), as
/// tall as the container's shape needs at equal scales (at most 1.5 × the width).
pub fn picture_size(packing: &Packing, options: &RenderOptions) -> (u32, u32) {
    Layout::new(packing, options).size
}

/// The SVG picture as text.
///
/// # Errors
/// [`Error::Draw`] or [`Error::Font`].
pub fn svg_string(packing: &Packing, options: &RenderOptions) -> Result<String, Error> {
    svg_until(packing, options, &|| false)
}

/// [`svg_string`], given up with [`Error::Stopped`] as soon as `stop` says so.
fn svg_until(
    packing: &Packing,
    options: &RenderOptions,
    stop: &dyn Fn() -> bool,
) -> Result<String, Error> {
    register_font()?;
    let layout = Layout::new(packing, options);
    let mut text = String::new();
    {
        let backend = SVGBackend::with_string(&mut text, layout.size);
        draw(backend.into_drawing_area(), packing, &layout, stop)
            .map_err(|e| e.into_error(SVG_FILE))?;
    }
    Ok(text)
}

/// The PNG picture as bytes.
///
/// # Errors
/// [`Error::Draw`], [`Error::Font`], or [`Error::Io`] for the encoder's
/// temporary file.
pub fn png_bytes(packing: &Packing, options: &RenderOptions) -> Result<Vec<u8>, Error> {
    png_until(packing, options, &|| false)
}

/// [`png_bytes`], given up with [`Error::Stopped`] as soon as `stop` says so.
fn png_until(
    packing: &Packing,
    options: &RenderOptions,
    stop: &dyn Fn() -> bool,
) -> Result<Vec<u8>, Error> {
    register_font()?;
    let layout = Layout::new(packing, options);
    // plotters encodes PNG only into a file; a private temporary file keeps the real target
    // for write_atomically.
    static COUNTER: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let tmp = std::env::temp_dir().join(format!("ellipack-render-{}-{n}.png", std::process::id()));
    let result = (|| {
        {
            let backend = BitMapBackend::new(&tmp, layout.size);
            let area = backend.into_drawing_area();
            draw(area.clone(), packing, &layout, stop).map_err(|e| e.into_error(PNG_FILE))?;
            area.present()
                .map_err(|e| draw_error(PNG_FILE, e.to_string()))?;
        }
        std::fs::read(&tmp).map_err(|source| Error::Io {
            path: tmp.clone(),
            source,
        })
    })();
    // Best effort: the temporary file is of no use once read (or once drawing failed).
    let _ = std::fs::remove_file(&tmp);
    result
}

/// Writes [`svg_string`] to `path` atomically.
///
/// # Errors
/// As [`svg_string`], or [`Error::Write`].
pub fn write_svg(path: &Path, packing: &Packing, options: &RenderOptions) -> Result<(), Error> {
    write_picture(path, svg_string(packing, options).map(String::into_bytes))
}

/// Writes [`png_bytes`] to `path` atomically.
///
/// # Errors
/// As [`png_bytes`], or [`Error::Write`].
pub fn write_png(path: &Path, packing: &Packing, options: &RenderOptions) -> Result<(), Error> {
    write_picture(path, png_bytes(packing, options))
}

/// Writes a drawn picture to `path` atomically; a drawing error is told against `path`.
fn write_picture(path: &Path, drawn: Result<Vec<u8>, Error>) -> Result<(), Error> {
    let bytes = drawn.map_err(|e| rename(e, path))?;
    crate::output::write_atomically(path, &bytes)
}

/// Writes [`SVG_FILE`] and [`PNG_FILE`] into `dir` (which must exist).
///
/// # Errors
/// The first error of [`write_svg`] and [`write_png`].
pub fn write_pictures(dir: &Path, packing: &Packing, options: &RenderOptions) -> Result<(), Error> {
    write_pictures_until(dir, packing, options, &|| false)
}

/// [`write_pictures`], given up as soon as `stop` says so (a run's time limit or a signal):
/// [`Error::Stopped`], and no picture is written then.
///
/// # Errors
/// As [`write_pictures`], or [`Error::Stopped`].
pub fn write_pictures_until(
    dir: &Path,
    packing: &Packing,
    options: &RenderOptions,
    stop: &dyn Fn() -> bool,
) -> Result<(), Error> {
    // Both drawn before either is written: a stop leaves neither.
    let svg = svg_until(packing, options, stop)?;
    let png = png_until(packing, options, stop)?;
    write_picture(&dir.join(SVG_FILE), Ok(svg.into_bytes()))?;
    write_picture(&dir.join(PNG_FILE), Ok(png))
}

/// Why [`draw`] ended early.
enum Drawing {
    /// plotters failed.
    Failed(String),
    /// The caller asked to stop.
    Stopped,
}

impl Drawing {
    fn into_error(self, file: &str) -> Error {
        match self {
            Drawing::Failed(message) => draw_error(file, message),
            Drawing::Stopped => Error::Stopped,
        }
    }
}

fn draw_error(file: &str, message: String) -> Error {
    Error::Draw {
        path: PathBuf::from(file),
        message,
    }
}

fn rename(e: Error, path: &Path) -> Error {
    match e {
        Error::Draw { message, .. } => Error::Draw {
            path: path.to_path_buf(),
            message,
        },
        other => other,
    }
}

pub(crate) fn register_font() -> Result<(), Error> {
    static REGISTERED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(FONT, FontStyle::Normal, FONT_BYTES).is_ok()
    });
    if ok { Ok(()) } else { Err(Error::Font) }
}

/// One projection: which world axes go right (`u`) and up (`v`), which axis points at the
/// viewer (`depth`, with its sign), where it sits on the canvas.
#[derive(Clone, Debug)]
struct Panel {
    u: usize,
    v: usize,
    depth: Option<(usize, f64)>,
    label: &'static str,
    /// World bounds [umin, umax, vmin, vmax].
    bounds: [f64; 4],
    /// Pixel position of the panel's top-left corner.
    origin: (i32, i32),
}

impl Panel {
    fn to_pixel(&self, scale: f64, u: f64, v: f64) -> (i32, i32) {
        let x = f64::from(self.origin.0) + (u - self.bounds[0]) * scale;
        let y = f64::from(self.origin.1) + (self.bounds[3] - v) * scale;
        // Far-off points (an item flung out of the container) are clamped so that i32
        // arithmetic in the backends cannot overflow.
        (
            x.clamp(-1e6, 1e6).round() as i32,
            y.clamp(-1e6, 1e6).round() as i32,
        )
    }

    fn width(&self) -> f64 {
        self.bounds[1] - self.bounds[0]
    }

    fn height(&self) -> f64 {
        self.bounds[3] - self.bounds[2]
    }
}

struct Layout {
    size: (u32, u32),
    margin: i32,
    font_px: f64,
    title: String,
    scale: f64,
    panels: Vec<Panel>,
    /// Top of the drawing band (panels are centred vertically in it).
    top: i32,
    /// Top of the scale bar band.
    footer_y: i32,
}

impl Layout {
    fn new(packing: &Packing, options: &RenderOptions) -> Self {
        let width = options.width.max(200);
        let w = f64::from(width);
        let margin = (w / 60.0).max(10.0);
        let font_px = (w / 55.0).clamp(12.0, 36.0);
        let title_band = 2.0 * font_px;
        let (lo, hi) = world_box(packing);
        let dimension = packing.container().dimension();
        let mut panels: Vec<Panel> = if dimension == 2 {
            vec![Panel {
                u: 0,
                v: 1,
                depth: None,
                label: "",
                bounds: [0.0; 4],
                origin: (0, 0),
            }]
        } else {
            vec![
                panel_3d(0, 1, (2, 1.0), "x →, y ↑ (seen from +z)"),
                panel_3d(0, 2, (1, -1.0), "x →, z ↑ (seen from −y)"),
                panel_3d(1, 2, (0, 1.0), "y →, z ↑ (seen from +x)"),
            ]
        };
        for p in &mut panels {
            p.bounds = [lo[p.u], hi[p.u], lo[p.v], hi[p.v]];
        }
        let label_band = if dimension == 2 { 0.0 } else { 1.6 * font_px };
        let gaps = margin * (panels.len() as f64 - 1.0);
        let total_width: f64 = panels.iter().map(Panel::width).sum();
        let max_height = panels.iter().map(Panel::height).fold(0.0, f64::max);
        let footer_band = 2.0 * font_px;
        let mut scale = (w - 2.0 * margin - gaps) / total_width;
        // A very tall container would make a very tall picture: cap its height.
        let max_drawing_height = 1.5 * w - title_band - label_band - footer_band - 2.0 * margin;
        if max_height * scale > max_drawing_height {
            scale = max_drawing_height / max_height;
        }
        if !(scale.is_finite() && scale > 0.0) {
            scale = 1.0;
        }
        let drawing_height = max_height * scale;
        let top = margin + title_band + label_band;
        let mut x = margin + (w - 2.0 * margin - gaps - total_width * scale) / 2.0;
        for p in &mut panels {
            // Centre each panel vertically in the drawing band.
            let y = top + (drawing_height - p.height() * scale) / 2.0;
            p.origin = (x.round() as i32, y.round() as i32);
            x += p.width() * scale + margin;
        }
        let footer_y = (top + drawing_height + 0.5 * margin) as i32;
        let height = (top + drawing_height + 0.5 * margin + footer_band).ceil() as u32;
        let title = match &options.label {
            Some(label) if !label.is_empty() => format!("{label}: {}", default_title(packing)),
            _ => default_title(packing),
        };
        Layout {
            size: (width, height),
            margin: margin as i32,
            font_px,
            title,
            scale,
            panels,
            top: top.round() as i32,
            footer_y,
        }
    }
}

fn panel_3d(u: usize, v: usize, depth: (usize, f64), label: &'static str) -> Panel {
    Panel {
        u,
        v,
        depth: Some(depth),
        label,
        bounds: [0.0; 4],
        origin: (0, 0),
    }
}

/// "30 ellipses in an ellipse (semi-axes 9.12, 7.54), density 0.87152".
fn default_title(packing: &Packing) -> String {
    let kind = packing.container().kind();
    let article = if kind.name().starts_with('e') {
        "an"
    } else {
        "a"
    };
    let size: Vec<String> = packing
        .container()
        .size()
        .iter()
        .map(|s| format!("{}", Sig(*s)))
        .collect();
    let size_name = packing.container().size_name().replace('_', "-");
    format!(
        "{} {} in {article} {kind} ({size_name} {}) — density {:.5}",
        packing.items().len(),
        packing.items().noun(),
        size.join(", "),
        packing.density()
    )
}

/// Six significant digits without trailing zeros.
struct Sig(f64);

impl std::fmt::Display for Sig {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let x = self.0;
        if x == 0.0 || !x.is_finite() {
            return write!(f, "{x}");
        }
        let digits = (5 - x.abs().log10().floor() as i32).clamp(0, 12) as usize;
        let s = format!("{x:.digits$}");
        let s = if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        };
        f.write_str(&s)
    }
}

/// The world box holding the container and every item (items may stick out of an
/// uncertified packing), padded by 2 %; never empty.
fn world_box(packing: &Packing) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let mut include = |c: &[f64], half: &[f64]| {
        for k in 0..c.len() {
            let (a, b) = (c[k] - half[k], c[k] + half[k]);
            if a.is_finite() && b.is_finite() {
                lo[k] = lo[k].min(a);
                hi[k] = hi[k].max(b);
            }
        }
    };
    if let Some(corners) = cell_corners(packing.container()) {
        // A periodic cell: the picture is the cell, its items cut by it.
        for c in &corners {
            include(c, &[0.0; 3]);
        }
    } else if packing.container().defect().is_none() {
        include(
            packing.container().center(),
            &packing.container().half_extents(),
        );
    }
    for (center, m) in quadratic_forms(packing.items()) {
        if packing.container().kind().is_periodic() {
            break;
        }
        let half: Vec<f64> = (0..center.len()).map(|k| m[k][k].sqrt()).collect();
        include(&center, &half);
    }
    let n = packing.container().dimension();
    let mut span = (0..n)
        .map(|k| hi[k] - lo[k])
        .filter(|s| s.is_finite())
        .fold(0.0, f64::max);
    if span <= 0.0 {
        span = 1.0;
    }
    for k in 0..3 {
        if !(lo[k].is_finite() && hi[k].is_finite()) || k >= n {
            lo[k] = -0.5 * span;
            hi[k] = 0.5 * span;
        }
        if hi[k] - lo[k] < 1e-3 * span {
            let mid = 0.5 * (lo[k] + hi[k]);
            lo[k] = mid - 0.5e-3 * span;
            hi[k] = mid + 0.5e-3 * span;
        }
        let pad = 0.02 * span;
        lo[k] -= pad;
        hi[k] += pad;
        // Coordinates so large that the padding vanishes in rounding (1e300 ± 1): give up on
        // this axis and show a unit box, rather than divide by a zero extent.
        if !(hi[k] - lo[k] > 0.0 && (hi[k] - lo[k]).is_finite()) {
            lo[k] = -0.5;
            hi[k] = 0.5;
        }
    }
    (lo, hi)
}

/// Centre and full matrix M = R diag(l²) Rᵀ of every drawable item (items whose shape is
/// invalid are skipped: a picture should still show the rest).
fn quadratic_forms(items: &Items) -> Vec<(Vec<f64>, [[f64; 3]; 3])> {
    match items {
        Items::Ellipses(v) => v
            .iter()
            .filter_map(|e| {
                let q = pw85::shape::from_axes_angle_2d(&e.semi_axes, e.theta()).ok()?;
                let m = [[q[0], q[1], 0.0], [q[1], q[2], 0.0], [0.0, 0.0, 0.0]];
                e.centre
                    .iter()
                    .all(|c| c.is_finite())
                    .then(|| (e.centre.to_vec(), m))
            })
            .collect(),
        Items::Ellipsoids(v) => v
            .iter()
            .filter_map(|e| {
                let q = pw85::shape::from_axes_quaternion(&e.semi_axes, &e.quaternion()).ok()?;
                let m = [[q[0], q[1], q[2]], [q[1], q[3], q[4]], [q[2], q[4], q[5]]];
                e.centre
                    .iter()
                    .all(|c| c.is_finite())
                    .then(|| (e.centre.to_vec(), m))
            })
            .collect(),
    }
}

/// The outline of the ellipse {c + L (cos t, sin t)} with L Lᵀ = [[m11, m12], [m12, m22]]
/// (a Cholesky factor: no eigen-decomposition needed), as pixels.
fn ellipse_polygon(
    panel: &Panel,
    scale: f64,
    c: (f64, f64),
    m11: f64,
    m12: f64,
    m22: f64,
) -> Option<Vec<(i32, i32)>> {
    if !(m11 > 0.0 && m11.is_finite() && m22.is_finite() && m12.is_finite()) {
        return None;
    }
    let l11 = m11.sqrt();
    let l21 = m12 / l11;
    // Rounding can leave a tiny negative Schur complement for a needle seen end-on.
    let l22 = (m22 - l21 * l21).max(0.0).sqrt();
    let radius_px = (m11 + m22).sqrt() * scale;
    let n = (radius_px.ceil() as usize).clamp(12, 48);
    let points = (0..n)
        .map(|i| {
            let t = std::f64::consts::TAU * i as f64 / n as f64;
            let (s, co) = t.sin_cos();
            panel.to_pixel(scale, c.0 + l11 * co, c.1 + l21 * co + l22 * s)
        })
        .collect();
    Some(points)
}

const LABEL: RGBColor = RGBColor(60, 60, 60);
const BACKGROUND: RGBColor = RGBColor(255, 255, 255);
const CONTAINER_FILL: RGBColor = RGBColor(244, 244, 246);
const CONTAINER_LINE: RGBColor = RGBColor(20, 20, 20);
const LIGHT: (f64, f64, f64) = (186.0, 214.0, 240.0);
const LIGHT_WARM: (f64, f64, f64) = (247.0, 205.0, 160.0);
const DEEP: (f64, f64, f64) = (60.0, 92.0, 140.0);

fn mix(a: (f64, f64, f64), b: (f64, f64, f64), t: f64) -> RGBColor {
    let t = t.clamp(0.0, 1.0);
    let f = |x: f64, y: f64| (x + (y - x) * t).round().clamp(0.0, 255.0) as u8;
    RGBColor(f(a.0, b.0), f(a.1, b.1), f(a.2, b.2))
}

fn darker(c: RGBColor, factor: f64) -> RGBColor {
    let f = |x: u8| (f64::from(x) * factor).round() as u8;
    RGBColor(f(c.0), f(c.1), f(c.2))
}

fn draw<DB: DrawingBackend>(
    area: DrawingArea<DB, Shift>,
    packing: &Packing,
    layout: &Layout,
    stop: &dyn Fn() -> bool,
) -> Result<(), Drawing> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| Drawing::Failed(e.to_string());
    area.fill(&BACKGROUND).map_err(err)?;
    let small = (FONT, 0.85 * layout.font_px).into_font().color(&LABEL);
    let room = f64::from(layout.size.0) - 2.0 * f64::from(layout.margin);
    let title_font = fitted(&area, &layout.title, layout.font_px, room);
    area.draw(&Text::new(
        layout.title.clone(),
        (layout.margin, layout.margin),
        (FONT, title_font).into_font().color(&BLACK),
    ))
    .map_err(err)?;
    let forms = with_images(packing.container(), quadratic_forms(packing.items()));
    // Colour by size when the items differ (mixed shapes), else one colour.
    let measures: Vec<f64> = forms
        .iter()
        .map(|(_, m)| {
            if packing.container().dimension() == 2 {
                (m[0][0] * m[1][1] - m[0][1] * m[0][1]).max(0.0).sqrt()
            } else {
                determinant(m).max(0.0).sqrt()
            }
        })
        .collect();
    let (mmin, mmax) = measures
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(*x), b.max(*x))
        });
    let varied = mmax > mmin * (1.0 + 1e-9);
    let periodic = packing.container().kind().is_periodic();
    for panel in &layout.panels {
        let scale = layout.scale;
        if !panel.label.is_empty() {
            // Labels in one row above the drawing band, each no wider than its panel.
            let room = panel.width() * scale + 0.8 * f64::from(layout.margin);
            let size = fitted(&area, panel.label, 0.85 * layout.font_px, room);
            let label_y = layout.top - (1.4 * layout.font_px) as i32;
            let style = (FONT, size).into_font().color(&LABEL);
            area.draw(&Text::new(panel.label, (panel.origin.0, label_y), style))
                .map_err(err)?;
        }
        let outline = container_outline(packing.container(), panel, scale);
        if let Some(points) = &outline {
            area.draw(&Polygon::new(points.clone(), CONTAINER_FILL.filled()))
                .map_err(err)?;
        }
        // Painter's order: farthest first.
        let mut order: Vec<(usize, f64)> = forms
            .iter()
            .enumerate()
            .map(|(i, (c, _))| {
                let d = panel.depth.map_or(0.0, |(axis, sign)| sign * c[axis]);
                (i, d)
            })
            .collect();
        order.sort_by(|a, b| a.1.total_cmp(&b.1));
        let (dmin, dmax) = match (order.first(), order.last()) {
            (Some(a), Some(b)) => (a.1, b.1),
            _ => (0.0, 0.0),
        };
        for (k, (i, d)) in order.into_iter().enumerate() {
            // Often enough to stop within milliseconds, seldom enough to cost nothing.
            if k % 256 == 0 && stop() {
                return Err(Drawing::Stopped);
            }
            let (c, m) = &forms[i];
            let fill = if panel.depth.is_some() {
                let t = if dmax > dmin {
                    (d - dmin) / (dmax - dmin)
                } else {
                    1.0
                };
                mix(DEEP, LIGHT, 0.25 + 0.75 * t)
            } else if varied {
                let t = (measures[i] / mmin).ln() / (mmax / mmin).ln();
                mix(LIGHT, LIGHT_WARM, t)
            } else {
                mix(LIGHT, LIGHT, 0.0)
            };
            let (u, v) = (panel.u, panel.v);
            let Some(mut points) =
                ellipse_polygon(panel, scale, (c[u], c[v]), m[u][u], m[u][v], m[v][v])
            else {
                continue;
            };
            if let (true, Some(cell)) = (periodic, &outline) {
                points = clipped(&points, cell);
                if points.len() < 3 {
                    continue;
                }
            }
            area.draw(&Polygon::new(points.clone(), fill.filled()))
                .map_err(err)?;
            let mut closed = points;
            closed.push(closed[0]);
            area.draw(&PathElement::new(
                closed,
                darker(fill, 0.55).stroke_width(1),
            ))
            .map_err(err)?;
        }
        if let Some(mut points) = outline {
            points.push(points[0]);
            let width = (layout.font_px / 8.0).round().max(2.0) as u32;
            area.draw(&PathElement::new(
                points,
                CONTAINER_LINE.stroke_width(width),
            ))
            .map_err(err)?;
        }
    }
    draw_scale_bar(&area, layout, &small).map_err(err)?;
    Ok(())
}

/// The font size (at most `size`) at which `text` is at most `room` pixels wide.
fn fitted<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    text: &str,
    size: f64,
    room: f64,
) -> f64 {
    let width = area
        .estimate_text_size(text, &(FONT, size).into_font().color(&LABEL))
        .map_or(0.0, |(w, _)| f64::from(w));
    if width > room && room > 0.0 {
        (size * room / width).max(6.0)
    } else {
        size
    }
}

fn determinant(m: &[[f64; 3]; 3]) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// The corners of a periodic cell (origin plus every sum of its edge vectors; z = 0 in 2D),
/// `None` for other containers.
fn cell_corners(container: &Container) -> Option<Vec<[f64; 3]>> {
    if container.defect().is_some() {
        return None;
    }
    let h = container.cell_matrix()?;
    let n = h.len();
    let o = container.center();
    Some(
        (0..1usize << n)
            .map(|bits| {
                std::array::from_fn(|r| {
                    if r >= n {
                        return 0.0;
                    }
                    o[r] + (0..n)
                        .filter(|&c| bits & (1 << c) != 0)
                        .map(|c| h[r][c])
                        .sum::<f64>()
                })
            })
            .collect(),
    )
}

/// The items of a periodic cell with their images in the neighbouring cells (translations by
/// −1, 0 or 1 edge vector along each axis), which the picture cuts by the cell; the forms
/// unchanged for other containers.
fn with_images(
    container: &Container,
    forms: Vec<(Vec<f64>, [[f64; 3]; 3])>,
) -> Vec<(Vec<f64>, [[f64; 3]; 3])> {
    let (Some(h), None) = (container.cell_matrix(), container.defect()) else {
        return forms;
    };
    let n = h.len();
    let mut out = Vec::with_capacity(forms.len() * 3usize.pow(n as u32));
    for (c, m) in &forms {
        for code in 0..3usize.pow(n as u32) {
            let shift: Vec<f64> = (0..n)
                .map(|k| (code / 3usize.pow(k as u32) % 3) as f64 - 1.0)
                .collect();
            let moved: Vec<f64> = (0..c.len())
                .map(|r| c[r] + (0..n).map(|k| h[r][k] * shift[k]).sum::<f64>())
                .collect();
            out.push((moved, *m));
        }
    }
    out
}

/// `polygon` cut by the convex polygon `window` (Sutherland–Hodgman; either orientation).
fn clipped(polygon: &[(i32, i32)], window: &[(i32, i32)]) -> Vec<(i32, i32)> {
    let area2: i64 = (0..window.len())
        .map(|i| {
            let (a, b) = (window[i], window[(i + 1) % window.len()]);
            i64::from(a.0) * i64::from(b.1) - i64::from(b.0) * i64::from(a.1)
        })
        .sum();
    let orientation = if area2 < 0 { -1.0 } else { 1.0 };
    let mut out: Vec<(f64, f64)> = polygon
        .iter()
        .map(|&(x, y)| (f64::from(x), f64::from(y)))
        .collect();
    for i in 0..window.len() {
        let (a, b) = (window[i], window[(i + 1) % window.len()]);
        let (ax, ay, bx, by) = (
            f64::from(a.0),
            f64::from(a.1),
            f64::from(b.0),
            f64::from(b.1),
        );
        let side = |p: (f64, f64)| orientation * ((bx - ax) * (p.1 - ay) - (by - ay) * (p.0 - ax));
        let input = std::mem::take(&mut out);
        for k in 0..input.len() {
            let (p, q) = (input[k], input[(k + 1) % input.len()]);
            let (sp, sq) = (side(p), side(q));
            if sp >= 0.0 {
                out.push(p);
            }
            if (sp >= 0.0) != (sq >= 0.0) {
                let t = sp / (sp - sq);
                out.push((p.0 + t * (q.0 - p.0), p.1 + t * (q.1 - p.1)));
            }
        }
        if out.is_empty() {
            break;
        }
    }
    out.iter()
        .map(|&(x, y)| (x.round() as i32, y.round() as i32))
        .collect()
}

/// The convex hull of points (monotone chain), counter-clockwise in pixel coordinates.
fn convex_hull(mut points: Vec<(i32, i32)>) -> Vec<(i32, i32)> {
    points.sort_unstable();
    points.dedup();
    if points.len() < 3 {
        return points;
    }
    let cross = |o: (i32, i32), a: (i32, i32), b: (i32, i32)| {
        i64::from(a.0 - o.0) * i64::from(b.1 - o.1) - i64::from(a.1 - o.1) * i64::from(b.0 - o.0)
    };
    let mut hull: Vec<(i32, i32)> = Vec::with_capacity(2 * points.len());
    for pass in [points.clone(), points.iter().rev().copied().collect()] {
        let start = hull.len();
        for p in pass {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

/// The container's outline in a panel: a circle or axis-aligned ellipse (192 vertices: it is
/// the largest thing on the page), a rectangle, or the projection of a periodic cell.
fn container_outline(container: &Container, panel: &Panel, scale: f64) -> Option<Vec<(i32, i32)>> {
    if container.defect().is_some() {
        return None;
    }
    if let Some(corners) = cell_corners(container) {
        return Some(convex_hull(
            corners
                .iter()
                .map(|c| panel.to_pixel(scale, c[panel.u], c[panel.v]))
                .collect(),
        ));
    }
    let c = container.center();
    let half = container.half_extents();
    let (cu, cv, hu, hv) = (c[panel.u], c[panel.v], half[panel.u], half[panel.v]);
    match container.kind().shape() {
        ContainerShape::Box => Some(vec![
            panel.to_pixel(scale, cu - hu, cv - hv),
            panel.to_pixel(scale, cu + hu, cv - hv),
            panel.to_pixel(scale, cu + hu, cv + hv),
            panel.to_pixel(scale, cu - hu, cv + hv),
        ]),
        _ => Some(
            (0..192)
                .map(|i| {
                    let (s, co) = (std::f64::consts::TAU * f64::from(i) / 192.0).sin_cos();
                    panel.to_pixel(scale, cu + hu * co, cv + hv * s)
                })
                .collect(),
        ),
    }
}

/// A bar of a round length (1, 2 or 5 × 10ᵏ) about a fifth of the first panel's width, with
/// its length written beside it.
fn draw_scale_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    layout: &Layout,
    style: &TextStyle<'_>,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let Some(panel) = layout.panels.first() else {
        return Ok(());
    };
    let target = 0.2 * panel.width();
    if !(target.is_finite() && target > 0.0) {
        return Ok(());
    }
    let power = 10f64.powf(target.log10().floor());
    let length = [5.0, 2.0, 1.0]
        .into_iter()
        .map(|k| k * power)
        .find(|l| *l <= target)
        .unwrap_or(power);
    let x0 = panel.origin.0;
    let x1 = x0 + (length * layout.scale).round() as i32;
    let y = layout.footer_y + (0.6 * layout.font_px) as i32;
    let tick = (0.3 * layout.font_px) as i32;
    let line = BLACK.stroke_width(2);
    area.draw(&PathElement::new(vec![(x0, y), (x1, y)], line))?;
    area.draw(&PathElement::new(
        vec![(x0, y - tick), (x0, y + tick)],
        line,
    ))?;
    area.draw(&PathElement::new(
        vec![(x1, y - tick), (x1, y + tick)],
        line,
    ))?;
    let label = style.pos(Pos::new(HPos::Left, VPos::Center));
    area.draw(&Text::new(
        format!("{}", Sig(length)),
        (x1 + tick * 2, y),
        label,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::packing::Centred;

    #[test]
    fn broken_data_draws_what_it_can_without_panicking() {
        use crate::packing::{Container, Item, Items, Packing};
        // Built by hand, bypassing Packing::new's checks.
        let packing = Packing {
            container: Container::plane([0.0, 0.0], Centred::Ball { radius: -1.0 }),
            items: Items::Ellipses(vec![
                Item::ellipse([f64::NAN, 0.0], [1.0, 1.0], 0.0),
                Item::ellipse([0.0, 0.0], [0.0, 1.0], 0.0),
                Item::ellipse([1e300, -1e300], [1.0, 1e-300], 1e300),
            ]),
        };
        png_bytes(&packing, &RenderOptions::default()).unwrap();
        svg_string(&packing, &RenderOptions::default()).unwrap();
        let packing = Packing {
            container: Container::space(
                [0.0; 3],
                Centred::Ball {
                    radius: f64::INFINITY,
                },
            ),
            items: Items::Ellipsoids(vec![Item::ellipsoid([0.0; 3], [1e6, 1e-6, 1.0], [0.0; 4])]),
        };
        png_bytes(
            &packing,
            &RenderOptions {
                width: 1,
                label: Some(String::new()),
            },
        )
        .unwrap();
    }

    /// The outline drawn for an ellipsoid is its exact shadow: every surface point projects
    /// inside the ellipse of the 2×2 sub-block of M, and some reach its boundary.
    #[test]
    fn projections_use_the_sub_block_of_m() {
        let item = crate::packing::Item::ellipsoid(
            [0.3, -1.0, 2.0],
            [2.0, 0.7, 0.3],
            [0.8, 0.3, -0.5, 0.2],
        );
        let r = pw85::shape::rotation_from_quaternion(&item.quaternion()).unwrap();
        let q = pw85::shape::from_axes_quaternion(&item.semi_axes, &item.quaternion()).unwrap();
        let m = [[q[0], q[1], q[2]], [q[1], q[3], q[4]], [q[2], q[4], q[5]]];
        for (u, v) in [(0, 1), (0, 2), (1, 2)] {
            let (a, b, c) = (m[u][u], m[u][v], m[v][v]);
            let det = a * c - b * b;
            let mut largest: f64 = 0.0;
            for i in 0..200 {
                for j in 0..100 {
                    let (st, ct) = (std::f64::consts::PI * f64::from(j) / 99.0).sin_cos();
                    let (sp, cp) = (std::f64::consts::TAU * f64::from(i) / 200.0).sin_cos();
                    let s = [st * cp, st * sp, ct];
                    let local: Vec<f64> = (0..3).map(|k| item.semi_axes[k] * s[k]).collect();
                    let x: Vec<f64> = (0..3)
                        .map(|row| (0..3).map(|k| r[row][k] * local[k]).sum())
                        .collect();
                    // (p)ᵀ [[a, b], [b, c]]⁻¹ p for the projected offset p.
                    let (pu, pv) = (x[u], x[v]);
                    let value = (c * pu * pu - 2.0 * b * pu * pv + a * pv * pv) / det;
                    assert!(value <= 1.0 + 1e-12, "{value}");
                    largest = largest.max(value);
                }
            }
            assert!(largest > 0.999, "plane {u}{v}: {largest}");
        }
    }

    #[test]
    fn scale_labels_have_six_significant_digits() {
        assert_eq!(Sig(18.710_000_1).to_string(), "18.71");
        assert_eq!(Sig(49.398_601).to_string(), "49.3986");
        assert_eq!(Sig(5.0).to_string(), "5");
        assert_eq!(Sig(0.002).to_string(), "0.002");
        assert_eq!(Sig(123_456_789.0).to_string(), "123456789");
    }
}
