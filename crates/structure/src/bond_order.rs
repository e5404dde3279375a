//! Bond-orientational order of the centres, over the bonds shorter than a cutoff.
//!
//! **3D, Steinhardt.** Each item's `q_lm(i) = (1/n_i) Σ_j Y_lm(r̂_ij)` over its n_i bonds; its
//! local order `q_l(i) = √(4π/(2l+1) Σ_m |q_lm(i)|²)`; the global order
//! `Q_l = √(4π/(2l+1) Σ_m |Q̄_lm|²)` of the mean `Q̄_lm` of `q_lm(i)` over the items with a
//! bond. For l = 6: 0.5745 for the face-centred cubic crystal (12 bonds), 0.6285 for
//! body-centred cubic (8), about `1/√(n m)` for m items with n random bonds each.
//!
//! **2D, hexatic.** Each item's `ψ₆(i) = (1/n_i) Σ_j e^{6iθ_ij}`; the global `|⟨ψ₆(i)⟩|`
//! and the mean local `⟨|ψ₆(i)|⟩`, both 1 for the hexagonal crystal.
//!
//! # References
//! - P. J. Steinhardt, D. R. Nelson, M. Ronchetti, *Bond-orientational order in liquids and
//!   glasses*, Phys. Rev. B 28, 784 (1983), eqs. (1.1)–(1.3).
//! - D. R. Nelson, B. I. Halperin, *Dislocation-mediated melting in two dimensions*, Phys.
//!   Rev. B 19, 2457 (1979): ψ₆.

use crate::neighbours::Bonds;

/// Bond-orientational order: Steinhardt's in 3D, hexatic in 2D.
#[derive(Clone, Debug, PartialEq)]
pub enum BondOrder {
    /// Steinhardt's Q₄ and Q₆.
    Steinhardt {
        /// The bond cutoff (a distance of centres).
        cutoff: f64,
        /// Mean bonds per item.
        mean_bonds: f64,
        /// Global Q₄.
        q4: f64,
        /// Global Q₆.
        q6: f64,
        /// Mean over the items with a bond of q₄(i).
        q4_local: f64,
        /// Mean over the items with a bond of q₆(i).
        q6_local: f64,
    },
    /// The hexatic ψ₆.
    Hexatic {
        /// The bond cutoff (a distance of centres).
        cutoff: f64,
        /// Mean bonds per item.
        mean_bonds: f64,
        /// `|⟨ψ₆(i)⟩|` over the items with a bond.
        psi6: f64,
        /// `⟨|ψ₆(i)|⟩` over the items with a bond.
        psi6_local: f64,
    },
}

impl BondOrder {
    /// Its kind (`steinhardt` or `hexatic`) and its figures by name, as `structure.json` gives
    /// them: `cutoff`, `mean_bonds`, then `q4`, `q6`, `q4_local_mean`, `q6_local_mean` or
    /// `psi6`, `psi6_local_mean`.
    pub fn named_figures(&self) -> (&'static str, Vec<(&'static str, f64)>) {
        match *self {
            BondOrder::Steinhardt {
                cutoff,
                mean_bonds,
                q4,
                q6,
                q4_local,
                q6_local,
            } => (
                "steinhardt",
                vec![
                    ("cutoff", cutoff),
                    ("mean_bonds", mean_bonds),
                    ("q4", q4),
                    ("q6", q6),
                    ("q4_local_mean", q4_local),
                    ("q6_local_mean", q6_local),
                ],
            ),
            BondOrder::Hexatic {
                cutoff,
                mean_bonds,
                psi6,
                psi6_local,
            } => (
                "hexatic",
                vec![
                    ("cutoff", cutoff),
                    ("mean_bonds", mean_bonds),
                    ("psi6", psi6),
                    ("psi6_local_mean", psi6_local),
                ],
            ),
        }
    }
}

/// [`BondOrder`] over the bonds shorter than `cutoff` (at most the bonds' own cutoff).
pub fn bond_order<const N: usize>(bonds: &Bonds<N>, cutoff: f64) -> BondOrder {
    let short = |d: &[f64; N]| d.iter().map(|v| v * v).sum::<f64>() < cutoff * cutoff;
    let counted: usize = bonds
        .of_item
        .iter()
        .map(|l| l.iter().filter(|(_, d)| short(d)).count())
        .sum();
    let mean_bonds = counted as f64 / bonds.of_item.len().max(1) as f64;
    if N == 2 {
        let (mut sum, mut local, mut with) = ((0.0, 0.0), 0.0, 0usize);
        for list in &bonds.of_item {
            let (mut re, mut im, mut n) = (0.0, 0.0, 0usize);
            for (_, d) in list.iter().filter(|(_, d)| short(d)) {
                let t = 6.0 * d[1].atan2(d[0]);
                re += t.cos();
                im += t.sin();
                n += 1;
            }
            if n > 0 {
                let (re, im) = (re / n as f64, im / n as f64);
                sum = (sum.0 + re, sum.1 + im);
                local += re.hypot(im);
                with += 1;
            }
        }
        let w = with.max(1) as f64;
        return BondOrder::Hexatic {
            cutoff,
            mean_bonds,
            psi6: (sum.0 / w).hypot(sum.1 / w),
            psi6_local: local / w,
        };
    }
    let mut global = [Harmonics::new(4), Harmonics::new(6)];
    let mut local = [0.0, 0.0];
    let mut with = 0usize;
    for list in &bonds.of_item {
        let mut mine = [Harmonics::new(4), Harmonics::new(6)];
        let mut n = 0usize;
        for (_, d) in list.iter().filter(|(_, d)| short(d)) {
            let r = d.iter().map(|v| v * v).sum::<f64>().sqrt();
            if r == 0.0 {
                continue;
            }
            let (x, phi) = (d[2] / r, d[1].atan2(d[0]));
            mine[0].add(x, phi);
            mine[1].add(x, phi);
            n += 1;
        }
        if n == 0 {
            continue;
        }
        with += 1;
        for (k, h) in mine.iter_mut().enumerate() {
            h.scale(1.0 / n as f64);
            local[k] += h.invariant();
            global[k].add_all(h);
        }
    }
    let w = with.max(1) as f64;
    for h in &mut global {
        h.scale(1.0 / w);
    }
    BondOrder::Steinhardt {
        cutoff,
        mean_bonds,
        q4: global[0].invariant(),
        q6: global[1].invariant(),
        q4_local: local[0] / w,
        q6_local: local[1] / w,
    }
}

/// Sums of `Y_lm` for one l and m = 0 … l (those of −m follow: `Y_l,−m = (−1)^m conj Y_lm`).
#[derive(Clone, Copy)]
struct Harmonics {
    l: usize,
    re: [f64; 7],
    im: [f64; 7],
}

impl Harmonics {
    /// For l ≤ 6.
    fn new(l: usize) -> Self {
        Self {
            l: l.min(6),
            re: [0.0; 7],
            im: [0.0; 7],
        }
    }

    /// Adds `Y_lm(θ, φ)` for m = 0 … l, with `x = cos θ`.
    fn add(&mut self, x: f64, phi: f64) {
        let p = legendre(self.l, x);
        for m in 0..=self.l {
            let (s, c) = (m as f64 * phi).sin_cos();
            let y = normalisation(self.l, m) * p[m];
            self.re[m] += y * c;
            self.im[m] += y * s;
        }
    }

    fn add_all(&mut self, other: &Self) {
        for m in 0..=self.l {
            self.re[m] += other.re[m];
            self.im[m] += other.im[m];
        }
    }

    fn scale(&mut self, f: f64) {
        for m in 0..=self.l {
            self.re[m] *= f;
            self.im[m] *= f;
        }
    }

    /// `√(4π/(2l+1) Σ_{m=−l}^{l} |q_lm|²)`.
    fn invariant(&self) -> f64 {
        let sum: f64 = (0..=self.l)
            .map(|m| {
                let a = self.re[m] * self.re[m] + self.im[m] * self.im[m];
                if m == 0 { a } else { 2.0 * a }
            })
            .sum();
        (4.0 * std::f64::consts::PI / (2 * self.l + 1) as f64 * sum).sqrt()
    }
}

/// `√((2l+1)/(4π) (l−m)!/(l+m)!)`.
fn normalisation(l: usize, m: usize) -> f64 {
    let ratio: f64 = ((l - m + 1)..=(l + m)).map(|k| 1.0 / k as f64).product();
    ((2 * l + 1) as f64 / (4.0 * std::f64::consts::PI) * ratio).sqrt()
}

/// The associated Legendre functions `P_l^m(x)`, m = 0 … l, by the recurrences
/// `P_m^m = (−1)^m (2m−1)!! (1−x²)^{m/2}`, `P_{m+1}^m = x (2m+1) P_m^m`,
/// `(l−m) P_l^m = x (2l−1) P_{l−1}^m − (l+m−1) P_{l−2}^m`.
fn legendre(l_max: usize, x: f64) -> [f64; 7] {
    let mut out = [0.0; 7];
    let s = (1.0 - x * x).max(0.0).sqrt();
    let mut pmm = 1.0;
    for m in 0..=l_max {
        if m > 0 {
            pmm *= -((2 * m - 1) as f64) * s;
        }
        if m == l_max {
            out[m] = pmm;
            continue;
        }
        let (mut a, mut b) = (pmm, x * (2 * m + 1) as f64 * pmm);
        for l in (m + 2)..=l_max {
            let c = (x * (2 * l - 1) as f64 * b - (l + m - 1) as f64 * a) / (l - m) as f64;
            a = b;
            b = c;
        }
        out[m] = b;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The addition theorem: `Σ_m |Y_lm|² = (2l+1)/(4π)` on any direction, so one bond has
    /// q_l = 1.
    #[test]
    fn one_bond_has_local_order_one() {
        for (x, phi) in [(0.3, 1.1), (-0.9, 4.0), (1.0, 0.0), (0.0, 2.5)] {
            let mut h = Harmonics::new(6);
            h.add(x, phi);
            assert!((h.invariant() - 1.0).abs() < 1e-13, "{x} {phi}");
            let mut h = Harmonics::new(4);
            h.add(x, phi);
            assert!((h.invariant() - 1.0).abs() < 1e-13, "{x} {phi}");
        }
    }

    fn lattice_bonds(basis: &[[f64; 3]]) -> Bonds<3> {
        // One item with its neighbour shell.
        Bonds {
            cutoff: 10.0,
            of_item: vec![basis.iter().map(|d| (0, *d)).collect()],
        }
    }

    #[test]
    fn fcc_and_bcc_shells_give_steinhardts_values() {
        let mut fcc = Vec::new();
        for a in [-1.0, 1.0] {
            for b in [-1.0, 1.0] {
                fcc.extend([[a, b, 0.0], [a, 0.0, b], [0.0, a, b]]);
            }
        }
        let BondOrder::Steinhardt { q4, q6, .. } = bond_order(&lattice_bonds(&fcc), 2.0) else {
            panic!()
        };
        assert!((q4 - 0.19094).abs() < 1e-5, "{q4}");
        assert!((q6 - 0.57452).abs() < 1e-5, "{q6}");
        let mut bcc = Vec::new();
        for a in [-1.0, 1.0] {
            for b in [-1.0, 1.0] {
                for c in [-1.0, 1.0] {
                    bcc.push([a, b, c]);
                }
            }
        }
        let BondOrder::Steinhardt { q4, q6, .. } = bond_order(&lattice_bonds(&bcc), 2.0) else {
            panic!()
        };
        assert!((q4 - 0.50918).abs() < 1e-5, "{q4}");
        assert!((q6 - 0.62854).abs() < 1e-5, "{q6}");
    }

    #[test]
    fn a_hexagonal_shell_has_psi6_one() {
        let shell: Vec<(usize, [f64; 2])> = (0..6)
            .map(|k| {
                let t = 0.2 + k as f64 * std::f64::consts::PI / 3.0;
                (0, [t.cos(), t.sin()])
            })
            .collect();
        let bonds = Bonds {
            cutoff: 2.0,
            of_item: vec![shell],
        };
        let BondOrder::Hexatic {
            psi6, psi6_local, ..
        } = bond_order(&bonds, 1.5)
        else {
            panic!()
        };
        assert!((psi6 - 1.0).abs() < 1e-12 && (psi6_local - 1.0).abs() < 1e-12);
    }
}
