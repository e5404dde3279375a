//! Output files are written to a temporary file beside the target and renamed into place, so
//! that an interrupted run never leaves a half-written file under the final name.
//!
//! What is not a regular file is written into, never replaced: a FIFO, a character device such
//! as `/dev/null`, and the names of open files (`/dev/stdout`, `/dev/stderr`, `/dev/fd/N`),
//! even when they lead to a regular file. A symbolic link is followed: its target is replaced
//! atomically and the link stays. A file that is replaced keeps its permission mode.

use crate::Error;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

/// Writes `bytes` to `path` atomically (temporary file in the same directory, then rename),
/// or into it when it is a FIFO or a device (see the module documentation).
///
/// # Errors
/// [`Error::Io`] naming the file when the directory is not writable or the disk is full.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    let mut file = OutputFile::create(path)?;
    file.write_all(bytes).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    file.commit()
}

/// Refuses to write `output` when it is the regular file `input` under any name (the same
/// path, `./`, a symbolic or hard link): writing would destroy what is being read. Call it
/// before reading or writing anything.
///
/// # Errors
/// [`Error::SameFile`].
pub fn refuse_overwriting_input(input: &Path, output: &Path) -> Result<(), Error> {
    let (Ok(a), Ok(b)) = (std::fs::metadata(input), std::fs::metadata(output)) else {
        // A file that does not exist is not the input; a missing input is reported by the
        // reader.
        return Ok(());
    };
    if a.is_file() && a.dev() == b.dev() && a.ino() == b.ino() {
        return Err(Error::SameFile {
            input: input.to_path_buf(),
            output: output.to_path_buf(),
        });
    }
    Ok(())
}

/// A temporary file that is removed when dropped, unless it was renamed into place.
struct Temporary {
    path: PathBuf,
    armed: bool,
}

impl Drop for Temporary {
    fn drop(&mut self) {
        if self.armed {
            // Best effort: nothing more can be done about a temporary file that cannot be
            // removed, and the error that led here is the one worth reporting.
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

enum Sink {
    Stdout(io::Stdout),
    Stderr(io::Stderr),
    Direct(File),
    Atomic {
        file: BufWriter<File>,
        temporary: Temporary,
        target: PathBuf,
        mode: Option<std::fs::Permissions>,
    },
}

/// An output being written: a temporary file renamed over the target by
/// [`OutputFile::commit`], or the FIFO, device or standard output itself. Dropped without
/// `commit`, the temporary file is removed and the target is untouched.
pub struct OutputFile {
    path: PathBuf,
    sink: Sink,
}

impl OutputFile {
    /// Prepares to write `path` (see the module documentation for what is replaced and what
    /// is written into).
    ///
    /// # Errors
    /// [`Error::Io`] naming the file when it is a directory, or the temporary file or the
    /// device cannot be opened.
    pub fn create(path: &Path) -> Result<OutputFile, Error> {
        let io = |source| Error::Io {
            path: path.to_path_buf(),
            source,
        };
        // The shell's streams and devices are written where they are, without a temporary file.
        let direct = |sink| OutputFile {
            path: path.to_path_buf(),
            sink,
        };
        match descriptor(path) {
            Some(Descriptor::Stdout) => return Ok(direct(Sink::Stdout(io::stdout()))),
            Some(Descriptor::Stderr) => return Ok(direct(Sink::Stderr(io::stderr()))),
            Some(Descriptor::Other) => {
                // Appending continues where the shell's redirection stands instead of
                // writing over it from offset 0.
                let file = std::fs::OpenOptions::new()
                    .append(true)
                    .open(path)
                    .map_err(io)?;
                return Ok(direct(Sink::Direct(file)));
            }
            None => {}
        }
        let (target, mode) = match std::fs::metadata(path) {
            Ok(m) if m.is_dir() => {
                return Err(io(io::Error::new(
                    io::ErrorKind::IsADirectory,
                    "is a directory, not a file",
                )));
            }
            Ok(m) if !m.is_file() => {
                let device = std::fs::OpenOptions::new()
                    .write(true)
                    .open(path)
                    .map_err(io)?;
                return Ok(direct(Sink::Direct(device)));
            }
            Ok(m) => (
                std::fs::canonicalize(path).map_err(io)?,
                Some(m.permissions()),
            ),
            Err(_) => (dangling_target(path), None),
        };
        let temporary = Temporary {
            path: temporary_sibling(&target),
            armed: true,
        };
        let file = File::create(&temporary.path).map_err(io)?;
        Ok(OutputFile {
            path: path.to_path_buf(),
            sink: Sink::Atomic {
                file: BufWriter::new(file),
                temporary,
                target,
                mode,
            },
        })
    }

    /// Finishes the output: flushes it, and for a regular file syncs the temporary file,
    /// gives it the mode of the file it replaces and renames it over the target.
    ///
    /// # Errors
    /// [`Error::Io`] naming the file (the temporary file is removed).
    pub fn commit(self) -> Result<(), Error> {
        let io = |source| Error::Io {
            path: self.path.clone(),
            source,
        };
        match self.sink {
            Sink::Stdout(mut out) => out.flush().map_err(io),
            Sink::Stderr(mut out) => out.flush().map_err(io),
            Sink::Direct(mut device) => device.flush().map_err(io),
            Sink::Atomic {
                file,
                mut temporary,
                target,
                mode,
            } => {
                let file = file.into_inner().map_err(|e| io(e.into_error()))?;
                file.sync_all().map_err(io)?;
                if let Some(mode) = mode {
                    file.set_permissions(mode).map_err(io)?;
                }
                drop(file);
                std::fs::rename(&temporary.path, &target).map_err(io)?;
                temporary.armed = false;
                Ok(())
            }
        }
    }
}

impl Write for OutputFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        match &mut self.sink {
            Sink::Stdout(out) => out.write(buf),
            Sink::Stderr(out) => out.write(buf),
            Sink::Direct(device) => device.write(buf),
            Sink::Atomic { file, .. } => file.write(buf),
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        match &mut self.sink {
            Sink::Stdout(out) => out.flush(),
            Sink::Stderr(out) => out.flush(),
            Sink::Direct(device) => device.flush(),
            Sink::Atomic { file, .. } => file.flush(),
        }
    }
}

/// A name of one of this process's open files.
enum Descriptor {
    Stdout,
    Stderr,
    Other,
}

/// Whether `path` names one of this process's open files (`/dev/stdout`, `/dev/fd/N`,
/// `/proc/self/fd/N`). Renamed over, the shell's redirected file would be replaced; opened
/// anew, it would be written from offset 0; so these are written through the open file.
fn descriptor(path: &Path) -> Option<Descriptor> {
    let is = |names: &[&str]| names.iter().any(|name| path == Path::new(name));
    if is(&["/dev/stdout", "/dev/fd/1", "/proc/self/fd/1"]) {
        Some(Descriptor::Stdout)
    } else if is(&["/dev/stderr", "/dev/fd/2", "/proc/self/fd/2"]) {
        Some(Descriptor::Stderr)
    } else if path.starts_with("/dev/fd") || path.starts_with("/proc/self/fd") {
        Some(Descriptor::Other)
    } else {
        None
    }
}

/// Where a path that does not exist (yet) is written: itself, or the target of a dangling
/// symbolic link, so that the link is kept.
fn dangling_target(path: &Path) -> PathBuf {
    match std::fs::read_link(path) {
        Ok(target) if target.is_absolute() => target,
        Ok(target) => path.parent().unwrap_or(Path::new("")).join(target),
        Err(_) => path.to_path_buf(),
    }
}

fn temporary_sibling(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    path.with_file_name(format!(".{name}.tmp-{}", std::process::id()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh folder of this process in the system's temporary folder, removed with all it
    /// holds when dropped (also when a test fails).
    struct TempDir(PathBuf);

    impl std::ops::Deref for TempDir {
        type Target = Path;
        fn deref(&self) -> &Path {
            &self.0
        }
    }

    impl Drop for TempDir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    fn temp(name: &str) -> TempDir {
        let dir = std::env::temp_dir().join(format!("ellipack-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }

    /// How many entries `dir` holds.
    fn entries(dir: &Path) -> usize {
        std::fs::read_dir(dir).unwrap().count()
    }

    #[test]
    fn writes_and_replaces() {
        let dir = temp("output");
        let path = dir.join("a.csv");
        write_atomically(&path, b"one").unwrap();
        write_atomically(&path, b"two").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"two");
        assert_eq!(entries(&dir), 1, "no temporary file left");
    }

    #[test]
    fn an_output_dropped_before_commit_leaves_nothing_behind() {
        let dir = temp("guard");
        let path = dir.join("a.csv");
        std::fs::write(&path, b"old").unwrap();
        {
            let mut file = OutputFile::create(&path).unwrap();
            file.write_all(&[b'x'; 100_000]).unwrap();
            assert_eq!(entries(&dir), 2, "temporary file");
        }
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
        assert_eq!(entries(&dir), 1, "temporary file removed");
    }

    #[test]
    fn a_directory_is_not_replaced() {
        let dir = temp("outdir");
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        let err = write_atomically(&dir.join("sub"), b"x")
            .unwrap_err()
            .to_string();
        assert!(err.contains("is a directory"), "{err}");
        assert!(dir.join("sub").is_dir());
        assert_eq!(entries(&dir), 1);
    }

    #[test]
    fn unwritable_directory_is_an_error_naming_the_file() {
        let path = Path::new("/nonexistent-dir-for-ellipack/x.csv");
        let err = write_atomically(path, b"x").unwrap_err().to_string();
        assert!(err.contains("x.csv"), "{err}");
    }
}
