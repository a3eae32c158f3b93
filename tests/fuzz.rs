//! A deterministic mutation fuzzer over the repository's and the shared scenes and PLY files.
//!
//! Each case takes one seed file (a scene, or one PLY of a scene that uses it), applies one to
//! three mutations chosen by a hash of the case number (byte flips, token swaps, numbers
//! replaced by extremes such as 1e38, -0, NaN, huge integers, truncation, duplication of a
//! run of lines) and runs `photon render` on it at 8x8 pixels, 1 spp and a few hundred photons
//! under a 1 GiB address-space cap and a timeout. Every run must exit 0 or 2; on 2 with
//! exactly one stderr line that says where the problem is; never a panic (101), an abort or
//! another signal, or a hang. Failing inputs are kept in `target/tmp/fuzz/failures/`.
//!
//! `cargo test --release --test fuzz` runs [`CASES`] cases; the long run,
//! `PHOTON_FUZZ_SECONDS=3600 cargo test --release --test fuzz -- --ignored`, keeps going with
//! new case numbers for that many seconds (default one hour).
mod common;

use common::*;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Cases of the normal run.
const CASES: u64 = 2000;
/// Case numbers of the long run start here (it never repeats the normal run's).
const LONG_RUN_FIRST_CASE: u64 = 1 << 32;

/// A seed: a scene file and, when fuzzing a PLY, which of its PLY files.
#[derive(Clone, Debug)]
struct Seed {
    scene: PathBuf,
    ply: Option<PathBuf>,
}

/// The scenes, and each PLY file of every scene directory with a `meshes/` folder.
fn seeds() -> Vec<Seed> {
    let mut v = Vec::new();
    for scene in all_scenes() {
        v.push(Seed {
            scene: scene.clone(),
            ply: None,
        });
        let meshes = scene.parent().unwrap().join("meshes");
        if let Ok(rd) = std::fs::read_dir(&meshes) {
            let mut plys: Vec<PathBuf> = rd
                .filter_map(|e| e.ok())
                .map(|e| e.path())
                .filter(|p| p.extension().is_some_and(|e| e == "ply"))
                .collect();
            plys.sort();
            for p in plys {
                v.push(Seed {
                    scene: scene.clone(),
                    ply: Some(p),
                });
            }
        }
    }
    assert!(v.len() >= 3, "seed files found: {v:?}");
    v
}

/// Number tokens substituted by [`mutate`].
const EXTREMES: [&str; 14] = [
    "1e38",
    "-1e38",
    "3.4e38",
    "-0",
    "0",
    "NaN",
    "inf",
    "1e-45",
    "2147483647",
    "-2147483648",
    "4294967296",
    "99999999999999999999",
    "1e-30",
    "-1",
];

/// Byte ranges of the whitespace-separated tokens of `b`.
fn tokens(b: &[u8]) -> Vec<(usize, usize)> {
    let mut v = Vec::new();
    let mut i = 0;
    while i < b.len() {
        while i < b.len() && b[i].is_ascii_whitespace() {
            i += 1;
        }
        let s = i;
        while i < b.len() && !b[i].is_ascii_whitespace() {
            i += 1;
        }
        if i > s {
            v.push((s, i));
        }
    }
    v
}

/// One mutation of `b`, chosen by `rng`.
fn mutate(b: &mut Vec<u8>, rng: &mut Rng) {
    if b.is_empty() {
        b.extend(b"WorldBegin");
        return;
    }
    match rng.below(6) {
        0 => {
            let i = rng.below(b.len());
            b[i] = rng.next_u64() as u8;
        }
        1 => {
            let t = tokens(b);
            if t.len() >= 2 {
                let (x, y) = (t[rng.below(t.len())], t[rng.below(t.len())]);
                let (a, c) = if x.0 <= y.0 { (x, y) } else { (y, x) };
                if a.1 <= c.0 {
                    let mut out = b[..a.0].to_vec();
                    out.extend_from_slice(&b[c.0..c.1]);
                    out.extend_from_slice(&b[a.1..c.0]);
                    out.extend_from_slice(&b[a.0..a.1]);
                    out.extend_from_slice(&b[c.1..]);
                    *b = out;
                }
            }
        }
        2 | 3 => {
            let nums: Vec<(usize, usize)> = tokens(b)
                .into_iter()
                .filter(|&(s, _)| b[s].is_ascii_digit() || b[s] == b'-' || b[s] == b'.')
                .collect();
            if let Some(&(s, e)) = nums.get(rng.below(nums.len())) {
                let x = EXTREMES[rng.below(EXTREMES.len())];
                b.splice(s..e, x.bytes());
            }
        }
        4 => {
            let cut = rng.below(b.len());
            b.truncate(cut);
        }
        _ => {
            let lines: Vec<usize> = std::iter::once(0)
                .chain(
                    b.iter()
                        .enumerate()
                        .filter(|(_, &c)| c == b'\n')
                        .map(|(i, _)| i + 1),
                )
                .collect();
            let a = lines[rng.below(lines.len())];
            let z = lines[rng.below(lines.len())].max(a);
            let copies = 1 + rng.below(3);
            let run = b[a..z].to_vec();
            for _ in 0..copies {
                b.splice(a..a, run.iter().copied());
            }
        }
    }
}

/// Builds case `n` in `dir` (scene, its meshes, one file mutated); returns the scene path.
fn build_case(n: u64, seeds: &[Seed], dir: &Path) -> PathBuf {
    let mut rng = Rng(n.wrapping_mul(0x2545_f491_4f6c_dd1d) ^ 0x5eed);
    let seed = &seeds[rng.below(seeds.len())];
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    let src_dir = seed.scene.parent().unwrap();
    if let Ok(rd) = std::fs::read_dir(src_dir.join("meshes")) {
        for e in rd.filter_map(|e| e.ok()) {
            std::fs::copy(e.path(), dir.join("meshes").join(e.file_name())).unwrap();
        }
    }
    let target = match &seed.ply {
        Some(p) => dir.join("meshes").join(p.file_name().unwrap()),
        None => dir.join("scene.pbrt"),
    };
    std::fs::copy(&seed.scene, dir.join("scene.pbrt")).unwrap();
    let mut bytes = std::fs::read(&target).unwrap();
    for _ in 0..1 + rng.below(3) {
        mutate(&mut bytes, &mut rng);
    }
    std::fs::write(&target, &bytes).unwrap();
    dir.join("scene.pbrt")
}

/// Runs case `n`; `Err` describes a failure (and keeps its files).
fn run_case(n: u64, seeds: &[Seed], root: &Path) -> Result<i32, String> {
    let dir = root.join(format!("work-{n}"));
    let scene = build_case(n, seeds, &dir);
    let photons = ["--global-photons", "300", "--caustic-photons", "300"];
    let args = render_args(&scene, &dir, &photons);
    let r = run_capped(&args, GIB, Duration::from_secs(120));
    match check_run(&r) {
        Ok(()) => {
            let _ = std::fs::remove_dir_all(&dir);
            Ok(r.code.unwrap_or(-1))
        }
        Err(e) => {
            let keep = root.join("failures").join(format!("case-{n}"));
            let _ = std::fs::remove_dir_all(&keep);
            let _ = std::fs::create_dir_all(keep.parent().unwrap());
            let _ = std::fs::rename(&dir, &keep);
            Err(format!("case {n} ({}): {e}", keep.display()))
        }
    }
}

/// Runs cases `first..` on all cores until `done(count, elapsed)`; returns (exit-code
/// histogram [ok, 2], failures).
fn fuzz(first: u64, done: impl Fn(u64, Duration) -> bool + Sync) -> ([u64; 2], Vec<String>) {
    let seeds = seeds();
    let root = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("fuzz");
    let next = AtomicU64::new(first);
    let ok = AtomicU64::new(0);
    let err2 = AtomicU64::new(0);
    let failures = Mutex::new(Vec::new());
    let start = Instant::now();
    let workers = std::thread::available_parallelism()
        .map_or(2, |n| n.get())
        .max(2);
    std::thread::scope(|s| {
        for _ in 0..workers {
            s.spawn(|| loop {
                let n = next.fetch_add(1, Ordering::Relaxed);
                if done(n - first, start.elapsed()) {
                    break;
                }
                match run_case(n, &seeds, &root) {
                    Ok(0) => ok.fetch_add(1, Ordering::Relaxed),
                    Ok(_) => err2.fetch_add(1, Ordering::Relaxed),
                    Err(e) => {
                        eprintln!("{e}");
                        failures.lock().unwrap().push(e);
                        0
                    }
                };
            });
        }
    });
    let hist = [ok.into_inner(), err2.into_inner()];
    (hist, failures.into_inner().unwrap())
}

#[test]
fn mutated_scenes_and_plys_exit_cleanly() {
    let t = Instant::now();
    let (hist, failures) = fuzz(0, |n, _| n >= CASES);
    println!(
        "{CASES} cases in {:.1} s: {} rendered, {} rejected with one located line, {} failures",
        t.elapsed().as_secs_f64(),
        hist[0],
        hist[1],
        failures.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // The mutations must exercise both outcomes.
    assert!(hist[0] > CASES / 20 && hist[1] > CASES / 20, "{hist:?}");
}

#[test]
#[ignore = "long run: PHOTON_FUZZ_SECONDS (default 3600)"]
fn long_fuzz_run() {
    let secs: u64 = std::env::var("PHOTON_FUZZ_SECONDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3600);
    let budget = Duration::from_secs(secs);
    let t = Instant::now();
    let (hist, failures) = fuzz(LONG_RUN_FIRST_CASE, |_, e| e >= budget);
    println!(
        "long run {:.0} s: {} cases, {} rendered, {} rejected with one located line, {} failures",
        t.elapsed().as_secs_f64(),
        hist[0] + hist[1] + failures.len() as u64,
        hist[0],
        hist[1],
        failures.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
