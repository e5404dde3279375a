//! Printing to standard output when its reader may have gone (`ellipack … | head`): a closed
//! pipe is the reader saying it has seen enough, not an error worth a panic.

use std::fmt;
use std::io::{self, Write};

/// Whether a write failed because the reader closed the pipe.
pub fn reader_gone(error: &io::Error) -> bool {
    error.kind() == io::ErrorKind::BrokenPipe
}

/// Prints `line` and a newline to standard output. Returns `false` when the reader has gone
/// (nothing more needs printing); another write error is reported on standard error.
pub fn say(line: fmt::Arguments<'_>) -> bool {
    let mut out = io::stdout().lock();
    match out.write_fmt(line).and_then(|()| out.write_all(b"\n")) {
        Ok(()) => true,
        Err(e) if reader_gone(&e) => false,
        Err(e) => {
            eprintln!("warning: standard output: {e}");
            false
        }
    }
}

/// Prints `line` and a newline to standard error, ignoring a failed write: with standard error
/// closed there is nowhere left to report anything, and the run's files matter more.
pub fn note(line: fmt::Arguments<'_>) {
    let mut err = io::stderr().lock();
    let _ = err.write_fmt(line).and_then(|()| err.write_all(b"\n"));
}

/// `println!` that never panics: a closed pipe or a full disk on standard output leaves the
/// line unprinted (see [`say`](crate::terminal::say)). Evaluates to `false` when the line was
/// not printed.
#[macro_export]
macro_rules! say {
    ($($arg:tt)*) => {
        $crate::terminal::say(::std::format_args!($($arg)*))
    };
}

/// `eprintln!` that never panics: a closed standard error leaves the line unprinted (see
/// [`note`](crate::terminal::note)).
#[macro_export]
macro_rules! note {
    ($($arg:tt)*) => {
        $crate::terminal::note(::std::format_args!($($arg)*))
    };
}
