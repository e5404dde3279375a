//! `ellipack pack` and `ellipack verify`: the terminal side (progress, Ctrl-C, files).

use ellipack::pack::{
    RunOptions, probe_output_folder, resume_start, run, time_limit_of, verify as check,
};
use ellipack::packing::{read_packing_dir, read_packing_files, write_files};
use ellipack::render::{RenderOptions, write_pictures};
use ellipack::scene::Scene;
use indicatif::{ProgressBar, ProgressStyle};
use std::error::Error;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Duration;

/// The arguments of `ellipack pack`.
pub struct PackArgs {
    pub scene: Option<PathBuf>,
    pub instance: Option<String>,
    pub out: Option<PathBuf>,
    pub time_limit: Option<f64>,
    pub seed: Option<u64>,
    pub threads: Option<usize>,
    pub resume: bool,
}

pub fn pack(args: PackArgs) -> Result<ExitCode, Box<dyn Error>> {
    let scene = match (&args.scene, &args.instance) {
        (Some(path), _) => Scene::from_file(path)?,
        (None, Some(name)) => ellipack::instances::by_name(name)
            .ok_or_else(|| {
                format!(
                    "unknown instance `{name}`; the instances are: {}",
                    ellipack::instances::names()
                )
            })?
            .scene(),
        (None, None) => {
            eprintln!(
                "no scene given: packing the built-in scene ({})",
                Scene::default_scene().title()
            );
            Scene::default_scene()
        }
    };
    let out = args
        .out
        .clone()
        .or_else(|| scene.output.directory.clone())
        .unwrap_or_else(|| PathBuf::from("out"));
    let time_limit = args.time_limit.map(time_limit_of).transpose()?;
    let resume_from = if args.resume {
        Some(resume_start(&scene, &out)?)
    } else {
        None
    };
    // Before the run: a folder found unwritable afterwards would lose the packing.
    probe_output_folder(&out)?;
    let options = RunOptions {
        time_limit,
        seed: args.seed,
        threads: args.threads,
        resume_from,
    };

    let interrupted = Arc::new(AtomicBool::new(false));
    {
        let flag = Arc::clone(&interrupted);
        // Ctrl-C, SIGTERM and SIGHUP (the `termination` feature of ctrlc: what `timeout`,
        // Slurm, systemd and a closed terminal send) all stop the run, which then writes its
        // best certified packing. Without a handler (another one already installed) a signal
        // simply ends the process.
        let _ = ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst));
    }
    // indicatif draws nothing when stderr is not a terminal.
    let bar = ProgressBar::new_spinner();
    bar.set_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    bar.enable_steady_tick(Duration::from_millis(200));
    bar.set_message(format!("{}: first local minimisation", scene.title()));
    let stop = {
        let flag = Arc::clone(&interrupted);
        move || flag.load(Ordering::SeqCst)
    };
    // The best certified density is known between local minimisations (main thread); the
    // objective and infeasibility inside them (worker threads): both feed one message.
    let best = Arc::new(AtomicU64::new(0f64.to_bits()));
    let observe = {
        let (bar, best) = (bar.clone(), Arc::clone(&best));
        move |p: &auglag::Progress<'_>| {
            if let auglag::Event::Outer {
                objective,
                infeasibility,
                ..
            } = p.event
            {
                let best = f64::from_bits(best.load(Ordering::Relaxed));
                bar.set_message(format!(
                    "objective {objective:.6}, infeasibility {infeasibility:.1e}, best certified \
                     density {best:.5}"
                ));
            }
        }
    };
    // One row per finished local minimisation, written beside the packing as history.csv.
    let mut history = String::from("local_minimisation,seconds,density,best_density\n");
    let outcome = run(
        &scene,
        &options,
        &mut |p| {
            history.push_str(&format!(
                "{},{:.3},{:.9},{:.9}\n",
                p.local_minimisations,
                p.elapsed.as_secs_f64(),
                p.last_density,
                p.best_density
            ));
            best.store(p.best_density.to_bits(), Ordering::Relaxed);
            bar.set_message(format!(
                "{} local minimisations, last density {:.5}, best certified density {:.5}",
                p.local_minimisations, p.last_density, p.best_density
            ));
        },
        &observe,
        &stop,
    )?;
    bar.finish_and_clear();

    write_files(&out, &outcome.packing, &outcome.summary, scene.output.xyz)?;
    ellipack::output::write_atomically(&out.join("history.csv"), history.as_bytes())?;
    if scene.output.pictures {
        let options = RenderOptions {
            width: scene.output.image_width,
            label: scene.name.clone(),
        };
        write_pictures(&out, &outcome.packing, &options)?;
    }
    let s = &outcome.summary;
    println!("{}", scene.title());
    println!(
        "density {:.5} ({} {}), found after {:.1} s of {:.1} s, {} local minimisations{}",
        s.density,
        s.container.size_name(),
        s.container
            .size()
            .iter()
            .map(|v| format!("{v:.6}"))
            .collect::<Vec<_>>()
            .join(" × "),
        outcome.seconds_to_best,
        s.wall_seconds,
        s.local_minimisations,
        if outcome.interrupted {
            " (interrupted)"
        } else {
            ""
        }
    );
    println!(
        "certificate: {} overlapping pairs, {} containment violations, min μ² = {}; repair \
         dilation {:.2e} (density {:.5} before)",
        s.certificate.overlapping_pairs,
        s.certificate.containment_violations,
        s.certificate
            .min_mu2
            .map_or("—".into(), |m| format!("{m:.9}")),
        outcome.repair_factor - 1.0,
        outcome.density_before_repair
    );
    if outcome.restarts > 0 {
        println!(
            "{} new chains from fresh lattice starts (after {} starts without improvement)",
            outcome.restarts, scene.solver.restart_after
        );
    }
    let limit = options
        .time_limit
        .unwrap_or(scene.solver.time_limit)
        .as_secs_f64();
    if outcome.start_kept && outcome.seconds_to_best >= limit {
        println!(
            "the time limit ({limit:.3e} s) is shorter than building and certifying the start \
             took ({:.3} s): give at least that for any local minimisation",
            outcome.seconds_to_best
        );
    }
    if outcome.start_kept {
        println!(
            "no local minimisation found a denser certified packing than the start{}: wrote \
             the start",
            if args.resume {
                " (the resumed packing)"
            } else {
                ""
            }
        );
    }
    if outcome.failed_starts > 0 {
        println!(
            "{} starts were abandoned: their local minimisation ended at a point that could \
             not be certified",
            outcome.failed_starts
        );
    }
    println!("wrote {}", out.display());
    Ok(if s.certificate.is_certified() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

pub fn verify(packing: &Path, summary: Option<&Path>) -> Result<ExitCode, Box<dyn Error>> {
    let (packing, stated) = match summary {
        Some(summary) => read_packing_files(packing, summary)?,
        None if packing.is_dir() => read_packing_dir(packing)?,
        None => {
            let dir = packing.parent().unwrap_or(Path::new("."));
            read_packing_files(packing, &dir.join("summary.json"))?
        }
    };
    let certificate = check(&packing)?;
    println!(
        "{} {}, container: {}, density {:.5}",
        packing.items.len(),
        packing.items.noun(),
        packing.container.kind().name(),
        packing.density()
    );
    println!(
        "certificate: {} overlapping pairs, {} containment violations, min μ² = {}",
        certificate.overlapping_pairs,
        certificate.containment_violations,
        certificate
            .min_mu2
            .map_or("—".into(), |m| format!("{m:.12}"))
    );
    if stated.certificate != certificate {
        println!(
            "note: summary.json states {} overlapping pairs, {} containment violations",
            stated.certificate.overlapping_pairs, stated.certificate.containment_violations
        );
    }
    Ok(if certificate.is_certified() {
        println!("certified");
        ExitCode::SUCCESS
    } else {
        println!("NOT certified");
        ExitCode::FAILURE
    })
}
