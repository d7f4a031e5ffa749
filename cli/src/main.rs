//! The `hyrt` binary: the command line over the `hyrt` library (`render`, `compare`, `plan`,
//! `bench`, `sweep`), and the measurement tooling only it needs (benchmarks, sweeps, plots,
//! FLIP), so that the library and the inspector do without them.

mod bench;
mod cli;
mod flip;
mod measure;
mod orbit;
mod plot;
mod report;
mod scaling;
mod stats;
mod sweep;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    hyrt::process::limit_malloc_arenas();
    let cli = cli::Cli::parse();
    // An interrupted render must not leave its half-written temporaries behind.
    if let Err(e) = hyrt::output::remove_temporaries_on_signal() {
        eprintln!("warning: {e:#}");
    }
    match cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
