//! Glossy light paths against Mitsuba 3's path tracer.
//!
//! **Caustics onto a rough-metal floor** (scenes/glass-on-metal.pbrt: a glass ball on GGX
//! alpha 0.2 aluminium, no diffuse surface at all; reference 128x128, 389120 spp, its own
//! relMSE about 1e-4). At 64x64 and 64 spp, over the 132 pixels where the reference's
//! caustic exceeds 3: the summed caustic within 4% of the reference (seeds 1-3: 0.999 ..
//! 1.013), the relMSE there below 0.02 (0.003 .. 0.005), and at least 5 times below that of the
//! same render without glossy receivers (`glossyalpha` 100: 0.09 .. 0.23, paths that must find
//! the lamp through the ball); the image mean within 2% (+0.25 .. +0.5%).
//!
//! **Caustic of near-smooth glass** (scenes/rough-glass.pbrt: a GGX alpha 0.03 glass ball on a
//! diffuse floor; reference 128x128, 135168 spp, own relMSE 1.3e-4). Its photons are caustic
//! photons (sharp bounces), estimated with the caustic map's radius. At 64x64 and 64 spp
//! (seeds 0-5): the whole image's relMSE below 0.01 (0.0032 .. 0.0062; 0.018 .. 0.021 when
//! these photons were glossy-caustic photons with the global radius), over the floor pixels
//! where the reference exceeds 1 below 0.012 (0.0024 .. 0.0075; before 0.015 .. 0.023), and
//! the image mean within 1.5% (-0.2% .. +0.9%; before +1.0% .. +1.9%).
//!
//! **Light that reaches a room only after a glossy bounce** (scenes/lamp-enclosed.pbrt: a bulb
//! facing up into a closed GGX-metal can), against Mitsuba 3's path tracer
//! (scenes/mitsuba/lamp-enclosed.xml, 128x128, 32768 spp, its own relMSE about 0.012: path
//! tracing converges slowly here, which is the point of the scene).
//!
//! Compared by 4 x 4 blocks of a 64x64 render (each block averages 256 pixels, so the
//! reference's noise there is about 0.7%), leaving out the block where the can's bright
//! inside shows (its mean is more than twice the image's): every other block within 6% of
//! the reference. Measured at 16 spp: 0.961 .. 1.015. Before glossy caustics were carried
//! by photons the floor blocks came out 16% dark (0.84), and before photon paths kept to the
//! scene's maxdepth the walls were 10-14% bright.
use photon::imageio::metrics::{relmse_map, MaskOptions};
use photon::imageio::{read_exr, RgbImage};
use std::path::Path;

use crate::support as common;
use common::TempDir;

/// Block means (RGB averaged) of `img` on a `n x n` grid.
fn blocks(img: &RgbImage, n: usize) -> Vec<f64> {
    let (bw, bh) = (img.width / n, img.height / n);
    let mut out = vec![0.0f64; n * n];
    for y in 0..bh * n {
        for x in 0..bw * n {
            let p = img.pixels[y * img.width + x];
            out[(y / bh) * n + x / bw] += (p[0] + p[1] + p[2]) as f64 / 3.0;
        }
    }
    out.iter().map(|s| s / (bw * bh) as f64).collect()
}

#[test]
fn enclosed_lamp_matches_mitsuba() {
    let dir = TempDir::new("photon-lamp");
    let out = common::render_repo_scene("scenes/lamp-enclosed.pbrt", "64x64", 16, &dir, "lamp.exr");
    let img = read_exr(&out).unwrap();
    let reference = reference_64("lamp-enclosed-reference-128.exr");
    let (ours, theirs) = (blocks(&img, 4), blocks(&reference, 4));
    let mean = theirs.iter().sum::<f64>() / theirs.len() as f64;
    let mut checked = 0;
    for (i, (a, b)) in ours.iter().zip(&theirs).enumerate() {
        if *b > 2.0 * mean {
            continue; // the can's inside
        }
        checked += 1;
        let ratio = a / b;
        assert!(
            (ratio - 1.0).abs() < 0.06,
            "block {i}: ours {a:.4} / Mitsuba {b:.4} = {ratio:.3}"
        );
    }
    assert!(checked >= 14, "{checked} blocks checked");
}

/// A 128x128 reference of scenes/mitsuba/, box-filtered to 64x64.
fn reference_64(name: &str) -> RgbImage {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    read_exr(&root.join("scenes/mitsuba").join(name))
        .unwrap()
        .downsample_box(2)
        .unwrap()
}

/// The caustic of the two ball scenes: pixels of the lower half (the floor in front of the
/// ball) whose RGB mean in `reference` exceeds `threshold`; and how many there are.
fn floor_above(reference: &RgbImage, threshold: f32) -> (Vec<bool>, usize) {
    let mask: Vec<bool> = reference
        .pixels
        .iter()
        .enumerate()
        .map(|(i, p)| {
            i / reference.width >= reference.height / 2 && (p[0] + p[1] + p[2]) / 3.0 > threshold
        })
        .collect();
    let n = mask.iter().filter(|&&k| k).count();
    (mask, n)
}

/// Mean of the RGB mean over the pixels where `keep` holds.
fn masked_mean(img: &RgbImage, keep: &[bool]) -> f64 {
    let (sum, n) = img
        .pixels
        .iter()
        .zip(keep)
        .filter(|(_, &k)| k)
        .fold((0.0, 0usize), |(s, n), (p, _)| {
            (s + (p[0] + p[1] + p[2]) as f64 / 3.0, n + 1)
        });
    sum / n.max(1) as f64
}

/// Mean relMSE over the pixels where `keep` holds.
fn masked_relmse(img: &RgbImage, reference: &RgbImage, keep: &[bool]) -> f64 {
    let map = relmse_map(img, reference, MaskOptions::default());
    let vals: Vec<f64> = map
        .iter()
        .zip(keep)
        .filter(|(_, &k)| k)
        .flat_map(|(v, _)| *v)
        .collect();
    vals.iter().sum::<f64>() / vals.len().max(1) as f64
}

#[test]
fn caustic_on_rough_metal_matches_mitsuba() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = TempDir::new("photon-glass-metal");
    let scene = "scenes/glass-on-metal.pbrt";
    let img = read_exr(&common::render_repo_scene(
        scene, "64x64", 64, &dir, "on.exr",
    ))
    .unwrap();
    // The same scene without glossy receivers: the caustic is left to camera paths.
    let text = std::fs::read_to_string(root.join(scene)).unwrap();
    let off = text.replace(
        "\"integer maxdepth\" [ 8 ]",
        "\"integer maxdepth\" [ 8 ] \"float glossyalpha\" [ 100 ]",
    );
    assert_ne!(off, text);
    let off_scene = dir.0.join("off.pbrt");
    std::fs::write(&off_scene, off).unwrap();
    let off_img = read_exr(&common::render_repo_scene(
        off_scene.to_str().unwrap(),
        "64x64",
        64,
        &dir,
        "off.exr",
    ))
    .unwrap();
    let reference = reference_64("glass-on-metal-reference-128.exr");
    let (caustic, n) = floor_above(&reference, 3.0);
    assert!(n >= 100, "{n} caustic pixels");
    let ratio = masked_mean(&img, &caustic) / masked_mean(&reference, &caustic);
    let (on, off) = (
        masked_relmse(&img, &reference, &caustic),
        masked_relmse(&off_img, &reference, &caustic),
    );
    let all = vec![true; caustic.len()];
    let mean = masked_mean(&img, &all) / masked_mean(&reference, &all);
    println!("{n} caustic px: ratio {ratio:.4}, relMSE {on:.4} (without receivers {off:.4}); image mean ratio {mean:.4}");
    assert!(
        (ratio - 1.0).abs() < 0.04,
        "caustic ours / Mitsuba = {ratio:.4}"
    );
    assert!(on < 0.02, "caustic relMSE {on:.4}");
    assert!(off > 5.0 * on, "without receivers {off:.4}, with {on:.4}");
    assert!(
        (mean - 1.0).abs() < 0.02,
        "image mean ours / Mitsuba = {mean:.4}"
    );
}

#[test]
fn near_smooth_glass_caustic_matches_mitsuba() {
    let dir = TempDir::new("photon-rough-glass");
    let out = common::render_repo_scene("scenes/rough-glass.pbrt", "64x64", 64, &dir, "rg.exr");
    let img = read_exr(&out).unwrap();
    let reference = reference_64("rough-glass-reference-128.exr");
    let (caustic, n) = floor_above(&reference, 1.0);
    assert!(n >= 40, "{n} caustic pixels");
    let e = masked_relmse(&img, &reference, &caustic);
    let all = vec![true; caustic.len()];
    let whole = masked_relmse(&img, &reference, &all);
    let mean = masked_mean(&img, &all) / masked_mean(&reference, &all);
    println!("relMSE {whole:.4}; {n} caustic px: relMSE {e:.4}; image mean ratio {mean:.4}");
    assert!(whole < 0.01, "image relMSE {whole:.4}");
    assert!(e < 0.012, "caustic relMSE {e:.4}");
    assert!(
        (mean - 1.0).abs() < 0.015,
        "image mean ours / Mitsuba = {mean:.4}"
    );
}
