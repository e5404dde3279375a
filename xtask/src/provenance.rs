//! Where a study's figures come from: the machine and the commit, stated beside every
//! generated table.

/// The processor model (`lscpu`'s model name) and the number of cores.
pub fn machine() -> String {
    let lscpu = std::process::Command::new("lscpu")
        .output()
        .ok()
        .map(|o| String::from_utf8_lossy(&o.stdout).into_owned())
        .unwrap_or_default();
    let field = |name: &str| {
        lscpu
            .lines()
            .find(|l| l.trim_start().starts_with(name))
            .and_then(|l| l.split_once(':'))
            .map(|(_, v)| v.trim().to_string())
    };
    let model = field("Model name").unwrap_or_else(|| "unknown processor".into());
    let cores = field("CPU(s)").unwrap_or_else(|| {
        std::thread::available_parallelism()
            .map_or(1, usize::from)
            .to_string()
    });
    format!("{model}, {cores} cores")
}

/// The commit the study runs from (`git rev-parse --short HEAD`), with `+changes` when the
/// working tree differs from it.
pub fn commit() -> String {
    let root = crate::workspace_root();
    let git = |args: &[&str]| {
        std::process::Command::new("git")
            .args(args)
            .current_dir(&root)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    let head = git(&["rev-parse", "--short", "HEAD"]).unwrap_or_else(|| "unknown".into());
    // Only the code matters: the study's own outputs change with every run.
    let dirty = git(&[
        "status",
        "--porcelain",
        "--",
        "crates",
        "xtask",
        "Cargo.lock",
    ])
    .is_some_and(|s| !s.is_empty());
    if dirty {
        format!("{head}+changes")
    } else {
        head
    }
}

/// [`machine`] with the number of threads a study used.
pub fn machine_with_threads(threads: usize) -> String {
    format!("{}, {threads} threads used", machine())
}
