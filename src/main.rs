//! The `photon` command line. Only argument parsing and exit codes live here; each subcommand
//! is one function in `photon::tools`.
use clap::{Parser, Subcommand};
use photon::tools::bench::{self, BenchOptions};
use photon::tools::check::{self, CheckOptions};
use photon::tools::compare::{self, CompareOptions};
use photon::tools::converge::{self, ConvergeOptions};
use photon::tools::convert::{self, ConvertOptions};
use photon::tools::crosscheck::{self, CrosscheckOptions};
use photon::tools::denoise::{self, DenoiseOptions};
use photon::tools::merge::{self, MergeOptions};
use photon::tools::render::{self, RenderOptions};
use photon::tools::upgrade::{self, UpgradeOptions};
use std::io::Write;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "photon",
    version,
    args_override_self = true,
    after_help = "Every on/off flag --x also has the form --no-x (the last one given wins).",
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
    /// Compare an image with a reference (EXR, PNG or PFM each): relMSE, RMSE, MAE, max error,
    /// PSNR and LDR-FLIP (exit 1 above --max-relmse).
    Compare(CompareOptions),
    /// Convert an EXR, PNG or PFM image to PNG (exposure, tone curve), EXR or PFM (linear),
    /// optionally cropped or from one EXR layer.
    Convert(ConvertOptions),
    /// Denoise a render with Intel Open Image Denoise (feature `denoise`), guided by its
    /// `albedo` and `normal` layers when it has them; the noisy beauty is kept as layer `noisy`.
    Denoise(DenoiseOptions),
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
    let args = negations(with_subcommand(std::env::args_os().collect()));
    Cli::try_parse_from(args).map_err(|e| match e.kind() {
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
                .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"))
                .filter(|l| !l.is_empty())
                .collect();
            let line = lines.join(" ");
            let line = line.strip_prefix("error: ").unwrap_or(&line);
            let _ = writeln!(std::io::stderr(), "photon: {}", one_line(line));
            ExitCode::from(2)
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

/// `--no-x` for every on/off flag `--x` of the subcommand (unless `--no-x` is a flag of its
/// own, as `--no-png` is): a switch that takes a value (`--final-gather[=BOOL]`) becomes
/// `--x=false`; a plain flag (`--progressive`) is taken back, with the `--x` before it. The
/// last of `--x` and `--no-x` wins, as clap lets a later flag override an earlier one.
fn negations(args: Vec<std::ffi::OsString>) -> Vec<std::ffi::OsString> {
    use clap::CommandFactory;
    let cli = Cli::command();
    let Some(sub) = (args.get(1).and_then(|a| a.to_str()))
        .and_then(|name| cli.get_subcommands().find(|c| c.get_name() == name))
    else {
        return args;
    };
    let longs: Vec<&str> = sub.get_arguments().filter_map(|a| a.get_long()).collect();
    let mut out: Vec<std::ffi::OsString> = Vec::with_capacity(args.len());
    for (i, arg) in args.iter().enumerate() {
        let negated = arg.to_str().and_then(|a| a.strip_prefix("--no-"));
        let Some(name) = negated.filter(|n| !longs.contains(&&*format!("no-{n}"))) else {
            out.push(arg.clone());
            continue;
        };
        let target = sub.get_arguments().find(|a| a.get_long() == Some(name));
        match target {
            _ if i < 2 || args[1..i].iter().any(|a| a == "--") => out.push(arg.clone()),
            Some(a) if matches!(a.get_action(), clap::ArgAction::SetTrue) => {
                out.retain(|o| o.to_str() != Some(&format!("--{name}")));
            }
            Some(a)
                if a.is_require_equals_set()
                    && a.get_num_args().is_some_and(|r| r.min_values() == 0) =>
            {
                out.push(format!("--{name}=false").into());
            }
            _ => out.push(arg.clone()),
        }
    }
    out
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
        Command::Convert(opts) => convert::run(&opts).map(|()| true),
        Command::Denoise(opts) => denoise::run(&opts).map(|()| true),
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
