//! # ellipack-structure — what a packing of ellipses or ellipsoids is, measured
//!
//! For any packing (ours, or one read from a file) of bodies of [`implicit_packing`] in a
//! container or a periodic cell:
//!
//! - [`nematic`] — the nematic order parameter S and the director of each body axis (2D: S₂);
//! - [`bond_order`] — Steinhardt's Q₄ and Q₆ (3D, global and mean local) and the hexatic ψ₆
//!   (2D), over the neighbours within a cutoff of the centres;
//! - [`contacts`] — pairs in contact to within a relative gap of the PW85 contact function,
//!   the contact number Z, its distribution and the rattlers;
//! - [`rdf`] — the radial distribution function g(r) of the centres.
//!
//! [`analyse`] computes all of them with one neighbour search ([`neighbours`]: a cell grid over
//! the centres and, in a periodic cell, their images within reach).
//!
//! ```
//! use implicit_packing::{Body, containment::Container};
//! use structure::{Settings, analyse};
//!
//! // A square lattice of unit discs, touching, in a periodic 4 × 4 cell.
//! let bodies: Vec<Body<2>> = (0..4)
//!     .flat_map(|i| (0..4).map(move |j| (i, j)))
//!     .map(|(i, j)| Body::ellipse([2.0 * i as f64, 2.0 * j as f64], [1.0, 1.0], 0.0))
//!     .collect::<Result<_, _>>()?;
//! let cell = Container::Periodic { cell: [[8.0, 0.0], [0.0, 8.0]] };
//! let s = analyse(&bodies, &cell, &Settings::default())?;
//! assert!((s.density - std::f64::consts::PI / 4.0).abs() < 1e-12);
//! assert_eq!(s.contacts.mean_contacts, 4.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![deny(missing_docs)]
// Index loops over m and k read like the sums they compute.
#![allow(clippy::needless_range_loop)]

pub mod bond_order;
pub mod contacts;
mod error;
pub mod neighbours;
pub mod nematic;
pub mod rdf;

pub use bond_order::BondOrder;
pub use contacts::Contacts;
pub use error::Error;
pub use nematic::Nematic;
pub use rdf::Rdf;

use implicit_packing::Body;
use implicit_packing::containment::Container;

/// The relative gap within which two items count as in contact unless the settings say
/// otherwise: μ < 1 + 1e-3, that is, the items would touch if each were scaled about its centre
/// by less than 1.001.
pub const DEFAULT_CONTACT_GAP: f64 = 1e-3;
/// The bond cutoff of the bond-order parameters unless the settings say otherwise, in
/// equivalent diameters: 1.4 d holds the 12 nearest neighbours of a face-centred cubic packing
/// of spheres (at d) and none of the next shell (at √2 d ≈ 1.414 d); the same for the 6 of the
/// hexagonal packing of discs (next shell at √3 d).
pub const DEFAULT_BOND_CUTOFF: f64 = 1.4;
/// The range of g(r) unless the settings say otherwise, in equivalent diameters (at most half
/// the smallest width of a periodic cell).
pub const DEFAULT_RDF_RANGE: f64 = 5.0;
/// Bins of g(r) unless the settings say otherwise.
pub const DEFAULT_RDF_BINS: usize = 200;

/// What to measure, and with which cutoffs.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct Settings {
    /// Relative gap of a contact: μ < 1 + gap (≥ 0).
    pub contact_gap: f64,
    /// Bond cutoff of the bond-order parameters, a distance of centres (`None`:
    /// [`DEFAULT_BOND_CUTOFF`] mean equivalent diameters).
    pub bond_cutoff: Option<f64>,
    /// Largest r of g(r) (`None`: [`DEFAULT_RDF_RANGE`] mean equivalent diameters, at most half
    /// the smallest width of a periodic cell).
    pub rdf_range: Option<f64>,
    /// Bins of g(r) (≥ 1).
    pub rdf_bins: usize,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            contact_gap: DEFAULT_CONTACT_GAP,
            bond_cutoff: None,
            rdf_range: None,
            rdf_bins: DEFAULT_RDF_BINS,
        }
    }
}

impl Settings {
    /// Sets [`Settings::contact_gap`].
    #[must_use]
    pub fn with_contact_gap(mut self, gap: f64) -> Self {
        self.contact_gap = gap;
        self
    }

    /// Sets [`Settings::bond_cutoff`].
    #[must_use]
    pub fn with_bond_cutoff(mut self, cutoff: Option<f64>) -> Self {
        self.bond_cutoff = cutoff;
        self
    }

    /// Sets [`Settings::rdf_range`].
    #[must_use]
    pub fn with_rdf_range(mut self, range: Option<f64>) -> Self {
        self.rdf_range = range;
        self
    }

    /// Sets [`Settings::rdf_bins`].
    #[must_use]
    pub fn with_rdf_bins(mut self, bins: usize) -> Self {
        self.rdf_bins = bins;
        self
    }
}

/// The structure of a packing.
#[derive(Clone, Debug, PartialEq)]
pub struct Structure {
    /// Number of items.
    pub items: usize,
    /// Item area or volume over the container's.
    pub density: f64,
    /// The mean equivalent diameter `2 (∏ l_k)^(1/N)` (the diameter of the disc or sphere of
    /// the same area or volume), the unit of the default cutoffs.
    pub mean_equivalent_diameter: f64,
    /// Nematic order of each body axis that some item defines (axis k: the column k of the
    /// rotation, along semi-axis k; none for round items, a spheroid's distinct axis only).
    pub nematic: Vec<Nematic>,
    /// Steinhardt's Q₄, Q₆ (3D) or the hexatic ψ₆ (2D).
    pub bond_order: BondOrder,
    /// Contacts, contact numbers and rattlers.
    pub contacts: Contacts,
    /// The radial distribution function of the centres.
    pub rdf: Rdf,
}

/// Everything of [`Structure`] for `bodies` in `container`.
///
/// # Errors
/// [`Error::Settings`] for a negative gap, a cutoff or range that is not positive and finite,
/// no bins, or a range beyond half the smallest width of a periodic cell; [`Error::Empty`]
/// without items; errors of the neighbour grid or of PW85 on a pair (with the pair).
pub fn analyse<const N: usize>(
    bodies: &[Body<N>],
    container: &Container<N>,
    settings: &Settings,
) -> Result<Structure, Error> {
    if bodies.is_empty() {
        return Err(Error::Empty);
    }
    if !(settings.contact_gap >= 0.0 && settings.contact_gap.is_finite()) {
        return Err(Error::Settings(format!(
            "the contact gap must be zero or positive and finite, not {}",
            settings.contact_gap
        )));
    }
    let d = mean_equivalent_diameter(bodies);
    let bond = settings.bond_cutoff.unwrap_or(DEFAULT_BOND_CUTOFF * d);
    let half_width = match container {
        Container::Periodic { cell } => {
            0.5 * implicit_packing::periodic::widths(cell)
                .iter()
                .fold(f64::INFINITY, |a, &b| a.min(b))
        }
        _ => f64::INFINITY,
    };
    let range = settings
        .rdf_range
        .unwrap_or((DEFAULT_RDF_RANGE * d).min(half_width));
    for (what, v) in [("bond cutoff", bond), ("range of g(r)", range)] {
        if !(v > 0.0 && v.is_finite()) {
            return Err(Error::Settings(format!(
                "the {what} must be positive and finite, not {v}"
            )));
        }
    }
    if range > half_width * (1.0 + 1e-12) {
        return Err(Error::Settings(format!(
            "the range of g(r), {range}, is beyond half the smallest width of the cell, \
             {half_width}"
        )));
    }
    if settings.rdf_bins == 0 {
        return Err(Error::Settings("g(r) needs at least one bin".into()));
    }
    let reach = 2.0
        * bodies.iter().map(Body::bounding_radius).fold(0.0, f64::max)
        * (1.0 + settings.contact_gap);
    let centres: Vec<[f64; N]> = bodies.iter().map(Body::centre).collect();
    let cell = match container {
        Container::Periodic { cell } => Some(cell),
        _ => None,
    };
    let bonds = neighbours::Bonds::within(&centres, cell, bond.max(reach))?;
    let measure = container.measure().0;
    let item_measure: f64 = bodies.iter().map(body_measure).sum();
    Ok(Structure {
        items: bodies.len(),
        density: item_measure / measure,
        mean_equivalent_diameter: d,
        nematic: nematic::nematic_order(bodies),
        bond_order: bond_order::bond_order(&bonds, bond),
        contacts: contacts::contacts(bodies, &bonds, settings.contact_gap)?,
        rdf: rdf::rdf(&centres, cell, measure, range, settings.rdf_bins)?,
    })
}

/// Area (2D) or volume (3D) of a body: `π ∏ l_k` or `4/3 π ∏ l_k`.
fn body_measure<const N: usize>(body: &Body<N>) -> f64 {
    let unit = if N == 2 {
        std::f64::consts::PI
    } else {
        4.0 / 3.0 * std::f64::consts::PI
    };
    unit * body.semi_axes().iter().product::<f64>()
}

/// The mean over the bodies of `2 (∏ l_k)^(1/N)`.
pub fn mean_equivalent_diameter<const N: usize>(bodies: &[Body<N>]) -> f64 {
    let sum: f64 = bodies
        .iter()
        .map(|b| 2.0 * b.semi_axes().iter().product::<f64>().powf(1.0 / N as f64))
        .sum();
    sum / bodies.len().max(1) as f64
}
