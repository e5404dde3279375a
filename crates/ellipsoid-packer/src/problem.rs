//! The model as the augmented Lagrangian sees it ([`auglag::Problem`]).

use auglag::Phr;
use implicit_packing::containment::ContainerShape;
use implicit_packing::model::{Model, ModelGradient};
use std::cell::RefCell;

/// The model as an [`auglag::Problem`]: objective = container measure, two equality
/// constraints h₁ = overlap, h₂ = containment, evaluated together. In energy mode (a fixed
/// container, [`Adapter::in_energy_mode`]) the objective is h₁ + h₂ and there are no constraints.
pub(crate) struct Adapter<'a, const N: usize> {
    model: RefCell<&'a mut Model<N>>,
    gradient: RefCell<ModelGradient>,
    /// The point of the last Hessian product, with its constraint values and gradients: a
    /// truncated-Newton step asks for many products at one point.
    hessian_point: RefCell<HessianPoint>,
    product: RefCell<ModelGradient>,
    lower: f64,
    centre_bound: f64,
    /// Feasibility mode: the container variables' fixed values; the objective is then 0.
    fixed: Option<Vec<f64>>,
    /// Angle variables held at these values: `(variable, value)`.
    frozen: Vec<(usize, f64)>,
    /// Energy mode: overlap + containment is the objective, unconstrained.
    energy: bool,
}

/// A point with the overlap and containment values and the three gradients there.
#[derive(Default)]
struct HessianPoint {
    x: Vec<f64>,
    overlap: f64,
    containment: f64,
    gradient: ModelGradient,
}

impl<'a, const N: usize> Adapter<'a, N> {
    pub(crate) fn new(model: &'a mut Model<N>, centre_bound: f64, fixed: Option<Vec<f64>>) -> Self {
        // Every item contains a ball of its smallest semi-axis, so no container dimension can
        // be smaller than the largest of those: a safe lower bound that keeps the container
        // from collapsing through zero during early iterations.
        let lower = model
            .semi_axes()
            .iter()
            .map(|l| l.iter().fold(f64::INFINITY, |a, &b| a.min(b)))
            .fold(0.0_f64, f64::max);
        Self {
            model: RefCell::new(model),
            gradient: RefCell::new(ModelGradient::default()),
            hessian_point: RefCell::new(HessianPoint::default()),
            product: RefCell::new(ModelGradient::default()),
            lower,
            centre_bound,
            fixed,
            frozen: Vec::new(),
            energy: false,
        }
    }

    /// Energy mode (with a fixed container only): the sum of the overlap and containment
    /// measures, `E = h₁ + h₂ ≥ 0` with `E = 0` exactly on packings, minimised as an objective
    /// without constraints. The penalty of the augmented Lagrangian, `λh + ρh²/2` with λ = 0
    /// in its first outer iteration, is quartic in the penetrations there; E is quadratic, as
    /// the overlap energies minimised in jamming studies. On random starts of 3·10⁴ and 10⁵
    /// ellipsoids compressed to φ = 0.6 the last placement took 751 and 1 000 inner
    /// iterations against 901 and 1 297 with the Lagrangian.
    pub(crate) fn in_energy_mode(mut self, energy: bool) -> Self {
        self.energy = energy && self.fixed.is_some();
        self
    }

    /// E and, when asked, ∇E (see [`Adapter::in_energy_mode`]); NaN where the model refuses `x`.
    fn energy(&self, x: &[f64], grad: Option<&mut [f64]>) -> f64 {
        let mut model = self.model.borrow_mut();
        let Some(g) = grad else {
            return model
                .evaluate(x, None)
                .map_or(f64::NAN, |e| e.overlap + e.containment);
        };
        let mut mg = self.gradient.borrow_mut();
        match model.evaluate(x, Some(&mut mg)) {
            Ok(e) => {
                for ((g, o), c) in g.iter_mut().zip(&mg.overlap).zip(&mg.containment) {
                    *g = o + c;
                }
                e.overlap + e.containment
            }
            Err(_) => {
                g.fill(f64::NAN);
                f64::NAN
            }
        }
    }

    /// The same with the angle variables of the items marked in `items` held at their values
    /// in `x`: those items keep their orientation.
    pub(crate) fn with_frozen_orientations(mut self, items: &[bool], x: &[f64]) -> Self {
        let model = self.model.borrow();
        let layout = model.layout();
        let frozen = items
            .iter()
            .enumerate()
            .filter(|&(i, frozen)| *frozen && i < layout.items())
            .flat_map(|(i, _)| (layout.start(i) + N..layout.range(i).end).map(|k| (k, x[k])))
            .filter(|(k, _)| *k < x.len())
            .collect();
        drop(model);
        self.frozen = frozen;
        self
    }

    /// The factor of the objective in the Lagrangian: 0 in feasibility mode, where the
    /// container measure is a constant that must not pull on anything.
    fn objective_weight(&self, phr: &Phr<'_>) -> f64 {
        if self.fixed.is_some() {
            0.0
        } else {
            phr.objective_scale()
        }
    }

    /// Runs `f` on the model between two evaluations (its values are a function of the point
    /// alone, so a certificate taken here changes nothing the solver sees).
    pub(crate) fn with_model<R>(&self, f: impl FnOnce(&mut Model<N>) -> R) -> R {
        f(&mut self.model.borrow_mut())
    }

    fn body_variables(&self) -> usize {
        self.model.borrow().layout().item_variables()
    }
}

impl<const N: usize> auglag::Problem for Adapter<'_, N> {
    fn dim(&self) -> usize {
        self.model.borrow().var_count()
    }

    fn bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        let start = self.body_variables();
        lower[start..].fill(self.lower);
        if self.model.borrow().container_kind() == ContainerShape::Periodic {
            // The tilts of a periodic cell (after its N diagonal entries) have either sign;
            // the bound only keeps them finite (the model is exact for any tilt).
            lower[start + N..].fill(-self.centre_bound);
            upper[start + N..].fill(self.centre_bound);
        }
        if let Some(fixed) = &self.fixed {
            lower[start..].copy_from_slice(fixed);
            upper[start..].copy_from_slice(fixed);
        }
        // Centres stay within a box far larger than any packing the start leads to: without
        // it a quasi-Newton step from a badly overlapping start could throw an item out to
        // 1e30, where the model refuses the point and the start is lost.
        let model = self.model.borrow();
        let layout = model.layout();
        for i in 0..layout.items() {
            let centre = layout.start(i)..layout.start(i) + N;
            lower[centre.clone()].fill(-self.centre_bound);
            upper[centre].fill(self.centre_bound);
        }
        for &(k, v) in &self.frozen {
            lower[k] = v;
            upper[k] = v;
        }
    }

    fn n_eq(&self) -> usize {
        if self.energy { 0 } else { 2 }
    }

    fn objective(&self, x: &[f64], grad: Option<&mut [f64]>) -> f64 {
        if self.energy {
            return self.energy(x, grad);
        }
        if self.fixed.is_some() {
            if let Some(g) = grad {
                g.fill(0.0);
            }
            return 0.0;
        }
        let mut model = self.model.borrow_mut();
        match grad {
            None => model.evaluate(x, None).map_or(f64::NAN, |e| e.objective),
            Some(g) => {
                let mut mg = self.gradient.borrow_mut();
                match model.evaluate(x, Some(&mut mg)) {
                    Ok(e) => {
                        g.copy_from_slice(&mg.objective);
                        e.objective
                    }
                    Err(_) => f64::NAN,
                }
            }
        }
    }

    fn constraints(&self, x: &[f64], c: &mut [f64]) {
        if self.energy {
            return;
        }
        match self.model.borrow_mut().evaluate(x, None) {
            Ok(e) => {
                c[0] = e.overlap;
                c[1] = e.containment;
            }
            Err(_) => c.fill(f64::NAN),
        }
    }

    fn constraints_jt_times(&self, x: &[f64], w: &[f64], out: &mut [f64]) {
        if self.energy {
            return;
        }
        let mut model = self.model.borrow_mut();
        let mut mg = self.gradient.borrow_mut();
        if model.evaluate(x, Some(&mut mg)).is_err() {
            out.fill(f64::NAN);
            return;
        }
        for (k, o) in out.iter_mut().enumerate() {
            *o += w[0] * mg.overlap[k] + w[1] * mg.containment[k];
        }
    }

    /// The model's exact products ([`Model::hessian_vector_product`]) assembled as the
    /// trait documents: sf ∇²V v + Σᵢ [λᵢ⁺ ∇²cᵢ v + ρ sᵢ² ∇cᵢ (∇cᵢᵀ v)] over the overlap and
    /// containment constraints.
    fn hessian_times(&self, x: &[f64], phr: &Phr<'_>, v: &[f64], out: &mut [f64]) -> bool {
        if self.energy {
            // The solver's difference quotient of gradients serves the energy.
            return false;
        }
        let mut model = self.model.borrow_mut();
        let mut at = self.hessian_point.borrow_mut();
        if at.x != x {
            let at = &mut *at;
            match model.evaluate(x, Some(&mut at.gradient)) {
                Ok(e) => {
                    at.x.clear();
                    at.x.extend_from_slice(x);
                    (at.overlap, at.containment) = (e.overlap, e.containment);
                }
                Err(_) => {
                    at.x.clear();
                    out.fill(f64::NAN);
                    return true;
                }
            }
        }
        let mut hv = self.product.borrow_mut();
        if model.hessian_vector_product(x, v, &mut hv).is_err() {
            out.fill(f64::NAN);
            return true;
        }
        let g = &at.gradient;
        let along = |gradient: &[f64]| gradient.iter().zip(v).map(|(a, b)| a * b).sum::<f64>();
        let sf = self.objective_weight(phr);
        let (d0, d1) = (
            phr.derivative(0, at.overlap),
            phr.derivative(1, at.containment),
        );
        let k0 = phr.curvature(0, at.overlap) * along(&g.overlap);
        let k1 = phr.curvature(1, at.containment) * along(&g.containment);
        for (k, o) in out.iter_mut().enumerate() {
            *o = sf * hv.objective[k]
                + d0 * hv.overlap[k]
                + d1 * hv.containment[k]
                + k0 * g.overlap[k]
                + k1 * g.containment[k];
        }
        true
    }

    fn lagrangian(&self, x: &[f64], phr: &Phr<'_>, grad: Option<&mut [f64]>) -> Option<f64> {
        if self.energy {
            let sf = phr.objective_scale();
            let value = match grad {
                None => self.energy(x, None),
                Some(g) => {
                    let value = self.energy(x, Some(&mut *g));
                    g.iter_mut().for_each(|v| *v *= sf);
                    value
                }
            };
            return Some(sf * value);
        }
        let sf = self.objective_weight(phr);
        let mut model = self.model.borrow_mut();
        Some(match grad {
            None => match model.evaluate(x, None) {
                Ok(e) => sf * e.objective + phr.term(0, e.overlap) + phr.term(1, e.containment),
                Err(_) => f64::NAN,
            },
            Some(g) => {
                let mut mg = self.gradient.borrow_mut();
                match model.evaluate(x, Some(&mut mg)) {
                    Ok(e) => {
                        let (d0, d1) = (
                            phr.derivative(0, e.overlap),
                            phr.derivative(1, e.containment),
                        );
                        for k in 0..g.len() {
                            g[k] =
                                sf * mg.objective[k] + d0 * mg.overlap[k] + d1 * mg.containment[k];
                        }
                        sf * e.objective + phr.term(0, e.overlap) + phr.term(1, e.containment)
                    }
                    Err(_) => {
                        g.fill(f64::NAN);
                        f64::NAN
                    }
                }
            }
        })
    }
}
