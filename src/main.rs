//! The `hyrt` binary: a thin shell over `hyrt::cli`.

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = hyrt::cli::Cli::parse();
    // An interrupted render must not leave its half-written temporaries behind.
    if let Err(e) = hyrt::output::remove_temporaries_on_signal() {
        eprintln!("warning: {e:#}");
    }
    match hyrt::cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
