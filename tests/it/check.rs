//! `photon check`: the loader's collect mode lists every problem of a scene with its location
//! (where a render stops at the first), the counts and memory estimate of a clean scene, and
//! the command's output and exit codes. Scenes are written by the tests.

use photon::scene::loader::{load, load_collecting};
use photon::tools::check::check_scene;
use std::process::Command;

use crate::support as common;
use common::TempDir;

const TRI: &str =
    r#"Shape "trianglemesh" "point3 P" [ 0 0 0  1 0 0  0 1 0 ] "integer indices" [ 0 1 2 ]"#;

/// A scene with one problem of each kind on known lines, and good geometry between them.
fn troubled_scene() -> String {
    format!(
        r#"Integrator "sppm" "float radius" 0.1
Accelerator "bvh"
WorldBegin
Texture "wood" "spectrum" "imagemap" "string filename" "wood.png"
MakeNamedMaterial "floor" "string type" "hair" "texture reflectance" "wood"
NamedMaterial "floor"
{TRI}
Shape "plymesh" "string filename" "missing.ply"
MakeNamedMedium "fog" "string type" "nanovdb" "string filename" "fog.nvdb"
Frobnicate "x" [ 1 2 3 ] "bool b" true
LightSource "infinite" "point3 portal" [ 0 0 0  1 0 0  1 1 0 ]
Material "diffuse" "texture reflectance" "wood"
{TRI}
Shape "disk"
"#
    )
}

/// (line, message) of every error.
fn lines_and_messages(errors: &[photon::scene::SceneError]) -> Vec<(u32, String)> {
    errors
        .iter()
        .map(|e| (e.loc.as_ref().expect("a location").line, e.msg.clone()))
        .collect()
}

#[test]
fn collect_mode_lists_every_problem_in_order() {
    let dir = TempDir::new("photon-check");
    let path = dir.write("scene.pbrt", troubled_scene());
    // A render stops at the first problem.
    let first = load(&path).unwrap_err();
    assert_eq!(first.loc.as_ref().unwrap().line, 4, "{first}");
    let got = load_collecting(&path);
    let errs = lines_and_messages(&got.errors);
    let want: [(u32, &str); 7] = [
        (4, "wood.png"),
        (5, "unsupported material type \"hair\""),
        (8, "missing.ply"),
        (9, "medium type \"nanovdb\" is not supported yet"),
        (10, "unknown directive \"Frobnicate\""),
        (11, "\"point3 portal\": expected 4 points, got 3"),
        // The texture failed to load on line 4, so the name is unknown here.
        (
            12,
            "\"texture reflectance\": unknown spectrum texture \"wood\"",
        ),
    ];
    assert_eq!(errs.len(), want.len(), "{errs:#?}");
    for ((line, msg), (wline, wmsg)) in errs.iter().zip(want) {
        assert_eq!(*line, wline, "{msg}");
        assert!(msg.contains(wmsg), "line {line}: {msg} (want {wmsg})");
    }
    // The failed named material stood in as the default (NamedMaterial "floor" did not fail);
    // the two triangles and the disk were read, after the skipped directives.
    assert_eq!(got.textures, 1);
    assert_eq!(got.scene.meshes.len(), 3);
    assert_eq!(
        got.scene.triangle_count(),
        2 + photon::scene::loader::shapes::SWEEP_SEGMENTS as usize
    );
    assert_eq!(got.scene.notes.len(), 2, "{:?}", got.scene.notes);
}

#[test]
fn check_scene_reports_counts_memory_and_integrator_errors() {
    let dir = TempDir::new("photon-check");
    let path = dir.write(
        "ok.pbrt",
        format!(
            r#"Film "rgb" "integer xresolution" 20 "integer yresolution" 10
Integrator "photonmap" "integer globalphotons" 1000 "integer causticphotons" 500
WorldBegin
AttributeBegin
AreaLightSource "diffuse" "rgb L" [ 1 1 1 ]
{TRI}
AttributeEnd
Material "conductor"
{TRI}
LightSource "point" "rgb I" [ 1 1 1 ]
Texture "a" "spectrum" "imagemap" "string filename" "t.png"
Texture "b" "float" "imagemap" "string filename" "t.png" "string encoding" "linear"
Texture "c" "spectrum" "imagemap" "string filename" "t.png" "float uscale" 2
"#
        ),
    );
    image::RgbImage::new(4, 3)
        .save(dir.0.join("t.png"))
        .unwrap();
    let r = check_scene(&path);
    assert!(r.problems.is_empty(), "{:?}", r.problems);
    assert_eq!(
        (r.triangles, r.lights, r.materials, r.textures),
        (2, 2, 2, 3)
    );
    // The model render checks its budget with, by hand from its documented sizes: the
    // process (13 MiB); 2 meshes of 1 triangle (160 B each with Embree, 768 B a mesh); 20 x 10
    // pixels at 116 B; 1000 + 500 photons (a diffuse 0.5 and a mirror: both maps) times the
    // photons stored per photon emitted that the pilot trace measures (here none lands: the
    // light faces away), with a margin of 1.25,
    // at 104 B; the 4x3 image decoded twice (sRGB for "a" and "c", linear for "b") at 12 B per
    // texel; 2 MiB a thread.
    let part = |name: &str| {
        r.memory
            .parts
            .iter()
            .find(|(n, _)| *n == name)
            .map_or(0, |(_, b)| *b)
    };
    let scene = photon::scene::loader::load(&path).unwrap();
    let settings = photon::integrator::RenderSettings::from_scene(&scene).unwrap();
    let kind = photon::integrator::IntegratorKind::Photonmap;
    let backend = photon::accel::BackendKind::Embree;
    let accel = photon::accel::Accel::build(&scene, backend, Default::default()).unwrap();
    let landings = photon::integrator::pilot(&scene, &accel, &settings, kind).unwrap();
    let photons = (1000.0 * landings.global + 500.0 * landings.caustic) * 1.25 * 104.0;
    assert_eq!(part("process"), 13 << 20);
    assert_eq!(part("geometry"), 2 * 160 + 2 * 768);
    assert_eq!(part("film"), 200 * 116);
    assert_eq!(part("photon maps"), photons as u64);
    assert_eq!(part("textures"), 2 * 12 * 12);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()) as u64;
    assert_eq!(part("threads"), threads * (2 << 20));
    let line = r.to_string();
    assert!(
        line.contains("ok.pbrt: ok | 2 triangles, 2 lights, 2 materials, 3 textures | ~")
            && line.contains("(process 13.6, film 0.0, geometry 0.0, textures 0.0, threads"),
        "{line}"
    );
    // The same estimate as a render of the file checks against its budget.
    let e = photon::memory::estimate(
        &scene,
        &settings,
        (kind, backend),
        threads as usize,
        Some(landings),
    );
    assert_eq!(e.total(), r.memory.total());
    // An integrator parameter photon does not read is found as a render would find it.
    let path = dir.write(
        "bad.pbrt",
        "Integrator \"photonmap\" \"float radius\" 1\nWorldBegin\n",
    );
    let r = check_scene(&path);
    // No surface at all: neither map is built, so none is counted.
    let photons = r.memory.parts.iter().find(|(n, _)| *n == "photon maps");
    assert_eq!(photons.map(|(_, b)| *b), Some(0));
    assert_eq!(r.problems.len(), 1);
    assert!(r.problems[0]
        .to_string()
        .contains("bad.pbrt:1:24: unused parameter \"float radius\""));
}

#[test]
fn an_unreadable_rest_of_file_ends_that_file_only() {
    let dir = TempDir::new("photon-check");
    dir.write(
        "part.pbrt",
        format!("{TRI}\nShape \"sphere\" \"float radius\" \"oops\n{TRI}\n"),
    );
    let path = dir.write(
        "main.pbrt",
        format!(
            "WorldBegin\nInclude \"part.pbrt\"\nInclude \"gone.pbrt\"\n{TRI}\nAttributeBegin\n"
        ),
    );
    let got = load_collecting(&path);
    let errs: Vec<String> = got.errors.iter().map(|e| e.to_string()).collect();
    assert_eq!(errs.len(), 3, "{errs:#?}");
    assert!(errs[0].contains("part.pbrt:2:") && errs[0].contains("unterminated string"));
    assert!(errs[1].contains("main.pbrt:3:1") && errs[1].contains("gone.pbrt"));
    assert!(errs[2].contains("main.pbrt:5:1") && errs[2].contains("AttributeBegin without"));
    // part.pbrt's first triangle and main's own were read; the one after the bad string not.
    assert_eq!(got.scene.triangle_count(), 2);
}

#[test]
fn command_prints_one_line_per_scene_and_exits_2_on_problems() {
    let dir = TempDir::new("photon-check");
    let good = dir.write("good.pbrt", format!("WorldBegin\n{TRI}\n"));
    let bad = dir.write("bad.pbrt", troubled_scene());
    let run = |args: &[&std::path::Path]| {
        Command::new(env!("CARGO_BIN_EXE_photon"))
            .arg("check")
            .args(args)
            .output()
            .unwrap()
    };
    let out = run(&[&good]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    assert_eq!(stdout.lines().count(), 1, "{stdout}");
    assert!(stdout.contains("good.pbrt: ok | 1 triangles"), "{stdout}");

    let out = run(&[&good, &bad]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stdout}{stderr}");
    assert_eq!(stderr.trim(), "photon: 1 of 2 scenes have problems");
    let lines: Vec<&str> = stdout.lines().collect();
    assert!(lines[1].contains("bad.pbrt: 7 problems |"), "{stdout}");
    let located = lines
        .iter()
        .filter(|l| l.starts_with("  ") && l.contains("bad.pbrt:"))
        .filter(|l| !l.starts_with("  note:"))
        .count();
    assert_eq!(located, 7, "{stdout}");
    assert!(stdout.contains("  note: ") && stdout.contains("Accelerator \"bvh\""));
}

/// The memory model's photon maps come from a pilot trace of 8192 photons per map: its
/// photons stored per photon emitted agree with a full pass 1 of 200,000 + 200,000 photons
/// (within 10%; the pilot's sampling error is ~1-3%) on a closed box (global map only) and a
/// box with glass (both maps, the caustic one aimed by projection maps).
#[test]
fn pilot_trace_predicts_the_photons_stored() {
    use photon::accel::{Accel, BackendKind};
    use photon::integrator::{pilot, IntegratorKind, RenderSettings};
    for file in [
        "../shared/scenes/cornell-box/scene-v4.pbrt",
        "scenes/cornell-glass.pbrt",
    ] {
        let scene = load(std::path::Path::new(file)).unwrap();
        let mut settings = RenderSettings::from_scene(&scene).unwrap();
        let t = &mut settings.photon.trace;
        (t.global_photons, t.caustic_photons) = (200_000, 200_000);
        let accel = Accel::build(&scene, BackendKind::Embree, Default::default()).unwrap();
        let kind = IntegratorKind::Photonmap;
        let predicted = pilot(&scene, &accel, &settings, kind).unwrap();
        let pass = photon::integrator::prepare(&scene, &accel, &settings, kind).unwrap();
        let st = &pass.maps.stats;
        let rate = |stored: usize, emitted: u64| stored as f64 / emitted.max(1) as f64;
        let global = rate(st.global_stored, st.global_emitted);
        let caustic = rate(st.caustic_stored, st.caustic_emitted);
        println!("{file}: pilot {predicted:?}, pass 1 global {global:.4} caustic {caustic:.4}");
        assert!(global > 0.1, "{file}: no global photons stored");
        for (p, full) in [(predicted.global, global), (predicted.caustic, caustic)] {
            assert!(
                (p - full).abs() <= 0.1 * full,
                "{file}: pilot {p:.4} vs pass 1 {full:.4}"
            );
        }
    }
}
