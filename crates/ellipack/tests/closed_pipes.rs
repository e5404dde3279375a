//! Every command ends with its usual exit status when the reader of its standard output or
//! standard error has gone (`ellipack verify out | grep -q certificate`): a closed pipe never
//! panics (exit status 101), and the files are written as without it.

mod common;
use common::{ellipack, folder_with, text};
use std::ffi::OsStr;
use std::process::{Command, Stdio};

/// Four circles in a circle, one local minimisation: a run that prints its title, its result
/// and the folder it wrote.
const CIRCLES: &str = "dimension = 2\nseed = 1\n[container]\nkind = \"circle\"\n\
                       [[shapes]]\ncount = 4\nsemi_axes = [1.0, 1.0]\n[solver]\n\
                       local_minimisations = 1\nthreads = 1\n[output]\npictures = false\n";

/// Twelve ellipses (2, 1) in a square at packing fraction 0.95, which no packing of them
/// reaches (0.9069 is the densest): the run ends with exit status 4 whatever the machine's
/// speed.
const UNREACHABLE: &str = "dimension = 2\nseed = 1\n[container]\nkind = \"rectangle\"\n\
                           packing_fraction = 0.95\n[[shapes]]\ncount = 12\n\
                           semi_axes = [2.0, 1.0]\n[solver]\ntime_limit = 1.0\nthreads = 1\n\
                           [output]\npictures = false\n";

/// Which of the two streams the reader closes before the command writes anything.
#[derive(Clone, Copy, Debug)]
enum Closed {
    Stdout,
    Stderr,
}

/// Runs `command` with `closed` closed from its start; returns its exit status and what it
/// wrote on the other stream.
fn with_closed(mut command: Command, closed: Closed) -> (Option<i32>, String) {
    let mut child = command
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    match closed {
        Closed::Stdout => drop(child.stdout.take()),
        Closed::Stderr => drop(child.stderr.take()),
    }
    let out = child.wait_with_output().unwrap();
    let said = text(&out.stdout) + &text(&out.stderr);
    (out.status.code(), said)
}

/// `ellipack` with `args`, each a word or a path.
fn ellipack_with(args: &[&OsStr]) -> Command {
    let mut c = ellipack();
    c.args(args);
    c
}

#[test]
fn no_command_panics_on_a_closed_stdout_or_stderr() {
    let (dir, scene) = folder_with("closed-pipes", "circles.toml", CIRCLES);
    let unreachable = dir.join("unreachable.toml");
    std::fs::write(&unreachable, UNREACHABLE).unwrap();
    for closed in [Closed::Stdout, Closed::Stderr] {
        let out = dir.join(format!("{closed:?}"));
        let merged = dir.join(format!("{closed:?}-merged"));
        let failed = dir.join(format!("{closed:?}-unfinished"));
        let w = OsStr::new;
        let runs: Vec<(&str, Command, i32)> = vec![
            (
                "pack",
                ellipack_with(&[w("pack"), scene.as_os_str(), w("--out"), out.as_os_str()]),
                0,
            ),
            ("verify", ellipack_with(&[w("verify"), out.as_os_str()]), 0),
            (
                "convert",
                ellipack_with(&[w("convert"), out.as_os_str()]),
                0,
            ),
            (
                "analyse",
                ellipack_with(&[w("analyse"), out.as_os_str()]),
                0,
            ),
            (
                "merge",
                ellipack_with(&[w("merge"), out.as_os_str(), w("--out"), merged.as_os_str()]),
                0,
            ),
            (
                "pack (not reached)",
                ellipack_with(&[
                    w("pack"),
                    unreachable.as_os_str(),
                    w("--out"),
                    failed.as_os_str(),
                ]),
                4,
            ),
            ("instances", ellipack_with(&[w("instances")]), 0),
        ];
        for (name, command, status) in runs {
            let (code, said) = with_closed(command, closed);
            assert_eq!(code, Some(status), "{name} with {closed:?} closed: {said}");
            assert!(!said.contains("panicked"), "{name}: {said}");
        }
        assert!(out.join("packing.csv").is_file(), "{closed:?}");
        assert!(merged.join("packing.csv").is_file(), "{closed:?}");
        assert!(failed.join("unfinished").join("packing.csv").is_file());
    }
}
