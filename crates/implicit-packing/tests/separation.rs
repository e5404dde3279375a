//! The separation certificate of the pair term ([`separated_along_centre_line`]): whenever it
//! says "separated", the full kernel — solved without any early exit — must give `f = 0` and a
//! gradient that is exactly zero, so that skipping the kernel changes nothing in the model.
//!
//! The certificate is only safe because a disjoint pair has both `d ≥ 1` and `U ≥ ε_ij`
//! (Prop. 3.3; eq. 34); the pairs are therefore put where either could fail: near contact
//! (PW85 `μ²` just above 1), along a common principal axis (where the certificate is tight, the
//! contact normal being the centre line), spheres (where `U = ε_ij d` exactly), and needles and
//! size ratios up to 1e3.
#![allow(clippy::needless_range_loop)]

use implicit_packing::derivatives::{PairGradient, pair_derivatives, pair_gradient};
use implicit_packing::pair::separated_along_centre_line;
use implicit_packing::{Body, Ellipse, Ellipsoid, pair_term};
use testkit::Rng;

fn sym3(m: &[[f64; 3]; 3]) -> [f64; 6] {
    [m[0][0], m[0][1], m[0][2], m[1][1], m[1][2], m[2][2]]
}

fn sym2(m: &[[f64; 2]; 2]) -> [f64; 3] {
    [m[0][0], m[0][1], m[1][1]]
}

fn is_zero<const N: usize>(g: &PairGradient<N>) -> bool {
    g.centre_i
        .iter()
        .chain(&g.centre_j)
        .chain(&g.angular_i)
        .chain(&g.angular_j)
        .all(|&v| v == 0.0)
}

/// Semi-axes of one of the shape families, scaled by `size`.
fn axes3(rng: &mut Rng, family: usize, size: f64) -> [f64; 3] {
    match family {
        0 => [size, 0.75 * size, 0.5 * size],
        1 => [size; 3],
        2 => [
            size,
            size * 10f64.powf(rng.range(-3.0, 0.0)),
            size * 10f64.powf(rng.range(-3.0, 0.0)),
        ],
        _ => [
            size * rng.range(0.3, 1.0),
            size * rng.range(0.3, 1.0),
            size * rng.range(0.3, 1.0),
        ],
    }
}

fn quaternion(rng: &mut Rng) -> [f64; 4] {
    loop {
        let q = rng.point::<4>(-1.0, 1.0);
        let n2: f64 = q.iter().map(|v| v * v).sum();
        if n2 > 1e-3 && n2 <= 1.0 {
            let n = n2.sqrt();
            return [q[0] / n, q[1] / n, q[2] / n, q[3] / n];
        }
    }
}

/// Checks one pair; returns whether the certificate said "separated".
fn check<const N: usize>(i: &Body<N>, j: &Body<N>, what: &str) -> bool {
    if !separated_along_centre_line(i, j) {
        return false;
    }
    let t = pair_term(i, j);
    assert!(
        t.f == 0.0 && t.d2 >= 1.0 && t.u >= t.eps,
        "{what}: certified separated but f = {:e} (d² = {:.17e}, U = {:e}, ε = {:e})\n{i:?}\n{j:?}",
        t.f,
        t.d2,
        t.u,
        t.eps
    );
    let d = pair_derivatives(i, j);
    assert!(
        d.f == 0.0 && is_zero(&d.grad_f),
        "{what}: certified separated but ∇f = {:?}\n{i:?}\n{j:?}",
        d.grad_f
    );
    let (f, g) = pair_gradient(i, j);
    assert!(f == 0.0 && is_zero(&g), "{what}: pair_gradient not zero");
    true
}

#[test]
fn certified_separated_pairs_have_zero_term_and_gradient_3d() {
    let mut rng = Rng::new(0x5E9A);
    let (mut certified, mut near_certified, mut overlapping) = (0usize, 0usize, 0usize);
    for n in 0..40_000 {
        let family = n % 4;
        let li = axes3(&mut rng, family, 1.0);
        let size = 10f64.powf(rng.range(-3.0, 3.0));
        let lj = axes3(&mut rng, family, size);
        let dir = rng.direction();
        let i = Ellipsoid::from_quaternion([0.0; 3], li, quaternion(&mut rng)).unwrap();
        let j0 = Ellipsoid::from_quaternion(dir, lj, quaternion(&mut rng)).unwrap();
        // Scale the centre distance to a target μ²: mostly just separated (1 + 10^−e, e up to
        // 13), a quarter within 20 % of contact on either side.
        let mu2 = pw85::contact_function(&dir, &sym3(&i.shape_matrix()), &sym3(&j0.shape_matrix()))
            .unwrap()
            .mu2;
        let target = if n % 4 == 3 {
            2f64.powf(rng.uniform() - 0.5)
        } else {
            1.0 + 10f64.powf(-rng.range(0.0, 13.0))
        };
        let s = (target / mu2).sqrt();
        let j = j0
            .with_centre([dir[0] * s, dir[1] * s, dir[2] * s])
            .unwrap();
        if check(&i, &j, "near contact") {
            certified += 1;
            if target < 1.0 + 1e-6 {
                near_certified += 1;
            }
        } else if pair_term(&i, &j).f > 0.0 {
            overlapping += 1;
        }
    }
    // Along a common principal axis the contact normal is the centre line: the certificate is
    // tight, and only the margin keeps it from certifying pairs at d² = 1 − rounding.
    let mut aligned = 0usize;
    for n in 0..20_000 {
        let family = n % 4;
        let li = axes3(&mut rng, family, 1.0);
        let size = 10f64.powf(rng.range(-2.0, 2.0));
        let lj = axes3(&mut rng, family, size);
        let i = Ellipsoid::from_quaternion([0.0; 3], li, quaternion(&mut rng)).unwrap();
        let q = i.rotation();
        let k = n % 3;
        let gap = 1.0 + 10f64.powf(-rng.range(6.0, 16.0));
        let dist = (li[k] + lj[k]) * gap;
        let centre = [q[0][k] * dist, q[1][k] * dist, q[2][k] * dist];
        let j = Ellipsoid::from_quaternion(centre, lj, i.quaternion()).unwrap();
        if check(&i, &j, "aligned") {
            aligned += 1;
        }
    }
    println!(
        "3D: {certified} of 40000 near-contact pairs certified ({near_certified} with μ² < 1 + 1e-6), {overlapping} overlapping; {aligned} of 20000 aligned pairs certified"
    );
    // The checks above must have had something to check, on both sides of the boundary.
    assert!(certified > 10_000 && near_certified > 1_000 && overlapping > 1_000);
    assert!(aligned > 5_000 && aligned < 20_000);
}

#[test]
fn certified_separated_pairs_have_zero_term_and_gradient_2d() {
    let mut rng = Rng::new(0x5E9B);
    let (mut certified, mut aligned) = (0usize, 0usize);
    for n in 0..20_000 {
        let a = axes3(&mut rng, n % 4, 1.0);
        let size = 10f64.powf(rng.range(-3.0, 3.0));
        let b = axes3(&mut rng, n % 4, size);
        let t = rng.range(0.0, 6.3);
        let dir = [t.cos(), t.sin()];
        let i = Ellipse::ellipse([0.0; 2], [a[0], a[1]], rng.range(-3.2, 3.2)).unwrap();
        let j0 = Ellipse::ellipse(dir, [b[0], b[1]], rng.range(-3.2, 3.2)).unwrap();
        let mu2 = pw85::contact_function(&dir, &sym2(&i.shape_matrix()), &sym2(&j0.shape_matrix()))
            .unwrap()
            .mu2;
        let target = 1.0 + 10f64.powf(-rng.range(0.0, 13.0));
        let s = (target / mu2).sqrt();
        let j = j0.with_centre([dir[0] * s, dir[1] * s]).unwrap();
        if check(&i, &j, "2D near contact") {
            certified += 1;
        }
        // Along a common principal axis.
        let theta = rng.range(-3.2, 3.2);
        let k = n % 2;
        let dist = (a[k] + b[k]) * (1.0 + 10f64.powf(-rng.range(6.0, 16.0)));
        let q = Ellipse::ellipse([0.0; 2], [a[0], a[1]], theta)
            .unwrap()
            .rotation();
        let i = Ellipse::ellipse([0.0; 2], [a[0], a[1]], theta).unwrap();
        let j = Ellipse::ellipse([q[0][k] * dist, q[1][k] * dist], [b[0], b[1]], theta).unwrap();
        if check(&i, &j, "2D aligned") {
            aligned += 1;
        }
    }
    println!("2D: {certified} of 20000 near-contact pairs certified; {aligned} of 20000 aligned");
    assert!(certified > 5_000 && aligned > 5_000 && aligned < 20_000);
}
