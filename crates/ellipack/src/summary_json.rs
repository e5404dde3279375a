//! `summary.json`: the container, the density and what the run found ([`Summary`]), or as much
//! of it as `ellipack verify` needs of a hand-made packing ([`StatedSummary`]).

use crate::Error;
use crate::items_csv::write_text;
use crate::packing::{CertificateCounts, Container, Summary};
use serde::Deserialize;
use std::path::Path;

/// The file name of the summary.
pub const SUMMARY_FILE: &str = "summary.json";

/// The text of [`SUMMARY_FILE`] (pretty-printed JSON).
///
/// # Errors
/// [`Error::NonFinite`] when a number is NaN or infinite (JSON would store `null`, which
/// the reader could not read back).
pub fn summary_json(summary: &Summary) -> Result<String, Error> {
    let mut fields: Vec<(&'static str, f64)> = vec![
        ("density", summary.density),
        ("objective", summary.objective),
        ("wall_seconds", summary.wall_seconds),
    ];
    if let Some(m) = summary.certificate.min_mu2 {
        fields.push(("certificate.min_mu2", m));
    }
    if let Some(r) = summary.repair {
        fields.push(("repair.dilation", r.dilation));
        fields.push(("repair.density_before", r.density_before));
    }
    fields.extend(
        summary
            .container
            .center()
            .iter()
            .map(|c| ("container.center", *c)),
    );
    let size_name = match summary.container.size_name() {
        "radius" => "container.radius",
        "semi_axes" => "container.semi_axes",
        _ => "container.half_sides",
    };
    fields.extend(summary.container.size().into_iter().map(|s| (size_name, s)));
    if let Some((field, value)) = fields.into_iter().find(|(_, v)| !v.is_finite()) {
        return Err(Error::NonFinite { field, value });
    }
    // Serialising plain structs of numbers and strings into a String cannot fail.
    let mut text = serde_json::to_string_pretty(summary).unwrap_or_default();
    text.push('\n');
    Ok(text)
}

/// Writes [`summary_json`] to `path` atomically.
///
/// # Errors
/// [`Error::NonFinite`] or [`Error::Write`].
pub fn write_summary(path: &Path, summary: &Summary) -> Result<(), Error> {
    write_text(path, &summary_json(summary)?)
}

/// Reads [`SUMMARY_FILE`] text.
///
/// # Errors
/// [`Error::Malformed`] (line, column) for invalid JSON, a missing key or a value of the
/// wrong type; [`Error::Inconsistent`] for a container size that is not positive.
pub fn read_summary(text: &str, source_name: &str) -> Result<Summary, Error> {
    summary_of(text, source_name, |s: &Summary| &s.container)
}

/// A summary of type `T` parsed from JSON `text`, with its container (`container_of`) checked.
fn summary_of<T: serde::de::DeserializeOwned>(
    text: &str,
    source_name: &str,
    container_of: impl Fn(&T) -> &Container,
) -> Result<T, Error> {
    let summary: T = serde_json::from_str(text).map_err(|e| Error::Malformed {
        source_name: source_name.to_string(),
        line: e.line() as u64,
        message: format!("column {}: {e}", e.column()),
    })?;
    if let Some((field, message)) = container_of(&summary).defect() {
        return Err(Error::Inconsistent {
            source_name: source_name.to_string(),
            message: format!("container.{field}: {message}"),
        });
    }
    Ok(summary)
}

/// What `ellipack verify` needs of a summary: the container, and when present the item count
/// and the certificate a run stated. A hand-made packing's summary can be as short as
/// `{"container": {"kind": "ball", "radius": 5}}`; other keys are ignored.
#[derive(Clone, Debug, PartialEq, Deserialize)]
pub struct StatedSummary {
    /// The container.
    pub container: Container,
    /// The number of items, when stated.
    #[serde(default)]
    pub items: Option<usize>,
    /// The certificate a run stated, when present.
    #[serde(default)]
    pub certificate: Option<CertificateCounts>,
}

/// Reads a [`StatedSummary`] from summary text.
///
/// # Errors
/// As [`read_summary`].
pub fn read_stated_summary(text: &str, source_name: &str) -> Result<StatedSummary, Error> {
    summary_of(text, source_name, |s: &StatedSummary| &s.container)
}
