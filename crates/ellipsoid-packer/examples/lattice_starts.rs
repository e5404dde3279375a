//! One local minimisation from each of the first K dense lattice starts, against the paper's
//! start: `cargo run --release -p ellipsoid-packer --example lattice_starts -- 3 box 100 8`;
//! with a fifth argument `tightest`, from the K tightest cuts of the lattice instead, each as
//! cut and with its items turned by up to 0.01 rad as a multi-start turns them
//! (`-- 2 box 1000 8 tightest`).

use ellipsoid_packer::local::{LocalSettings, item_measure, local_minimisation};
use ellipsoid_packer::starts::lattice_start;
use ellipsoid_packer::starts::{LatticeStart, lattice_start_of, tightest_lattice_starts, turned};
use implicit_packing::containment::ContainerShape;
use implicit_packing::model::Model;
use std::time::Instant;

mod common;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let dim: usize = args.get(1).map_or(Ok(3), |s| s.parse())?;
    let kind = common::container_kind(args.get(2).map_or("ball", String::as_str))?;
    let m: usize = args.get(3).map_or(Ok(100), |s| s.parse())?;
    let k: usize = args.get(4).map_or(Ok(8), |s| s.parse())?;
    let tightest = args.get(5).is_some_and(|s| s == "tightest");
    if dim == 2 {
        run::<2>(vec![[2.0, 1.0]; m], kind, k, tightest)
    } else {
        run::<3>(vec![[1.0, 0.75, 0.5]; m], kind, k, tightest)
    }
}

fn run<const N: usize>(
    axes: Vec<[f64; N]>,
    kind: ContainerShape,
    k: usize,
    tightest: bool,
) -> Result<(), Box<dyn std::error::Error>> {
    let p = Model::<N>::new(axes.clone(), kind)?;
    let settings = LocalSettings::default();
    let measure = item_measure(&p);
    // A fresh model per start, as in a multi-start: a local minimisation is chaotic in the
    // rounding of its first evaluations.
    let one = |label: String, x0: Vec<f64>| -> Result<(), Box<dyn std::error::Error>> {
        let mut p = Model::<N>::new(axes.clone(), kind)?;
        let d0 = measure / p.evaluate(&x0, None)?.objective;
        let t = Instant::now();
        let r = local_minimisation(&mut p, &x0, &settings, &mut |_| false)?;
        println!(
            "{label}: start {d0:.4} -> {:.5} in {:.1} s",
            r.density,
            t.elapsed().as_secs_f64()
        );
        Ok(())
    };
    let x0 = lattice_start(&p);
    one("paper".into(), x0)?;
    let starts = if tightest {
        tightest_lattice_starts(&p, k)
    } else {
        (0..k).map(LatticeStart::<N>::sequence).collect()
    };
    for (i, s) in starts.into_iter().enumerate() {
        let x0 = lattice_start_of(&p, &s);
        let label = format!("{s:?}, container {:.4?}", &x0[x0.len() - N..]);
        if tightest {
            let x1 = turned::<N>(&x0, p.layout(), 0.01, 0, i as u64);
            one(format!("{label}, turned"), x1)?;
        }
        one(label, x0)?;
    }
    Ok(())
}
