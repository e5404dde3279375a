//! An output folder holds the files of one run, or those of the run before it, never a mix.
//!
//! A run writes its complete set of files into a staging folder beside the output folder
//! (`<out>.ellipack-staging-<pid>`, on the same file system), carries over everything in the
//! output folder that ellipack did not write (a scene file, notes, sub-folders: hard links, so
//! nothing is copied and nothing is moved out of the folder before the swap), and then swaps the
//! two folders in one step: `renameat2(RENAME_EXCHANGE)` on Linux. Where the file system cannot
//! exchange, two renames do it (`<out>` → `<out>.ellipack-retired-<pid>`, staging → `<out>`):
//! a crash between them leaves the old set under the retired name, which the next run puts back
//! when the output folder is missing or empty. The old set is then removed. Files of an earlier run that the new run does not write (its
//! pictures, its XYZ file) are thereby gone: they were never carried over.
//!
//! A killed run leaves at most a staging or retired folder and temporary files; the next run
//! removes them before it stages (those of processes that are still running on Linux are left
//! alone), and nothing reads them as a packing.
//!
//! When no sibling folder can be made (the parent is not writable, or the output folder is a
//! mount point), when the user's files are too many to carry over (more than 10 000 entries,
//! a mount point inside, more than 64 MiB to copy where hard links are refused), or the swap
//! fails, the run's files are renamed into place one by one: each file is whole and stale run
//! files are removed, but the set is not swapped in one step; [`Published::InPlace`] says so.
//!
//! The swap replaces the folder's directory entry: a shell whose working directory is the
//! output folder still sees the old, removed folder until it changes into it again.

use crate::Error;
use crate::gsd::GSD_FILE;
use crate::items_csv::{CSV_FILE, read_csv, write_csv};
use crate::lammps::LAMMPS_FILE;
use crate::obj::MESH_FILE;
use crate::packing::{Packing, Summary};
use crate::summary_json::{SUMMARY_FILE, read_summary, write_summary};
use crate::xyz::{XYZ_FILE, write_xyz};
use std::ffi::OsStr;
use std::path::{Path, PathBuf};

/// The file name of the per-run history table.
pub const HISTORY_FILE: &str = "history.csv";
/// The structure of the packing ([`crate::analysis`]).
pub const STRUCTURE_FILE: &str = "structure.json";
/// Its g(r), one row per bin: `r,g`.
pub const RDF_FILE: &str = "rdf.csv";
/// The picture of g(r).
pub const RDF_PICTURE: &str = "rdf.svg";
/// The picture of the orientation distribution.
pub const ORIENTATIONS_PICTURE: &str = "orientations.svg";
/// The file name of the SVG picture (drawn by `render` with the `pictures` feature).
pub const SVG_FILE: &str = "packing.svg";
/// The file name of the PNG picture (drawn by `render` with the `pictures` feature).
pub const PNG_FILE: &str = "packing.png";

/// Every file `ellipack pack` writes into an output folder. Anything else there belongs to the
/// user and is kept.
pub const RUN_FILES: [&str; 13] = [
    CSV_FILE,
    SUMMARY_FILE,
    STRUCTURE_FILE,
    RDF_FILE,
    RDF_PICTURE,
    ORIENTATIONS_PICTURE,
    XYZ_FILE,
    LAMMPS_FILE,
    GSD_FILE,
    MESH_FILE,
    HISTORY_FILE,
    SVG_FILE,
    PNG_FILE,
];

const STAGING: &str = ".ellipack-staging-";

/// The prefix of the file by which a run tests, before it starts, that it can write its output
/// folder (`<prefix><pid>`), where the file system cannot make an unnamed one.
pub const PROBE: &str = ".ellipack-probe-";
const RETIRED: &str = ".ellipack-retired-";

fn io(path: &Path, action: &'static str) -> impl FnOnce(std::io::Error) -> Error {
    let path = path.to_path_buf();
    move |source| Error::Folder {
        path,
        action,
        source,
    }
}

/// How a staged set of files reached the output folder.
#[derive(Debug)]
pub enum Published {
    /// In one step: the folder held the old set, then the new one.
    Swapped,
    /// File by file: no staging folder could be made beside the output folder (`None`), or
    /// the swap failed for the reason given.
    InPlace(Option<Error>),
}

/// A staging folder for the next set of files of an output folder. Dropping it without
/// [`Staging::commit`] removes it and leaves the output folder as it was.
#[derive(Debug)]
pub struct Staging {
    out: PathBuf,
    dir: PathBuf,
    in_place: bool,
    committed: bool,
}

impl Staging {
    /// Removes what killed runs left behind in and beside `out` (which must exist) and makes an
    /// empty staging folder for it.
    ///
    /// # Errors
    /// [`Error::Folder`] when `out` cannot be resolved or no staging folder can be made.
    pub fn begin(out: &Path) -> Result<Staging, Error> {
        // Symbolic links to the folder stay links: the real folder is the one swapped.
        let out = std::fs::canonicalize(out).map_err(io(out, "resolve the output folder"))?;
        clean_up(&out);
        let pid = std::process::id();
        if let Some(sibling) = sibling(&out, STAGING, pid) {
            let _ = std::fs::remove_dir_all(&sibling);
            if std::fs::create_dir(&sibling).is_ok() {
                if same_device(&out, &sibling) {
                    copy_mode(&out, &sibling);
                    return Ok(Staging {
                        out,
                        dir: sibling,
                        in_place: false,
                        committed: false,
                    });
                }
                let _ = std::fs::remove_dir(&sibling);
            }
        }
        Staging::inside(out)
    }

    /// The folder to write the new set of files into.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// Makes the staged files the content of the output folder, with the files ellipack did
    /// not write kept, and removes the previous set. When the swap cannot be made (a user's
    /// file that can be neither linked nor copied, a file system that refuses), the run's files
    /// are renamed into place one by one rather than lost: [`Published::InPlace`] says why.
    ///
    /// # Errors
    /// [`Error::Folder`] when even that fails.
    pub fn commit(mut self) -> Result<Published, Error> {
        self.committed = true;
        let mut why = None;
        if !self.in_place {
            match carry(&self.out, &self.dir, true).and_then(|()| swap(&self.dir, &self.out)) {
                Ok(()) => return Ok(Published::Swapped),
                Err(e) => why = Some(e),
            }
        }
        let result = self.move_in_place();
        let _ = std::fs::remove_dir_all(&self.dir);
        result.map(|()| Published::InPlace(why))
    }

    fn move_in_place(&self) -> Result<(), Error> {
        let staged: Vec<&str> = RUN_FILES
            .into_iter()
            .filter(|name| self.dir.join(name).is_file())
            .collect();
        for name in &staged {
            let target = self.out.join(name);
            std::fs::rename(self.dir.join(name), &target).map_err(io(&target, "replace"))?;
        }
        for name in RUN_FILES {
            if !staged.contains(&name) {
                let _ = std::fs::remove_file(self.out.join(name));
            }
        }
        Ok(())
    }

    fn inside(out: PathBuf) -> Result<Staging, Error> {
        let inside = out.join(format!("{STAGING}{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&inside);
        std::fs::create_dir(&inside).map_err(io(&inside, "create the staging folder"))?;
        Ok(Staging {
            out,
            dir: inside,
            in_place: true,
            committed: false,
        })
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.dir);
        }
    }
}

/// `<parent>/<name><mark><pid>`, or `None` for a folder without a parent (the root).
fn sibling(out: &Path, mark: &str, pid: u32) -> Option<PathBuf> {
    let name = out.file_name()?.to_string_lossy().into_owned();
    Some(out.with_file_name(format!("{name}{mark}{pid}")))
}

/// The process id in a name `<prefix><pid>`, when the name has that form.
fn pid_after(name: &OsStr, prefix: &str) -> Option<u32> {
    name.to_str()?.strip_prefix(prefix)?.parse().ok()
}

/// Whether a leftover of process `pid` may be removed: ours (a staging folder of this process is
/// made afresh), or of a process that no longer runs.
fn is_stale(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    if cfg!(target_os = "linux") && Path::new("/proc/self").exists() {
        !Path::new("/proc").join(pid.to_string()).exists()
    } else {
        // No portable liveness test: two runs into one folder at once are not supported.
        true
    }
}

/// Whether a top-level entry of an output folder was written by ellipack: a run file, the
/// temporary file of one (`.<file>.tmp-<pid>`, see [`crate::output`]), or an in-place staging
/// folder.
fn is_ours(name: &OsStr) -> bool {
    let Some(name) = name.to_str() else {
        return false;
    };
    RUN_FILES.contains(&name)
        || temporary_of(name).is_some()
        || name.starts_with(STAGING)
        || name.starts_with(PROBE)
}

/// The process id of a temporary file of a run file.
fn temporary_of(name: &str) -> Option<u32> {
    RUN_FILES.iter().find_map(|file| {
        name.strip_prefix('.')?
            .strip_prefix(file)?
            .strip_prefix(".tmp-")?
            .parse()
            .ok()
    })
}

/// Removes the leftovers of killed runs: temporary files and staging folders in `out`, staging
/// folders beside it, and puts back a retired previous set when the swap by two renames was cut
/// between them (the output folder then is missing or empty). Best effort: what cannot be
/// removed is left, and is never read as a packing.
fn clean_up(out: &Path) {
    if let Ok(entries) = std::fs::read_dir(out) {
        for entry in entries.filter_map(Result::ok) {
            let name = entry.file_name();
            let Some(text) = name.to_str() else { continue };
            let stale_file = temporary_of(text).is_some_and(is_stale)
                || pid_after(&name, PROBE).is_some_and(is_stale);
            if stale_file {
                let _ = std::fs::remove_file(entry.path());
            } else if pid_after(&name, STAGING).is_some_and(is_stale) {
                let _ = std::fs::remove_dir_all(entry.path());
            }
        }
    }
    let (Some(parent), Some(base)) = (out.parent(), out.file_name()) else {
        return;
    };
    let base = base.to_string_lossy().into_owned();
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    for entry in entries.filter_map(Result::ok) {
        let name = entry.file_name();
        let path = entry.path();
        if pid_after(&name, &format!("{base}{STAGING}")).is_some_and(is_stale) {
            let _ = std::fs::remove_dir_all(&path);
        } else if pid_after(&name, &format!("{base}{RETIRED}")).is_some_and(is_stale) {
            let empty = std::fs::read_dir(out).map_or(true, |mut d| d.next().is_none());
            if empty {
                let _ = std::fs::remove_dir(out);
                if std::fs::rename(&path, out).is_ok() {
                    continue;
                }
            }
            let _ = std::fs::remove_dir_all(&path);
        }
    }
}

/// At most this many of the user's entries are carried over; a folder that holds more (a home
/// folder given as `--out`) gets the run's files one by one instead.
const MAX_CARRIED_ENTRIES: usize = 10_000;

/// At most this many bytes are copied where hard links are refused.
const MAX_COPIED_BYTES: u64 = 64 << 20;

/// What carrying over may still cost.
struct Budget {
    entries: usize,
    bytes: u64,
    device: Option<u64>,
}

/// Mirrors `from` into `to` without copying data: hard links for files, new folders for
/// folders, new links for symbolic links (a copy only where hard links are refused). At the top
/// level, ellipack's own files are skipped. Refuses (so that the caller falls back to replacing
/// files one by one) rather than mirror a large tree, cross into another file system or copy
/// much data.
fn carry(from: &Path, to: &Path, top: bool) -> Result<(), Error> {
    let mut budget = Budget {
        entries: MAX_CARRIED_ENTRIES,
        bytes: MAX_COPIED_BYTES,
        device: device_of(from),
    };
    carry_within(from, to, top, &mut budget)
}

fn carry_within(from: &Path, to: &Path, top: bool, budget: &mut Budget) -> Result<(), Error> {
    let entries = std::fs::read_dir(from).map_err(io(from, "read the folder"))?;
    for entry in entries {
        let entry = entry.map_err(io(from, "read the folder"))?;
        let name = entry.file_name();
        if top && is_ours(&name) {
            continue;
        }
        let (src, dst) = (entry.path(), to.join(&name));
        budget.entries = budget.entries.checked_sub(1).ok_or_else(|| Error::Carry {
            path: from.to_path_buf(),
            reason: "more than 10 000 of the user's files and folders",
        })?;
        let kind = entry.file_type().map_err(io(&src, "inspect"))?;
        if kind.is_dir() {
            if device_of(&src) != budget.device {
                return Err(Error::Carry {
                    path: src,
                    reason: "another file system is mounted there",
                });
            }
            std::fs::create_dir(&dst).map_err(io(&dst, "create"))?;
            copy_mode(&src, &dst);
            carry_within(&src, &dst, false, budget)?;
        } else if kind.is_symlink() {
            link_like(&src, &dst)?;
        } else if std::fs::hard_link(&src, &dst).is_err() {
            let len = entry.metadata().map_err(io(&src, "inspect"))?.len();
            budget.bytes = budget.bytes.checked_sub(len).ok_or_else(|| Error::Carry {
                path: src.clone(),
                reason: "cannot be hard-linked and is too large to copy",
            })?;
            std::fs::copy(&src, &dst).map_err(io(&src, "keep (copy)"))?;
        }
    }
    Ok(())
}

#[cfg(unix)]
fn device_of(path: &Path) -> Option<u64> {
    use std::os::unix::fs::MetadataExt;
    std::fs::symlink_metadata(path).ok().map(|m| m.dev())
}

#[cfg(not(unix))]
fn device_of(_: &Path) -> Option<u64> {
    None
}

#[cfg(unix)]
fn link_like(src: &Path, dst: &Path) -> Result<(), Error> {
    let target = std::fs::read_link(src).map_err(io(src, "read the link"))?;
    std::os::unix::fs::symlink(target, dst).map_err(io(dst, "create the link"))
}

#[cfg(not(unix))]
fn link_like(src: &Path, dst: &Path) -> Result<(), Error> {
    std::fs::copy(src, dst)
        .map(|_| ())
        .map_err(io(src, "keep (copy)"))
}

fn copy_mode(from: &Path, to: &Path) {
    if let Ok(meta) = std::fs::metadata(from) {
        let _ = std::fs::set_permissions(to, meta.permissions());
    }
}

fn same_device(a: &Path, b: &Path) -> bool {
    device_of(a) == device_of(b)
}

/// Puts the staging folder in the place of `out` and removes the previous set.
fn swap(staging: &Path, out: &Path) -> Result<(), Error> {
    match exchange(staging, out) {
        Ok(()) => {
            // `staging` now names the previous set. Left behind if this fails: the next run
            // removes it.
            let _ = std::fs::remove_dir_all(staging);
            return Ok(());
        }
        Err(e) if !exchange_unsupported(&e) => return Err(io(out, "swap in the new files")(e)),
        Err(_) => {}
    }
    swap_by_renames(staging, out)
}

/// The swap where the file system cannot exchange: `out` is set aside under the retired name
/// (which the next run puts back if this one dies before the second rename), then the staging
/// folder takes its place.
fn swap_by_renames(staging: &Path, out: &Path) -> Result<(), Error> {
    let retired = sibling(out, RETIRED, std::process::id())
        .unwrap_or_else(|| staging.with_extension("retired"));
    std::fs::rename(out, &retired).map_err(io(out, "set the previous files aside"))?;
    if let Err(e) = std::fs::rename(staging, out) {
        let _ = std::fs::rename(&retired, out);
        return Err(io(out, "move the new files in")(e));
    }
    let _ = std::fs::remove_dir_all(&retired);
    Ok(())
}

#[cfg(all(target_os = "linux", any(target_env = "gnu", target_env = "musl")))]
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    use std::os::unix::ffi::OsStrExt;
    let a = std::ffi::CString::new(a.as_os_str().as_bytes())?;
    let b = std::ffi::CString::new(b.as_os_str().as_bytes())?;
    // SAFETY: both pointers are to NUL-terminated strings that live across the call;
    // renameat2 only reads them.
    let rc = unsafe {
        libc::renameat2(
            libc::AT_FDCWD,
            a.as_ptr(),
            libc::AT_FDCWD,
            b.as_ptr(),
            libc::RENAME_EXCHANGE,
        )
    };
    if rc == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error())
    }
}

#[cfg(not(all(target_os = "linux", any(target_env = "gnu", target_env = "musl"))))]
fn exchange(_: &Path, _: &Path) -> std::io::Result<()> {
    Err(std::io::Error::from(std::io::ErrorKind::Unsupported))
}

/// Whether the exchange failed because the system or file system cannot do it (so that two
/// renames must), rather than for a reason two renames would meet too.
fn exchange_unsupported(e: &std::io::Error) -> bool {
    #[cfg(all(target_os = "linux", any(target_env = "gnu", target_env = "musl")))]
    if let Some(code) = e.raw_os_error() {
        return [libc::EINVAL, libc::ENOSYS, libc::ENOTSUP, libc::EOPNOTSUPP].contains(&code);
    }
    e.kind() == std::io::ErrorKind::Unsupported
}

/// Writes `packing.csv`, `summary.json` and (when `xyz`) `packing.xyz` into `dir`, each
/// atomically. The directory must exist.
///
/// # Errors
/// The first error of [`write_csv`], [`write_summary`], [`write_xyz`].
pub fn write_files(
    dir: &Path,
    packing: &Packing,
    summary: &Summary,
    xyz: bool,
) -> Result<(), Error> {
    write_csv(&dir.join(CSV_FILE), &packing.items)?;
    write_summary(&dir.join(SUMMARY_FILE), summary)?;
    if xyz {
        write_xyz(&dir.join(XYZ_FILE), packing)?;
    }
    Ok(())
}

/// Reads `packing.csv` and `summary.json` and checks that they agree (dimension, item count).
///
/// # Errors
/// [`Error::Io`] naming the file, and every error of [`read_csv`] and
/// [`read_summary`]; [`Error::Inconsistent`] when they disagree.
pub fn read_packing_files(
    csv_path: &Path,
    summary_path: &Path,
) -> Result<(Packing, Summary), Error> {
    let read = |path: &Path| {
        std::fs::read_to_string(path).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })
    };
    let csv_name = csv_path.display().to_string();
    let summary_name = summary_path.display().to_string();
    let items = read_csv(&read(csv_path)?, &csv_name)?;
    let summary = read_summary(&read(summary_path)?, &summary_name)?;
    if summary.container.dimension() != items.dimension() {
        return Err(Error::Inconsistent {
            source_name: csv_name,
            message: format!(
                "{}D items (by the header) but {summary_name} has a {} container",
                items.dimension(),
                summary.container.kind()
            ),
        });
    }
    if summary.items != items.len() {
        return Err(Error::Inconsistent {
            source_name: csv_name,
            message: format!(
                "{} items, but {summary_name} says `items`: {}",
                items.len(),
                summary.items
            ),
        });
    }
    let packing = Packing::new(summary.container.clone(), items).map_err(|e| match e {
        Error::Inconsistent { message, .. } => Error::Inconsistent {
            source_name: csv_name.clone(),
            message,
        },
        other => other,
    })?;
    Ok((packing, summary))
}

/// Reads [`CSV_FILE`] and [`SUMMARY_FILE`] from a directory (see [`read_packing_files`]).
///
/// # Errors
/// As [`read_packing_files`].
pub fn read_packing_dir(dir: &Path) -> Result<(Packing, Summary), Error> {
    read_packing_files(&dir.join(CSV_FILE), &dir.join(SUMMARY_FILE))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh folder of this process in the system's temporary folder, and an empty output
    /// folder `out` in it.
    fn temp(name: &str) -> (PathBuf, PathBuf) {
        let dir =
            std::env::temp_dir().join(format!("ellipack-folder-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let out = dir.join("out");
        std::fs::create_dir_all(&out).unwrap();
        (dir, out)
    }

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_commit_replaces_our_files_and_keeps_the_users() {
        let (dir, out) = temp("commit");
        std::fs::write(out.join(CSV_FILE), "old").unwrap();
        std::fs::write(out.join(PNG_FILE), "old picture").unwrap();
        std::fs::write(out.join("notes.txt"), "mine").unwrap();
        std::fs::create_dir(out.join("sub")).unwrap();
        std::fs::write(out.join("sub").join(CSV_FILE), "mine too").unwrap();
        let staging = Staging::begin(&out).unwrap();
        std::fs::write(staging.path().join(CSV_FILE), "new").unwrap();
        assert!(matches!(staging.commit().unwrap(), Published::Swapped));
        assert_eq!(names(&out), ["notes.txt", CSV_FILE, "sub"]);
        assert_eq!(std::fs::read_to_string(out.join(CSV_FILE)).unwrap(), "new");
        assert_eq!(
            std::fs::read_to_string(out.join("sub").join(CSV_FILE)).unwrap(),
            "mine too"
        );
        assert_eq!(names(&dir), ["out"], "no staging or retired folder left");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_failure_before_the_commit_leaves_the_folder_as_it_was() {
        let (dir, out) = temp("failure");
        std::fs::write(out.join(CSV_FILE), "old").unwrap();
        std::fs::write(out.join(SUMMARY_FILE), "old summary").unwrap();
        let write_set = |into: &Path| -> Result<(), String> {
            std::fs::write(into.join(CSV_FILE), "new").map_err(|e| e.to_string())?;
            Err("injected failure after the first file".into())
        };
        {
            let staging = Staging::begin(&out).unwrap();
            assert!(write_set(staging.path()).is_err());
        }
        assert_eq!(names(&out), [CSV_FILE, SUMMARY_FILE]);
        assert_eq!(std::fs::read_to_string(out.join(CSV_FILE)).unwrap(), "old");
        assert_eq!(names(&dir), ["out"], "the staging folder is removed");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn leftovers_of_killed_runs_are_removed_and_a_retired_set_is_put_back() {
        let (dir, out) = temp("leftovers");
        // A process id above Linux's limit (2²²) never runs.
        let dead = 999_999_999u32;
        std::fs::write(out.join(format!(".{CSV_FILE}.tmp-{dead}")), "half").unwrap();
        std::fs::write(out.join(".notes.tmp-1"), "mine").unwrap();
        std::fs::create_dir(out.join(format!("{STAGING}{dead}"))).unwrap();
        std::fs::create_dir(dir.join(format!("out{STAGING}{dead}"))).unwrap();
        let staging = Staging::begin(&out).unwrap();
        assert_eq!(names(&out), [".notes.tmp-1"]);
        drop(staging);
        assert_eq!(names(&dir), ["out"]);

        // A swap by two renames cut between them: the output folder is gone.
        let retired = dir.join(format!("out{RETIRED}{dead}"));
        std::fs::rename(&out, &retired).unwrap();
        std::fs::create_dir(&out).unwrap();
        let staging = Staging::begin(&out).unwrap();
        assert_eq!(names(&out), [".notes.tmp-1"], "the previous set is back");
        drop(staging);
        assert_eq!(names(&dir), ["out"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn in_place_the_run_files_are_replaced_and_stale_ones_removed() {
        let (dir, out) = temp("inplace");
        let out = out.canonicalize().unwrap();
        std::fs::write(out.join(CSV_FILE), "old").unwrap();
        std::fs::write(out.join(XYZ_FILE), "old xyz").unwrap();
        std::fs::write(out.join("notes.txt"), "mine").unwrap();
        let staging = Staging::inside(out.clone()).unwrap();
        std::fs::write(staging.path().join(CSV_FILE), "new").unwrap();
        std::fs::write(staging.path().join(SUMMARY_FILE), "new summary").unwrap();
        assert!(matches!(
            staging.commit().unwrap(),
            Published::InPlace(None)
        ));
        assert_eq!(names(&out), ["notes.txt", CSV_FILE, SUMMARY_FILE]);
        assert_eq!(std::fs::read_to_string(out.join(CSV_FILE)).unwrap(), "new");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_failed_swap_still_delivers_the_run_files() {
        let (dir, out) = temp("fallback");
        std::fs::write(out.join(PNG_FILE), "old picture").unwrap();
        // A user's folder that cannot be carried over: a file of the same name is in its way
        // in the staging folder.
        std::fs::create_dir(out.join("notes")).unwrap();
        std::fs::write(out.join("notes").join("a.txt"), "mine").unwrap();
        let staging = Staging::begin(&out).unwrap();
        std::fs::write(staging.path().join(CSV_FILE), "new").unwrap();
        std::fs::write(staging.path().join("notes"), "in the way").unwrap();
        let published = staging.commit().unwrap();
        assert!(
            matches!(&published, Published::InPlace(Some(e)) if e.to_string().contains("notes")),
            "{published:?}"
        );
        assert_eq!(names(&out), ["notes", CSV_FILE]);
        let kept = std::fs::read_to_string(out.join("notes").join("a.txt")).unwrap();
        assert_eq!(kept, "mine");
        assert_eq!(std::fs::read_to_string(out.join(CSV_FILE)).unwrap(), "new");
        assert_eq!(names(&dir), ["out"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_large_folder_of_the_users_gets_the_run_files_in_place() {
        let (dir, out) = temp("large");
        std::fs::create_dir(out.join("data")).unwrap();
        for k in 0..=MAX_CARRIED_ENTRIES {
            std::fs::write(out.join("data").join(k.to_string()), "").unwrap();
        }
        std::fs::write(out.join(XYZ_FILE), "old").unwrap();
        let staging = Staging::begin(&out).unwrap();
        std::fs::write(staging.path().join(CSV_FILE), "new").unwrap();
        let published = staging.commit().unwrap();
        assert!(
            matches!(&published, Published::InPlace(Some(Error::Carry { .. }))),
            "{published:?}"
        );
        assert_eq!(names(&out), ["data", CSV_FILE]);
        assert_eq!(
            std::fs::read_dir(out.join("data")).unwrap().count(),
            MAX_CARRIED_ENTRIES + 1
        );
        assert_eq!(names(&dir), ["out"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_two_rename_swap_works_where_exchange_does_not() {
        let (dir, out) = temp("renames");
        let staging = dir.join("staged");
        std::fs::write(out.join(CSV_FILE), "old").unwrap();
        std::fs::create_dir(&staging).unwrap();
        std::fs::write(staging.join(CSV_FILE), "new").unwrap();
        swap_by_renames(&staging, &out).unwrap();
        assert_eq!(std::fs::read_to_string(out.join(CSV_FILE)).unwrap(), "new");
        assert_eq!(names(&dir), ["out"]);
        assert!(exchange_unsupported(&std::io::Error::from(
            std::io::ErrorKind::Unsupported
        )));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
