//! A multi-start run on one of the paper's instances:
//! `cargo run --release -p ellipsoid-packer --example multistart -- 3 ball 100 60 2`
//! (dimension, container, items, seconds, threads), then optionally: local minimisations
//! (0: no cap), lattice starts, from best (0/1), perturbation levels, a fresh lattice start
//! every n perturbations (0: never), a new chain after n starts without improvement (0:
//! never).

use ellipsoid_packer::{
    multistart::{Callbacks, MultiStartProgress, MultiStartSettings, multistart},
    starts::paper_start,
};
use std::time::Duration;

mod common;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let arg = |k: usize, default: &str| args.get(k).cloned().unwrap_or_else(|| default.into());
    let dim: usize = arg(1, "3").parse()?;
    let kind = common::container_kind(arg(2, "ball").as_str())?;
    let m: usize = arg(3, "100").parse()?;
    let seconds: f64 = arg(4, "60").parse()?;
    let threads: usize = arg(5, "2").parse()?;
    let mut settings = MultiStartSettings::paper(dim, 1);
    settings.threads = threads;
    settings.max_local_minimisations = match arg(6, "0").parse()? {
        0 => usize::MAX,
        n => n,
    };
    settings.lattice_starts = arg(7, "0").parse()?;
    settings.from_best = arg(8, "0").parse::<u8>()? == 1;
    settings.perturbation_levels = arg(9, "1").parse()?;
    settings.fresh_lattice_every = arg(10, "0").parse()?;
    settings.restart_after = arg(11, "0").parse()?;
    settings.time_limit = Some(Duration::from_secs_f64(seconds));
    let mut report = Callbacks::on_finished(|p: &MultiStartProgress| {
        eprintln!(
            "{:4} local minimisations, {:7.1} s: last {:.5}, best {:.5}",
            p.local_minimisations,
            p.elapsed.as_secs_f64(),
            p.last_density,
            p.best_density
        );
    });
    let r = if dim == 2 {
        let axes = vec![[2.0, 1.0]; m];
        let x0 = paper_start(&axes, kind)?;
        multistart(&axes, kind, &x0, &settings, &mut report)?
    } else {
        let axes = vec![[1.0, 0.75, 0.5]; m];
        let x0 = paper_start(&axes, kind)?;
        multistart(&axes, kind, &x0, &settings, &mut report)?
    };
    println!(
        "{dim}D m = {m} {kind:?}: best density {:.5} after {:.1} s ({} local minimisations, {} restarts, in {:.1} s, {threads} threads)",
        r.best.density,
        r.time_to_best.as_secs_f64(),
        r.local_minimisations,
        r.restarts,
        r.wall_time.as_secs_f64()
    );
    Ok(())
}
