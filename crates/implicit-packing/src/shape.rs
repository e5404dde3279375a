//! Shapes and their parametrisation: centres, semi-axes, rotations (paper eqs. 1–2), quaternions.
//!
//! An ellipsoid is
//!
//! ```text
//! E_i = { x : (x − c_i)ᵀ Q_i P_i⁻¹ Q_iᵀ (x − c_i) ≤ 1 },   P_i^½ = diag(l_i1, …, l_in)
//! ```
//!
//! so semi-axis `l_ik` lies along **column k** of the rotation `Q_i` (semi-axes are not sorted).
//!
//! * 2D (eq. 1): `Q = [[cos θ, −sin θ], [sin θ, cos θ]]`.
//! * 3D (eq. 2): `Q = R_z(ψ) R_y(θ) R_x(φ)`; angles are stored in the order `[φ, θ, ψ]`.
//! * 3D from a quaternion `(w, x, y, z)`: the Hamilton active rotation `Q v = q v q*`,
//!   normalised by `w² + x² + y² + z²`.
//!
//! Derivatives with respect to angles are expressed through the world-frame angular velocity of
//! each angle: `∂Q/∂α = [ω_α]× Q`. Eq. 2 gives `ω_ψ = e_z`, `ω_θ = R_z(ψ) e_y`,
//! `ω_φ = R_z(ψ) R_y(θ) e_x` (the first column of `Q`); in 2D `ω_θ = e_z`.
//!
//! # References
//! E. G. Birgin, R. D. Lobato, J. M. Martínez, *A nonlinear programming model with implicit
//! variables for packing ellipsoids*, J. Global Optim. (2016), Section 3, eqs. (1)–(2).

use crate::error::Error;
use std::f64::consts::PI;

/// Largest magnitude accepted for a coordinate or a semi-axis, and the reciprocal of the smallest
/// semi-axis: keeps every intermediate quantity (ratios of semi-axes squared, squared distances in
/// scaled frames) far from overflow and underflow.
pub const MAX_MAGNITUDE: f64 = 1e30;

/// Tolerance on `|q|² − 1` for a quaternion to be accepted (and then normalised exactly).
pub const QUATERNION_TOLERANCE: f64 = 1e-6;

/// An ellipse (`N = 2`) or an ellipsoid (`N = 3`): centre, semi-axes and rotation.
///
/// Built through validated constructors; the fields are private so that every `Body` in the
/// crate has finite coordinates, positive semi-axes in `[1e-30, 1e30]` and an orthogonal `Q`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Body<const N: usize> {
    centre: [f64; N],
    semi_axes: [f64; N],
    rotation: [[f64; N]; N],
    // Smallest and largest semi-axis, cached: the pair term needs them for ε_ij, the bounding
    // spheres and the choice of route, every time.
    l_min: f64,
    l_max: f64,
    // 1/l_k, cached: the pair kernel scales by them on every pair that reaches it (N
    // divisions per body once instead of 2N per pair).
    inv_semi_axes: [f64; N],
}

fn extremes<const N: usize>(l: &[f64; N]) -> (f64, f64) {
    l.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &v| {
        (lo.min(v), hi.max(v))
    })
}

/// An ellipse in the plane.
pub type Ellipse = Body<2>;
/// An ellipsoid in space.
pub type Ellipsoid = Body<3>;

pub(crate) fn check_centre<const N: usize>(
    item: Option<usize>,
    centre: &[f64; N],
) -> Result<(), Error> {
    for (axis, &value) in centre.iter().enumerate() {
        if !(value.is_finite() && value.abs() <= MAX_MAGNITUDE) {
            return Err(Error::NonFiniteCentre { item, axis, value });
        }
    }
    Ok(())
}

pub(crate) fn check_semi_axes(item: Option<usize>, semi_axes: &[f64]) -> Result<(), Error> {
    for (axis, &value) in semi_axes.iter().enumerate() {
        if !(value.is_finite() && (1.0 / MAX_MAGNITUDE..=MAX_MAGNITUDE).contains(&value)) {
            return Err(Error::InvalidSemiAxis { item, axis, value });
        }
    }
    Ok(())
}

pub(crate) fn check_angles(item: Option<usize>, angles: &[f64]) -> Result<(), Error> {
    for (angle, &value) in angles.iter().enumerate() {
        if !value.is_finite() {
            return Err(Error::NonFiniteAngle { item, angle, value });
        }
    }
    Ok(())
}

impl<const N: usize> Body<N> {
    /// The centre `c_i`.
    pub fn centre(&self) -> [f64; N] {
        self.centre
    }

    /// The semi-axes `l_i1, …, l_in` (the diagonal of `P_i^½`); `l_ik` lies along column k of `Q_i`.
    pub fn semi_axes(&self) -> [f64; N] {
        self.semi_axes
    }

    /// The rotation `Q_i`, row-major: `rotation()[r][k]` is row r of column k.
    pub fn rotation(&self) -> [[f64; N]; N] {
        self.rotation
    }

    /// Radius of the smallest ball about the centre that encloses the body: `λ_max(P_i^½)`
    /// (Section 5.2).
    pub fn bounding_radius(&self) -> f64 {
        self.l_max
    }

    /// The reciprocals of the semi-axes, the diagonal of `P_i^−½`.
    pub(crate) fn inv_semi_axes(&self) -> [f64; N] {
        self.inv_semi_axes
    }

    /// The smallest semi-axis, `λ_min(P_i^½)`.
    pub fn min_semi_axis(&self) -> f64 {
        self.l_min
    }

    /// Whether the body is round (a circle or a ball): all semi-axes equal, so that its
    /// rotation does not matter.
    pub fn is_round(&self) -> bool {
        self.l_min == self.l_max
    }

    fn assemble(centre: [f64; N], semi_axes: [f64; N], rotation: [[f64; N]; N]) -> Self {
        let (l_min, l_max) = extremes(&semi_axes);
        Body {
            centre,
            semi_axes,
            rotation,
            l_min,
            l_max,
            inv_semi_axes: semi_axes.map(|l| 1.0 / l),
        }
    }

    /// The same body with another centre (validated).
    pub fn with_centre(mut self, centre: [f64; N]) -> Result<Self, Error> {
        check_centre(None, &centre)?;
        self.centre = centre;
        Ok(self)
    }

    /// The body scaled by `ν > 0` about the origin: centre `ν c`, semi-axes `ν l` (Definition 4.1).
    pub fn scaled(&self, nu: f64) -> Result<Self, Error> {
        let mut centre = self.centre;
        let mut semi_axes = self.semi_axes;
        centre.iter_mut().for_each(|x| *x *= nu);
        semi_axes.iter_mut().for_each(|x| *x *= nu);
        Self::checked(centre, semi_axes, || Ok(self.rotation))
    }

    /// A body from a checked centre and checked semi-axes, then the rotation `rotation` makes
    /// (which may refuse its own input): the checks of every public constructor, in their order.
    fn checked(
        centre: [f64; N],
        semi_axes: [f64; N],
        rotation: impl FnOnce() -> Result<[[f64; N]; N], Error>,
    ) -> Result<Self, Error> {
        check_centre(None, &centre)?;
        check_semi_axes(None, &semi_axes)?;
        Ok(Body::assemble(centre, semi_axes, rotation()?))
    }

    /// The shape matrix `M = Q P Qᵀ` of `{x : (x − c)ᵀ M⁻¹ (x − c) ≤ 1}`.
    pub fn shape_matrix(&self) -> [[f64; N]; N] {
        let mut m = [[0.0; N]; N];
        for (r, row) in m.iter_mut().enumerate() {
            for (s, entry) in row.iter_mut().enumerate() {
                *entry = (0..N)
                    .map(|k| {
                        self.rotation[r][k]
                            * self.semi_axes[k]
                            * self.semi_axes[k]
                            * self.rotation[s][k]
                    })
                    .sum();
            }
        }
        m
    }

    /// Builds a body from a rotation that the crate computed itself (orthogonal by construction).
    pub(crate) fn from_parts_unchecked(
        centre: [f64; N],
        semi_axes: [f64; N],
        rotation: [[f64; N]; N],
    ) -> Self {
        Body::assemble(centre, semi_axes, rotation)
    }
}

impl<const N: usize> Body<N> {
    /// A body in either dimension from its orientation: `[θ]`, the angle of eq. 1, in 2D; a
    /// quaternion `[w, x, y, z]` (as [`Body::from_quaternion`]) in 3D. For code generic over
    /// the dimension (random orientations, items read from a file).
    ///
    /// # Errors
    /// Those of [`Body::ellipse`] and [`Body::from_quaternion`]; [`Error::LengthMismatch`]
    /// when `orientation` does not have 1 (2D) or 4 (3D) values.
    pub fn oriented(
        centre: [f64; N],
        semi_axes: [f64; N],
        orientation: &[f64],
    ) -> Result<Self, Error> {
        Self::checked(centre, semi_axes, || {
            let rotation: Vec<[f64; 3]> = match (N, orientation) {
                (2, &[theta]) => {
                    check_angles(None, &[theta])?;
                    rotation_2d(theta)
                        .iter()
                        .map(|r| [r[0], r[1], 0.0])
                        .collect()
                }
                (3, &[w, x, y, z]) => rotation_from_quaternion([w, x, y, z])?.to_vec(),
                _ => {
                    return Err(Error::LengthMismatch {
                        what: "orientation",
                        expected: if N == 2 { 1 } else { 4 },
                        found: orientation.len(),
                    });
                }
            };
            Ok(std::array::from_fn(|r| {
                std::array::from_fn(|c| rotation[r][c])
            }))
        })
    }
}

impl Body<2> {
    /// An ellipse with centre `c`, semi-axes `(a, b)` along the columns of `Q(θ)` (eq. 1).
    pub fn ellipse(centre: [f64; 2], semi_axes: [f64; 2], theta: f64) -> Result<Self, Error> {
        Self::checked(centre, semi_axes, || {
            check_angles(None, &[theta])?;
            Ok(rotation_2d(theta))
        })
    }
}

impl Body<3> {
    /// An ellipsoid with centre `c`, semi-axes `(a, b, c)` and the angles `[φ, θ, ψ]` of eq. 2.
    pub fn from_angles(
        centre: [f64; 3],
        semi_axes: [f64; 3],
        angles: [f64; 3],
    ) -> Result<Self, Error> {
        Self::checked(centre, semi_axes, || {
            check_angles(None, &angles)?;
            Ok(rotation_3d(angles))
        })
    }

    /// An ellipsoid whose rotation is the quaternion `(w, x, y, z)` (Hamilton, active).
    ///
    /// The quaternion must be finite with `| |q|² − 1 | ≤ 1e-6`; it is then normalised exactly, so
    /// that quaternions rounded to `f64` give the rotation they stand for.
    pub fn from_quaternion(
        centre: [f64; 3],
        semi_axes: [f64; 3],
        q: [f64; 4],
    ) -> Result<Self, Error> {
        Self::checked(centre, semi_axes, || rotation_from_quaternion(q))
    }

    /// The rotation as a unit quaternion `(w, x, y, z)` with `w ≥ 0`.
    pub fn quaternion(&self) -> [f64; 4] {
        quaternion_from_rotation(&self.rotation)
    }

    /// The angles `[φ, θ, ψ]` of eq. 2 that give this rotation (`θ ∈ [−π/2, π/2]`).
    pub fn angles(&self) -> [f64; 3] {
        angles_from_rotation(&self.rotation)
    }
}

/// Eq. 1: `Q(θ) = [[cos θ, −sin θ], [sin θ, cos θ]]`.
pub fn rotation_2d(theta: f64) -> [[f64; 2]; 2] {
    let (s, c) = theta.sin_cos();
    [[c, -s], [s, c]]
}

/// Eq. 2: `Q(φ, θ, ψ) = R_z(ψ) R_y(θ) R_x(φ)`, angles given as `[φ, θ, ψ]` (the convention of
/// `pw85::shape::rotation_from_angles`, which computes it).
pub fn rotation_3d(angles: [f64; 3]) -> [[f64; 3]; 3] {
    pw85::shape::rotation_from_angles(&angles)
}

/// World-frame angular velocities `ω_φ, ω_θ, ω_ψ` of the angles of eq. 2:
/// `∂Q/∂α = [ω_α]× Q`.
pub fn angular_velocities_3d(angles: [f64; 3]) -> [[f64; 3]; 3] {
    let [_, theta, psi] = angles;
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = psi.sin_cos();
    [[ct * cp, ct * sp, -st], [-sp, cp, 0.0], [0.0, 0.0, 1.0]]
}

/// Eq. 2's rotation and the angular velocities of its angles from one set of sines and
/// cosines: the model needs both for every ellipsoid at every evaluation, and the sines and
/// cosines are most of their cost, so the three are computed in one pass
/// ([`crate::trig::sin_cos3`], within 1 ulp of the C library's). The same expressions as
/// `pw85::shape::rotation_from_angles` (hence [`rotation_3d`]) and [`angular_velocities_3d`],
/// in the same order; the entries agree with theirs to a few ulps (a unit test checks it).
pub(crate) fn rotation_and_velocities_3d(angles: [f64; 3]) -> ([[f64; 3]; 3], [[f64; 3]; 3]) {
    let [(sf, cf), (st, ct), (sp, cp)] = crate::trig::sin_cos3(angles);
    (
        [
            [ct * cp, sf * st * cp - cf * sp, sf * sp + cf * st * cp],
            [ct * sp, cf * cp + sf * st * sp, cf * st * sp - sf * cp],
            [-st, sf * ct, cf * ct],
        ],
        [[ct * cp, ct * sp, -st], [-sp, cp, 0.0], [0.0, 0.0, 1.0]],
    )
}

/// The rotation of a quaternion `(w, x, y, z)`: `Q v = q v q* / |q|²`.
pub fn rotation_from_quaternion(q: [f64; 4]) -> Result<[[f64; 3]; 3], Error> {
    let norm2 = q.iter().map(|v| v * v).sum::<f64>();
    if !(q.iter().all(|v| v.is_finite()) && (norm2 - 1.0).abs() <= QUATERNION_TOLERANCE) {
        return Err(Error::InvalidQuaternion {
            item: None,
            quaternion: q,
            norm2,
        });
    }
    // The same normalisation by |q|² as pw85's, which computes the matrix; it cannot fail on
    // the finite, nearly unit quaternion checked above.
    pw85::shape::rotation_from_quaternion(&q).map_err(|_| Error::InvalidQuaternion {
        item: None,
        quaternion: q,
        norm2,
    })
}

/// A unit quaternion `(w, x, y, z)`, `w ≥ 0`, of a rotation matrix (Shepperd's branch choice:
/// the largest of `w², x², y², z²` is taken from the diagonal, the others from off-diagonals).
pub fn quaternion_from_rotation(m: &[[f64; 3]; 3]) -> [f64; 4] {
    let tr = m[0][0] + m[1][1] + m[2][2];
    let cand = [tr, m[0][0], m[1][1], m[2][2]];
    let mut best = 0;
    for k in 1..4 {
        if cand[k] > cand[best] {
            best = k;
        }
    }
    let mut q = match best {
        0 => {
            let w = 0.5 * (1.0 + tr).max(0.0).sqrt();
            let f = 0.25 / w;
            [
                w,
                (m[2][1] - m[1][2]) * f,
                (m[0][2] - m[2][0]) * f,
                (m[1][0] - m[0][1]) * f,
            ]
        }
        1 => {
            let x = 0.5 * (1.0 + m[0][0] - m[1][1] - m[2][2]).max(0.0).sqrt();
            let f = 0.25 / x;
            [
                (m[2][1] - m[1][2]) * f,
                x,
                (m[0][1] + m[1][0]) * f,
                (m[0][2] + m[2][0]) * f,
            ]
        }
        2 => {
            let y = 0.5 * (1.0 - m[0][0] + m[1][1] - m[2][2]).max(0.0).sqrt();
            let f = 0.25 / y;
            [
                (m[0][2] - m[2][0]) * f,
                (m[0][1] + m[1][0]) * f,
                y,
                (m[1][2] + m[2][1]) * f,
            ]
        }
        _ => {
            let z = 0.5 * (1.0 - m[0][0] - m[1][1] + m[2][2]).max(0.0).sqrt();
            let f = 0.25 / z;
            [
                (m[1][0] - m[0][1]) * f,
                (m[0][2] + m[2][0]) * f,
                (m[1][2] + m[2][1]) * f,
                z,
            ]
        }
    };
    if q[0] < 0.0 {
        q.iter_mut().for_each(|v| *v = -*v);
    }
    let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    q.iter_mut().for_each(|v| *v /= n);
    q
}

/// The angles `[φ, θ, ψ]` of eq. 2 of a rotation matrix, `θ ∈ [−π/2, π/2]`; at gimbal lock
/// (`cos θ = 0`) `φ` is set to 0 and the whole rotation about the axis goes to `ψ`.
pub fn angles_from_rotation(m: &[[f64; 3]; 3]) -> [f64; 3] {
    let st = (-m[2][0]).clamp(-1.0, 1.0);
    let ct = m[0][0].hypot(m[1][0]);
    let theta = st.atan2(ct);
    if ct > 1e-12 {
        let phi = m[2][1].atan2(m[2][2]);
        let psi = m[1][0].atan2(m[0][0]);
        [phi, theta, psi]
    } else {
        // Q = R_z(ψ) R_y(±π/2) R_x(0): the second column is (−sin ψ, cos ψ, 0).
        let psi = (-m[0][1]).atan2(m[1][1]);
        [0.0, theta, psi]
    }
}

/// How an item's rotation is stated outside the model: the angle θ of eq. 1 in 2D, a unit
/// quaternion `(w, x, y, z)` in 3D (the forms of packing files).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Orientation {
    /// The angle θ of eq. 1 (2D).
    Angle(f64),
    /// A unit quaternion `(w, x, y, z)`, Hamilton, active (3D).
    Quaternion([f64; 4]),
}

impl Orientation {
    /// The values, as [`Body::oriented`] takes them.
    pub fn values(&self) -> &[f64] {
        match self {
            Orientation::Angle(theta) => std::slice::from_ref(theta),
            Orientation::Quaternion(q) => q,
        }
    }
}

/// An item as it is stated outside the model: centre, semi-axes and the orientation its
/// rotation is built from. A packing stated by items and written with round-trip precision
/// reads back as the same bodies, bit for bit, so a certificate of [`Item::body`]s holds for the
/// files.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Item<const N: usize> {
    /// The centre.
    pub centre: [f64; N],
    /// The semi-axes, along the columns of the rotation.
    pub semi_axes: [f64; N],
    /// The orientation.
    pub orientation: Orientation,
}

impl<const N: usize> Item<N> {
    /// The item stating `body`: θ = atan2(Q₂₁, Q₁₁) in 2D, the quaternion of `Q` with `w ≥ 0` in
    /// 3D. Its [`Item::body`] is `body` up to the rounding of that conversion.
    pub fn stating(body: &Body<N>) -> Self {
        let r = body.rotation();
        let orientation = if N == 2 {
            Orientation::Angle(r[1][0].atan2(r[0][0]))
        } else {
            let m: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|k| r[i][k]));
            Orientation::Quaternion(quaternion_from_rotation(&m))
        };
        Item {
            centre: body.centre(),
            semi_axes: body.semi_axes(),
            orientation,
        }
    }

    /// The body this item states ([`Body::oriented`]).
    ///
    /// # Errors
    /// Those of [`Body::oriented`], naming no item: callers name it.
    pub fn body(&self) -> Result<Body<N>, Error> {
        Body::oriented(self.centre, self.semi_axes, self.orientation.values())
    }

    /// Its area πab (2D) or volume 4/3 πabc (3D).
    pub fn measure(&self) -> f64 {
        let unit = if N == 2 { PI } else { 4.0 / 3.0 * PI };
        self.semi_axes.iter().fold(unit, |m, l| m * l)
    }
}

impl Item<2> {
    /// The ellipse with centre `c`, semi-axes `(a, b)` and the angle θ of eq. 1.
    pub fn ellipse(centre: [f64; 2], semi_axes: [f64; 2], theta: f64) -> Self {
        Item {
            centre,
            semi_axes,
            orientation: Orientation::Angle(theta),
        }
    }

    /// The angle θ of eq. 1; NaN when the orientation is a quaternion (which no ellipse has,
    /// and which [`Item::body`] refuses).
    pub fn theta(&self) -> f64 {
        match self.orientation {
            Orientation::Angle(theta) => theta,
            Orientation::Quaternion(_) => f64::NAN,
        }
    }
}

impl Item<3> {
    /// The ellipsoid with centre `c`, semi-axes `(a, b, c)` and the quaternion `(w, x, y, z)`.
    pub fn ellipsoid(centre: [f64; 3], semi_axes: [f64; 3], quaternion: [f64; 4]) -> Self {
        Item {
            centre,
            semi_axes,
            orientation: Orientation::Quaternion(quaternion),
        }
    }

    /// The quaternion `(w, x, y, z)`; NaNs when the orientation is an angle (which no
    /// ellipsoid has, and which [`Item::body`] refuses).
    pub fn quaternion(&self) -> [f64; 4] {
        match self.orientation {
            Orientation::Quaternion(q) => q,
            Orientation::Angle(_) => [f64::NAN; 4],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn eq2_matches_product_of_elementary_rotations() {
        let ang = [0.3, -1.1, 2.4];
        let q = rotation_3d(ang);
        let rx = |a: f64| {
            [
                [1.0, 0.0, 0.0],
                [0.0, a.cos(), -a.sin()],
                [0.0, a.sin(), a.cos()],
            ]
        };
        let ry = |a: f64| {
            [
                [a.cos(), 0.0, a.sin()],
                [0.0, 1.0, 0.0],
                [-a.sin(), 0.0, a.cos()],
            ]
        };
        let rz = |a: f64| {
            [
                [a.cos(), -a.sin(), 0.0],
                [a.sin(), a.cos(), 0.0],
                [0.0, 0.0, 1.0],
            ]
        };
        let mul = |a: [[f64; 3]; 3], b: [[f64; 3]; 3]| {
            let mut c = [[0.0; 3]; 3];
            for i in 0..3 {
                for j in 0..3 {
                    c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
                }
            }
            c
        };
        let p = mul(rz(ang[2]), mul(ry(ang[1]), rx(ang[0])));
        for i in 0..3 {
            for j in 0..3 {
                assert!(close(p[i][j], q[i][j], 1e-15));
            }
        }
    }

    #[test]
    fn angular_velocities_match_finite_differences() {
        let ang = [0.7, 0.4, -2.0];
        let w = angular_velocities_3d(ang);
        let q = rotation_3d(ang);
        for a in 0..3 {
            let h = 1e-6;
            let mut p = ang;
            p[a] += h;
            let qp = rotation_3d(p);
            let mut m = ang;
            m[a] -= h;
            let qm = rotation_3d(m);
            for col in 0..3 {
                let v = [q[0][col], q[1][col], q[2][col]];
                let cross = [
                    w[a][1] * v[2] - w[a][2] * v[1],
                    w[a][2] * v[0] - w[a][0] * v[2],
                    w[a][0] * v[1] - w[a][1] * v[0],
                ];
                for row in 0..3 {
                    let fd = (qp[row][col] - qm[row][col]) / (2.0 * h);
                    assert!(close(fd, cross[row], 1e-8), "angle {a} col {col} row {row}");
                }
            }
        }
    }

    #[test]
    fn rotation_and_velocities_agree_with_the_separate_functions() {
        for ang in [
            [0.3, -1.1, 2.4],
            [-2.9, 1.5, 0.01],
            [1e-9, -0.7, -3.1],
            [40.0, -7.0, 1e3],
        ] {
            let (q, w) = rotation_and_velocities_3d(ang);
            let (q0, w0) = (rotation_3d(ang), angular_velocities_3d(ang));
            for r in 0..3 {
                for c in 0..3 {
                    // Entries are sums of up to two products of three factors, each within
                    // an ulp: a few units of 2⁻⁵³ absolute.
                    assert!((q[r][c] - q0[r][c]).abs() <= 6e-16, "Q {ang:?} {r} {c}");
                    assert!((w[r][c] - w0[r][c]).abs() <= 6e-16, "ω {ang:?} {r} {c}");
                }
            }
        }
    }

    #[test]
    fn quaternion_round_trip_and_angles_round_trip() {
        for &ang in &[
            [0.1, 0.2, 0.3],
            [-2.0, 1.2, 3.0],
            [3.0, -1.5, -0.2],
            [0.0, std::f64::consts::FRAC_PI_2, 0.4],
        ] {
            let q = rotation_3d(ang);
            let quat = quaternion_from_rotation(&q);
            let back = rotation_from_quaternion(quat).unwrap();
            let again = rotation_3d(angles_from_rotation(&q));
            for i in 0..3 {
                for j in 0..3 {
                    assert!(close(back[i][j], q[i][j], 1e-14));
                    assert!(close(again[i][j], q[i][j], 1e-12));
                }
            }
        }
    }

    #[test]
    fn bad_input_is_rejected_with_named_item() {
        assert!(matches!(
            Body::ellipse([0.0, 0.0], [1.0, -2.0], 0.0),
            Err(Error::InvalidSemiAxis { axis: 1, .. })
        ));
        assert!(matches!(
            Body::ellipse([f64::NAN, 0.0], [1.0, 2.0], 0.0),
            Err(Error::NonFiniteCentre { axis: 0, .. })
        ));
        assert!(matches!(
            Body::from_quaternion([0.0; 3], [1.0; 3], [0.0; 4]),
            Err(Error::InvalidQuaternion { .. })
        ));
        assert!(matches!(
            Body::from_quaternion([0.0; 3], [1.0; 3], [1.0, 1.0, 0.0, 0.0]),
            Err(Error::InvalidQuaternion { .. })
        ));
        assert!(matches!(
            Body::from_angles([0.0; 3], [1.0, 0.0, 1.0], [0.0; 3]),
            Err(Error::InvalidSemiAxis { axis: 1, .. })
        ));
        assert!(matches!(
            Body::from_angles([0.0; 3], [1.0; 3], [0.0, f64::INFINITY, 0.0]),
            Err(Error::NonFiniteAngle { angle: 1, .. })
        ));
        let msg = Error::InvalidSemiAxis {
            item: Some(7),
            axis: 2,
            value: -1.0,
        }
        .to_string();
        assert!(msg.contains("item 7") && msg.contains("semi-axis 2") && msg.contains("-1"));
    }
}
