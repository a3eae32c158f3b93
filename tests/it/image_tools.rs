//! The image tools: `photon convert` (EXR/PNG/PFM in and out, crop, tone curves, flags) and
//! `photon compare` on PNG and PFM inputs, its LDR-FLIP and its error PNG's legend.
use crate::support::{self as common, assert_error, run_capped, TempDir, GIB};
use photon::imageio::metrics::{error_colour, MASKED_COLOUR};
use photon::imageio::png::encode_srgb8;
use photon::imageio::{read_exr, read_linear, write_exr, ExrPixel, RgbImage};
use photon::texture::Encoding;
use photon::tools::compare::{bar_column, BAR_BOTTOM, BAR_TOP, LEGEND_HEIGHT, LEGEND_WIDTH};
use std::path::Path;
use std::time::Duration;

/// One argument of a `photon` run.
type Arg<'a> = &'a dyn AsRef<std::ffi::OsStr>;

/// A 48x32 image with every value below 1: smooth ramps and a brighter square.
fn ramps() -> RgbImage {
    let (w, h) = (48, 32);
    let mut im = RgbImage::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let a = x as f32 / w as f32;
            let b = y as f32 / h as f32;
            let square = (16..28).contains(&x) && (8..20).contains(&y);
            let p = if square {
                [0.93, 0.6, 0.2]
            } else {
                [0.9 * a, 0.5 * b, 0.02 + 0.3 * a * b]
            };
            im.set(x, y, p);
        }
    }
    im
}

/// `photon ARGS` (1 GiB address space, 60 s).
fn photon(args: &[Arg]) -> common::Run {
    let args: Vec<std::ffi::OsString> = args.iter().map(|a| a.as_ref().to_owned()).collect();
    run_capped(args, GIB, Duration::from_secs(60))
}

/// `photon compare IMAGE REFERENCE --json ...` parsed (asserting exit 0).
fn compare_json(image: &Path, reference: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args: Vec<Arg> = vec![&"compare", &image, &reference, &"--json"];
    for e in extra {
        args.push(e);
    }
    let r = photon(&args);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    serde_json::from_str(r.stdout.trim()).unwrap_or_else(|e| panic!("{e}: {}", r.stdout))
}

fn relmse(v: &serde_json::Value) -> f64 {
    v["overall"]["relmse"].as_f64().expect("relmse")
}

fn flip(v: &serde_json::Value) -> f64 {
    v["flip"]["mean"].as_f64().expect("flip mean")
}

/// The converted PNG (clamp, exposure 0) compared with its own EXR: the error is the 8-bit
/// quantisation of the sRGB codes alone. Each sample's linear error is bounded by half a code
/// step in sRGB decoded back, `max(EOTF(c + h) - r, r - EOTF(c - h))` with `c = OETF(r)` and
/// `h = 0.5 / 255`; the bound is the mean of those squared over `r^2 + 0.01`.
#[test]
fn png_from_convert_compares_within_the_8_bit_quantisation_bound() {
    let dir = TempDir::new("image-tools-png");
    let exr = dir.0.join("ramps.exr");
    let png = dir.0.join("ramps.png");
    let image = ramps();
    write_exr(&exr, &image, &[], ExrPixel::Float).unwrap();
    let r = photon(&[&"convert", &exr, &"-o", &png]);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    assert!(r.stdout.contains("48x32"), "{}", r.stdout);
    // The PNG reads back (sRGB decoded) within half a code of every value.
    let eotf = |c: f64| Encoding::Srgb.decode(c.clamp(0.0, 1.0) as f32) as f64;
    let oetf = |v: f64| photon::imageio::png::srgb_oetf(v as f32) as f64;
    let h = 0.5 / 255.0;
    let mut bound = 0.0;
    for p in &image.pixels {
        for &v in p {
            let (r, c) = (v as f64, oetf(v as f64));
            let err = (eotf(c + h) - r).max(r - eotf(c - h));
            bound += err * err / (r * r + 0.01);
        }
    }
    let bound = bound / (3 * image.pixels.len()) as f64;
    let m = compare_json(&png, &exr, &[]);
    let measured = relmse(&m);
    println!("PNG vs EXR: relMSE {measured:.3e}, 8-bit quantisation bound {bound:.3e}");
    assert!(measured > 0.0, "an 8-bit PNG cannot be exact: {m}");
    assert!(
        measured <= bound * 1.001,
        "{measured} above the bound {bound}"
    );
    // The PNG of the same image through `convert` is what `render`'s preview writer makes.
    let preview = dir.0.join("preview.png");
    photon::imageio::write_png(&preview, &image, 0.0).unwrap();
    assert_eq!(
        std::fs::read(&preview).unwrap(),
        std::fs::read(&png).unwrap()
    );
}

/// A 16-bit PNG is sRGB too: the same image coded in 16 bits compares with its EXR 256 times
/// more finely quantised than the 8-bit one (relMSE far below the 8-bit bound).
#[test]
fn sixteen_bit_png_is_decoded_as_srgb() {
    let dir = TempDir::new("image-tools-png16");
    let exr = dir.0.join("ramps.exr");
    let png = dir.0.join("ramps16.png");
    let image = ramps();
    write_exr(&exr, &image, &[], ExrPixel::Float).unwrap();
    let oetf = photon::imageio::png::srgb_oetf;
    let words: Vec<u16> = image
        .pixels
        .iter()
        .flat_map(|p| p.map(|v| (oetf(v) * 65535.0).round() as u16))
        .collect();
    let (w, h) = (image.width as u32, image.height as u32);
    image::ImageBuffer::<image::Rgb<u16>, _>::from_raw(w, h, words)
        .unwrap()
        .save(&png)
        .unwrap();
    let m = compare_json(&png, &exr, &[]);
    println!("16-bit PNG vs EXR: relMSE {:.3e}", relmse(&m));
    assert!(relmse(&m) < 1e-9, "{m}");
    // Read as linear (no sRGB decoding), mid grey would be off by far more.
    let back = read_linear(&png, None).unwrap();
    let (x, y) = (20, 10); // inside the square: 0.93, 0.6, 0.2
    let p = back.get(x, y).unwrap();
    assert!((p[1] - 0.6).abs() < 1e-4, "{p:?}");
}

/// EXR -> PFM -> EXR: bit for bit, rows in order (PFM stores them bottom-up), relMSE 0.
#[test]
fn pfm_round_trip_is_exact() {
    let dir = TempDir::new("image-tools-pfm");
    let exr = dir.0.join("ramps.exr");
    let pfm = dir.0.join("ramps.pfm");
    let back = dir.0.join("back.exr");
    let mut image = ramps();
    image.set(0, 0, [7.5, 1e-9, 123.0]); // HDR and tiny values survive too
    write_exr(&exr, &image, &[], ExrPixel::Float).unwrap();
    for (from, to) in [(&exr, &pfm), (&pfm, &back)] {
        let r = photon(&[&"convert", from, &"-o", to]);
        assert_eq!(r.code, Some(0), "{}", r.describe());
    }
    assert_eq!(read_linear(&pfm, None).unwrap(), image);
    assert_eq!(read_exr(&back).unwrap(), image);
    let m = compare_json(&pfm, &exr, &[]);
    println!("PFM vs EXR: relMSE {}, FLIP {}", relmse(&m), flip(&m));
    assert_eq!(relmse(&m), 0.0, "{m}");
    // A PFM without its extension is found by its first bytes.
    let bare = dir.0.join("ramps-no-extension");
    std::fs::copy(&pfm, &bare).unwrap();
    assert_eq!(relmse(&compare_json(&bare, &exr, &[])), 0.0);
}

/// FLIP of an image against itself is 0; against a clearly different one it is well above 0;
/// both in the text and the JSON output.
#[test]
fn flip_is_zero_against_itself_and_positive_against_another_image() {
    let dir = TempDir::new("image-tools-flip");
    let a = dir.0.join("a.exr");
    let b = dir.0.join("b.exr");
    write_exr(&a, &ramps(), &[], ExrPixel::Float).unwrap();
    let mut other = ramps();
    for (i, p) in other.pixels.iter_mut().enumerate() {
        *p = if (i / 4) % 2 == 0 {
            [0.8, 0.1, 0.1]
        } else {
            p.map(|v| v * 0.25)
        };
    }
    write_exr(&b, &other, &[], ExrPixel::Float).unwrap();
    let same = flip(&compare_json(&a, &a, &[]));
    let differ = flip(&compare_json(&b, &a, &[]));
    let aces = flip(&compare_json(
        &b,
        &a,
        &["--flip-tonemap", "aces", "--flip-exposure", "1"],
    ));
    println!("FLIP(self) {same}, FLIP(different) {differ}, with aces +1 stop {aces}");
    assert_eq!(same, 0.0);
    assert!(differ > 0.1 && differ <= 1.0, "{differ}");
    assert!(aces > 0.1 && aces != differ, "{aces}");
    let r = photon(&[&"compare", &b, &a]);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    assert!(
        r.stdout.contains(&format!(
            "LDR-FLIP {differ:.6} (both images tone-mapped alike: exposure 0 stops, clamp"
        )),
        "{}",
        r.stdout
    );
}

/// `--error-png` draws the false-colour image with a legend below: the colour bar's colours at
/// the decade ticks, black tick marks, and label text under them.
#[test]
fn error_png_has_a_legend() {
    let dir = TempDir::new("image-tools-legend");
    let a = dir.0.join("a.exr");
    let b = dir.0.join("b.pfm");
    let errors = dir.0.join("errors.png");
    let image = ramps();
    write_exr(&a, &image, &[], ExrPixel::Float).unwrap();
    let mut other = image.clone();
    other.pixels[0] = [f32::NAN; 3]; // a masked reference pixel
    photon::imageio::write_pfm(&b, &other).unwrap();
    let r = photon(&[&"compare", &a, &b, &"--error-png", &errors]);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    let png = image::open(&errors).unwrap().into_rgb8();
    let (w, h) = (LEGEND_WIDTH, image.height + LEGEND_HEIGHT);
    assert_eq!((png.width() as usize, png.height() as usize), (w, h));
    let px = |x: usize, y: usize| png.get_pixel(x as u32, y as u32).0;
    let rgb8 = |c: [f32; 3]| c.map(|v| encode_srgb8(v, 1.0));
    // The image itself: the masked pixel grey, an exact one black.
    assert_eq!(px(0, 0), rgb8(MASKED_COLOUR));
    assert_eq!(px(5, 5), [0, 0, 0]);
    let top = image.height;
    let bar_row = top + (BAR_TOP + BAR_BOTTOM) / 2;
    for d in -4..=1 {
        let x = bar_column(w, d as f64);
        let want = rgb8(error_colour(10f64.powi(d)));
        let got = px(x, bar_row);
        let near = got.iter().zip(&want).all(|(g, w)| g.abs_diff(*w) <= 2);
        assert!(near, "bar at 1e{d}: {got:?}, want {want:?}");
        assert_eq!(px(x, top + BAR_BOTTOM + 1), [0, 0, 0], "tick at 1e{d}");
    }
    // Labels below the ticks and the title above the bar: dark pixels off the tick columns.
    let ticks: Vec<usize> = (-4..=1).map(|d| bar_column(w, d as f64)).collect();
    let dark_in = |rows: std::ops::Range<usize>| {
        rows.flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, _)| !ticks.contains(&x))
            .filter(|&(x, y)| px(x, y).iter().all(|&c| c < 128))
            .count()
    };
    assert!(dark_in(top + BAR_BOTTOM + 5..h) > 20, "tick labels");
    assert!(dark_in(top..top + BAR_TOP) > 20, "title");
}

/// `--crop` keeps the half-open pixel bounds: the size and the pixels of the block.
#[test]
fn convert_crops_to_the_given_bounds() {
    let dir = TempDir::new("image-tools-crop");
    let exr = dir.0.join("ramps.exr");
    let cut = dir.0.join("cut.exr");
    let cut_png = dir.0.join("cut.png");
    let image = ramps();
    write_exr(&exr, &image, &[], ExrPixel::Float).unwrap();
    let r = photon(&[&"convert", &exr, &"-o", &cut, &"--crop", &"5,17,3,10"]);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    let got = read_exr(&cut).unwrap();
    assert_eq!((got.width, got.height), (12, 7));
    for y in 0..7 {
        for x in 0..12 {
            assert_eq!(got.get(x, y), image.get(x + 5, y + 3), "pixel {x},{y}");
        }
    }
    let r = photon(&[&"convert", &exr, &"-o", &cut_png, &"--crop", &"0,48,31,32"]);
    assert_eq!(r.code, Some(0), "{}", r.describe());
    let png = image::open(&cut_png).unwrap();
    assert_eq!((png.width(), png.height()), (48, 1));
}

/// PNG output through `aces` and `filmic`: black stays black, a rising ramp stays rising, and
/// the highlights are compressed rather than clipped (`clamp` clips them).
#[test]
fn tone_curves_keep_a_ramp_in_order() {
    let dir = TempDir::new("image-tools-tonemap");
    let exr = dir.0.join("hdr-ramp.exr");
    let mut ramp = RgbImage::new(64, 1);
    for x in 0..64 {
        let v = if x == 0 {
            0.0
        } else {
            0.01 * 1.1f32.powi(x as i32)
        }; // 0, 0.011 .. 4.1
        ramp.set(x, 0, [v; 3]);
    }
    write_exr(&exr, &ramp, &[], ExrPixel::Float).unwrap();
    let mut top = Vec::new();
    for curve in ["clamp", "aces", "filmic"] {
        let png = dir.0.join(format!("{curve}.png"));
        let r = photon(&[&"convert", &exr, &"-o", &png, &"--tonemap", &curve]);
        assert_eq!(r.code, Some(0), "{}", r.describe());
        assert!(r.stdout.contains(curve), "{}", r.stdout);
        let codes: Vec<u8> = image::open(&png)
            .unwrap()
            .into_rgb8()
            .pixels()
            .map(|p| p.0[0])
            .collect();
        assert_eq!(codes[0], 0, "{curve}: black");
        assert!(codes.windows(2).all(|w| w[0] <= w[1]), "{curve}: {codes:?}");
        // How many of the brightest values (above 1.5) are distinct codes.
        let distinct = codes[54..].windows(2).filter(|w| w[0] != w[1]).count();
        top.push(distinct);
    }
    assert_eq!(top[0], 0, "clamp clips the highlights");
    assert!(
        top[1] > 3 && top[2] > 3,
        "aces and filmic compress them: {top:?}"
    );
}

/// Bad flags and inputs: exit 2 and one line naming the flag or the file.
#[test]
fn bad_flags_and_files_fail_in_one_line() {
    let dir = TempDir::new("image-tools-bad");
    let exr = dir.0.join("ramps.exr");
    write_exr(&exr, &ramps(), &[], ExrPixel::Float).unwrap();
    let out = dir.0.join("out.png");
    let out_exr = dir.0.join("out.exr");
    let cases: Vec<(Vec<Arg>, &[&str])> = vec![
        (vec![&"--crop", &"1,2,3"], &["--crop", "x0,x1,y0,y1"]),
        (vec![&"--crop", &"4,2,0,1"], &["--crop", "empty"]),
        (vec![&"--crop", &"0,49,0,1"], &["--crop 0,49,0,1", "48x32"]),
        (vec![&"--tonemap", &"sepia"], &["--tonemap", "sepia"]),
        (vec![&"--exposure", &"1e9"], &["--exposure"]),
        (vec![&"--layer", &"nosuch"], &["nosuch"]),
    ];
    for (extra, needles) in cases {
        let mut args: Vec<Arg> = vec![&"convert", &exr, &"-o", &out];
        args.extend(extra);
        let r = photon(&args);
        assert_error(&r, needles);
        assert!(!out.exists(), "nothing written on an error");
    }
    let r = photon(&[&"convert", &exr, &"-o", &out_exr, &"--tonemap", &"aces"]);
    assert_error(&r, &["--tonemap", "PNG output only"]);
    let r = photon(&[&"convert", &exr, &"-o", &out_exr, &"--exposure", &"2"]);
    assert_error(&r, &["--exposure", "PNG output only"]);
    let r = photon(&[&"convert", &exr, &"-o", &dir.0.join("out.tiff")]);
    assert_error(&r, &["-o ", "out.tiff", ".png, .exr or .pfm"]);
    let r = photon(&[&"compare", &exr, &exr, &"--flip-tonemap", &"x"]);
    assert_error(&r, &["--flip-tonemap"]);
    // Files that are no image: one line naming the file and what is wrong.
    let text = dir.0.join("notes.txt");
    std::fs::write(&text, "not an image").unwrap();
    let fake_png = dir.0.join("fake.png");
    std::fs::write(&fake_png, "not a png either").unwrap();
    let png = dir.0.join("real.png");
    photon::imageio::write_png(&png, &ramps(), 0.0).unwrap();
    let runs: [(Vec<Arg>, &Path, &str); 3] = [
        (
            vec![&"compare", &text, &exr],
            &text,
            "not an EXR, PNG or PFM image",
        ),
        (vec![&"compare", &exr, &fake_png], &fake_png, "PNG"),
        (
            vec![&"convert", &png, &"-o", &out_exr, &"--layer", &"albedo"],
            &png,
            "has no layers",
        ),
    ];
    for (args, file, needle) in runs {
        let r = photon(&args);
        assert_eq!(r.code, Some(2), "{}", r.describe());
        let lines: Vec<&str> = r.stderr.lines().collect();
        assert_eq!(lines.len(), 1, "{}", r.describe());
        assert!(
            lines[0].contains(&file.display().to_string()),
            "{}",
            lines[0]
        );
        assert!(lines[0].contains(needle), "{}", lines[0]);
    }
}
