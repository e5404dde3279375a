//! Items as the particle formats (extended XYZ, LAMMPS data, GSD) state them: a simulation
//! cell, every item an ellipsoid with a unit quaternion (an ellipse flattened at z = 0), and
//! the shape groups that become atom types and element names.

use crate::packing::{Items, Packing};

/// The simulation cell the files state: a parallelepiped with lower corner `lo`, edge lengths
/// `lengths` and LAMMPS tilt factors (xy, xz, yz), periodic or not along each axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cell {
    /// The lower corner (xlo, ylo, zlo).
    pub lo: [f64; 3],
    /// The edge lengths (Lx, Ly, Lz). In 2D, Lz is the thickness of the slab around z = 0
    /// that holds the flattened ellipses.
    pub lengths: [f64; 3],
    /// The tilt factors (xy, xz, yz) of a sheared cell; zero for a box.
    pub tilt: [f64; 3],
    /// Periodic along x, y, z.
    pub periodic: [bool; 3],
    /// 2 or 3.
    pub dimension: usize,
}

impl Cell {
    /// The smallest axis-aligned box centred on the container's centre that holds the
    /// container and every item, not periodic. In 2D its z extent is ± the largest third
    /// semi-axis min(a, b) of the flattened ellipses, so that it straddles z = 0 as LAMMPS
    /// requires of a 2D box.
    pub fn enclosing(packing: &Packing) -> Cell {
        let container = packing.container();
        let dimension = container.dimension();
        let mut center = [0.0; 3];
        center[..dimension].copy_from_slice(container.center());
        let mut half = [0.0; 3];
        half[..dimension].copy_from_slice(&container.half_extents());
        for body in bodies(packing.items()) {
            let r = rotation(body.quaternion);
            for k in 0..3 {
                let reach = (0..3)
                    .map(|j| (r[k][j] * body.semi_axes[j]).powi(2))
                    .sum::<f64>()
                    .sqrt();
                half[k] = half[k].max((body.center[k] - center[k]).abs() + reach);
            }
        }
        if container.kind().is_periodic() {
            let size = container.size();
            let (lengths, tilts) = size.split_at(dimension);
            // The periodic cell itself; in 2D a slab around z = 0 as above.
            let mut cell = Cell {
                lo: [0.0, 0.0, -half[2]],
                lengths: [0.0, 0.0, 2.0 * half[2]],
                tilt: [0.0; 3],
                periodic: [true, true, dimension == 3],
                dimension,
            };
            cell.lo[..dimension].copy_from_slice(container.center());
            cell.lengths[..dimension].copy_from_slice(lengths);
            cell.tilt[..tilts.len()].copy_from_slice(tilts);
            return cell;
        }
        Cell {
            lo: [0, 1, 2].map(|k| center[k] - half[k]),
            lengths: half.map(|h| 2.0 * h),
            tilt: [0.0; 3],
            periodic: [false; 3],
            dimension,
        }
    }

    /// The upper corner of the box part (lo + lengths).
    pub fn hi(&self) -> [f64; 3] {
        [0, 1, 2].map(|k| self.lo[k] + self.lengths[k])
    }

    /// The centre of the cell: lo + (a + b + c) / 2 for the edge vectors a, b, c.
    pub fn center(&self) -> [f64; 3] {
        let [xy, xz, yz] = self.tilt;
        let [lx, ly, lz] = self.lengths;
        [
            self.lo[0] + 0.5 * (lx + xy + xz),
            self.lo[1] + 0.5 * (ly + yz),
            self.lo[2] + 0.5 * lz,
        ]
    }

    /// The edge vectors as the rows a, b, c (upper-triangular cell matrix of LAMMPS and
    /// HOOMD: a = (Lx, 0, 0), b = (xy, Ly, 0), c = (xz, yz, Lz)).
    pub fn vectors(&self) -> [[f64; 3]; 3] {
        let [xy, xz, yz] = self.tilt;
        let [lx, ly, lz] = self.lengths;
        [[lx, 0.0, 0.0], [xy, ly, 0.0], [xz, yz, lz]]
    }
}

/// One item as the files state it: an ellipsoid with a unit quaternion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Body {
    /// Its centre (z = 0 for an ellipse).
    pub center: [f64; 3],
    /// Its semi-axes (a, b, min(a, b) for an ellipse).
    pub semi_axes: [f64; 3],
    /// Its orientation (w, x, y, z), of norm 1.
    pub quaternion: [f64; 4],
}

/// The items as ellipsoids with unit quaternions (see the module documentation).
pub fn bodies(items: &Items) -> Vec<Body> {
    match items {
        Items::Ellipses(v) => v
            .iter()
            .map(|e| {
                let (s, c) = (0.5 * e.theta()).sin_cos();
                let [a, b] = e.semi_axes;
                Body {
                    center: [e.centre[0], e.centre[1], 0.0],
                    semi_axes: [a, b, a.min(b)],
                    quaternion: [c, 0.0, 0.0, s],
                }
            })
            .collect(),
        Items::Ellipsoids(v) => v
            .iter()
            .map(|e| Body {
                center: e.centre,
                semi_axes: e.semi_axes,
                quaternion: unit(e.quaternion()),
            })
            .collect(),
    }
}

/// `q / |q|`. A packing's quaternions are non-zero and finite ([`Packing::new`] checks).
fn unit(q: [f64; 4]) -> [f64; 4] {
    let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    q.map(|x| x / norm)
}

/// The rotation matrix of a unit quaternion (w, x, y, z).
fn rotation([w, x, y, z]: [f64; 4]) -> [[f64; 3]; 3] {
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

/// The shape groups of a packing: the distinct semi-axes (of the [`Body`]s) in the order their
/// first item appears, and the group of each item (0-based).
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeGroups {
    /// The semi-axes of each group.
    pub semi_axes: Vec<[f64; 3]>,
    /// The group of each item.
    pub of_item: Vec<usize>,
}

/// Groups the bodies by their semi-axes (compared exactly, bit for bit).
pub fn shape_groups(bodies: &[Body]) -> ShapeGroups {
    let mut semi_axes: Vec<[f64; 3]> = Vec::new();
    let mut index = std::collections::HashMap::new();
    let of_item = bodies
        .iter()
        .map(|b| {
            let key = b.semi_axes.map(f64::to_bits);
            *index.entry(key).or_insert_with(|| {
                semi_axes.push(b.semi_axes);
                semi_axes.len() - 1
            })
        })
        .collect();
    ShapeGroups { semi_axes, of_item }
}

/// The chemical symbols that stand for the shape groups where a format needs an element
/// (extended XYZ for ASE): group g is `GROUP_ELEMENTS[g % len]`. Light and heavy elements
/// alternate so that OVITO's default colours tell neighbouring groups apart.
pub const GROUP_ELEMENTS: [&str; 24] = [
    "C", "O", "N", "S", "Fe", "Cu", "Au", "Si", "Al", "P", "Cl", "Ca", "Ti", "Cr", "Mn", "Co",
    "Ni", "Zn", "Ag", "Pt", "Mg", "Na", "K", "Pb",
];

/// The name of group `g`: its element, with the round number after it once the elements are
/// used up (`C`, …, `Pb`, `C1`, …), so that names stay distinct.
pub fn group_name(g: usize) -> String {
    let n = GROUP_ELEMENTS.len();
    let element = GROUP_ELEMENTS[g % n];
    if g < n {
        element.to_string()
    } else {
        format!("{element}{}", g / n)
    }
}
