//! A user's own optimiser on the model: plain gradient descent with a backtracking line search
//! on `overlap + containment`, the container held fixed, until a few overlapping ellipses
//! are pulled apart inside a circle. The model supplies the value and the gradient
//! ([`Model::evaluate`]) and, at the end, the PW85 certificate ([`Model::certify`]).
//!
//! Gradient descent approaches a feasible point from outside and ends with items touching to
//! within rounding, which a strict certificate may call overlapping. So the descent runs on
//! ellipses inflated by 1 %, and the certificate judges the true ones.
//!
//! Run with `cargo run --release -p implicit-packing --example gradient_descent`.

use implicit_packing::containment::ContainerShape;
use implicit_packing::model::{Model, ModelGradient};

/// Ellipses of semi-axes (1, 0.5) in a circle of radius 2.3: density 0.57.
const ELLIPSES: usize = 6;
const RADIUS: f64 = 2.3;
const SEMI_AXES: [f64; 2] = [1.0, 0.5];
const INFLATION: f64 = 1.01;
const MAX_ITERATIONS: usize = 5000;

fn main() -> Result<(), implicit_packing::Error> {
    let inflated = SEMI_AXES.map(|l| INFLATION * l);
    let mut problem = Model::<2>::new(vec![inflated; ELLIPSES], ContainerShape::Ball)?;
    // Variables: [c_x, c_y, θ] per ellipse, then the container's radius. The start crowds the
    // ellipses near the centre, every one overlapping its neighbours.
    let mut x = Vec::with_capacity(problem.var_count());
    for i in 0..ELLIPSES {
        let phi = i as f64 * std::f64::consts::TAU / ELLIPSES as f64;
        x.extend([0.4 * phi.cos(), 0.4 * phi.sin(), phi + 0.3]);
    }
    x.push(RADIUS);
    let fixed = x.len() - 1;

    let mut gradient = ModelGradient::default();
    let merit = |e: &implicit_packing::model::Evaluation| e.overlap + e.containment;
    let mut value = merit(&problem.evaluate(&x, Some(&mut gradient))?);
    println!("start: overlap + containment = {value:.3e}");
    let mut step = 1.0;
    let mut iterations = 0;
    while value > 0.0 && iterations < MAX_ITERATIONS {
        iterations += 1;
        let mut direction: Vec<f64> = gradient
            .overlap
            .iter()
            .zip(&gradient.containment)
            .map(|(a, b)| -(a + b))
            .collect();
        direction[fixed] = 0.0;
        let slope: f64 = direction.iter().map(|d| -d * d).sum();
        // Armijo backtracking; the step grows again after each success, so that a flat
        // stretch does not keep the iteration at a tiny step.
        let (trial, trial_value) = loop {
            let trial: Vec<f64> = x
                .iter()
                .zip(&direction)
                .map(|(x, d)| x + step * d)
                .collect();
            let trial_value = merit(&problem.evaluate(&trial, None)?);
            if trial_value <= value + 1e-4 * step * slope || step < 1e-12 {
                break (trial, trial_value);
            }
            step *= 0.5;
        };
        if trial_value >= value {
            break;
        }
        x = trial;
        value = merit(&problem.evaluate(&x, Some(&mut gradient))?);
        debug_assert_eq!(value, trial_value);
        step *= 2.0;
        if iterations % 20 == 0 {
            println!("iteration {iterations:5}: overlap + containment = {value:.3e}");
        }
    }
    println!("stopped after {iterations} iterations at {value:.3e}");

    let mut exact = Model::<2>::new(vec![SEMI_AXES; ELLIPSES], ContainerShape::Ball)?;
    let certificate = exact.certify(&x)?;
    println!(
        "PW85 certificate: {} overlapping pairs, {} ellipses outside ({} pairs checked)",
        certificate.overlapping.len(),
        certificate.outside.len(),
        certificate.pairs_checked
    );
    assert!(
        certificate.is_feasible(),
        "the descent ended without a packing"
    );
    for i in 0..ELLIPSES {
        let b = &x[3 * i..3 * i + 3];
        println!(
            "ellipse {i}: centre ({:+.4}, {:+.4}), angle {:+.4}",
            b[0], b[1], b[2]
        );
    }
    Ok(())
}
