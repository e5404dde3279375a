//! Writing generated files: only when the content changed (so that an unchanged result keeps
//! its timestamp and the working tree stays clean), through a temporary file and a rename (so
//! that an interrupted run never leaves half a file), and not at all in `--check` mode, where
//! a difference is reported instead.

use crate::error::{self, Error};
use std::path::{Path, PathBuf};

/// Whether a file's content depends on the machine or the moment (timings, rasterised
/// pictures): `--check` cannot compare those.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stability {
    /// Same bytes on every run and machine.
    Stable,
    /// Contains timings or rendering details.
    Volatile,
}

/// What happened to each output of a run.
#[derive(Debug, Default)]
pub struct Outputs {
    /// `--check`: compare instead of writing.
    pub check: bool,
    /// Files written (content changed).
    pub written: Vec<PathBuf>,
    /// Files whose content was already up to date.
    pub unchanged: Vec<PathBuf>,
    /// `--check`: stable files that differ from what the code produces now.
    pub stale: Vec<PathBuf>,
}

impl Outputs {
    /// A writer; `check` selects the compare-only mode.
    pub fn new(check: bool) -> Self {
        Outputs {
            check,
            ..Outputs::default()
        }
    }

    /// Writes `bytes` to `path` unless it already holds them.
    pub fn write(&mut self, path: &Path, bytes: &[u8], stability: Stability) -> Result<(), Error> {
        let current = std::fs::read(path).ok();
        if current.as_deref() == Some(bytes) {
            self.unchanged.push(path.to_path_buf());
            return Ok(());
        }
        if self.check {
            if stability == Stability::Stable {
                self.stale.push(path.to_path_buf());
            }
            return Ok(());
        }
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).map_err(error::io(parent))?;
        }
        let tmp = path.with_extension(format!(
            "{}.tmp",
            path.extension().and_then(|e| e.to_str()).unwrap_or("")
        ));
        std::fs::write(&tmp, bytes).map_err(error::io(&tmp))?;
        std::fs::rename(&tmp, path).map_err(error::io(path))?;
        self.written.push(path.to_path_buf());
        Ok(())
    }

    /// A path for a figure that plotters writes itself: a temporary file in the same folder,
    /// which [`Outputs::adopt`] then moves into place if its content changed.
    pub fn scratch(path: &Path) -> PathBuf {
        let name = path
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        path.with_file_name(format!(".new-{name}"))
    }

    /// Moves a scratch file into place (or compares it, in check mode) and removes it.
    pub fn adopt(
        &mut self,
        scratch: &Path,
        path: &Path,
        stability: Stability,
    ) -> Result<(), Error> {
        let bytes = std::fs::read(scratch).map_err(error::io(scratch))?;
        let _ = std::fs::remove_file(scratch);
        self.write(path, &bytes, stability)
    }
}

/// CSV text from a header and rows of already formatted fields.
pub fn csv_text(header: &[&str], rows: &[Vec<String>]) -> String {
    let mut s = header.join(",");
    s.push('\n');
    for r in rows {
        s.push_str(&r.join(","));
        s.push('\n');
    }
    s
}

/// `head`, then every row as `line` writes it: the text of a CSV file or Markdown table whose
/// rows each format their own fields, so that the studies share the loop around them.
pub fn table_text<R>(
    head: &str,
    rows: &[R],
    line: impl Fn(&mut String, &R) -> std::fmt::Result,
) -> String {
    let mut out = head.to_string();
    for r in rows {
        // Writing into a String cannot fail.
        let _ = line(&mut out, r);
    }
    out
}

/// A float for a CSV file: 17 significant digits (round-trips).
pub fn full(x: f64) -> String {
    format!("{x:.16e}")
}

/// A float rounded to 4 significant digits (measured errors and timings: more digits are noise).
pub fn short(x: f64) -> String {
    format!("{x:.3e}")
}

/// `text` with what lies between the markers `begin` and `end` replaced by `table` (`None`
/// when a marker is missing): the generated part of a page, the rest kept as written.
pub fn between_markers(text: &str, (begin, end): (&str, &str), table: &str) -> Option<String> {
    let start = text.find(begin)? + begin.len();
    let stop = start + text[start..].find(end)?;
    Some(format!("{}\n{table}{}", &text[..start], &text[stop..]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_only_changes_and_check_mode_reports_instead_of_writing() {
        let dir = std::env::temp_dir().join(format!("xtask-output-test-{}", std::process::id()));
        let path = dir.join("a.csv");
        let mut out = Outputs::new(false);
        out.write(&path, b"x\n", Stability::Stable).unwrap();
        out.write(&path, b"x\n", Stability::Stable).unwrap();
        assert_eq!((out.written.len(), out.unchanged.len()), (1, 1));

        let mut check = Outputs::new(true);
        check.write(&path, b"y\n", Stability::Stable).unwrap();
        check.write(&path, b"z\n", Stability::Volatile).unwrap();
        assert_eq!(check.stale, vec![path.clone()]);
        assert_eq!(std::fs::read(&path).unwrap(), b"x\n");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
