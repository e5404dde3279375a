//! Pictures of a packing's structure: `rdf.svg`, g(r) of the centres, and `orientations.svg`,
//! the distribution of the first body axis — in 3D of |cos| of its angle to the director (flat
//! for isotropic axes), in 2D of its angle θ ∈ [0°, 180°) (flat for isotropic axes).

use crate::Error;
use crate::folder::{ORIENTATIONS_PICTURE, RDF_PICTURE};
use crate::packing::{Items, Packing};
use crate::render::{FONT, register_font};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use std::path::Path;
use structure::Structure;

/// Bins of the orientation histogram.
const ORIENTATION_BINS: usize = 36;

/// Writes [`RDF_PICTURE`] and [`ORIENTATIONS_PICTURE`] into `dir`, each atomically.
///
/// # Errors
/// [`Error`] naming the picture that could not be drawn or written.
pub fn write_structure_pictures(dir: &Path, packing: &Packing, s: &Structure) -> Result<(), Error> {
    register_font()?;
    let rdf = rdf_svg(s).map_err(|message| draw_error(RDF_PICTURE, message))?;
    crate::output::write_atomically(&dir.join(RDF_PICTURE), rdf.as_bytes())?;
    let orientations = orientations_svg(packing, s)
        .map_err(|message| draw_error(ORIENTATIONS_PICTURE, message))?;
    crate::output::write_atomically(&dir.join(ORIENTATIONS_PICTURE), orientations.as_bytes())?;
    Ok(())
}

fn draw_error(file: &str, message: String) -> Error {
    Error::Draw {
        path: file.into(),
        message,
    }
}

/// g(r) against r over the mean equivalent diameter.
fn rdf_svg(s: &Structure) -> Result<String, String> {
    let d = s.mean_equivalent_diameter;
    let points: Vec<(f64, f64)> = s
        .rdf
        .r
        .iter()
        .zip(&s.rdf.g)
        .map(|(r, g)| (r / d, *g))
        .collect();
    let x_max = points.last().map_or(1.0, |p| p.0) * 1.02;
    let y_max = points.iter().map(|p| p.1).fold(1.0_f64, f64::max) * 1.1;
    let caption = format!("g(r) of {} centres, density {:.4}", s.items, s.density);
    let axes = ("r / mean equivalent diameter", "g(r)");
    chart_svg(&caption, axes, (x_max, y_max), |chart| {
        chart
            .draw_series(LineSeries::new(points, BLUE.stroke_width(2)))
            .map(|_| ())
    })
}

/// The chart both pictures share: a caption, the axes `[0, x_max] × [0, y_max]` with their
/// labels, what `draw` puts on them, and the line y = 1 (an ideal gas's g, an isotropic
/// histogram).
fn chart_svg<D>(
    caption: &str,
    (x_desc, y_desc): (&str, &str),
    (x_max, y_max): (f64, f64),
    draw: D,
) -> Result<String, String>
where
    D: FnOnce(
        &mut ChartContext<'_, SVGBackend<'_>, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    ) -> Result<(), DrawingAreaErrorKind<std::io::Error>>,
{
    let mut text = String::new();
    {
        let area = SVGBackend::with_string(&mut text, (800, 500)).into_drawing_area();
        area.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut chart = ChartBuilder::on(&area)
            .caption(caption, (FONT, 20))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d(0.0..x_max, 0.0..y_max)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .label_style((FONT, 14))
            .draw()
            .map_err(|e| e.to_string())?;
        draw(&mut chart).map_err(|e| e.to_string())?;
        chart
            .draw_series(LineSeries::new([(0.0, 1.0), (x_max, 1.0)], BLACK.mix(0.4)))
            .map_err(|e| e.to_string())?;
        area.present().map_err(|e| e.to_string())?;
    }
    Ok(text)
}

/// The histogram of the first body axis (see the module documentation), as a fraction of the
/// items per bin over the fraction an isotropic packing has (1: isotropic).
fn orientations_svg(packing: &Packing, s: &Structure) -> Result<String, String> {
    let director = s.nematic.first().map_or([1.0, 0.0, 0.0], |n| n.director);
    let (values, range, label): (Vec<f64>, f64, &str) = match packing.items() {
        Items::Ellipses(items) => (
            items
                .iter()
                .map(|e| e.theta().rem_euclid(std::f64::consts::PI).to_degrees())
                .collect(),
            180.0,
            "angle of the first axis (degrees)",
        ),
        Items::Ellipsoids(items) => (
            items
                .iter()
                .map(|e| {
                    let [w, x, y, z] = e.quaternion();
                    // The first column of the rotation of (w, x, y, z).
                    let u = [
                        1.0 - 2.0 * (y * y + z * z),
                        2.0 * (x * y + w * z),
                        2.0 * (x * z - w * y),
                    ];
                    let norm = u
                        .iter()
                        .map(|v| v * v)
                        .sum::<f64>()
                        .sqrt()
                        .max(f64::MIN_POSITIVE);
                    (u.iter().zip(&director).map(|(a, b)| a * b).sum::<f64>() / norm)
                        .abs()
                        .min(1.0)
                })
                .collect(),
            1.0,
            "|cos| of the first axis to the director",
        ),
    };
    let mut counts = vec![0usize; ORIENTATION_BINS];
    for v in &values {
        let k = ((v / range) * ORIENTATION_BINS as f64) as usize;
        counts[k.min(ORIENTATION_BINS - 1)] += 1;
    }
    let n = values.len().max(1) as f64;
    let density: Vec<f64> = counts
        .iter()
        .map(|&c| c as f64 / n * ORIENTATION_BINS as f64)
        .collect();
    let y_max = density.iter().copied().fold(2.0_f64, f64::max) * 1.1;
    let width = range / ORIENTATION_BINS as f64;
    let order = s.nematic.first().map_or(0.0, |n| n.order);
    let caption = format!(
        "orientations of {} items, nematic order S = {order:.3}",
        s.items
    );
    chart_svg(
        &caption,
        (label, "items per bin / isotropic"),
        (range, y_max),
        |chart| {
            chart
                .draw_series(density.iter().enumerate().map(|(k, &h)| {
                    let x = k as f64 * width;
                    Rectangle::new([(x, 0.0), (x + width, h)], BLUE.mix(0.5).filled())
                }))
                .map(|_| ())
        },
    )
}
