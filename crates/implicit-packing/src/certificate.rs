//! The certificate of a configuration, independent of the model's overlap measure: the PW85
//! contact function μ² of every pair whose enclosing balls meet (one pass of a neighbour grid,
//! [`cell_grid`]), and exact containment. This is the one test that decides whether a packing
//! is written: the packer, `ellipack verify` and the validation studies all call [`certify`].
//!
//! A pair overlaps iff μ² < 1 (PW85 theory, eq. 6); the smallest μ² over the checked pairs
//! says how close the packing is to touching (μ² = 1: tangent). An item is outside iff its
//! containment residual (eq. 36 of the packing paper, via [`crate::containment`]) is positive;
//! by how much is the factor by which the container, scaled about its centre, would have to
//! grow to hold it.
//!
//! # References
//! - J. W. Perram and M. S. Wertheim, J. Comput. Phys. 58 (1985) 409–416 (the contact
//!   function).
//! - E. G. Birgin, R. D. Lobato, J. M. Martínez, *A nonlinear programming model with implicit
//!   variables for packing ellipsoids*, J. Global Optim. (2017), Section 5.2 (the grid).

use crate::containment::{Container, containment_residual, farthest_point};
use crate::error::Error;
use crate::shape::{Body, Item};

/// Two items that overlap: their indices and μ² < 1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Overlap {
    /// The items `(i, j)`, `i < j`.
    pub items: (usize, usize),
    /// Their PW85 contact function μ² (< 1).
    pub mu2: f64,
}

/// An item outside the container, and by how much.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outside {
    /// The item's index.
    pub item: usize,
    /// The least factor t > 1 by which the container, scaled about its centre, holds the item.
    pub scale: f64,
}

/// What [`certify`] found.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Certificate {
    /// The overlapping pairs, in increasing `(i, j)`.
    pub overlapping: Vec<Overlap>,
    /// The items outside the container, in increasing index.
    pub outside: Vec<Outside>,
    /// Number of pairs tested (enclosing balls meeting).
    pub pairs_checked: usize,
    /// The smallest μ² over the tested pairs (`None` when no pair was tested).
    pub min_mu2: Option<f64>,
}

impl Certificate {
    /// No overlap and every item inside.
    pub fn is_feasible(&self) -> bool {
        self.overlapping.is_empty() && self.outside.is_empty()
    }

    /// The overlapping pairs `(i, j)`, without their μ².
    pub fn overlapping_pairs(&self) -> Vec<(usize, usize)> {
        self.overlapping.iter().map(|o| o.items).collect()
    }

    /// The indices of the items outside, without by how much.
    pub fn outside_items(&self) -> Vec<usize> {
        self.outside.iter().map(|o| o.item).collect()
    }
}

/// μ² as a message shows it: `decimals` decimals, or as many as it takes for a value below 1
/// (an overlap) not to read as 1 (0.9999999 is not "1.000000").
pub fn shown_mu2(mu2: f64, decimals: usize) -> String {
    let text = format!("{mu2:.decimals$}");
    if mu2 < 1.0 && text.parse::<f64>().is_ok_and(|v| v >= 1.0) {
        // Rust's shortest representation that reads back to the same double.
        format!("{mu2}")
    } else {
        text
    }
}

/// The PW85 contact function of two bodies, from their shape matrices in PW85's storage
/// (upper triangle, row-major) and r12 = c_j − c_i.
///
/// # Errors
/// PW85's refusal (a shape matrix that is not positive definite, non-finite entries).
pub fn contact<const N: usize>(i: &Body<N>, j: &Body<N>) -> Result<pw85::Contact, pw85::Error> {
    let (mi, mj) = (i.shape_matrix(), j.shape_matrix());
    let (ci, cj) = (i.centre(), j.centre());
    let at = |m: &[[f64; N]; N], r: usize, c: usize| {
        m.get(r).and_then(|row| row.get(c)).copied().unwrap_or(0.0)
    };
    let d = |k: usize| cj.get(k).copied().unwrap_or(0.0) - ci.get(k).copied().unwrap_or(0.0);
    if N == 3 {
        let sym = |m: &[[f64; N]; N]| {
            [
                at(m, 0, 0),
                at(m, 0, 1),
                at(m, 0, 2),
                at(m, 1, 1),
                at(m, 1, 2),
                at(m, 2, 2),
            ]
        };
        pw85::contact_function(&[d(0), d(1), d(2)], &sym(&mi), &sym(&mj))
    } else {
        let sym = |m: &[[f64; N]; N]| [at(m, 0, 0), at(m, 0, 1), at(m, 1, 1)];
        pw85::contact_function(&[d(0), d(1)], &sym(&mi), &sym(&mj))
    }
}

/// The certificate of `items` as they are stated (centres relative to the container's centre):
/// [`certify`] on their bodies, so that a packing written with round-trip precision and read
/// back is certified exactly as it was made.
///
/// # Errors
/// An item that is not a body ([`Item::body`]'s errors, naming the item), an item of a periodic
/// cell beyond 2³⁰ cells of it ([`Error::ItemFarFromCell`]), and those of [`certify`].
pub fn certify_items<const N: usize>(
    items: &[Item<N>],
    container: &Container<N>,
) -> Result<Certificate, Error> {
    let bodies = bodies_of(items)?;
    if let Container::Periodic { cell } = container {
        for (item, body) in bodies.iter().enumerate() {
            let s = crate::periodic::to_fractional(cell, &body.centre());
            if let Some(edge) = (0..N).find(|&k| !s[k].is_finite() || s[k].abs() > MAX_CELLS) {
                let value = s[edge];
                return Err(Error::ItemFarFromCell { item, edge, value });
            }
        }
    }
    certify(&bodies, container)
}

/// Fractional coordinates beyond this many cells are refused: their lattice translations
/// must be `i32`.
pub(crate) const MAX_CELLS: f64 = (1u32 << 30) as f64;

/// The bodies `items` state, an error naming the first that is not one.
///
/// # Errors
/// [`Item::body`]'s, naming the item.
pub fn bodies_of<const N: usize>(items: &[Item<N>]) -> Result<Vec<Body<N>>, Error> {
    items
        .iter()
        .enumerate()
        .map(|(i, item)| item.body().map_err(|e| e.for_item(i)))
        .collect()
}

/// The certificate of `bodies` in `container` (centred at the origin).
///
/// # Errors
/// [`Error::Grid`] when the neighbour grid refuses the centres, [`Error::Certification`] when
/// PW85 refuses a pair.
pub fn certify<const N: usize>(
    bodies: &[Body<N>],
    container: &Container<N>,
) -> Result<Certificate, Error> {
    if let Container::Periodic { cell } = *container {
        return certify_periodic(bodies, &cell);
    }
    let mut cert = Certificate::default();
    if bodies.len() > 1 {
        check_close_pairs(bodies, |i, j| Some(((i, j), (i, j))), &mut cert)?;
    }
    for (item, body) in bodies.iter().enumerate() {
        if containment_residual(body, container) > 0.0 {
            cert.outside.push(Outside {
                item,
                scale: containment_scale(body, container),
            });
        }
    }
    Ok(cert)
}

/// The certificate of `bodies` in a periodic cell: PW85 on every pair of the infinite packing
/// whose enclosing balls meet, one per lattice translation class (an item with its own images
/// included), found through the images of [`crate::periodic`]. An overlap names the two items
/// (the same item twice when it overlaps its own image).
fn certify_periodic<const N: usize>(
    bodies: &[Body<N>],
    cell: &[[f64; N]; N],
) -> Result<Certificate, Error> {
    let mut cert = Certificate::default();
    let (images, extended) = periodic_images(bodies, cell, 0.0)?;
    check_close_pairs(
        &extended,
        |a, b| {
            let (a, b) = (a.min(b), a.max(b));
            images.is_representative(a, b).then(|| {
                let (i, j) = (images.owner[a] as usize, images.owner[b] as usize);
                ((a, b), (i, j))
            })
        },
        &mut cert,
    )?;
    Ok(cert)
}

/// What the PW85 calls of a set of pairs found: the count, the least μ², the overlaps and
/// the refused pair with the least items. Every part is independent of the order the pairs
/// come in, so that the pairs may be split over threads.
#[derive(Default)]
struct Verdicts {
    checked: usize,
    min_mu2: Option<f64>,
    overlapping: Vec<Overlap>,
    failure: Option<((usize, usize), pw85::Error)>,
}

impl Verdicts {
    fn add<const N: usize>(
        &mut self,
        bodies: &[Body<N>],
        (a, b): (usize, usize),
        (i, j): (usize, usize),
    ) {
        self.checked += 1;
        match contact(&bodies[a], &bodies[b]) {
            Ok(c) => {
                self.min_mu2 = Some(self.min_mu2.map_or(c.mu2, |m| m.min(c.mu2)));
                if c.mu2 < 1.0 {
                    self.overlapping.push(Overlap {
                        items: (i.min(j), i.max(j)),
                        mu2: c.mu2,
                    });
                }
            }
            Err(e) => {
                let items = (i.min(j), i.max(j));
                if self
                    .failure
                    .as_ref()
                    .is_none_or(|(least, _)| items < *least)
                {
                    self.failure = Some((items, e));
                }
            }
        }
    }

    /// Both sets of verdicts as one.
    #[cfg_attr(not(feature = "rayon"), allow(dead_code))]
    fn merged(mut self, other: Self) -> Self {
        self.checked += other.checked;
        self.min_mu2 = match (self.min_mu2, other.min_mu2) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        self.overlapping.extend(other.overlapping);
        if let Some((items, e)) = other.failure
            && self
                .failure
                .as_ref()
                .is_none_or(|(least, _)| items < *least)
        {
            self.failure = Some((items, e));
        }
        self
    }
}

/// PW85 on the pairs of `bodies` whose enclosing balls meet, into `cert`: the count, the least
/// μ² and the overlaps (sorted). `pair` maps a close pair of bodies to the bodies to compare
/// and the items they stand for, or skips it (`None`). The refused pair with the least items
/// is the error. With the `rayon` feature the pairs are split over the current pool's
/// threads; the certificate is the same on any number.
fn check_close_pairs<const N: usize>(
    bodies: &[Body<N>],
    pair: impl Fn(usize, usize) -> Option<((usize, usize), (usize, usize))> + Sync + Send,
    cert: &mut Certificate,
) -> Result<(), Error> {
    let centres: Vec<[f64; N]> = bodies.iter().map(Body::centre).collect();
    let radii: Vec<f64> = bodies.iter().map(Body::bounding_radius).collect();
    let grid = cell_grid::Grid::<N>::with_radii(&radii)
        .build(&centres)
        .map_err(Error::Grid)?;
    let fold = |v: &mut Verdicts, a: usize, b: usize| {
        if let Some((bodies_ab, items)) = pair(a, b) {
            v.add(bodies, bodies_ab, items);
        }
    };
    #[cfg(feature = "rayon")]
    let verdicts = grid.par_fold_close_pairs(
        Verdicts::default,
        |v, a, b, _, _| fold(v, a, b),
        Verdicts::merged,
    );
    #[cfg(not(feature = "rayon"))]
    let verdicts = {
        let mut v = Verdicts::default();
        grid.for_each_close_pair(|a, b, _, _| fold(&mut v, a, b));
        v
    };
    if let Some(((i, j), source)) = verdicts.failure {
        return Err(Error::Certification {
            pair: (i, j),
            source,
        });
    }
    cert.pairs_checked += verdicts.checked;
    cert.min_mu2 = match (cert.min_mu2, verdicts.min_mu2) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    };
    cert.overlapping.extend(verdicts.overlapping);
    // Items pair once each in a container; in a periodic cell two items may overlap through
    // several images, ordered by μ².
    cert.overlapping
        .sort_unstable_by(|x, y| x.items.cmp(&y.items).then(x.mu2.total_cmp(&y.mu2)));
    Ok(())
}

/// The items of a periodic cell and their images within reach of any item (enclosing balls of
/// radius up to `r_max`, plus `skin`): the image set and the bodies at its points.
pub(crate) fn periodic_images<const N: usize>(
    bodies: &[Body<N>],
    cell: &[[f64; N]; N],
    skin: f64,
) -> Result<(crate::periodic::ImageSet<N>, Vec<Body<N>>), Error> {
    use crate::periodic::{ImageSet, check_crowding, image_limit, to_cartesian, to_fractional};
    let fractional: Vec<[f64; N]> = bodies
        .iter()
        .map(|b| to_fractional(cell, &b.centre()))
        .collect();
    let r_max = bodies.iter().map(Body::bounding_radius).fold(0.0, f64::max);
    check_crowding(cell, bodies.iter().map(Body::bounding_radius))?;
    let images = ImageSet::new(
        cell,
        &fractional,
        2.0 * r_max + skin,
        image_limit(bodies.len()),
    )?;
    let point = |e: usize| {
        let b = &bodies[images.owner[e] as usize];
        Body::from_parts_unchecked(
            to_cartesian(cell, &images.fractional(e, &fractional)),
            b.semi_axes(),
            b.rotation(),
        )
    };
    #[cfg(feature = "rayon")]
    let extended = {
        use rayon::prelude::*;
        (0..images.owner.len())
            .into_par_iter()
            .with_min_len(4096)
            .map(point)
            .collect()
    };
    #[cfg(not(feature = "rayon"))]
    let extended = (0..images.owner.len()).map(point).collect();
    Ok((images, extended))
}

/// The least factor t by which `container`, scaled about its centre, holds `body`: for a ball
/// or an ellipsoid with semi-axes A, t² = max over the body of |A⁻¹ p|² (the farthest point in
/// the container's own metric, [`farthest_point`]); for a box, the largest ratio of the body's
/// support (|c_k| + √M_kk along ±e_k) to the half-side.
pub fn containment_scale<const N: usize>(body: &Body<N>, container: &Container<N>) -> f64 {
    match *container {
        Container::Box { half_sides } => {
            let (c, m) = (body.centre(), body.shape_matrix());
            (0..N)
                .map(|k| (c[k].abs() + m[k][k].sqrt()) / half_sides[k])
                .fold(0.0, f64::max)
        }
        Container::Ball { radius } => farthest_point(body, &[radius; N]).0.sqrt(),
        Container::Ellipsoid { semi_axes } => farthest_point(body, &semi_axes).0.sqrt(),
        Container::Periodic { .. } => 1.0,
    }
}
