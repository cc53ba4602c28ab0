//! Writing to stdout and stderr without panicking: a closed stdout (`autobio check --json F |
//! head -1`) ends the program quietly with success, as ripgrep does; a closed stderr is ignored.

use std::fmt::Arguments;
use std::io::Write;

/// Writes to stdout; exits quietly when the reader has gone away.
pub(crate) fn stdout(args: Arguments) {
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_fmt(args).and_then(|_| out.flush()) {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(0);
        }
        let _ = writeln!(std::io::stderr(), "error: cannot write to stdout: {e}");
        std::process::exit(2);
    }
}

/// Writes to stderr, ignoring failure (there is nowhere left to report it).
pub(crate) fn stderr(args: Arguments) {
    let _ = std::io::stderr().lock().write_fmt(args);
}

/// `println!` through [`stdout`].
macro_rules! outln {
    ($($t:tt)*) => { $crate::output::stdout(format_args!("{}\n", format_args!($($t)*))) };
}

/// `print!` through [`stdout`].
macro_rules! out {
    ($($t:tt)*) => { $crate::output::stdout(format_args!($($t)*)) };
}

/// `eprintln!` through [`stderr`].
macro_rules! errln {
    ($($t:tt)*) => { $crate::output::stderr(format_args!("{}\n", format_args!($($t)*))) };
}

/// `eprint!` through [`stderr`].
macro_rules! err {
    ($($t:tt)*) => { $crate::output::stderr(format_args!($($t)*)) };
}
