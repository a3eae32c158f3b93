//! The `photon` command line. Only argument parsing and exit codes live here; each subcommand
//! is one function in `photon::tools`.
use clap::{Parser, Subcommand};
use photon::tools::bench::{self, BenchOptions};
use photon::tools::compare::{self, CompareOptions};
use photon::tools::converge::{self, ConvergeOptions};
use photon::tools::crosscheck::{self, CrosscheckOptions};
use photon::tools::merge::{self, MergeOptions};
use photon::tools::render::{self, RenderOptions};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "photon",
    version,
    about = "A two-pass photon-mapping renderer for pbrt-v4 scenes"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a pbrt-v4 scene to a linear EXR (with per-component layers) and a PNG preview.
    Render(RenderOptions),
    /// Compare an EXR with a reference: relMSE, RMSE, MAE, max error, PSNR (exit 1 above
    /// --max-relmse).
    Compare(CompareOptions),
    /// Error against time: each integrator and a few photon-map settings at a series of time
    /// budgets; writes a CSV and a log-log plot.
    Converge(ConvergeOptions),
    /// Cross-check Embree against obvhs on the rays of a real render, by ray kind, and compare
    /// renders made with each (exit 1 above the thresholds).
    Crosscheck(CrosscheckOptions),
    /// Benchmark both backends (build, camera/secondary/shadow rays, packets, threads) and the
    /// photon side (tracing, kd-tree, k-nearest, radiance estimates); table, CSV, JSON.
    Bench(BenchOptions),
    /// Sum partial images of one render (`render --passes A..B`) into the final image, bit for
    /// bit the same whatever the split.
    Merge(MergeOptions),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(opts) => render::run(&opts).map(|()| true),
        Command::Compare(opts) => compare::run(&opts),
        Command::Converge(opts) => converge::run(&opts),
        Command::Crosscheck(opts) => crosscheck::run(&opts),
        Command::Bench(opts) => bench::run(&opts).map(|()| true),
        Command::Merge(opts) => merge::run(&opts).map(|()| true),
    };
    // A render stopped by SIGINT/SIGTERM has saved what it finished; report the signal.
    if let Some(sig) = photon::interrupt::requested() {
        if let Err(e) = &result {
            eprintln!("photon: {e}");
        }
        return ExitCode::from(sig.exit_code());
    }
    match result {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            eprintln!("photon: {e}");
            ExitCode::from(2)
        }
    }
}
