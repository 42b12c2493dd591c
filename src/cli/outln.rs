//! `outln!`: the command line's `println!` (declared first in `cli/mod.rs`, so every subcommand has it).

/// `println!` for command output that a closed pipe (`dualcal … | head`) ends quietly, as Unix tools
/// do, instead of panicking: the process exits with 141 (128 + SIGPIPE). Any other write error (a full
/// disk behind a redirection) is reported and exits with 1.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        if let Err(err) = writeln!(std::io::stdout(), $($arg)*) {
            if err.kind() == std::io::ErrorKind::BrokenPipe {
                std::process::exit(141);
            }
            eprintln!("error: writing to standard output: {err}");
            std::process::exit(1);
        }
    }};
}
