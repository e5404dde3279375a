//! Times the two parts of a random packing of m ellipsoids (1, 0.75, 0.5) in a periodic cube:
//! the random start and the compression to a packing fraction (or until jammed).
//!
//! `cargo run --release -p ellipsoid-packer --example random_scale -- 100000 0.6 [start]`
//! (`jammed` instead of a fraction; `start` the start fraction, default 0.2).

use ellipsoid_packer::compression::compression_to;
use ellipsoid_packer::local::{LocalMethod, LocalSettings, item_measure};
use ellipsoid_packer::random::{ATTEMPTS_PER_ITEM, sequential_addition};
use implicit_packing::containment::ContainerShape;
use implicit_packing::model::Model;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let m: usize = args.get(1).map_or(Ok(10_000), |a| a.parse())?;
    let target: Option<f64> = match args.get(2).map(String::as_str) {
        None | Some("jammed") => None,
        Some(f) => Some(f.parse()?),
    };
    let start: f64 = args.get(3).map_or(Ok(0.2), |a| a.parse())?;
    let mut p = Model::<3>::new(vec![[1.0, 0.75, 0.5]; m], ContainerShape::Periodic)?;
    let volume = item_measure(&p);
    let side = (volume / start).cbrt();
    let t = Instant::now();
    let x0 = sequential_addition(&p, &[side, side, side, 0.0, 0.0, 0.0], 1, ATTEMPTS_PER_ITEM)?;
    println!(
        "random start of {m} at {start}: {:.2} s",
        t.elapsed().as_secs_f64()
    );
    let t = Instant::now();
    let c = p.certify(&x0)?;
    println!(
        "certificate: {:.3} s ({} pairs)",
        t.elapsed().as_secs_f64(),
        c.pairs_checked
    );
    let t = Instant::now();
    p.evaluate(&x0, None)?;
    println!("one evaluation: {:.3} s", t.elapsed().as_secs_f64());
    let t = Instant::now();
    let y = p.dilated(&x0, 0.98);
    let inf = ellipsoid_packer::local::infeasibility(&mut p, &y)?;
    println!(
        "infeasibility after a 2 % shrink {inf:.3e}: {:.3} s",
        t.elapsed().as_secs_f64()
    );
    let largest: f64 = std::env::var("LARGEST").map_or(0.02, |v| v.parse().unwrap_or(0.02));
    let settings = LocalSettings::default()
        .with_method(LocalMethod::Compression)
        .with_largest_compression_step(largest);
    let t = Instant::now();
    let mut last = Instant::now();
    let r = compression_to(
        &mut p,
        &x0,
        &settings,
        target.map(|f| volume / f),
        &mut |progress| {
            if let auglag::Event::Outer { infeasibility, .. } = progress.event
                && last.elapsed().as_secs_f64() > 1.0
            {
                println!(
                    "  {:.1} s: outer {} inner {} evaluations {}, infeasibility {infeasibility:.3e}",
                    t.elapsed().as_secs_f64(),
                    progress.outer_iteration,
                    progress.total_inner_iterations,
                    progress.evaluations
                );
                last = Instant::now();
            }
            false
        },
        &mut |_| {},
    )?;
    println!(
        "compression to {:.5}: {:.2} s, {} outer / {} inner iterations",
        r.density,
        t.elapsed().as_secs_f64(),
        r.report.outer_iterations,
        r.report.inner_iterations
    );
    Ok(())
}
