//! The benchmark harness on a tiny configuration: it reports every number it should, in the
//! table, the CSV and the JSON, for a shared scene and a generated mesh. It never asserts a
//! speed. The kiddo baseline runs too, so the harness's own check that both kd-trees find the
//! same k-th distances is exercised.
use crate::support::CORNELL;
use photon::scene::generate;
use photon::tools::bench::{run_with, BenchOptions, Row};
use std::path::{Path, PathBuf};

#[path = "../../benches/common/kiddo.rs"]
mod kiddo;

#[test]
fn tiny_benchmark_reports_every_number() {
    let dir = std::env::temp_dir().join(format!("photon-bench-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let opts = BenchOptions {
        quick: true,
        scenes: vec![PathBuf::from(CORNELL)],
        generated: Some(vec![3000]),
        rays: Some(3000),
        runs: Some(2),
        photons: Some(4000),
        queries: Some(500),
        threads: vec![1, 2],
        csv: Some(dir.join("b.csv")),
        json: Some(dir.join("b.json")),
    };
    let mut baseline = kiddo::Kiddo::default();
    let rows = run_with(&opts, Some(&mut baseline)).expect("bench runs");

    // The expected rows, from the options alone.
    let tris = [
        (
            "cornell-box",
            photon::scene::loader::load(Path::new(CORNELL))
                .unwrap()
                .triangle_count(),
        ),
        ("sphere-3k", generate::sphere_scene(3000).triangle_count()),
    ];
    let mut want: Vec<(String, String, usize)> = Vec::new();
    for t in [1, 2] {
        for imp in ["embree", "obvhs"] {
            want.push(("build".into(), imp.into(), t));
            want.push(("photons".into(), imp.into(), t));
        }
        for m in ["camera", "photon paths", "shadow"] {
            for imp in ["embree x1", "embree x8", "obvhs"] {
                want.push((m.into(), imp.into(), t));
            }
        }
    }
    for imp in ["ours", "kiddo"] {
        for m in ["kd build", "knn k=50", "knn k=200"] {
            want.push((m.into(), imp.into(), 1));
        }
    }
    want.push(("estimate".into(), "ours".into(), 1));
    for (scene, n) in tris {
        let mine: Vec<&Row> = rows.iter().filter(|r| r.scene == scene).collect();
        assert_eq!(mine.len(), want.len(), "{scene}: {mine:#?}");
        for (m, imp, t) in &want {
            let r = mine
                .iter()
                .find(|r| &r.metric == m && &r.imp == imp && r.threads == *t)
                .unwrap_or_else(|| panic!("{scene}: no row {m} / {imp} / {t} threads"));
            assert_eq!(r.triangles, n);
            assert_eq!(r.runs, 2);
            assert!(r.median.is_finite() && r.median > 0.0, "{r:?}");
            assert!(r.min <= r.median && r.median <= r.max, "{r:?}");
            assert_eq!(r.unit, if m.contains("build") { "ms" } else { "1/s" });
        }
    }
    let csv = std::fs::read_to_string(dir.join("b.csv")).unwrap();
    assert_eq!(csv.lines().count(), rows.len() + 1);
    assert!(csv.starts_with("scene,triangles,metric,implementation,threads,median"));
    let json = std::fs::read_to_string(dir.join("b.json")).unwrap();
    assert_eq!(json.matches("\"median\":").count(), rows.len());
    assert!(json.trim_start().starts_with('[') && json.trim_end().ends_with(']'));
    let table = photon::tools::bench::table(&rows[..want.len()]);
    print!("{table}");
    assert!(table.contains("| camera (Mrays/s) | 2 |") && table.contains("ours/kiddo"));
    std::fs::remove_dir_all(&dir).ok();
}
