//! A convex QP on which proptest (tests/quadratic_kkt.rs) once found the projected L-BFGS
//! stopping short of the KKT tolerance. Kept as a plain test so it runs on every build.

use auglag::{InnerSolver, Options, Problem, StopReason, minimize};

const A: [f64; 36] = [
    7.776638393174111,
    1.2654374171945144,
    -0.006941194962154396,
    -4.8240657402393134,
    0.6286726867013279,
    -3.3161085380106505,
    1.2654374171945144,
    14.773147548034888,
    4.0824765507071445,
    2.3164209419983157,
    8.835090744733828,
    1.7317823490831519,
    -0.006941194962154396,
    4.0824765507071445,
    8.651670651579568,
    -0.8382706857408679,
    3.2630164419863545,
    -3.4238302845608297,
    -4.8240657402393134,
    2.3164209419983157,
    -0.8382706857408679,
    9.404190004709655,
    2.870105383033743,
    5.81231547602925,
    0.6286726867013279,
    8.835090744733828,
    3.2630164419863545,
    2.870105383033743,
    8.617152690141136,
    0.06086470121322085,
    -3.3161085380106505,
    1.7317823490831519,
    -3.4238302845608297,
    5.81231547602925,
    0.06086470121322085,
    5.818152554606071,
];
const B: [f64; 6] = [
    1.3011357561602648,
    2.085008684301463,
    0.6456220341001759,
    -2.85005475979483,
    -2.6629633299220483,
    -4.074537863790499,
];
const LO: [f64; 6] = [
    f64::NEG_INFINITY,
    f64::NEG_INFINITY,
    0.0,
    f64::NEG_INFINITY,
    f64::NEG_INFINITY,
    f64::NEG_INFINITY,
];
const UP: [f64; 6] = [
    -1.9197107246018454,
    f64::INFINITY,
    f64::INFINITY,
    0.0,
    f64::INFINITY,
    1.5885969915368645,
];
const X0: [f64; 6] = [
    0.0,
    0.0,
    0.0,
    -0.9085909151802326,
    -0.43436208584164704,
    -0.6949062792482161,
];

struct Qp;

impl Problem for Qp {
    fn dim(&self) -> usize {
        6
    }
    fn bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.copy_from_slice(&LO);
        upper.copy_from_slice(&UP);
    }
    fn objective(&self, x: &[f64], grad: Option<&mut [f64]>) -> f64 {
        let g: Vec<f64> = (0..6)
            .map(|i| (0..6).map(|j| A[i * 6 + j] * x[j]).sum::<f64>() + B[i])
            .collect();
        // Same summation as tests/quadratic_kkt.rs: the case is sensitive to rounding.
        let f = 0.5 * g.iter().zip(x).map(|(g, x)| g * x).sum::<f64>()
            + 0.5 * B.iter().zip(x).map(|(b, x)| b * x).sum::<f64>();
        if let Some(out) = grad {
            out.copy_from_slice(&g);
        }
        f
    }
}

#[test]
fn both_inner_solvers_converge_on_the_saved_case() {
    for solver in [
        InnerSolver::Spg,
        InnerSolver::ProjectedLbfgs,
        InnerSolver::TruncatedNewton,
    ] {
        let options = Options::default()
            .with_optimality_tolerance(1e-9)
            .with_inner_solver(solver)
            .with_max_inner_iterations(1_000_000);
        let s = minimize(&Qp, &X0, &options).unwrap();
        eprintln!("{solver:?}: {:?}", s.report);
        assert_eq!(s.report.stop_reason, StopReason::Converged, "{solver:?}");
        let mut g = [0.0; 6];
        Qp.objective(&s.x, Some(&mut g));
        for i in 0..6 {
            assert!(s.x[i] >= LO[i] && s.x[i] <= UP[i]);
            let step = (s.x[i] - g[i]).max(LO[i]).min(UP[i]) - s.x[i];
            assert!(
                step.abs() <= 1e-9 * (1.0 + 1e-6),
                "{solver:?}: component {i}: {step:e}"
            );
        }
    }
}
