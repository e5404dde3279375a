//! The structure of a packing ([`structure`]: density, nematic order, bond order, contacts,
//! g(r)) as the files hold it: `structure.json` and `rdf.csv`, written beside every packing
//! and by `ellipack analyse` for any packing folder.

use crate::error::Error;
use crate::pack::bodies_of;
use crate::packing::{Items, Packing};
use serde_json::json;
use std::path::Path;
use structure::{Settings, Structure};

pub use crate::folder::{RDF_FILE, STRUCTURE_FILE};

/// The contact gap of a packing that its run dilated by `repair` ≥ 1 to certify it (the
/// summary's `repair.dilation`): `(1 + gap)·repair − 1`. Every pair the run left touching then
/// has μ ≈ repair (μ scales with a dilation), which a fixed gap smaller than `repair − 1`
/// would miss; `None` or 1: `gap` itself.
pub fn contact_gap(gap: f64, repair: Option<f64>) -> f64 {
    (1.0 + gap) * repair.unwrap_or(1.0).max(1.0) - 1.0
}

/// The default settings of [`structure::Settings`] with the contact gap of a packing repaired
/// by `repair` ([`contact_gap`]).
pub fn settings(gap: f64, repair: Option<f64>) -> structure::Settings {
    structure::Settings::default().with_contact_gap(contact_gap(gap, repair))
}

/// The repair dilation a summary states (`repair.dilation`), if any.
pub fn stated_repair(summary_text: &str) -> Option<f64> {
    let value: serde_json::Value = serde_json::from_str(summary_text).ok()?;
    value.get("repair")?.get("dilation")?.as_f64()
}

/// The structure of `packing` ([`structure::analyse`] on its items and container).
///
/// # Errors
/// [`Error`] when the items do not form valid bodies, or the settings are refused
/// ([`structure::Error`]).
pub fn analyse(packing: &Packing, settings: &Settings) -> Result<Structure, Error> {
    match packing.items() {
        Items::Ellipses(_) => {
            let (bodies, container) = bodies_of::<2>(packing)?;
            Ok(structure::analyse(&bodies, &container, settings)?)
        }
        Items::Ellipsoids(_) => {
            let (bodies, container) = bodies_of::<3>(packing)?;
            Ok(structure::analyse(&bodies, &container, settings)?)
        }
    }
}

/// The text of [`STRUCTURE_FILE`]: every figure of [`Structure`] but g(r), with the settings
/// that made it.
pub fn structure_json(s: &Structure) -> String {
    let (kind, figures) = s.bond_order.named_figures();
    let mut bond_order = serde_json::Map::new();
    bond_order.insert("kind".to_string(), json!(kind));
    for (name, value) in figures {
        bond_order.insert(name.to_string(), json!(value));
    }
    let nematic: Vec<_> = s
        .nematic
        .iter()
        .map(|n| json!({"axis": n.axis, "order": n.order, "director": n.director}))
        .collect();
    let c = &s.contacts;
    let value = json!({
        "items": s.items,
        "density": s.density,
        "mean_equivalent_diameter": s.mean_equivalent_diameter,
        "nematic": nematic,
        "bond_order": bond_order,
        "contacts": {
            "gap": c.gap,
            "pairs": c.pairs,
            "mean_contacts": c.mean_contacts,
            "distribution": c.distribution,
            "rattlers": c.rattlers,
            "mean_contacts_without_rattlers": c.mean_contacts_without_rattlers,
        },
    });
    let mut text = serde_json::to_string_pretty(&value).unwrap_or_default();
    text.push('\n');
    text
}

/// The text of [`RDF_FILE`].
pub fn rdf_csv(s: &Structure) -> String {
    let mut out = String::from("r,g\n");
    for (r, g) in s.rdf.r.iter().zip(&s.rdf.g) {
        out.push_str(&format!("{r:.9e},{g:.9e}\n"));
    }
    out
}

/// Writes [`STRUCTURE_FILE`] and [`RDF_FILE`] into `dir`, each atomically.
///
/// # Errors
/// [`Error`] naming the file that could not be written.
pub fn write_structure(dir: &Path, s: &Structure) -> Result<(), Error> {
    crate::output::write_atomically(&dir.join(STRUCTURE_FILE), structure_json(s).as_bytes())?;
    crate::output::write_atomically(&dir.join(RDF_FILE), rdf_csv(s).as_bytes())?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_contact_gap_grows_with_the_repair_the_summary_states() {
        assert!((contact_gap(1e-3, None) - 1e-3).abs() < 1e-15);
        assert!((contact_gap(1e-3, Some(1.002)) - 3.002e-3).abs() < 1e-15);
        // A dilation below 1 is no repair.
        assert_eq!(contact_gap(1e-3, Some(0.5)), contact_gap(1e-3, None));
        let summary = r#"{"container": {"kind": "ball", "radius": 5}, "repair": {"dilation": 1.25, "density_before": 0.5}}"#;
        assert_eq!(stated_repair(summary), Some(1.25));
        assert_eq!(stated_repair(r#"{"container": {}}"#), None);
        assert_eq!(stated_repair("not json"), None);
    }
}
