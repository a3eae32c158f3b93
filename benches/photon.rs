//! `cargo bench`: the same benchmark as `photon bench`, plus the `kiddo` k-nearest baseline
//! (a dev-dependency). Arguments after `--` are `photon bench`'s, e.g.
//! `cargo bench --bench photon -- --quick --csv bench.csv`.
use clap::Parser;
use photon::tools::bench::{self, BenchOptions};
use std::process::ExitCode;

#[path = "common/kiddo.rs"]
mod kiddo;

#[derive(Parser)]
#[command(name = "photon-bench")]
struct Args {
    #[command(flatten)]
    opts: BenchOptions,
    /// Passed by `cargo bench`; ignored.
    #[arg(long, hide = true)]
    bench: bool,
}

fn main() -> ExitCode {
    let args = Args::parse();
    photon::accel::cpu::enable_flush_denormals();
    let mut baseline = kiddo::Kiddo::default();
    match bench::run_with(&args.opts, Some(&mut baseline)) {
        Ok(_) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("photon-bench: {e}");
            ExitCode::from(2)
        }
    }
}
