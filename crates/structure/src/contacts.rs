//! Contacts: two items touch when the PW85 contact function says they would meet if each were
//! scaled about its centre by `μ < 1 + gap` (μ² is the contact function at its maximum, PW85
//! theory eqs. (4)–(8); μ = 1 at tangency, μ < 1 for an overlap). The contact number of an item
//! is how many items (in a periodic cell: images) touch it; Z is their mean.
//!
//! Rattlers are the items held by fewer than N + 1 contacts (N the dimension): they are not
//! part of the rigid network. They are removed one after another until none is left, each
//! removal taking its contacts from its neighbours, and Z is also given over the rest.
//!
//! # References
//! - S. W. Perram, M. S. Wertheim, *Statistical mechanics of hard ellipsoids. I. Overlap
//!   algorithm and the contact function*, J. Comput. Phys. 58 (1985).
//! - A. Donev, S. Torquato, F. H. Stillinger, *Pair correlation function characteristics of
//!   nearly jammed disordered and ordered hard-sphere packings*, Phys. Rev. E 71, 011105
//!   (2005): rattlers.

use crate::Error;
use crate::neighbours::Bonds;
use implicit_packing::Body;

/// Contacts of a packing.
#[derive(Clone, Debug, PartialEq)]
pub struct Contacts {
    /// The relative gap: μ < 1 + gap.
    pub gap: f64,
    /// Pairs in contact (a pair of items touching through two images counts twice).
    pub pairs: usize,
    /// Mean contact number Z over all items.
    pub mean_contacts: f64,
    /// Items with each number of contacts: `distribution[z]` items have z.
    pub distribution: Vec<usize>,
    /// Rattlers: items left with fewer than N + 1 contacts as rattlers are removed.
    pub rattlers: usize,
    /// Mean contact number over the items that are not rattlers, counting only contacts
    /// between them (0 when all are rattlers).
    pub mean_contacts_without_rattlers: f64,
}

/// [`Contacts`] of `bodies` over the pairs of `bonds` (which must reach every pair whose
/// enclosing balls, grown by `1 + gap`, meet).
///
/// # Errors
/// [`Error::Contact`] when PW85 refuses a pair.
pub fn contacts<const N: usize>(
    bodies: &[Body<N>],
    bonds: &Bonds<N>,
    gap: f64,
) -> Result<Contacts, Error> {
    let limit = (1.0 + gap) * (1.0 + gap);
    let mut touching: Vec<(usize, usize)> = Vec::new();
    for (i, j, d) in bonds.pairs() {
        let (a, b) = (&bodies[i], &bodies[j]);
        let reach = (a.bounding_radius() + b.bounding_radius()) * (1.0 + gap);
        if d.iter().map(|v| v * v).sum::<f64>() >= reach * reach {
            continue;
        }
        let c = a.centre();
        let moved = b
            .with_centre(std::array::from_fn(|k| c[k] + d[k]))
            .map_err(|source| Error::Contact {
                pair: (i, j),
                source,
            })?;
        let mu2 = implicit_packing::certificate::contact(a, &moved)
            .map_err(|source| Error::Contact {
                pair: (i, j),
                source: implicit_packing::Error::Certification {
                    pair: (i, j),
                    source,
                },
            })?
            .mu2;
        if mu2 < limit {
            touching.push((i, j));
        }
    }
    let m = bodies.len();
    let mut z = vec![0usize; m];
    for &(i, j) in &touching {
        z[i] += 1;
        z[j] += 1;
    }
    let top = z.iter().copied().max().unwrap_or(0);
    let mut distribution = vec![0usize; top + 1];
    for &k in &z {
        distribution[k] += 1;
    }
    let (rattlers, kept_z) = without_rattlers(m, &touching, N + 1);
    let kept = m - rattlers;
    Ok(Contacts {
        gap,
        pairs: touching.len(),
        mean_contacts: 2.0 * touching.len() as f64 / m.max(1) as f64,
        distribution,
        rattlers,
        mean_contacts_without_rattlers: if kept == 0 {
            0.0
        } else {
            kept_z as f64 / kept as f64
        },
    })
}

/// The rattlers, removed one after another (an item with fewer than `least` contacts with the
/// items still there), and the sum of the contact numbers of the rest among themselves.
fn without_rattlers(m: usize, touching: &[(usize, usize)], least: usize) -> (usize, usize) {
    let mut neighbours = vec![Vec::new(); m];
    for &(i, j) in touching {
        neighbours[i].push(j);
        if i != j {
            neighbours[j].push(i);
        } else {
            neighbours[i].push(i);
        }
    }
    let mut z: Vec<usize> = neighbours.iter().map(Vec::len).collect();
    let mut removed = vec![false; m];
    let mut queue: Vec<usize> = (0..m).filter(|&i| z[i] < least).collect();
    while let Some(i) = queue.pop() {
        if removed[i] {
            continue;
        }
        removed[i] = true;
        for &j in &neighbours[i] {
            if !removed[j] {
                z[j] -= 1;
                if z[j] < least {
                    queue.push(j);
                }
            }
        }
    }
    let rattlers = removed.iter().filter(|r| **r).count();
    let kept_z = (0..m).filter(|&i| !removed[i]).map(|i| z[i]).sum();
    (rattlers, kept_z)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rattlers_are_removed_in_turn() {
        // A triangle (each with 2 contacts) and a chain hanging from it: with 3 contacts
        // needed, everything rattles; with 2, the triangle stays and the chain goes.
        let touching = [(0, 1), (1, 2), (0, 2), (2, 3), (3, 4)];
        assert_eq!(without_rattlers(5, &touching, 3), (5, 0));
        assert_eq!(without_rattlers(5, &touching, 2), (2, 6));
    }
}
