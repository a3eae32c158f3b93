//! The `photon` command line. Only argument parsing and exit codes live here; each subcommand
//! is one function in `photon::tools`.
use clap::{Parser, Subcommand};
use photon::tools::bench::{self, BenchOptions};
use photon::tools::check::{self, CheckOptions};
use photon::tools::compare::{self, CompareOptions};
use photon::tools::converge::{self, ConvergeOptions};
use photon::tools::crosscheck::{self, CrosscheckOptions};
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
    /// Load scenes without rendering: one line each (triangles, lights, materials, textures,
    /// memory estimate), then every unsupported feature or error with its file:line:column
    /// (exit 2 if any scene has one).
    Check(CheckOptions),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(opts) => render::run(&opts).map(|()| true),
        Command::Compare(opts) => compare::run(&opts),
        Command::Converge(opts) => converge::run(&opts),
        Command::Crosscheck(opts) => crosscheck::run(&opts),
        Command::Bench(opts) => bench::run(&opts).map(|()| true),
        Command::Check(opts) => check::run(&opts).map(|()| true),
    };
    match result {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            eprintln!("photon: {e}");
            ExitCode::from(2)
        }
    }
}
