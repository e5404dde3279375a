//! Contact function, verdict and gradient of two of the packing paper's ellipsoids, then the
//! same pair pushed until the ellipsoids touch.
//!
//! Run with `cargo run --release -p pw85 --example contact`.

use pw85::shape::from_axes_angles;
use pw85::{contact_details, contact_function, overlap};

fn main() -> Result<(), pw85::Error> {
    let axes = [1.0, 0.75, 0.5];
    let q1 = from_axes_angles(&axes, &[0.0, 0.0, 0.0])?;
    let q2 = from_axes_angles(&axes, &[0.3, 1.1, -0.4])?;
    let r12 = [1.2, 0.9, 0.2];

    let c = contact_function(&r12, &q1, &q2)?;
    println!("μ² = {:.15}, λ = {:.15}", c.mu2, c.lambda);
    println!("overlap: {}", overlap(&r12, &q1, &q2)?);

    let d = contact_details(&r12, &q1, &q2)?;
    println!("contact point (relative to c1): {:?}", d.point);
    println!("common normal: {:?}", d.normal);
    println!("∂μ²/∂r12: {:?}", d.grad_r12);

    // μ² scales with |r12|²: dividing r12 by μ puts the ellipsoids in external contact.
    let mu = c.mu2.sqrt();
    let touching = r12.map(|x| x / mu);
    println!(
        "scaled by 1/μ: μ² = {:.15}",
        contact_function(&touching, &q1, &q2)?.mu2
    );
    Ok(())
}
