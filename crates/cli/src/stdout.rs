//! Standard output that may be closed: `flatcut inspect --json … | head -1` closes the pipe after
//! one line, which is the reader saying it has seen enough, not an error. Every command prints
//! its results through [`outln!`](crate::outln) (or [`out!`](crate::out)); a closed pipe becomes
//! [`ClosedStdout`], which the binary turns into a normal end (exit 0) after the command's own
//! cleanup (temporary files) has run.

use std::io::Write as _;

/// Standard output was closed by its reader (a broken pipe).
#[derive(Debug)]
pub struct ClosedStdout;

impl std::fmt::Display for ClosedStdout {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("standard output was closed")
    }
}

impl std::error::Error for ClosedStdout {}

/// Writes formatted text to standard output; a broken pipe is [`ClosedStdout`].
pub fn write(args: std::fmt::Arguments<'_>) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    match out.write_fmt(args).and_then(|()| out.flush()) {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Err(ClosedStdout.into()),
        r => Ok(r?),
    }
}

/// True when the error (or one of its causes) is a closed standard output.
pub fn is_closed(e: &anyhow::Error) -> bool {
    e.chain().any(|c| c.is::<ClosedStdout>())
}

/// `println!` for command output: returns early from the command with [`ClosedStdout`] when the
/// reader has gone.
#[macro_export]
macro_rules! outln {
    () => {
        $crate::stdout::write(format_args!("\n"))?
    };
    ($($arg:tt)*) => {
        $crate::stdout::write(format_args!("{}\n", format_args!($($arg)*)))?
    };
}

/// `print!` for command output (see [`outln!`](crate::outln)).
#[macro_export]
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::stdout::write(format_args!($($arg)*))?
    };
}
