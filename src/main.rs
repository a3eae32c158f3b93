//! The `photon` command line. Only argument parsing and exit codes live here; each subcommand
//! is one function in `photon::tools`.
use clap::{Parser, Subcommand};
use photon::tools::bench::{self, BenchOptions};
use photon::tools::check::{self, CheckOptions};
use photon::tools::compare::{self, CompareOptions};
use photon::tools::converge::{self, ConvergeOptions};
use photon::tools::crosscheck::{self, CrosscheckOptions};
use photon::tools::merge::{self, MergeOptions};
use photon::tools::render::{self, RenderOptions};
use photon::tools::upgrade::{self, UpgradeOptions};
use std::io::Write;
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
    Render(Box<RenderOptions>),
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
    /// Load scenes without rendering: one line each (triangles, lights, materials, textures,
    /// memory estimate), then every unsupported feature or error with its file:line:column
    /// (exit 2 if any scene has one).
    Check(CheckOptions),
    /// Translate a pbrt-v3 scene file to pbrt-v4 syntax, as `pbrt --upgrade` does (warnings
    /// with file:line:column on stderr; the scene to -o or stdout).
    Upgrade(UpgradeOptions),
}

/// Parses the command line; a usage error becomes one line naming the flag (exit 2), help and
/// version print as usual.
fn parse() -> Result<Cli, ExitCode> {
    use clap::error::ErrorKind;
    Cli::try_parse_from(with_subcommand(std::env::args_os().collect())).map_err(|e| {
        match e.kind() {
            ErrorKind::DisplayHelp
            | ErrorKind::DisplayVersion
            | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
                let _ = e.print();
                ExitCode::SUCCESS
            }
            _ => {
                let text = e.to_string();
                let lines: Vec<&str> = text
                    .lines()
                    .map(str::trim)
                    .take_while(|l| {
                        !l.starts_with("Usage:") && !l.starts_with("For more information")
                    })
                    .filter(|l| !l.is_empty())
                    .collect();
                let line = lines.join(" ");
                let line = line.strip_prefix("error: ").unwrap_or(&line);
                let _ = writeln!(std::io::stderr(), "photon: {}", one_line(line));
                ExitCode::from(2)
            }
        }
    })
}

/// `photon SCENE.pbrt ...` as pbrt-v4 users type it: a first argument that is no subcommand
/// and no flag but names a `.pbrt` file (or a `.pbrt.gz`) means `render`.
fn with_subcommand(mut args: Vec<std::ffi::OsString>) -> Vec<std::ffi::OsString> {
    use clap::CommandFactory;
    let Some(first) = args.get(1).and_then(|a| a.to_str()) else {
        return args;
    };
    let is_subcommand = Cli::command()
        .get_subcommands()
        .any(|c| c.get_name() == first)
        || first == "help";
    if !is_subcommand
        && !first.starts_with('-')
        && (first.ends_with(".pbrt") || first.ends_with(".pbrt.gz"))
    {
        args.insert(1, "render".into());
    }
    args
}

/// An error as the one line photon prints after `photon: ` (at most
/// [`photon::scene::MAX_LINE`] bytes in all).
fn one_line(msg: &str) -> String {
    photon::scene::one_line(msg, photon::scene::MAX_LINE - "photon: ".len())
}

fn main() -> ExitCode {
    let cli = match parse() {
        Ok(c) => c,
        Err(code) => return code,
    };
    let result = match cli.command {
        Command::Render(opts) => render::run(&opts).map(|()| true),
        Command::Compare(opts) => compare::run(&opts),
        Command::Converge(opts) => converge::run(&opts),
        Command::Crosscheck(opts) => crosscheck::run(&opts),
        Command::Bench(opts) => bench::run(&opts).map(|()| true),
        Command::Merge(opts) => merge::run(&opts).map(|()| true),
        Command::Check(opts) => check::run(&opts).map(|()| true),
        Command::Upgrade(opts) => upgrade::run(&opts).map(|()| true),
    };
    // A render stopped by SIGINT/SIGTERM has saved what it finished; report the signal.
    if let Some(sig) = photon::interrupt::requested() {
        if let Err(e) = &result {
            let _ = writeln!(std::io::stderr(), "photon: {}", one_line(&e.to_string()));
        }
        return ExitCode::from(sig.exit_code());
    }
    match result {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            let _ = writeln!(std::io::stderr(), "photon: {}", one_line(&e.to_string()));
            match photon::interrupt::requested() {
                Some(sig) => ExitCode::from(sig.exit_code()),
                None => ExitCode::from(2),
            }
        }
    }
}
