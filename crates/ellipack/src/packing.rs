//! A packing as `ellipack pack` writes it and `ellipack verify` reads it: the container, the
//! items (centre, semi-axes, orientation) and a summary with the certificate.
//!
//! Conventions (`validation/reference/README.md`, packing paper eqs. 1–2): semi-axis k lies along
//! column k of the rotation R, so the item is {x : (x − c)ᵀ M⁻¹ (x − c) ≤ 1} with
//! M = R diag(l²) Rᵀ. In 2D, R = [[cos θ, −sin θ], [sin θ, cos θ]] (eq. 1): θ is the angle of
//! the first semi-axis `a` with the x axis, in radians. In 3D the orientation is a quaternion
//! (w, x, y, z), the Hamilton active rotation v ↦ q v q*, normalised by w² + x² + y² + z².
//! Containers are axis-aligned.
//!
//! The files, each in its module (all written atomically, numbers with 17 significant digits so
//! that they read back to the same double): the items table [`crate::items_csv`], the summary
//! [`crate::summary_json`], extended XYZ [`crate::xyz`], LAMMPS data [`crate::lammps`], GSD
//! [`crate::gsd`] and the container's surface [`crate::obj`].

use crate::Error;
use implicit_packing::ContainerShape;
pub use implicit_packing::Item;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::fmt;

/// The shape of a container in a dimension, as `summary.json` and scene files name it. Read
/// from its name; `periodic` reads as the plane's cell, which a scene of ellipsoids makes the
/// cell in space ([`ContainerKind::named`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Deserialize)]
#[serde(try_from = "String")]
pub enum ContainerKind {
    /// A disc (2D).
    Circle,
    /// An axis-aligned ellipse (2D).
    Ellipse,
    /// An axis-aligned rectangle (2D).
    Rectangle,
    /// A ball (3D).
    Ball,
    /// An axis-aligned ellipsoid (3D).
    Ellipsoid,
    /// An axis-aligned cuboid (3D).
    Cuboid,
    /// A periodic cell in the plane (2D), named `periodic`.
    Parallelogram,
    /// A periodic cell in space (3D), named `periodic`.
    Parallelepiped,
}

impl TryFrom<String> for ContainerKind {
    type Error = String;

    fn try_from(name: String) -> Result<Self, String> {
        ContainerKind::from_name(&name).ok_or_else(|| {
            format!(
                "unknown variant `{name}`, expected one of `circle`, `ellipse`, `rectangle`, \
                 `ball`, `ellipsoid`, `cuboid`, `periodic`"
            )
        })
    }
}

impl ContainerKind {
    /// Every kind, 2D first.
    pub const ALL: [ContainerKind; 8] = [
        ContainerKind::Circle,
        ContainerKind::Ellipse,
        ContainerKind::Rectangle,
        ContainerKind::Parallelogram,
        ContainerKind::Ball,
        ContainerKind::Ellipsoid,
        ContainerKind::Cuboid,
        ContainerKind::Parallelepiped,
    ];

    /// The name in files: `circle`, `ellipse`, `rectangle`, `ball`, `ellipsoid`, `cuboid`, and
    /// `periodic` for the periodic cells of both dimensions.
    pub fn name(self) -> &'static str {
        match self {
            ContainerKind::Circle => "circle",
            ContainerKind::Ellipse => "ellipse",
            ContainerKind::Rectangle => "rectangle",
            ContainerKind::Ball => "ball",
            ContainerKind::Ellipsoid => "ellipsoid",
            ContainerKind::Cuboid => "cuboid",
            ContainerKind::Parallelogram | ContainerKind::Parallelepiped => "periodic",
        }
    }

    /// The kind of a name, or `None`; `periodic` is the 2D cell (see [`ContainerKind::named`]).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }

    /// The kind of a name in a given dimension (`periodic` names a cell of either), or `None`.
    pub fn named(name: &str, dimension: usize) -> Option<Self> {
        Self::ALL
            .into_iter()
            .find(|k| k.name() == name && k.dimension() == dimension)
    }

    /// The kind of the model's container `shape` in dimension `n` (2 or 3).
    pub fn of(shape: ContainerShape, n: usize) -> Self {
        let plane = n == 2;
        match shape {
            ContainerShape::Ball if plane => ContainerKind::Circle,
            ContainerShape::Ball => ContainerKind::Ball,
            ContainerShape::Ellipsoid if plane => ContainerKind::Ellipse,
            ContainerShape::Ellipsoid => ContainerKind::Ellipsoid,
            ContainerShape::Box if plane => ContainerKind::Rectangle,
            ContainerShape::Box => ContainerKind::Cuboid,
            ContainerShape::Periodic if plane => ContainerKind::Parallelogram,
            ContainerShape::Periodic => ContainerKind::Parallelepiped,
        }
    }

    /// The model's shape of this kind: a circle is a ball, a rectangle a box.
    pub fn shape(self) -> ContainerShape {
        match self {
            ContainerKind::Circle | ContainerKind::Ball => ContainerShape::Ball,
            ContainerKind::Ellipse | ContainerKind::Ellipsoid => ContainerShape::Ellipsoid,
            ContainerKind::Rectangle | ContainerKind::Cuboid => ContainerShape::Box,
            ContainerKind::Parallelogram | ContainerKind::Parallelepiped => {
                ContainerShape::Periodic
            }
        }
    }

    /// 2 or 3.
    pub fn dimension(self) -> usize {
        match self {
            ContainerKind::Circle
            | ContainerKind::Ellipse
            | ContainerKind::Rectangle
            | ContainerKind::Parallelogram => 2,
            ContainerKind::Ball
            | ContainerKind::Ellipsoid
            | ContainerKind::Cuboid
            | ContainerKind::Parallelepiped => 3,
        }
    }

    /// Whether it is a periodic cell.
    pub fn is_periodic(self) -> bool {
        matches!(
            self,
            ContainerKind::Parallelogram | ContainerKind::Parallelepiped
        )
    }

    /// What the paper minimises: "area" in 2D, "volume" in 3D.
    pub fn measure_name(self) -> &'static str {
        if self.dimension() == 2 {
            "area"
        } else {
            "volume"
        }
    }
}

/// The kind as a person reads it: its name, and `periodic cell` for the cells.
impl fmt::Display for ContainerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.is_periodic() {
            // Both periodic kinds are named `periodic`: the dimension tells them apart.
            write!(f, "{}D {} cell", self.dimension(), self.name())
        } else {
            f.write_str(self.name())
        }
    }
}

/// A container where a packing places it: the packing model's container
/// ([`implicit_packing::Container`], centred at the origin; a periodic cell by its
/// upper-triangular cell matrix) moved to `center`, the corner of a periodic cell.
///
/// In JSON, as `summary.json` and scene files state it: `{"kind": "ball", "center": [..],
/// "radius": r}`, with `half_sides` for a rectangle or cuboid and `semi_axes` for an ellipse or
/// ellipsoid; a missing `center` is the origin. A periodic cell is LAMMPS's triclinic box,
/// `{"kind": "periodic", "origin": [..], "lengths": [l_x, l_y, l_z], "tilts": [xy, xz, yz]}`
/// (2D: `[l_x, l_y]`, `[xy]`): lattice vectors `a = (l_x, 0, 0)`, `b = (xy, l_y, 0)`,
/// `c = (xz, yz, l_z)` from `origin`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "ContainerForm", into = "ContainerForm")]
pub enum Container {
    /// A container in the plane.
    Plane {
        /// Its centre; a periodic cell's corner.
        center: [f64; 2],
        /// Its shape and size.
        shape: Centred<2>,
    },
    /// A container in space.
    Space {
        /// Its centre; a periodic cell's corner.
        center: [f64; 3],
        /// Its shape and size.
        shape: Centred<3>,
    },
}

impl From<([f64; 2], Centred<2>)> for Container {
    fn from((center, shape): ([f64; 2], Centred<2>)) -> Self {
        Container::Plane { center, shape }
    }
}

impl From<([f64; 3], Centred<3>)> for Container {
    fn from((center, shape): ([f64; 3], Centred<3>)) -> Self {
        Container::Space { center, shape }
    }
}

/// The packing model's container, centred at the origin: a ball, an axis-aligned ellipsoid or
/// box with its size, or a periodic cell.
pub type Centred<const N: usize> = implicit_packing::Container<N>;

/// `$body` with `$center` and `$shape` bound in either dimension.
macro_rules! in_either_dimension {
    ($container:expr, |$center:ident, $shape:ident| $body:expr) => {
        match $container {
            Container::Plane {
                center: $center,
                shape: $shape,
            } => $body,
            Container::Space {
                center: $center,
                shape: $shape,
            } => $body,
        }
    };
}

impl Container {
    /// The container `shape` (centred at the origin) moved to `center` in the plane.
    pub fn plane(center: [f64; 2], shape: Centred<2>) -> Self {
        Container::Plane { center, shape }
    }

    /// The container `shape` (centred at the origin) moved to `center` in space.
    pub fn space(center: [f64; 3], shape: Centred<3>) -> Self {
        Container::Space { center, shape }
    }

    /// The periodic cell at `origin` (2 or 3 coordinates) with `lengths` and LAMMPS's `tilts`
    /// (`[xy]`, or `[xy, xz, yz]`; missing tilts are zero), without the checks of
    /// [`Container::from_parts`].
    pub fn periodic(origin: &[f64], lengths: &[f64], tilts: &[f64]) -> Self {
        let kind = if origin.len() == 2 {
            ContainerKind::Parallelogram
        } else {
            ContainerKind::Parallelepiped
        };
        let size: Vec<f64> = lengths.iter().chain(tilts).copied().collect();
        Container::unchecked(kind, origin, &size)
    }

    /// The model's `shape` at `center`, in dimension `N` (2 or 3).
    pub fn placed<const N: usize>(center: [f64; N], shape: &Centred<N>) -> Self {
        let kind = ContainerKind::of(shape.kind(), N);
        Container::unchecked(kind, &center, &shape.dimensions())
    }

    /// The container of a kind from its centre and its size (`[r]`, the semi-axes or the half
    /// sides: the container variables of the solver, in that order).
    ///
    /// # Errors
    /// [`Error::Inconsistent`] when the lengths do not fit the kind, or the size is not
    /// positive and finite, or the centre not finite.
    pub fn from_parts(
        kind: ContainerKind,
        center: &[f64],
        size: &[f64],
    ) -> Result<Container, Error> {
        let wrong = |what: &str, expected: usize, found: usize| Error::Inconsistent {
            source_name: "container".to_string(),
            message: format!("a {kind} needs {expected} {what} values, not {found}"),
        };
        let n = kind.dimension();
        if center.len() != n {
            return Err(wrong("centre", n, center.len()));
        }
        let size_len = match kind.shape() {
            ContainerShape::Ball => 1,
            // A periodic cell's tilts may be left out: a rectangular cell.
            ContainerShape::Periodic if size.len() == n => n,
            shape => shape.dimension_count(n),
        };
        if size.len() != size_len {
            return Err(wrong("size", size_len, size.len()));
        }
        let container = Container::unchecked(kind, center, size);
        match container.defect() {
            None => Ok(container),
            Some((_, message)) => Err(Error::Inconsistent {
                source_name: "container".to_string(),
                message,
            }),
        }
    }

    /// The container of a kind from its centre and its size, as [`Container::from_parts`]
    /// reads them, without checks: a missing value is NaN (which [`Container::defect`] names)
    /// and missing tilts of a periodic cell are zero (a rectangular cell).
    pub(crate) fn unchecked(kind: ContainerKind, center: &[f64], size: &[f64]) -> Container {
        let c = |k: usize| center.get(k).copied().unwrap_or(f64::NAN);
        if kind.dimension() == 2 {
            Container::Plane {
                center: [c(0), c(1)],
                shape: sized_of(kind.shape(), size),
            }
        } else {
            Container::Space {
                center: [c(0), c(1), c(2)],
                shape: sized_of(kind.shape(), size),
            }
        }
    }

    /// Its kind.
    pub fn kind(&self) -> ContainerKind {
        let shape = in_either_dimension!(self, |_c, shape| shape.kind());
        ContainerKind::of(shape, self.dimension())
    }

    /// The cell matrix of a periodic cell (rows, upper triangular: columns are the lattice
    /// vectors), `None` for the other containers.
    pub fn cell_matrix(&self) -> Option<Vec<Vec<f64>>> {
        in_either_dimension!(self, |_c, shape| match shape {
            Centred::Periodic { cell } => Some(cell.iter().map(|row| row.to_vec()).collect()),
            _ => None,
        })
    }

    /// 2 or 3.
    pub fn dimension(&self) -> usize {
        self.center().len()
    }

    /// Its centre (2 or 3 coordinates); a periodic cell's corner.
    pub fn center(&self) -> &[f64] {
        in_either_dimension!(self, |center, _s| center)
    }

    /// Its size: `[radius]`, the semi-axes, the half sides, or a periodic cell's lengths and
    /// then its tilts.
    pub fn size(&self) -> Vec<f64> {
        in_either_dimension!(self, |_c, shape| shape.dimensions())
    }

    /// The name of [`Container::size`] in `summary.json`: `radius`, `semi_axes`,
    /// `half_sides`, or `lengths` (a periodic cell, whose size is its lengths and then its
    /// tilts).
    pub fn size_name(&self) -> &'static str {
        match self.kind().shape() {
            ContainerShape::Ball => "radius",
            ContainerShape::Ellipsoid => "semi_axes",
            ContainerShape::Box => "half_sides",
            ContainerShape::Periodic => "lengths",
        }
    }

    /// Half the extent of its bounding box along each axis (of one cell, for a periodic cell).
    pub fn half_extents(&self) -> Vec<f64> {
        let n = self.dimension();
        match self.cell_matrix() {
            Some(h) => h
                .iter()
                .map(|row| {
                    let (lo, hi) = row.iter().fold((0.0f64, 0.0f64), |(lo, hi), &v| {
                        (lo + v.min(0.0), hi + v.max(0.0))
                    });
                    0.5 * (hi - lo)
                })
                .collect(),
            None if self.kind().shape() == ContainerShape::Ball => vec![self.size()[0]; n],
            None => self.size(),
        }
    }

    /// Its area (2D) or volume (3D): πr², πab, 4ab; 4/3 πr³, 4/3 πabc, 8abc; a cell's
    /// determinant.
    pub fn measure(&self) -> f64 {
        let size = self.size();
        let n = self.dimension();
        match self.kind().shape() {
            ContainerShape::Ball if n == 2 => PI * size[0] * size[0],
            ContainerShape::Ball => 4.0 / 3.0 * PI * size[0].powi(3),
            ContainerShape::Ellipsoid if n == 2 => PI * size[0] * size[1],
            ContainerShape::Ellipsoid => 4.0 / 3.0 * PI * size[0] * size[1] * size[2],
            ContainerShape::Box => size.iter().fold(2f64.powi(n as i32), |m, l| m * l),
            ContainerShape::Periodic => size[..n].iter().product(),
        }
    }

    /// `None` when the container is usable, else what is wrong (a size that is not positive
    /// and finite, a centre that is not finite) and the name of the offending field.
    pub fn defect(&self) -> Option<(&'static str, String)> {
        // The magnitudes the packing model holds.
        const MAX: f64 = implicit_packing::shape::MAX_MAGNITUDE;
        let in_range = |v: f64| (1.0 / MAX..=MAX).contains(&v);
        let within = |v: f64| (-MAX..=MAX).contains(&v);
        if let Some(x) = self.center().iter().find(|x| !within(**x)) {
            return Some((
                "center",
                format!("the centre has a coordinate {x}, beyond ±{MAX:e}"),
            ));
        }
        let n = self.dimension();
        let size = self.size();
        let (sizes, tilts) = match self.kind().shape() {
            ContainerShape::Periodic => size.split_at(n),
            _ => (&size[..], &[][..]),
        };
        if let Some(t) = tilts.iter().find(|t| !within(**t)) {
            return Some((
                "tilts",
                format!("tilts must be finite, within ±{MAX:e}, not {t}"),
            ));
        }
        sizes.iter().find(|s| !in_range(**s)).map(|s| {
            let name = self.size_name();
            let message = format!(
                "{name} must be positive, in [{:e}, {MAX:e}], not {s}",
                1.0 / MAX
            );
            (name, message)
        })
    }
}

/// The model's container of a shape and a size as [`Container::size`] states it; a missing
/// value is NaN, a missing tilt zero.
fn sized_of<const N: usize>(shape: ContainerShape, size: &[f64]) -> Centred<N> {
    let d = |k: usize| size.get(k).copied().unwrap_or(f64::NAN);
    match shape {
        ContainerShape::Ball => Centred::Ball { radius: d(0) },
        ContainerShape::Ellipsoid => Centred::Ellipsoid {
            semi_axes: std::array::from_fn(d),
        },
        ContainerShape::Box => Centred::Box {
            half_sides: std::array::from_fn(d),
        },
        ContainerShape::Periodic => Centred::Periodic {
            cell: cell_of(size),
        },
    }
}

/// The upper-triangular cell matrix of a periodic cell's size (lengths, then LAMMPS's tilts
/// `xy, xz, yz`); missing lengths are NaN, missing tilts zero.
fn cell_of<const N: usize>(size: &[f64]) -> [[f64; N]; N] {
    let mut cell = [[0.0; N]; N];
    for k in 0..N * (N + 1) / 2 {
        let (r, c) = implicit_packing::periodic::entry::<N>(k);
        let missing = if r == c { f64::NAN } else { 0.0 };
        cell[r][c] = size.get(k).copied().unwrap_or(missing);
    }
    cell
}

/// [`Container`] as JSON states it (see there).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
enum ContainerForm {
    Circle(Round<[f64; 2]>),
    Ellipse(Axes<[f64; 2]>),
    Rectangle(Sides<[f64; 2]>),
    Ball(Round<[f64; 3]>),
    Ellipsoid(Axes<[f64; 3]>),
    Cuboid(Sides<[f64; 3]>),
    Periodic(Cell),
}

/// A struct of the JSON form: a centre (the origin when missing) and one size field, and the
/// model's container (`variant`) it states.
macro_rules! json_shape {
    ($(#[$doc:meta])* $name:ident { $size:ident: $size_type:ty } => $variant:ident) => {
        $(#[$doc])*
        #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
        #[serde(deny_unknown_fields)]
        struct $name<C: Default> {
            #[serde(default)]
            center: C,
            $size: $size_type,
        }

        impl<C: Default> $name<C> {
            fn new(center: C, $size: $size_type) -> Self {
                $name { center, $size }
            }
        }

        impl<const N: usize> $name<[f64; N]>
        where
            [f64; N]: Default,
        {
            /// The centre and the model's container.
            fn centred(self) -> ([f64; N], Centred<N>) {
                (self.center, Centred::$variant { $size: self.$size })
            }
        }
    };
}

json_shape!(
    /// A disc or ball in JSON.
    Round { radius: f64 } => Ball
);
json_shape!(
    /// An ellipse or ellipsoid in JSON.
    Axes { semi_axes: C } => Ellipsoid
);
json_shape!(
    /// A rectangle or cuboid in JSON.
    Sides { half_sides: C } => Box
);

/// A periodic cell in JSON; a missing origin is the origin.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Cell {
    #[serde(default)]
    origin: Vec<f64>,
    lengths: Vec<f64>,
    tilts: Vec<f64>,
}

impl From<Container> for ContainerForm {
    fn from(c: Container) -> Self {
        use ContainerForm as F;
        let (center, size) = (c.center(), c.size());
        let at = |v: &[f64], k: usize| v.get(k).copied().unwrap_or(f64::NAN);
        let two = |v: &[f64]| [at(v, 0), at(v, 1)];
        let three = |v: &[f64]| [at(v, 0), at(v, 1), at(v, 2)];
        let radius = at(&size, 0);
        let n = c.dimension();
        match c.kind() {
            ContainerKind::Circle => F::Circle(Round::new(two(center), radius)),
            ContainerKind::Ellipse => F::Ellipse(Axes::new(two(center), two(&size))),
            ContainerKind::Rectangle => F::Rectangle(Sides::new(two(center), two(&size))),
            ContainerKind::Ball => F::Ball(Round::new(three(center), radius)),
            ContainerKind::Ellipsoid => F::Ellipsoid(Axes::new(three(center), three(&size))),
            ContainerKind::Cuboid => F::Cuboid(Sides::new(three(center), three(&size))),
            ContainerKind::Parallelogram | ContainerKind::Parallelepiped => F::Periodic(Cell {
                origin: center.to_vec(),
                lengths: size[..n].to_vec(),
                tilts: size[n..].to_vec(),
            }),
        }
    }
}

impl TryFrom<ContainerForm> for Container {
    type Error = String;

    fn try_from(form: ContainerForm) -> Result<Self, String> {
        use ContainerForm as F;
        Ok(match form {
            F::Circle(r) => r.centred().into(),
            F::Ellipse(e) => e.centred().into(),
            F::Rectangle(b) => b.centred().into(),
            F::Ball(r) => r.centred().into(),
            F::Ellipsoid(e) => e.centred().into(),
            F::Cuboid(b) => b.centred().into(),
            F::Periodic(Cell {
                mut origin,
                lengths,
                tilts,
            }) => {
                let n = lengths.len();
                if origin.is_empty() {
                    origin = vec![0.0; n];
                }
                if !(n == 2 || n == 3) || origin.len() != n || tilts.len() != n * (n - 1) / 2 {
                    return Err(format!(
                        "a periodic cell has 2 or 3 lengths, as many origin coordinates and 1 \
                         or 3 tilts, not {n}, {} and {}",
                        origin.len(),
                        tilts.len()
                    ));
                }
                Container::periodic(&origin, &lengths, &tilts)
            }
        })
    }
}

/// The items of a packing, all ellipses or all ellipsoids.
#[derive(Clone, Debug, PartialEq)]
pub enum Items {
    /// 2D.
    Ellipses(Vec<Item<2>>),
    /// 3D.
    Ellipsoids(Vec<Item<3>>),
}

impl Items {
    /// The items of a dimension known only as a parameter: [`Items::Ellipses`] for `N = 2`,
    /// else [`Items::Ellipsoids`].
    pub fn of<const N: usize>(items: &[Item<N>]) -> Items {
        if N == 2 {
            Items::Ellipses(items.iter().map(resized).collect())
        } else {
            Items::Ellipsoids(items.iter().map(resized).collect())
        }
    }

    /// The items as `Item<N>`, `None` when they have the other dimension.
    pub fn in_dimension<const N: usize>(&self) -> Option<Vec<Item<N>>> {
        fn all<const M: usize, const N: usize>(v: &[Item<M>]) -> Option<Vec<Item<N>>> {
            (M == N).then(|| v.iter().map(resized).collect())
        }
        match self {
            Items::Ellipses(v) => all(v),
            Items::Ellipsoids(v) => all(v),
        }
    }

    /// How many.
    pub fn len(&self) -> usize {
        match self {
            Items::Ellipses(v) => v.len(),
            Items::Ellipsoids(v) => v.len(),
        }
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// 2 or 3.
    pub fn dimension(&self) -> usize {
        match self {
            Items::Ellipses(_) => 2,
            Items::Ellipsoids(_) => 3,
        }
    }

    /// Their total area (2D) or volume (3D).
    pub fn total_measure(&self) -> f64 {
        // A fold from +0.0: `sum()` of no floats is −0.0, which prints as a density "-0".
        match self {
            Items::Ellipses(v) => v.iter().map(Item::measure).fold(0.0, |a, x| a + x),
            Items::Ellipsoids(v) => v.iter().map(Item::measure).fold(0.0, |a, x| a + x),
        }
    }

    /// "ellipses" or "ellipsoids" (or the singular for one item).
    pub fn noun(&self) -> &'static str {
        match (self, self.len() == 1) {
            (Items::Ellipses(_), false) => "ellipses",
            (Items::Ellipses(_), true) => "ellipse",
            (Items::Ellipsoids(_), false) => "ellipsoids",
            (Items::Ellipsoids(_), true) => "ellipsoid",
        }
    }
}

/// The item of dimension `N` as one of dimension `M` (the same item when `M = N`, which is
/// how the callers use it: the dimension is known only as a parameter).
fn resized<const N: usize, const M: usize>(i: &Item<N>) -> Item<M> {
    Item {
        centre: std::array::from_fn(|k| i.centre[k]),
        semi_axes: std::array::from_fn(|k| i.semi_axes[k]),
        orientation: i.orientation,
    }
}

/// Total item area or volume divided by the container's: the packing density.
///
/// NaN when the container has no area or volume (a zero size).
pub fn density(container: &Container, items: &Items) -> f64 {
    let measure = container.measure();
    if measure > 0.0 {
        items.total_measure() / measure
    } else {
        f64::NAN
    }
}

/// A container and the items in it.
#[derive(Clone, Debug, PartialEq)]
pub struct Packing {
    // Crate-visible so that the crate's own tests can draw broken data; users go through
    // `Packing::new`, which checks.
    pub(crate) container: Container,
    pub(crate) items: Items,
}

impl Packing {
    /// The same packing in the form the files state a periodic cell in: its tilts reduced
    /// (`|xy| ≤ l_x / 2`, `|xz| ≤ l_x / 2`, `|yz| ≤ l_y / 2`, as LAMMPS and HOOMD ask; the
    /// same lattice) and every centre moved by a lattice translation into the cell (fractional
    /// coordinates in `[0, 1)` from the origin). Other containers are returned as they are.
    pub fn in_reduced_cell(&self) -> Packing {
        let mut packing = self.clone();
        match (&mut packing.container, &mut packing.items) {
            (
                Container::Plane {
                    center,
                    shape: Centred::Periodic { cell },
                },
                Items::Ellipses(items),
            ) => wrap_into_reduced(center, cell, items),
            (
                Container::Space {
                    center,
                    shape: Centred::Periodic { cell },
                },
                Items::Ellipsoids(items),
            ) => wrap_into_reduced(center, cell, items),
            _ => {}
        }
        packing
    }

    /// The container.
    pub fn container(&self) -> &Container {
        &self.container
    }

    /// The items.
    pub fn items(&self) -> &Items {
        &self.items
    }

    /// The container and the items, taken apart.
    pub fn into_parts(self) -> (Container, Items) {
        (self.container, self.items)
    }

    /// A packing, checked: items and container of the same dimension, positive finite sizes,
    /// finite centres and angles, non-zero quaternions.
    ///
    /// # Errors
    /// [`Error::Inconsistent`] naming the first offending item (0-based id).
    pub fn new(container: Container, items: Items) -> Result<Self, Error> {
        let inconsistent = |message: String| Error::Inconsistent {
            source_name: "packing".to_string(),
            message,
        };
        if let Some((_, message)) = container.defect() {
            return Err(inconsistent(format!("container: {message}")));
        }
        if container.dimension() != items.dimension() {
            return Err(inconsistent(format!(
                "a {} container holds {}D items",
                container.kind(),
                items.dimension()
            )));
        }
        let check = |id: usize, fields: &[(&str, f64)], semi_axes: &[f64]| {
            if let Some((name, v)) = fields.iter().find(|(_, v)| !v.is_finite()) {
                return Err(inconsistent(format!("item {id}: `{name}` is {v}")));
            }
            if let Some(l) = semi_axes.iter().find(|l| **l <= 0.0) {
                return Err(inconsistent(format!(
                    "item {id}: semi-axis {l} is not positive"
                )));
            }
            Ok(())
        };
        match &items {
            Items::Ellipses(v) => {
                for (id, e) in v.iter().enumerate() {
                    let [x, y] = e.centre;
                    let [a, b] = e.semi_axes;
                    let fields = [("x", x), ("y", y), ("a", a), ("b", b), ("theta", e.theta())];
                    check(id, &fields, &e.semi_axes)?;
                }
            }
            Items::Ellipsoids(v) => {
                for (id, e) in v.iter().enumerate() {
                    let [x, y, z] = e.centre;
                    let [a, b, c] = e.semi_axes;
                    let [qw, qx, qy, qz] = e.quaternion();
                    let fields = [
                        ("x", x),
                        ("y", y),
                        ("z", z),
                        ("a", a),
                        ("b", b),
                        ("c", c),
                        ("qw", qw),
                        ("qx", qx),
                        ("qy", qy),
                        ("qz", qz),
                    ];
                    check(id, &fields, &e.semi_axes)?;
                    if e.quaternion().iter().all(|q| *q == 0.0) {
                        return Err(inconsistent(format!("item {id}: the quaternion is zero")));
                    }
                }
            }
        }
        Ok(Packing { container, items })
    }

    /// The packing density (see [`density`]).
    pub fn density(&self) -> f64 {
        density(&self.container, &self.items)
    }
}

/// What the certification of a packing found (PW85 on every candidate pair, exact
/// containment).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CertificateCounts {
    /// Pairs with μ² < 1 (overlapping interiors).
    pub overlapping_pairs: u64,
    /// Items not inside the container.
    pub containment_violations: u64,
    /// The smallest PW85 μ² over the candidate pairs (≥ 1 when no pair overlaps); `null` when
    /// there was no pair to check.
    pub min_mu2: Option<f64>,
}

impl CertificateCounts {
    /// No overlap and every item inside.
    pub fn is_certified(&self) -> bool {
        self.overlapping_pairs == 0 && self.containment_violations == 0
    }
}

/// The contents of `summary.json`.
///
/// ```json
/// {
///   "container": { "kind": "ellipse", "center": [0.0, 0.0], "semi_axes": [9.1, 7.5] },
///   "items": 30,
///   "density": 0.8790,
///   "objective": 214.4,
///   "wall_seconds": 12.5,
///   "local_minimisations": 17,
///   "certificate": { "overlapping_pairs": 0, "containment_violations": 0, "min_mu2": 1.0000003 }
/// }
/// ```
///
/// Unknown top-level keys are ignored when reading, so that later versions can add fields.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// The container.
    pub container: Container,
    /// The number of items (rows of `packing.csv`).
    pub items: usize,
    /// Total item area or volume / container area or volume.
    pub density: f64,
    /// The solver's objective at the packing (the container's area or volume, or whatever the
    /// model minimised).
    pub objective: f64,
    /// Wall-clock seconds of the run.
    pub wall_seconds: f64,
    /// Local minimisations completed.
    pub local_minimisations: u64,
    /// The certificate.
    pub certificate: CertificateCounts,
    /// What the certified repair cost, when the packing came from the solver.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub repair: Option<Repair>,
    /// True when no local minimisation beat the run's start (a `--resume` folder or the
    /// certified lattice start), which was written as it was.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub start_kept: bool,
    /// The shard of a multi-start spread over several runs that found this packing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<ShardOrigin>,
    /// True for the least overlapping configuration of a run that did not reach a packing in
    /// its fixed container (written to `unfinished/`): not a packing, and not certified.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub not_reached: bool,
    /// True when the container (or periodic cell) is the scene's, fixed: the run filled it
    /// rather than shrinking it. `ellipack merge` keeps packings of one fixed container apart
    /// from those of another or of a variable one.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub fixed_container: bool,
}

/// Which shard of which multi-start a packing came from (`ellipack pack --shard K/N`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShardOrigin {
    /// The shard's number K, from 0.
    pub index: usize,
    /// The number of shards N.
    pub count: usize,
    /// The multi-start's seed, shared by its shards.
    pub seed: u64,
}

/// The repair that made the solver's point certifiable: the centres and the container were
/// scaled by the factor that separates the overlapping pairs, then the container alone by the
/// one that holds the items still outside; `dilation` ≥ 1 is the container's linear scale in
/// all, which lowered the density from `density_before` to the summary's.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Repair {
    /// The container's linear scale s ≥ 1 (1: nothing needed repair).
    pub dilation: f64,
    /// Density of the solver's point before the dilation.
    pub density_before: f64,
}

impl Summary {
    /// The dilation by which the run repaired its packing, when it did.
    pub fn repair_dilation(&self) -> Option<f64> {
        self.repair.as_ref().map(|r| r.dilation)
    }

    /// The summary of `packing` (container, item count and density taken from it).
    pub fn new(
        packing: &Packing,
        objective: f64,
        wall_seconds: f64,
        local_minimisations: u64,
        certificate: CertificateCounts,
    ) -> Self {
        Summary {
            container: packing.container.clone(),
            items: packing.items.len(),
            density: packing.density(),
            objective,
            wall_seconds,
            local_minimisations,
            certificate,
            repair: None,
            start_kept: false,
            shard: None,
            not_reached: false,
            fixed_container: false,
        }
    }
}

/// The cell at `origin` reduced ([`implicit_packing::periodic::reduced`]) and every item
/// moved by a lattice translation into it.
fn wrap_into_reduced<const N: usize>(
    origin: &[f64; N],
    cell: &mut [[f64; N]; N],
    items: &mut [Item<N>],
) {
    use implicit_packing::periodic::{reduced, to_cartesian, to_fractional};
    *cell = reduced(cell);
    for item in items {
        let relative: [f64; N] = std::array::from_fn(|k| item.centre[k] - origin[k]);
        let s = to_fractional(cell, &relative);
        let inside = to_cartesian(cell, &s.map(|v| v - v.floor()));
        item.centre = std::array::from_fn(|k| origin[k] + inside[k]);
    }
}
