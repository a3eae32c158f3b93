//! The thin-lens camera and the film's sensor parameters, checked on rendered images against
//! answers worked out here:
//! - depth of field: an emitting square on the plane in focus keeps its pinhole image, one
//!   behind it spreads by the thin-lens circle of confusion `c = R |1/f - 1/z| res / tan(fov/2)`
//!   (pixels), measured from the horizontal variance of its image (a box of width W blurred by a
//!   disc of diameter c has variance W^2/12 + c^2/16) and from its width (W + c);
//! - `focaldistance` with `lensradius 0` is the pinhole image, bit for bit; a lens render is the
//!   same on 1 and 2 threads;
//! - `iso` and `shutteropen`/`shutterclose` scale every pixel by `exposure * iso / 100`;
//! - `cropwindow` renders exactly the pixels (pbrt-v4's `ceil` bounds) of the full render;
//! - `whitebalance` 7500 (pbrt-v4's correlated temperature 7504 K: CIE D75, whose published
//!   chromaticity is (0.29902, 0.31485)) turns an emitter of D75's colour neutral grey, and
//!   6500 (D65, sRGB's white) leaves colours as they were;
//! - `maxcomponentvalue` scales each camera sample so its largest XYZ component is the maximum:
//!   with one emitter colour, every pixel (edge pixels included, whose mean is far below the
//!   maximum) is the unclamped pixel times `max / max(XYZ(L))`.
use crate::support as common;

use common::{render_with, TempDir};
use photon::accel::BackendKind;
use photon::film::xyz_from_srgb;
use photon::imageio::RgbImage;
use photon::integrator::{IntegratorKind, RenderOutput};
use photon::math::Vec3;
use photon::scene::{loader, Scene};

fn load(text: &str) -> Scene {
    let dir = TempDir::new("photon-camera-film");
    loader::load(&dir.write("scene.pbrt", text)).expect("scene loads")
}

fn render(scene: &Scene, kind: IntegratorKind, spp: u32, threads: usize) -> RenderOutput {
    let (w, h) = (scene.film.xres, scene.film.yres);
    render_with(scene, kind, BackendKind::Embree, (w, h, spp), threads, 7)
}

/// A square emitter (L = 1, black, two-sided) of half-width `a` centred at `(x, y, z)`, facing
/// the camera.
fn square(x: f32, y: f32, z: f32, a: f32) -> String {
    let (x0, x1, y0, y1) = (x - a, x + a, y - a, y + a);
    format!(
        r#"AttributeBegin
AreaLightSource "diffuse" "rgb L" [ 1 1 1 ] "bool twosided" true
Shape "trianglemesh" "point3 P" [ {x0} {y0} {z}  {x1} {y0} {z}  {x1} {y1} {z}  {x0} {y1} {z} ] "integer indices" [ 0 1 2 0 2 3 ]
AttributeEnd
"#
    )
}

const RES: u32 = 128;
const FOV: f32 = 40.0;
const FOCUS: f32 = 5.0;
const LENS: f32 = 0.4;

/// The camera at the origin looking down +z (camera space is world space), `camera` its extra
/// parameters; two squares whose pinhole images are 14 pixels wide: one on the plane z = 5
/// (upper half of the image), one at z = 10 (lower half).
fn dof_scene(camera: &str) -> Scene {
    let world = format!(
        "Material \"diffuse\" \"rgb reflectance\" [ 0 0 0 ]\n{}{}",
        square(0.0, 0.9, FOCUS, 0.2),
        square(0.0, -1.8, 2.0 * FOCUS, 0.4)
    );
    load(&format!(
        r#"Camera "perspective" "float fov" [ {FOV} ] {camera}
Film "rgb" "integer xresolution" [ {RES} ] "integer yresolution" [ {RES} ]
PixelFilter "box" "float xradius" [ 0.5 ] "float yradius" [ 0.5 ]
WorldBegin
{world}"#
    ))
}

/// Column sums of the green channel over rows `rows`.
fn column_profile(img: &RgbImage, rows: std::ops::Range<usize>) -> Vec<f64> {
    (0..img.width)
        .map(|x| {
            rows.clone()
                .map(|y| img.pixels[y * img.width + x][1] as f64)
                .sum()
        })
        .collect()
}

/// Variance of the column positions weighted by `p`.
fn variance(p: &[f64]) -> f64 {
    let total: f64 = p.iter().sum();
    let mean: f64 = p.iter().enumerate().map(|(i, v)| i as f64 * v).sum::<f64>() / total;
    p.iter()
        .enumerate()
        .map(|(i, v)| (i as f64 - mean).powi(2) * v)
        .sum::<f64>()
        / total
}

/// Columns whose sum exceeds `frac` of the largest (any light: `frac` = 0).
fn width(p: &[f64], frac: f64) -> usize {
    let max = p.iter().cloned().fold(0.0, f64::max);
    p.iter().filter(|&&v| v > frac * max).count()
}

/// The circle of confusion (diameter, pixels) of a point at depth `z`.
fn coc_pixels(z: f32) -> f64 {
    let tan_half = (FOV.to_radians() as f64 * 0.5).tan();
    LENS as f64 * (1.0 / FOCUS as f64 - 1.0 / z as f64).abs() * RES as f64 / tan_half
}

#[test]
fn thin_lens_blurs_by_the_circle_of_confusion() {
    let pin = render(&dof_scene(""), IntegratorKind::Direct, 64, 0).image;
    let lens_params =
        format!("\"float lensradius\" [ {LENS} ] \"float focaldistance\" [ {FOCUS} ]");
    let lens = render(&dof_scene(&lens_params), IntegratorKind::Direct, 1024, 0).image;
    let half = RES as usize / 2;
    // Upper half: on the plane in focus. The pinhole image is 14 pixels wide either way.
    let (p, l) = (
        column_profile(&pin, 0..half),
        column_profile(&lens, 0..half),
    );
    let (vp, vl) = (variance(&p), variance(&l));
    assert!(
        (width(&p, 0.5) as i32 - 14).abs() <= 1,
        "pinhole width {}",
        width(&p, 0.5)
    );
    assert!(
        (vl - vp).abs() < 0.02 * vp,
        "in focus: variance {vl} against pinhole {vp}"
    );
    assert_eq!(width(&l, 0.01), width(&p, 0.01), "in focus: same width");
    // Lower half: at z = 10, c = 0.4 * 0.1 * 128 / tan 20 = 14.07 pixels.
    let c = coc_pixels(2.0 * FOCUS);
    assert!((c - 14.07).abs() < 0.01, "{c}");
    let (p, l) = (
        column_profile(&pin, half..RES as usize),
        column_profile(&lens, half..RES as usize),
    );
    let c_measured = 4.0 * (variance(&l) - variance(&p)).sqrt();
    assert!(
        (c_measured - c).abs() < 0.5,
        "blur diameter {c_measured} against {c}"
    );
    // The support of the blurred image (every column any light reaches) is the pinhole image's
    // continuous extent [a, b] grown by c / 2 on each side: the columns it overlaps are
    // ceil(b + c / 2) - floor(a - c / 2) (30 here: 49.93 .. 78.07). The pinhole image's edges
    // are its edge columns' coverage (their light over the peak column's); each of the two
    // blurred tails is a sliver of the disc's edge and may catch no sample.
    let peak = p.iter().cloned().fold(0.0, f64::max);
    let w = p.iter().sum::<f64>() / peak;
    assert!((w - 14.07).abs() < 0.1, "pinhole width {w}");
    let first = p.iter().position(|&v| v > 0.0).expect("pinhole image");
    let last = p.iter().rposition(|&v| v > 0.0).expect("pinhole image");
    let (a, b) = (
        (first + 1) as f64 - p[first] / peak,
        last as f64 + p[last] / peak,
    );
    let support = ((b + c / 2.0).ceil() - (a - c / 2.0).floor()) as usize;
    let wl = width(&l, 0.0);
    assert!(
        wl <= support && wl + 2 >= support,
        "blurred width {wl} against {support} columns ({a:.2} .. {b:.2} grown by {c:.2} / 2)"
    );
    // The total light is the same (the lens only moves it).
    let (sp, sl): (f64, f64) = (p.iter().sum(), l.iter().sum());
    assert!((sl - sp).abs() < 0.01 * sp, "{sl} {sp}");
}

#[test]
fn focal_distance_without_lens_is_the_pinhole_and_lenses_are_deterministic() {
    let pin = render(&dof_scene(""), IntegratorKind::Direct, 4, 0).image;
    let f0 = render(
        &dof_scene("\"float lensradius\" [ 0 ] \"float focaldistance\" [ 3 ]"),
        IntegratorKind::Direct,
        4,
        0,
    )
    .image;
    assert!(pin.pixels == f0.pixels);
    let lens = dof_scene("\"float lensradius\" [ 0.4 ] \"float focaldistance\" [ 5 ]");
    let one = render(&lens, IntegratorKind::Direct, 4, 1).image;
    let two = render(&lens, IntegratorKind::Direct, 4, 2).image;
    assert!(one.pixels == two.pixels);
    assert!(one.pixels != pin.pixels, "the lens changes the image");
}

/// The repository's small test room at `w x h` with `film` and `camera` extra parameters.
fn room(w: u32, h: u32, camera: &str, film: &str) -> Scene {
    let text = common::small_scene("").replacen(
        "Camera \"perspective\" \"float fov\" [ 45 ]",
        &format!("Camera \"perspective\" \"float fov\" [ 45 ] {camera}"),
        1,
    );
    let text = text.replacen(
        "Film \"rgb\" \"integer xresolution\" [ 8 ] \"integer yresolution\" [ 8 ]",
        &format!(
            "Film \"rgb\" \"integer xresolution\" [ {w} ] \"integer yresolution\" [ {h} ] {film}"
        ),
        1,
    );
    assert!(text.contains(film) && text.contains(camera));
    load(&text)
}

#[test]
fn iso_and_exposure_scale_the_image() {
    let base = render(&room(16, 16, "", ""), IntegratorKind::Path, 4, 0);
    // 0.5 s at iso 400: x2, exact in binary.
    let cases = [
        (
            "\"float shutteropen\" 0.25 \"float shutterclose\" 0.75",
            "\"float iso\" 400",
            2.0,
        ),
        ("", "\"float iso\" 300", 3.0),
    ];
    for (camera, film, k) in cases {
        let out = render(&room(16, 16, camera, film), IntegratorKind::Path, 4, 0);
        assert!(base.image.pixels.iter().any(|p| p[1] > 0.0));
        for (a, b) in out.image.pixels.iter().zip(&base.image.pixels) {
            for c in 0..3 {
                let want = b[c] * k;
                assert!(
                    (a[c] - want).abs() <= 1e-6 * want.abs(),
                    "{film}: {a:?} {b:?}"
                );
            }
        }
        for ((_, part), (_, bpart)) in out.components.iter().zip(&base.components) {
            for (a, b) in part.pixels.iter().zip(&bpart.pixels) {
                assert!((a[0] - b[0] * k).abs() <= 1e-6 * (b[0] * k).abs());
            }
        }
    }
}

#[test]
fn crop_window_renders_those_pixels_of_the_full_image() {
    // x: ceil(16 * 0.25) = 4 .. ceil(16 * 0.8) = 13; y: ceil(12 * 0.1) = 2 .. ceil(12 * 0.6) = 8.
    let crop = "\"float cropwindow\" [ 0.8 0.25 0.1 0.6 ]";
    for kind in [
        IntegratorKind::Direct,
        IntegratorKind::Path,
        IntegratorKind::Photonmap,
    ] {
        let full = render(&room(16, 12, "", ""), kind, 4, 0).image;
        let part = render(&room(16, 12, "", crop), kind, 4, 0).image;
        assert_eq!((part.width, part.height), (9, 6), "{kind:?}");
        for y in 0..6 {
            for x in 0..9 {
                assert_eq!(
                    part.pixels[y * 9 + x],
                    full.pixels[(y + 2) * 16 + x + 4],
                    "{kind:?} pixel ({x}, {y})"
                );
            }
        }
    }
}

#[test]
fn max_component_value_clamps_each_camera_sample() {
    let scene = |film: &str| {
        let l = "[ 4 2 1 ]";
        load(&format!(
            r#"Camera "perspective" "float fov" [ 40 ]
Film "rgb" "integer xresolution" [ 24 ] "integer yresolution" [ 24 ] {film}
WorldBegin
Material "diffuse" "rgb reflectance" [ 0 0 0 ]
AreaLightSource "diffuse" "rgb L" {l} "bool twosided" true
Shape "trianglemesh" "point3 P" [ -0.61 -0.47 3  0.53 -0.47 3  0.53 0.71 3  -0.61 0.71 3 ] "integer indices" [ 0 1 2 0 2 3 ]
"#
        ))
    };
    let m = xyz_from_srgb(Vec3::new(4.0, 2.0, 1.0)).max_element();
    assert!((m - 2.5454).abs() < 1e-3, "X of (4, 2, 1): {m}");
    let free = render(&scene(""), IntegratorKind::Direct, 16, 0).image;
    for (film, max, ratio) in [
        ("\"float maxcomponentvalue\" 1.5", 1.5f32, 1.0f32),
        (
            "\"float maxcomponentvalue\" 1.5 \"float iso\" 200",
            1.5,
            2.0,
        ),
        ("\"float maxcomponentvalue\" 100", 100.0, 1.0),
    ] {
        let img = render(&scene(film), IntegratorKind::Direct, 16, 0).image;
        // Each sample is L or 0: the clamp scales every pixel by the same factor.
        let k = (max / (m * ratio)).min(1.0) * ratio;
        let mut edges = 0;
        for (a, b) in img.pixels.iter().zip(&free.pixels) {
            for c in 0..3 {
                assert!(
                    (a[c] - b[c] * k).abs() <= 2e-6 * b[c],
                    "{film}: {a:?} {b:?} x {k}"
                );
            }
            // A pixel on the square's edge: its mean is below the maximum, so a clamp of the
            // pixel mean instead of each sample would have left it alone.
            let mean = xyz_from_srgb(Vec3::from(*b)).max_element() * ratio;
            edges += (mean > 0.0 && mean < 0.9 * max.min(m * ratio)) as u32;
        }
        assert!(edges >= 10, "{film}: {edges} edge pixels");
    }
}

/// sRGB of the colour with chromaticity `(x, y)` and Y = 1 (the inverse of the IEC 61966-2-1
/// matrix, to 4 digits).
fn srgb_of_xy(x: f32, y: f32) -> [f32; 3] {
    let (cx, cz) = (x / y, (1.0 - x - y) / y);
    [
        3.2405 * cx - 1.5371 - 0.4985 * cz,
        -0.9693 * cx + 1.8760 + 0.0416 * cz,
        0.0556 * cx - 0.2040 + 1.0572 * cz,
    ]
}

#[test]
fn white_balance_adapts_daylight_to_srgb_white() {
    let scene = |l: [f32; 3], film: &str| {
        load(&format!(
            r#"Camera "perspective" "float fov" [ 40 ]
Film "rgb" "integer xresolution" [ 8 ] "integer yresolution" [ 8 ] {film}
WorldBegin
Material "diffuse" "rgb reflectance" [ 0 0 0 ]
AreaLightSource "diffuse" "rgb L" [ {} {} {} ] "bool twosided" true
Shape "trianglemesh" "point3 P" [ -5 -5 3  5 -5 3  5 5 3  -5 5 3 ] "integer indices" [ 0 1 2 0 2 3 ]
"#,
            l[0], l[1], l[2]
        ))
    };
    let d75 = srgb_of_xy(0.29902, 0.31485);
    assert!(d75[2] > 1.1 * d75[0], "D75 is bluish: {d75:?}");
    let img = render(
        &scene(d75, "\"float whitebalance\" 7500"),
        IntegratorKind::Direct,
        1,
        0,
    )
    .image;
    for p in &img.pixels {
        // Neutral, with the luminance kept near 1 (Bradford adapts Y only slightly). The
        // daylight-locus formula photon uses puts D75 at (0.29904, 0.31497), (2e-5, 1.2e-4) off
        // the published (integrated) value: that moves the channels apart by about 1e-3.
        assert!(
            (p[0] - p[2]).abs() < 2e-3 && (p[1] - p[2]).abs() < 2e-3,
            "{p:?}"
        );
        assert!((p[1] - 1.0).abs() < 0.03, "{p:?}");
    }
    let colour = [0.8, 0.3, 0.1];
    let img = render(
        &scene(colour, "\"float whitebalance\" 6500"),
        IntegratorKind::Direct,
        1,
        0,
    )
    .image;
    for p in &img.pixels {
        for c in 0..3 {
            assert!((p[c] - colour[c]).abs() < 2e-3, "{p:?}");
        }
    }
}
