//! The `caustic` command: parses the command line and reports errors; the work is in the library.

use std::process::ExitCode;

fn main() -> ExitCode {
    // A closed stdout (`caustic render --stats | head`) ends the process quietly, as it ends
    // any Unix tool, instead of making `println!` panic: Rust's runtime ignores SIGPIPE.
    #[cfg(unix)]
    // SAFETY: setting a signal's disposition to the default before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    caustic::mem::return_big_blocks();
    let cli = caustic::cli::Cli::from_env();
    match caustic::cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        // 128 + SIGINT, as a shell reports a process that Ctrl-C ended.
        Err(e @ caustic::Error::Interrupted(_)) => {
            eprintln!("{e}");
            ExitCode::from(130)
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
