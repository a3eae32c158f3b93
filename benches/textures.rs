//! `cargo bench --bench textures`: texture lookups per second on one thread, by filter, on a
//! 1024x1024 image (and its MIP pyramid) at pseudo-random uv with pixel-sized footprints, plus
//! the procedural textures. Prints one line per case: name, lookups, seconds, Mlookups/s.
use photon::math::{Vec2, Vec3};
use photon::texture::{Filter, Image, ImageMap, Pyramid, Tex, TexCoord, Texture, UvMapping, Wrap};
use std::hint::black_box;
use std::sync::Arc;
use std::time::Instant;

const SIDE: usize = 1024;
const LOOKUPS: usize = 4_000_000;

fn image() -> Arc<Image> {
    let texels = (0..SIDE * SIDE)
        .map(|i| Vec3::new((i % 7) as f32, (i % 11) as f32, (i % 13) as f32) / 13.0)
        .collect();
    Arc::new(Image {
        width: SIDE,
        height: SIDE,
        texels,
    })
}

fn image_map(im: &Arc<Image>, filter: Filter, pyramid: Option<Arc<Pyramid>>) -> Tex {
    Tex::Map(Arc::new(Texture::Image(ImageMap {
        image: im.clone(),
        mapping: UvMapping::default(),
        wrap: Wrap::Repeat,
        filter,
        scale: 1.0,
        invert: false,
        float: false,
        pyramid,
    })))
}

/// Lookup points: a cheap LCG over [0, 1)^2, footprints of 1/512 (two texels: level 1).
fn coords() -> Vec<TexCoord> {
    let mut s = 0x2545_f491u32;
    let mut next = || {
        s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (s >> 8) as f32 / (1u32 << 24) as f32
    };
    (0..LOOKUPS)
        .map(|_| TexCoord {
            uv: Vec2::new(next(), next()),
            duvdx: Vec2::new(1.0 / 1024.0, 0.0),
            duvdy: Vec2::new(0.0, 1.0 / 1024.0),
            ..Default::default()
        })
        .collect()
}

fn main() {
    let im = image();
    let t0 = Instant::now();
    let pyramid = Arc::new(Pyramid::build(&im));
    println!(
        "pyramid build {SIDE}x{SIDE}: {:.3} s",
        t0.elapsed().as_secs_f64()
    );
    let c = |v: f32| Arc::new(Texture::Constant(Vec3::splat(v)));
    let cases = [
        ("constant", Tex::Const(Vec3::splat(0.5))),
        ("point", image_map(&im, Filter::Point, None)),
        ("bilinear", image_map(&im, Filter::Bilinear, None)),
        (
            "trilinear",
            image_map(&im, Filter::Trilinear, Some(pyramid)),
        ),
        (
            "checkerboard",
            Tex::Map(Arc::new(Texture::Checkerboard {
                mapping: UvMapping {
                    scale: Vec2::splat(64.0),
                    delta: Vec2::ZERO,
                },
                tex1: c(1.0),
                tex2: c(0.0),
            })),
        ),
    ];
    let at = coords();
    println!("case,lookups,seconds,mlookups_per_s");
    for (name, tex) in &cases {
        let t0 = Instant::now();
        let mut sum = Vec3::ZERO;
        for tc in &at {
            sum += tex.eval(black_box(tc));
        }
        black_box(sum);
        let secs = t0.elapsed().as_secs_f64();
        println!(
            "{name},{LOOKUPS},{secs:.3},{:.1}",
            LOOKUPS as f64 / secs / 1e6
        );
    }
}
