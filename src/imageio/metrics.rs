//! Image error metrics against a reference, as used everywhere in this project:
//! `relMSE = mean((x - r)^2 / (r^2 + 0.01))` over pixels and channels, plus RMSE, MAE, max
//! absolute error and PSNR (peak 1, i.e. display white). Pixels whose reference is not finite
//! are masked and counted; so, optionally, are pixels next to bright emitters in the reference
//! (where a pixel-filter mismatch alone dominates the error, see `../shared/README.md`).
//! [`flip`] gives NVIDIA's perceptual LDR-FLIP of the two images tone-mapped alike.
use super::{RgbImage, Tonemap};

/// The `0.01` of relMSE's denominator.
pub const RELMSE_EPSILON: f64 = 0.01;

/// Error of one channel, or of all channels together.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ChannelError {
    pub rmse: f64,
    pub relmse: f64,
    pub mae: f64,
    pub max_abs: f64,
    pub psnr: f64,
}

/// All metrics of an image against a reference.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Metrics {
    pub channels: [ChannelError; 3],
    pub overall: ChannelError,
    /// Pixels compared.
    pub pixels: usize,
    /// Pixels skipped because the reference was not finite.
    pub masked_nonfinite: usize,
    /// Pixels skipped because they are near a bright emitter (`mask_above`).
    pub masked_emitter: usize,
    /// Pixels of the image (not the reference) that are not finite (counted as errors of 1e6).
    pub image_nonfinite: usize,
}

/// Which pixels to leave out.
#[derive(Clone, Copy, Debug, Default)]
pub struct MaskOptions {
    /// Leave out pixels within one pixel of a reference pixel whose max channel exceeds this.
    pub mask_above: Option<f32>,
}

/// Mask of pixels to compare (true = compare).
fn compare_mask(reference: &RgbImage, opts: MaskOptions) -> (Vec<bool>, usize, usize) {
    let (w, h) = (reference.width, reference.height);
    let mut keep = vec![true; w * h];
    let (mut nonfinite, mut emitter) = (0, 0);
    for (i, p) in reference.pixels.iter().enumerate() {
        if !p.iter().all(|c| c.is_finite()) {
            keep[i] = false;
            nonfinite += 1;
        }
    }
    if let Some(t) = opts.mask_above {
        let bright: Vec<bool> = reference
            .pixels
            .iter()
            .map(|p| p.iter().any(|&c| c > t))
            .collect();
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                if !keep[i] {
                    continue;
                }
                let near = (y.saturating_sub(1)..=(y + 1).min(h - 1)).any(|yy| {
                    (x.saturating_sub(1)..=(x + 1).min(w - 1)).any(|xx| bright[yy * w + xx])
                });
                if near {
                    keep[i] = false;
                    emitter += 1;
                }
            }
        }
    }
    (keep, nonfinite, emitter)
}

/// Per-pixel relMSE (mean over channels); `None` where masked.
pub fn relmse_map(image: &RgbImage, reference: &RgbImage, opts: MaskOptions) -> Vec<Option<f64>> {
    let (keep, _, _) = compare_mask(reference, opts);
    image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .zip(keep)
        .map(|((a, r), k)| {
            k.then(|| {
                (0..3)
                    .map(|c| sq_rel(value(a[c]), r[c] as f64))
                    .sum::<f64>()
                    / 3.0
            })
        })
        .collect()
}

fn value(x: f32) -> f64 {
    if x.is_finite() {
        x as f64
    } else {
        1e6
    }
}

fn sq_rel(a: f64, r: f64) -> f64 {
    (a - r).powi(2) / (r * r + RELMSE_EPSILON)
}

/// Compares `image` with `reference` (same size).
pub fn compare(
    image: &RgbImage,
    reference: &RgbImage,
    opts: MaskOptions,
) -> Result<Metrics, String> {
    if image.width != reference.width || image.height != reference.height {
        return Err(format!(
            "image is {}x{} but the reference is {}x{}",
            image.width, image.height, reference.width, reference.height
        ));
    }
    let (keep, masked_nonfinite, masked_emitter) = compare_mask(reference, opts);
    // Sums per channel: squared error, relative squared error, absolute error, max.
    let mut sums = [[0.0f64; 4]; 3];
    let mut n = 0usize;
    let mut image_nonfinite = 0;
    for ((a, r), k) in image.pixels.iter().zip(&reference.pixels).zip(keep) {
        if !k {
            continue;
        }
        n += 1;
        if !a.iter().all(|c| c.is_finite()) {
            image_nonfinite += 1;
        }
        for c in 0..3 {
            let (x, y) = (value(a[c]), r[c] as f64);
            let d = (x - y).abs();
            sums[c][0] += d * d;
            sums[c][1] += sq_rel(x, y);
            sums[c][2] += d;
            sums[c][3] = sums[c][3].max(d);
        }
    }
    let finish = |se: f64, rel: f64, ae: f64, max: f64, count: f64| {
        let mse = se / count.max(1.0);
        ChannelError {
            rmse: mse.sqrt(),
            relmse: rel / count.max(1.0),
            mae: ae / count.max(1.0),
            max_abs: max,
            psnr: if mse > 0.0 {
                -10.0 * mse.log10()
            } else {
                f64::INFINITY
            },
        }
    };
    let channels: [ChannelError; 3] =
        std::array::from_fn(|c| finish(sums[c][0], sums[c][1], sums[c][2], sums[c][3], n as f64));
    let total = |k: usize| sums.iter().map(|s| s[k]).sum::<f64>();
    let max = sums.iter().map(|s| s[3]).fold(0.0, f64::max);
    let overall = finish(total(0), total(1), total(2), max, 3.0 * n as f64);
    Ok(Metrics {
        channels,
        overall,
        pixels: n,
        masked_nonfinite,
        masked_emitter,
        image_nonfinite,
    })
}

/// Box-filters the larger of two images down to the smaller one's size when an integer factor
/// relates them; returns the pair at a common size.
pub fn match_sizes(image: RgbImage, reference: RgbImage) -> Result<(RgbImage, RgbImage), String> {
    if image.width == reference.width && image.height == reference.height {
        return Ok((image, reference));
    }
    let shrink = |big: &RgbImage, small: &RgbImage| -> Option<RgbImage> {
        if !big.width.is_multiple_of(small.width)
            || big.width / small.width != big.height / small.height.max(1)
        {
            return None;
        }
        big.downsample_box(big.width / small.width)
    };
    if image.width > reference.width {
        let img = shrink(&image, &reference);
        img.map(|i| (i, reference.clone()))
    } else {
        shrink(&reference, &image).map(|r| (image.clone(), r))
    }
    .ok_or_else(|| {
        format!(
            "sizes {}x{} and {}x{} are not related by an integer factor",
            image.width, image.height, reference.width, reference.height
        )
    })
}

/// A false-colour image of per-pixel relMSE on a log scale from 1e-4 (black-blue) to 1 (red,
/// then white above); masked pixels are [`MASKED_COLOUR`].
pub fn error_image(image: &RgbImage, reference: &RgbImage, opts: MaskOptions) -> RgbImage {
    let map = relmse_map(image, reference, opts);
    let mut out = RgbImage::new(image.width, image.height);
    for (o, e) in out.pixels.iter_mut().zip(map) {
        *o = e.map_or(MASKED_COLOUR, error_colour);
    }
    out
}

/// The (linear) colour of masked pixels in [`error_image`].
pub const MASKED_COLOUR: [f32; 3] = [0.2, 0.2, 0.2];

/// The (linear) colour of a relative error `e` in [`error_image`]: black to blue from 1e-4 to
/// 1e-2, blue to red up to 1, red to white up to 10 (`log10 e` from -4 to 1).
pub fn error_colour(e: f64) -> [f32; 3] {
    let t = ((e.max(1e-12).log10() + 4.0) / 4.0).clamp(0.0, 1.25) as f32;
    if t <= 0.5 {
        [0.0, 0.0, t * 2.0]
    } else if t <= 1.0 {
        let s = (t - 0.5) * 2.0;
        [s, 0.0, 1.0 - s]
    } else {
        let s = (t - 1.0) * 4.0;
        [1.0, s, s]
    }
}

/// How the two images are shown to FLIP ([`flip`]); the default is the PNG preview's view
/// (exposure 0, clip).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FlipOptions {
    /// Exposure in stops applied to both images before the tone curve.
    pub exposure: f32,
    /// The tone curve applied to both images.
    pub tonemap: Tonemap,
}

/// Mean LDR-FLIP (NVIDIA's perceptual error, 0 = identical, 1 = the largest difference) of
/// `image` against `reference`, through the `nv-flip` crate, at its default 67 pixels per
/// degree. nv-flip exposes LDR-FLIP only, on 8-bit sRGB images: both linear images are first
/// tone-mapped the same way (`opts`: exposure, curve, sRGB OETF, 8 bits; see
/// [`super::tonemap`]), as a PNG preview would show them. Every pixel counts (no masks;
/// non-finite values become black, or white for +inf).
pub fn flip(image: &RgbImage, reference: &RgbImage, opts: FlipOptions) -> Result<f64, String> {
    if image.width != reference.width || image.height != reference.height {
        return Err(format!(
            "image is {}x{} but the reference is {}x{}",
            image.width, image.height, reference.width, reference.height
        ));
    }
    let pixels = image.width.checked_mul(image.height);
    let fits = |n: usize| n.checked_mul(3).is_some_and(|b| u32::try_from(b).is_ok());
    if !image.is_consistent() || !reference.is_consistent() || !pixels.is_some_and(fits) {
        return Err(format!(
            "FLIP takes images up to {} pixels, not {}x{}",
            u32::MAX / 3,
            image.width,
            image.height
        ));
    }
    if pixels == Some(0) {
        return Ok(0.0);
    }
    let (w, h) = (image.width as u32, image.height as u32);
    let rgb8 = |im: &RgbImage| {
        let bytes = super::tonemap::to_srgb8(&im.pixels, opts.exposure, opts.tonemap);
        nv_flip::FlipImageRgb8::with_data(w, h, &bytes)
    };
    let map = nv_flip::flip(
        rgb8(reference),
        rgb8(image),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    let values = map.to_vec();
    let sum: f64 = values.iter().map(|&v| f64::from(v)).sum();
    Ok(sum / values.len() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(w: usize, h: usize, f: impl Fn(usize) -> [f32; 3]) -> RgbImage {
        RgbImage {
            width: w,
            height: h,
            pixels: (0..w * h).map(f).collect(),
        }
    }

    /// Hand-computed values on a 2x1 image.
    #[test]
    fn metrics_by_hand() {
        let r = img(2, 1, |_| [1.0, 0.0, 0.5]);
        let a = img(2, 1, |i| {
            if i == 0 {
                [1.1, 0.0, 0.5]
            } else {
                [1.0, 0.2, 0.5]
            }
        });
        let m = compare(&a, &r, MaskOptions::default()).unwrap();
        // relMSE: (0.01/1.01 + 0.04/0.01) / 6
        let want = (0.01 / 1.01 + 0.04 / 0.01) / 6.0;
        assert!(
            (m.overall.relmse - want).abs() < 1e-7,
            "{} vs {want}",
            m.overall.relmse
        );
        assert!((m.overall.rmse - ((0.01 + 0.04) / 6.0f64).sqrt()).abs() < 1e-7);
        assert!((m.overall.max_abs - 0.2).abs() < 1e-6 && (m.overall.mae - 0.3 / 6.0).abs() < 1e-7);
        assert!((m.channels[1].relmse - 0.04 / 0.01 / 2.0).abs() < 1e-6);
        assert_eq!(m.pixels, 2);
    }

    #[test]
    fn masks_nonfinite_and_emitters() {
        let r = img(4, 1, |i| match i {
            0 => [f32::NAN, 0.0, 0.0],
            3 => [20.0, 20.0, 20.0],
            _ => [0.5; 3],
        });
        let a = img(4, 1, |_| [0.5; 3]);
        let m = compare(
            &a,
            &r,
            MaskOptions {
                mask_above: Some(10.0),
            },
        )
        .unwrap();
        assert_eq!((m.pixels, m.masked_nonfinite, m.masked_emitter), (1, 1, 2));
        assert_eq!(m.overall.relmse, 0.0);
        assert!(compare(&img(2, 2, |_| [0.0; 3]), &r, MaskOptions::default()).is_err());
    }

    #[test]
    fn sizes_match_by_box_filtering() {
        let big = img(4, 4, |i| [i as f32; 3]);
        let small = img(2, 2, |_| [0.0; 3]);
        let (a, b) = match_sizes(small, big).unwrap();
        assert_eq!((b.width, b.height), (2, 2));
        assert_eq!(b.pixels[0], [2.5; 3]); // mean of 0, 1, 4, 5
        assert_eq!(a.width, 2);
        assert!(match_sizes(img(3, 3, |_| [0.0; 3]), img(4, 4, |_| [0.0; 3])).is_err());
    }

    #[test]
    fn flip_is_zero_against_itself_and_positive_against_another_image() {
        let opts = FlipOptions {
            exposure: 0.0,
            tonemap: Tonemap::Clamp,
        };
        let a = img(32, 24, |i| {
            [(i % 32) as f32 / 32.0, 0.3, (i / 32) as f32 / 24.0]
        });
        assert_eq!(flip(&a, &a, opts).unwrap(), 0.0);
        let b = img(32, 24, |i| [0.9 - (i % 32) as f32 / 40.0, 0.3, 0.1]);
        let d = flip(&a, &b, opts).unwrap();
        assert!(d > 0.05 && d <= 1.0, "{d}");
        assert!(flip(&a, &img(2, 2, |_| [0.0; 3]), opts).is_err());
    }
}
