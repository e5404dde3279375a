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

/// `println!` that never panics: a closed pipe or a full disk on standard output leaves the
/// line unprinted (see [`say`](crate::terminal::say)). Evaluates to `false` when the line was
/// not printed.
#[macro_export]
macro_rules! say {
    ($($arg:tt)*) => {
        $crate::terminal::say(::std::format_args!($($arg)*))
    };
}
