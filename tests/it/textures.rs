//! Textures and bump mapping in renders, against analytic answers.
//!
//! A 10 x 10 floor at y = 0 with uv = ((x + 5) / 10, (z + 5) / 10), lit by a distant light
//! straight down (irradiance E = L) and seen from above by the direct-lighting integrator,
//! has radiance albedo(uv) E / pi at every point; a bump map of slope g along u tilts the
//! shading normal to normalize(-g, 1, 0) (per world unit), so the radiance there is
//! albedo E cos / pi with cos = 1 / sqrt(1 + g^2).
use photon::accel::{Accel, AccelOptions, BackendKind};
use photon::interaction::SurfaceInteraction;
use photon::math::{Ray, Vec2, Vec3};
use photon::scene::{loader, Scene};
use std::f32::consts::PI;
use std::path::Path;

use crate::support as common;
use common::TempDir;

/// Irradiance of the distant light (radiance `L` arriving straight down).
const E: f32 = 3.0;

/// The scene: camera at height `height` looking down, `res` pixels, `spp` samples, the floor
/// with material line `material`, after the `Texture` lines `textures`.
fn floor_scene(height: f32, res: u32, spp: u32, textures: &str, material: &str) -> String {
    format!(
        r#"LookAt 0 {height} 0  0 0 0  0 0 1
Camera "perspective" "float fov" [ 60 ]
Film "rgb" "integer xresolution" [ {res} ] "integer yresolution" [ {res} ]
PixelFilter "box" "float xradius" [ 0.0001 ] "float yradius" [ 0.0001 ]
Sampler "independent" "integer pixelsamples" [ {spp} ]
Integrator "path" "integer maxdepth" [ 1 ]
WorldBegin
LightSource "distant" "point3 from" [ 0 1 0 ] "point3 to" [ 0 0 0 ] "rgb L" [ {E} {E} {E} ]
{textures}
{material}
Shape "trianglemesh" "point3 P" [ -5 0 -5  5 0 -5  5 0 5  -5 0 5 ]
    "integer indices" [ 0 2 1 0 3 2 ] "point2 uv" [ 0 0  1 0  1 1  0 1 ]
"#
    )
}

/// Renders `path` with the direct integrator; per pixel (rendered radiance, floor uv seen
/// through the pixel centre).
fn render(path: &Path) -> (Scene, Vec<(Vec3, Vec2)>) {
    let (scene, px) = common::render_floor(path, BackendKind::Embree);
    let uv = |p: Vec3| Vec2::new((p.x + 5.0) / 10.0, (p.z + 5.0) / 10.0);
    (scene, px.into_iter().map(|(v, p)| (v, uv(p))).collect())
}

/// sRGB-encoded 8-bit value to linear (IEC 61966-2-1), computed here independently.
fn srgb(b: u8) -> f32 {
    let v = b as f64 / 255.0;
    (if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }) as f32
}

/// A 4x4 PNG of distinct colours; texel (i, j) (column, row from the top).
fn texel_bytes(i: u32, j: u32) -> [u8; 3] {
    [
        (30 + 60 * i) as u8,
        (20 + 70 * j) as u8,
        (200 - 15 * (i + 4 * j)) as u8,
    ]
}

fn write_png(dir: &TempDir) {
    let mut img = image::RgbImage::new(4, 4);
    for j in 0..4 {
        for i in 0..4 {
            img.put_pixel(i, j, image::Rgb(texel_bytes(i, j)));
        }
    }
    img.save(dir.0.join("grid.png")).unwrap();
}

#[test]
fn image_texture_reflectance_is_albedo_times_e_over_pi() {
    let dir = TempDir::new("photon-tex-image");
    write_png(&dir);
    let scene = floor_scene(
        6.0,
        48,
        1,
        r#"Texture "grid" "spectrum" "imagemap" "string filename" "grid.png" "string filter" "point""#,
        r#"Material "diffuse" "texture reflectance" "grid""#,
    );
    let (_, px) = render(&dir.write("s.pbrt", scene));
    let (mut worst, mut n) = (0.0f32, 0);
    for (got, uv) in px {
        // Texel (i, j): s = u, t = 1 - v (image rows run downwards); skip texel edges.
        let (s, t) = (uv.x * 4.0, (1.0 - uv.y) * 4.0);
        if !(0.0..4.0).contains(&s) || !(0.0..4.0).contains(&t) {
            continue;
        }
        if (s - s.round()).abs() < 0.1 || (t - t.round()).abs() < 0.1 {
            continue;
        }
        let b = texel_bytes(s as u32, t as u32);
        let albedo = Vec3::new(srgb(b[0]), srgb(b[1]), srgb(b[2]));
        let want = albedo * E / PI;
        worst = worst.max(((got - want) / want).abs().max_element());
        n += 1;
    }
    assert!(n > 1000, "{n} pixels checked");
    assert!(worst < 1e-3, "worst relative error {worst} over {n} pixels");
}

/// pbrt-v4's decoding rules for 8-bit images (`Image::Read`): a PNG follows `encoding` (sRGB
/// by default), TGA and JPEG are sRGB whatever `encoding` says, and a float imagemap of an RGB
/// image reads its red channel. The floor's radiance is albedo E / pi, with the albedo computed
/// here from the bytes (`srgb`): a uniform (128, 128, 128) TGA gives 0.2159, not 0.502.
#[test]
fn eight_bit_images_decode_as_pbrt_v4_does() {
    let dir = TempDir::new("photon-tex-encodings");
    let grey = image::RgbImage::from_pixel(4, 4, image::Rgb([128, 128, 128]));
    let red = image::RgbImage::from_pixel(4, 4, image::Rgb([200, 20, 60]));
    grey.save(dir.0.join("grey.tga")).unwrap();
    grey.save(dir.0.join("grey.jpg")).unwrap();
    grey.save(dir.0.join("grey.png")).unwrap();
    red.save(dir.0.join("red.tga")).unwrap();
    // (texture lines, expected albedo, whether a note is expected)
    let cases = [
        (r#""grey.tga""#, Vec3::splat(srgb(128)), false),
        (
            r#""grey.tga" "string encoding" "linear""#,
            Vec3::splat(srgb(128)),
            true,
        ),
        (r#""grey.jpg""#, Vec3::splat(srgb(128)), false),
        (r#""grey.png""#, Vec3::splat(srgb(128)), false),
        (
            r#""grey.png" "string encoding" "linear""#,
            Vec3::splat(128.0 / 255.0),
            false,
        ),
    ];
    for (file, albedo, note) in cases {
        let scene = floor_scene(
            6.0,
            8,
            1,
            &format!(r#"Texture "t" "spectrum" "imagemap" "string filename" {file}"#),
            r#"Material "diffuse" "texture reflectance" "t""#,
        );
        let (scene, px) = render(&dir.write("s.pbrt", scene));
        assert_eq!(
            scene.notes.len(),
            note as usize,
            "{file}: {:?}",
            scene.notes
        );
        if note {
            assert!(scene.notes[0].contains("s.pbrt:") && scene.notes[0].contains("sRGB"));
        }
        let want = albedo * E / PI;
        for (got, _) in px {
            // JPEG may round a level: 1/255 of 128 is 0.8%.
            let err = ((got - want) / want).abs().max_element();
            assert!(err < 0.01, "{file}: {got} against {want}");
        }
    }
    // A float texture of an RGB image reads R: reflectance = srgb(200) everywhere.
    let scene = floor_scene(
        6.0,
        8,
        1,
        r#"Texture "f" "float" "imagemap" "string filename" "red.tga"
Texture "t" "spectrum" "scale" "rgb tex" [ 1 1 1 ] "texture scale" "f""#,
        r#"Material "diffuse" "texture reflectance" "t""#,
    );
    let (_, px) = render(&dir.write("s.pbrt", scene));
    let want = srgb(200) * E / PI;
    for (got, _) in px {
        assert!(
            ((got - Vec3::splat(want)) / want).abs().max_element() < 1e-3,
            "{got} against {want}"
        );
    }
}

#[test]
fn checkerboard_and_scale_textures() {
    let dir = TempDir::new("photon-tex-checks");
    // 4 x 4 cells: tex1 0.8 (scaled by 0.5 -> 0.4 red), tex2 0.2 grey.
    let scene = floor_scene(
        6.0,
        48,
        1,
        r#"Texture "red" "spectrum" "constant" "rgb value" [ 0.8 0.1 0.1 ]
Texture "half" "spectrum" "scale" "texture tex" "red" "float scale" 0.5
Texture "checks" "spectrum" "checkerboard" "float uscale" 4 "float vscale" 4
    "texture tex1" "half" "rgb tex2" [ 0.2 0.2 0.2 ]"#,
        r#"Material "diffuse" "texture reflectance" "checks""#,
    );
    let (_, px) = render(&dir.write("s.pbrt", scene));
    let (mut worst, mut n) = (0.0f32, 0);
    for (got, uv) in px {
        let st = uv * 4.0;
        if !(0.0..4.0).contains(&st.x) || !(0.0..4.0).contains(&st.y) {
            continue;
        }
        // The filter averages over about 1.5 pixel steps (0.17 of a cell here): skip edges.
        if (st.x - st.x.round()).abs() < 0.25 || (st.y - st.y.round()).abs() < 0.25 {
            continue;
        }
        let even = (st.x.floor() as i32 + st.y.floor() as i32) % 2 == 0;
        let albedo = if even {
            Vec3::new(0.4, 0.05, 0.05)
        } else {
            Vec3::splat(0.2)
        };
        let want = albedo * E / PI;
        worst = worst.max(((got - want) / want).abs().max_element());
        n += 1;
    }
    assert!(n > 300, "{n} pixels checked");
    assert!(worst < 1e-3, "worst relative error {worst} over {n} pixels");
}

/// A 2x1 float PFM [0, 1]: with `clamp` and bilinear filtering it is linear in s on
/// [0.25, 0.75] (slope 2), so `scale k` gives a height field of slope 2k per unit u.
fn write_ramp(dir: &TempDir) {
    let mut bytes = b"Pf\n2 1\n-1.0\n".to_vec();
    for v in [0.0f32, 1.0] {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    dir.write("ramp.pfm", bytes);
}

/// Slope of the height field per world unit: 2 k per unit u, u spans 10 units.
const K: f32 = 2.5;
const SLOPE: f32 = 2.0 * K / 10.0;

fn bump_scene(dir: &TempDir) -> std::path::PathBuf {
    write_ramp(dir);
    let scene = floor_scene(
        6.0,
        48,
        1,
        &format!(
            r#"Texture "h" "float" "imagemap" "string filename" "ramp.pfm" "string wrap" "clamp" "float scale" {K}"#
        ),
        r#"Material "diffuse" "rgb reflectance" [ 0.5 0.5 0.5 ] "texture displacement" "h""#,
    );
    dir.write("s.pbrt", scene)
}

#[test]
fn linear_height_field_tilts_the_shading_normal() {
    let dir = TempDir::new("photon-bump");
    let path = bump_scene(&dir);
    let scene = loader::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let accel = Accel::build(&scene, BackendKind::Embree, AccelOptions::default()).unwrap();
    // Height h = 2K (u - 1/4) along the normal +y: dp/du' = (10, 2K, 0), dp/dv = (0, 0, 10),
    // so n = normalize(-2K/10, 1, 0) = normalize(-SLOPE, 1, 0).
    let want = Vec3::new(-SLOPE, 1.0, 0.0).normalize();
    for x in [-2.0f32, -0.5, 0.0, 1.3, 2.0] {
        let ray = Ray::new(Vec3::new(x, 3.0, 0.7), Vec3::new(0.0, -1.0, 0.0));
        let hit = accel.backend().intersect(&ray).expect("hits the floor");
        let mut si = SurfaceInteraction::new(&scene, &hit, &ray);
        // The winding makes the normal +y (displacement goes up).
        assert!(
            (si.ns - Vec3::Y).length() < 1e-6,
            "unbumped before the BSDF"
        );
        let _ = si.bsdf(
            &scene,
            photon::camera::Footprint::of_file(&scene),
            photon::spectrum::Lambda::Rgb,
        );
        assert!((si.ns - want).length() < 1e-4, "x {x}: {} != {want}", si.ns);
        assert!((si.frame.n - want).length() < 1e-4);
        assert!((si.wo - si.frame.to_local(Vec3::Y)).length() < 1e-6);
    }
    // Outside [0.25, 0.75] in u the clamped ramp is flat: no tilt.
    let ray = Ray::new(Vec3::new(4.0, 3.0, 0.0), Vec3::new(0.0, -1.0, 0.0));
    let hit = accel.backend().intersect(&ray).unwrap();
    let mut si = SurfaceInteraction::new(&scene, &hit, &ray);
    let _ = si.bsdf(
        &scene,
        photon::camera::Footprint::of_file(&scene),
        photon::spectrum::Lambda::Rgb,
    );
    assert!((si.ns - Vec3::Y).length() < 1e-6, "{}", si.ns);
}

#[test]
fn bumped_floor_radiance_follows_the_tilted_normal() {
    let dir = TempDir::new("photon-bump-render");
    let (_, px) = render(&bump_scene(&dir));
    let cos = 1.0 / (1.0 + SLOPE * SLOPE).sqrt();
    let (mut worst, mut n) = (0.0f32, 0);
    for (got, uv) in px {
        // The linear part of the ramp, away from its kinks (the bump step looks 0.0005 ahead).
        if !(0.3..0.7).contains(&uv.x) || !(0.05..0.95).contains(&uv.y) {
            continue;
        }
        let want = 0.5 * E * cos / PI;
        worst = worst.max((got.x - want).abs() / want);
        n += 1;
    }
    assert!(n > 300, "{n}");
    assert!(
        worst < 1e-3,
        "worst relative error {worst} over {n} pixels (cos {cos})"
    );
}

/// A floor of one-texel black and white checks, 512 texels across, seen from far enough that
/// a pixel covers about 18 texels: bilinear lookups alias (pixel values scatter between
/// black and white), trilinear ones average (grey, smooth).
#[test]
fn trilinear_filtering_removes_aliasing() {
    let dir = TempDir::new("photon-mip");
    let mut img = image::RgbImage::new(512, 512);
    for (x, y, p) in img.enumerate_pixels_mut() {
        let v = if (x + y) % 2 == 0 { 255 } else { 0 };
        *p = image::Rgb([v, v, v]);
    }
    img.save(dir.0.join("fine.png")).unwrap();
    let stats = |filter: &str| {
        let scene = floor_scene(
            20.0,
            64,
            1,
            &format!(
                r#"Texture "fine" "spectrum" "imagemap" "string filename" "fine.png" "string filter" "{filter}" "string encoding" "linear""#
            ),
            r#"Material "diffuse" "texture reflectance" "fine""#,
        );
        let (_, px) = render(&dir.write(&format!("{filter}.pbrt"), scene));
        let v: Vec<f32> = px
            .iter()
            .filter(|(_, uv)| (0.05..0.95).contains(&uv.x) && (0.05..0.95).contains(&uv.y))
            .map(|(c, _)| c.x * PI / E)
            .collect();
        let mean = v.iter().sum::<f32>() / v.len() as f32;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f32>() / v.len() as f32;
        (mean, var.sqrt(), v.len())
    };
    let (mb, sb, n) = stats("bilinear");
    let (mt, st, _) = stats("trilinear");
    assert!(n > 500, "{n}");
    // The texture's mean albedo is 1/2.
    assert!((mt - 0.5).abs() < 0.02, "trilinear mean {mt}");
    assert!(sb > 0.1, "bilinear should alias: std {sb} (mean {mb})");
    assert!(st < 0.1 * sb, "trilinear std {st} vs bilinear {sb}");
}

/// CRC-32 (IEEE) of `bytes`, bit by bit, for hand-made PNG chunks.
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xffff_ffffu32;
    for &b in bytes {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xedb8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

/// A PNG whose header claims 100000 x 100000 pixels (40 GB as RGB f32) with no image data is
/// refused from its header, with the file and line of the texture, before any decoding.
#[test]
fn huge_image_header_is_refused_before_decoding() {
    let dir = TempDir::new("photon-tex-huge");
    let mut ihdr = b"IHDR".to_vec();
    ihdr.extend_from_slice(&100_000u32.to_be_bytes());
    ihdr.extend_from_slice(&100_000u32.to_be_bytes());
    ihdr.extend_from_slice(&[8, 2, 0, 0, 0]); // 8-bit RGB
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend_from_slice(&13u32.to_be_bytes());
    png.extend_from_slice(&ihdr);
    png.extend_from_slice(&crc32(&ihdr).to_be_bytes());
    for chunk in [&b"IDAT"[..], b"IEND"] {
        png.extend_from_slice(&0u32.to_be_bytes());
        png.extend_from_slice(chunk);
        png.extend_from_slice(&crc32(chunk).to_be_bytes());
    }
    dir.write("huge.png", png);
    let scene = floor_scene(
        6.0,
        8,
        1,
        r#"Texture "big" "spectrum" "imagemap" "string filename" "huge.png""#,
        r#"Material "diffuse" "texture reflectance" "big""#,
    );
    let e = loader::load(&dir.write("s.pbrt", scene))
        .unwrap_err()
        .to_string();
    assert!(e.contains("s.pbrt:9:"), "{e}");
    assert!(
        e.contains("100000x100000 pixels is more than the 268435456"),
        "{e}"
    );
}

/// scenes/cornell-textured.pbrt (a checkerboard floor and an sRGB image on the back wall)
/// against Mitsuba 3's rendering of its transcription (scenes/mitsuba/cornell-textured.xml,
/// 49152 spp at 64x64, its own relMSE about 3.6e-5): the photon mapper at 16 spp measured
/// 0.0038. Mistakes in the texture conventions are far above the bound: the same render with
/// the back wall's image flipped in v gave 0.073, with a plain grey floor 0.014.
#[test]
fn textured_cornell_box_matches_mitsuba() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = TempDir::new("photon-tex-mitsuba");
    let out =
        common::render_repo_scene("scenes/cornell-textured.pbrt", "64x64", 16, &dir, "tex.exr");
    let cmp = common::photon()
        .args(["compare", "--max-relmse", "0.006"])
        .arg(&out)
        .arg(root.join("scenes/mitsuba/cornell-textured-reference-64.exr"))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&cmp.stdout);
    assert!(
        cmp.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&cmp.stderr)
    );
    assert!(text.contains("relMSE 0.00"), "{text}");
}

/// `mix` (pbrt-v4's stochastic `MixMaterial`): every hit takes one of the two materials, the
/// second with probability `amount`. A floor mixing black and white 0.8 at amount 0.25 shows
/// each pixel (1 spp, one hit) as exactly 0 or 0.8 E / pi, the white share near 0.25; with
/// `amount` a 0/1 checkerboard the choice follows the cells exactly.
#[test]
fn mix_material_picks_one_material_per_hit() {
    let dir = TempDir::new("photon-mix");
    let named = r#"MakeNamedMaterial "black" "string type" "diffuse" "rgb reflectance" [ 0 0 0 ]
MakeNamedMaterial "white" "string type" "diffuse" "rgb reflectance" [ 0.8 0.8 0.8 ]"#;
    let white = 0.8 * E / PI;
    let scene = floor_scene(
        6.0,
        48,
        1,
        named,
        r#"Material "mix" "string materials" [ "black" "white" ] "float amount" 0.25"#,
    );
    let (_, px) = render(&dir.write("mix.pbrt", scene));
    let floor: Vec<f32> = px
        .iter()
        .filter(|(_, uv)| (0.0..1.0).contains(&uv.x) && (0.0..1.0).contains(&uv.y))
        .map(|(c, _)| c.x)
        .collect();
    assert!(floor.len() > 1000, "{}", floor.len());
    assert!(
        floor
            .iter()
            .all(|&v| v.abs() < 1e-6 || (v / white - 1.0).abs() < 1e-3),
        "a pixel that is neither material"
    );
    let share = floor.iter().filter(|&&v| v > 0.0).count() as f64 / floor.len() as f64;
    // Binomial: sd sqrt(0.25 0.75 / n) < 0.014 for n > 1000; 4 sd.
    assert!((share - 0.25).abs() < 0.055, "white share {share}");
    // amount a checkerboard of 0 and 1: black where even, white where odd.
    let scene = floor_scene(
        6.0,
        48,
        1,
        &format!(
            "{named}\nTexture \"pick\" \"float\" \"checkerboard\" \"float uscale\" 4 \"float vscale\" 4 \"float tex1\" 0 \"float tex2\" 1"
        ),
        r#"Material "mix" "string materials" [ "black" "white" ] "texture amount" "pick""#,
    );
    let (_, px) = render(&dir.write("mix2.pbrt", scene));
    let mut n = 0;
    for (c, uv) in px {
        let st = uv * 4.0;
        if !(0.0..4.0).contains(&st.x) || !(0.0..4.0).contains(&st.y) {
            continue;
        }
        if (st.x - st.x.round()).abs() < 0.1 || (st.y - st.y.round()).abs() < 0.1 {
            continue;
        }
        let odd = (st.x.floor() as i32 + st.y.floor() as i32) % 2 == 1;
        let want = if odd { white } else { 0.0 };
        assert!((c.x - want).abs() < 1e-3 * white, "{uv}: {} vs {want}", c.x);
        n += 1;
    }
    assert!(n > 800, "{n}");
}

/// Texture footprints follow the render's image, not the file's: `--res 64x64 --spp 4` on
/// the textured Cornell box (its file: 256x256, 16 spp; a checkerboard floor, filtered over
/// the footprint) gives the same bytes as a copy of the file that
/// asks for 64x64 and 2x2 samples itself. The footprint used the file's film and sampler
/// whatever the command line said, so every `--res` render filtered textures for the wrong
/// pixel size (4x too small here).
#[test]
fn texture_footprints_follow_the_command_lines_resolution_and_samples() {
    let dir = TempDir::new("photon-footprint");
    let text = std::fs::read_to_string("scenes/cornell-textured.pbrt").unwrap();
    let small = text
        .replace(
            "\"integer xresolution\" [ 256 ]",
            "\"integer xresolution\" [ 64 ]",
        )
        .replace(
            "\"integer yresolution\" [ 256 ]",
            "\"integer yresolution\" [ 64 ]",
        )
        .replace("\"integer xsamples\" [ 4 ]", "\"integer xsamples\" [ 2 ]")
        .replace("\"integer ysamples\" [ 4 ]", "\"integer ysamples\" [ 2 ]");
    assert_ne!(small, text, "the file's Film and Sampler lines changed");
    let local = dir.0.join("scene.pbrt");
    let base = Path::new("scenes").canonicalize().unwrap();
    // Textures are named relative to the scene file: point them at the repository's folder.
    let small = small.replace("\"textures/", &format!("\"{}/textures/", base.display()));
    std::fs::write(&local, small).unwrap();
    let run = |scene: &Path, extra: &[&str], out: &str| {
        let o = common::photon()
            .arg("render")
            .arg(scene)
            .args(["--seed", "3", "--threads", "2", "--no-png", "-o"])
            .arg(dir.0.join(out))
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        crate::support::exr_image_bits(&dir.0.join(out))
    };
    let by_flags = run(
        Path::new("scenes/cornell-textured.pbrt"),
        &["--res", "64x64", "--spp", "4"],
        "flags.exr",
    );
    let by_file = run(&local, &[], "file.exr");
    assert!(
        by_flags == by_file,
        "--res/--spp and the file's own 64x64, 4 spp differ"
    );
}
