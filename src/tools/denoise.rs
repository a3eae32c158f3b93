//! `photon denoise IN.exr -o OUT.exr`: Open Image Denoise on a rendered image
//! ([`crate::imageio::denoise`], feature `denoise`), and the one step that `render --denoise`
//! and `converge --denoise` share with it ([`denoise_image`]).
//!
//! ```text
//! photon denoise render.exr -o denoised.exr         # guides from the file's layers
//! photon denoise render.exr -o denoised.png --no-guides
//! ```
//!
//! The guides are the layers `albedo` (`albedo.R/G/B`) and `normal` (`normal.X/Y/Z`, or
//! `normal.R/G/B`) when the image has them: the first non-specular hit's albedo and shading
//! normal, as `render` writes them. The output's format follows its extension as `render -o`'s
//! does: an EXR gets the denoised `R,G,B`, the noisy beauty as layer `noisy` (`noisy.R/G/B`)
//! and every other float channel of the input, each stored as in the input (`UINT` channels,
//! a partial image's exact sums, are left out: the result is no partial image); a PNG (sRGB,
//! clamped) or PFM gets the denoised beauty alone. An input that already has a `noisy` layer
//! (an output of this command) is denoised from that layer again, not from its denoised RGB.
//! The output is planned before anything is read and replaced only once it is complete.
use super::output::{kind_only, ImageFormat, Outputs, Writer};
use super::ToolError;
use crate::imageio::denoise::{self as oidn, guides_used};
use crate::imageio::{
    self, ExrChannel, ExrCompression, ExrLayout, ExrSamples, ExrStored, RgbImage,
};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of `photon denoise`.
#[derive(clap::Args, Clone, Debug)]
pub struct DenoiseOptions {
    /// The image to denoise: an EXR (R,G,B and the guide layers `albedo`, `normal` if it has
    /// them), or a PNG or PFM (no guides).
    pub input: PathBuf,
    /// The image to write; its extension picks the format: `.exr` (denoised R,G,B, the noisy
    /// beauty as layer `noisy`, the input's other layers), `.png` or `.pfm` (denoised only).
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    /// Denoise the beauty alone, even when the input has albedo and normal layers.
    #[arg(long)]
    pub no_guides: bool,
}

/// The layer that keeps the undenoised beauty.
pub const NOISY: &str = "noisy";

/// One channel of an image, one sample per pixel (row-major), as stored in its file.
pub type Channel = (String, ExrStored, Vec<f32>);

/// A denoised image and what it was denoised with.
pub struct Denoised {
    pub image: RgbImage,
    /// `"albedo and normal guides (prefiltered)"`, `"no guides"`, ...
    pub guides: &'static str,
    pub seconds: f64,
}

/// Denoises `beauty` with the guides found among `channels` (named single channels of the
/// same size: `albedo.R/G/B`, `normal.X/Y/Z` or `normal.R/G/B`); `use_guides` false ignores
/// them. The one denoising step of `photon denoise`, `render --denoise` and `converge
/// --denoise`.
pub fn denoise_image(
    beauty: &RgbImage,
    channels: &[(&str, &[f32])],
    use_guides: bool,
) -> Result<Denoised, String> {
    let find = |names: [&str; 3]| use_guides.then(|| interleave(channels, names)).flatten();
    let albedo = find(["albedo.R", "albedo.G", "albedo.B"]);
    let normal = find(["normal.X", "normal.Y", "normal.Z"])
        .or_else(|| find(["normal.R", "normal.G", "normal.B"]));
    let start = Instant::now();
    let flat = oidn::denoise(
        beauty.pixels.as_flattened(),
        albedo.as_deref(),
        normal.as_deref(),
        beauty.width,
        beauty.height,
    )?;
    Ok(Denoised {
        image: RgbImage {
            width: beauty.width,
            height: beauty.height,
            pixels: flat.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect(),
        },
        guides: guides_used(albedo.is_some(), normal.is_some()),
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// The three channels `names` of `channels` as one RGB-interleaved buffer, if all are there.
fn interleave(channels: &[(&str, &[f32])], names: [&str; 3]) -> Option<Vec<f32>> {
    let planes = names.map(|n| channels.iter().find(|(c, _)| *c == n).map(|(_, s)| *s));
    let [Some(a), Some(b), Some(c)] = planes else {
        return None;
    };
    let n = a.len();
    (b.len() == n && c.len() == n).then(|| (0..n).flat_map(|i| [a[i], b[i], c[i]]).collect())
}

/// The layers `(name, image)` of a render as named single channels (`name.R/G/B`), the form
/// [`denoise_image`] finds its guides in.
pub fn layer_channels(layers: &[(&str, &RgbImage)]) -> Vec<(String, Vec<f32>)> {
    layers
        .iter()
        .flat_map(|(name, img)| {
            ["R", "G", "B"].into_iter().enumerate().map(move |(c, ch)| {
                let plane = img.pixels.iter().map(|p| p[c]).collect();
                (format!("{name}.{ch}"), plane)
            })
        })
        .collect()
}

/// `(name, samples)` views of owned channels.
pub fn views<T: AsRef<str>>(owned: &[(T, Vec<f32>)]) -> Vec<(&str, &[f32])> {
    owned
        .iter()
        .map(|(n, s)| (n.as_ref(), s.as_slice()))
        .collect()
}

/// An input image: its beauty, its other channels, and what was left out.
struct Input {
    beauty: RgbImage,
    /// Every float channel but R, G, B (and but `noisy.*` when that is the beauty).
    others: Vec<Channel>,
    /// How R, G, B are stored (the output keeps it).
    stored: ExrStored,
    /// Channels not copied (`UINT`), for the message.
    dropped: Vec<String>,
    /// True when the beauty came from an existing `noisy` layer.
    from_noisy: bool,
}

/// Runs `photon denoise`.
pub fn run(opts: &DenoiseOptions) -> Result<(), ToolError> {
    oidn::available().map_err(|e| ToolError(format!("denoise: {e}")))?;
    let out = &opts.output;
    let format = ImageFormat::of("-o", out).map_err(ToolError)?;
    let planned = Outputs::plan_files(&[("-o", out.as_path())]).map_err(ToolError)?;
    let input = read_input(&opts.input)?;
    let channels: Vec<(&str, &[f32])> = input
        .others
        .iter()
        .map(|(n, _, s)| (n.as_str(), s.as_slice()))
        .collect();
    let done = denoise_image(&input.beauty, &channels, !opts.no_guides)
        .map_err(|e| ToolError(format!("{}: {e}", opts.input.display())))?;
    let writer: Writer = Box::new(|tmp: &Path| {
        match format {
            ImageFormat::Exr => write_exr_output(tmp, &done.image, &input),
            ImageFormat::Png => imageio::write_png(tmp, &done.image, 0.0),
            ImageFormat::Pfm => imageio::write_pfm(tmp, &done.image),
        }
        .map_err(|e| kind_only(&e))
    });
    planned.commit(vec![writer])?;
    let (w, h) = (done.image.width, done.image.height);
    let mut how = format!(
        "{w}x{h} denoised with {} in {:.2} s",
        done.guides, done.seconds
    );
    if input.from_noisy {
        how += ", from the input's noisy layer";
    }
    if format == ImageFormat::Exr {
        how += "; noisy beauty kept as layer noisy";
        if !input.dropped.is_empty() {
            how += &format!("; UINT channels left out: {}", input.dropped.join(", "));
        }
    }
    say!("{}: {how}", out.display());
    Ok(())
}

/// Reads the beauty and the other channels of `path` (an EXR), or the beauty alone of a PNG
/// or PFM.
fn read_input(path: &Path) -> Result<Input, ToolError> {
    let list = match imageio::decode::FileFormat::from_extension(path) {
        Some(imageio::decode::FileFormat::Exr) | None => imageio::read_exr_channel_list(path).ok(),
        _ => None,
    };
    let Some(list) = list else {
        return Ok(Input {
            beauty: imageio::read_linear(path, None)?,
            others: Vec::new(),
            stored: ExrStored::Float,
            dropped: Vec::new(),
            from_noisy: false,
        });
    };
    let has = |n: &str| list.iter().any(|(c, _)| c == n);
    let from_noisy = ["R", "G", "B"].iter().all(|c| has(&format!("{NOISY}.{c}")));
    let beauty = match from_noisy {
        true => imageio::read_exr_layer(path, NOISY)?,
        false => imageio::read_exr(path)?,
    };
    let skip = |n: &str| match from_noisy {
        true => n.starts_with(&format!("{NOISY}.")) || ["R", "G", "B"].contains(&n),
        false => ["R", "G", "B"].contains(&n),
    };
    let stored = list
        .iter()
        .find(|(n, _)| n == "R")
        .map_or(ExrStored::Float, |(_, s)| float_kind(*s));
    let (floats, uints): (Vec<_>, Vec<_>) = list
        .into_iter()
        .filter(|(n, _)| !skip(n))
        .partition(|(_, s)| *s != ExrStored::Uint);
    Ok(Input {
        beauty,
        others: read_channels(path, floats)?,
        stored,
        dropped: uints.into_iter().map(|(n, _)| n).collect(),
        from_noisy,
    })
}

/// How a beauty stored as `s` is written: half stays half, anything else is float.
fn float_kind(s: ExrStored) -> ExrStored {
    match s {
        ExrStored::Half => ExrStored::Half,
        _ => ExrStored::Float,
    }
}

/// Reads the channels `list` of the EXR `path`, three at a time.
fn read_channels(path: &Path, list: Vec<(String, ExrStored)>) -> Result<Vec<Channel>, ToolError> {
    let mut out = Vec::with_capacity(list.len());
    for group in list.chunks(3) {
        let name = |i: usize| group[i.min(group.len() - 1)].0.as_str();
        let img = imageio::read_exr_named(path, [name(0), name(1), name(2)])?;
        for (i, (n, stored)) in group.iter().enumerate() {
            out.push((
                n.clone(),
                *stored,
                img.pixels.iter().map(|p| p[i]).collect(),
            ));
        }
    }
    Ok(out)
}

/// Writes the denoised `image` as R,G,B, the input's beauty as `noisy.R/G/B` and its other
/// channels, to `tmp`.
fn write_exr_output(
    tmp: &Path,
    image: &RgbImage,
    input: &Input,
) -> Result<(), imageio::ImageError> {
    let planes =
        |img: &RgbImage| [0, 1, 2].map(|c| img.pixels.iter().map(|p| p[c]).collect::<Vec<f32>>());
    let (clean, noisy) = (planes(image), planes(&input.beauty));
    let mut channels: Vec<ExrChannel> = Vec::new();
    for (c, ch) in ["R", "G", "B"].iter().enumerate() {
        channels.push(ExrChannel {
            name: ch,
            stored: input.stored,
            samples: ExrSamples::F32(&clean[c]),
        });
    }
    let noisy_names = ["R", "G", "B"].map(|c| format!("{NOISY}.{c}"));
    for (c, name) in noisy_names.iter().enumerate() {
        channels.push(ExrChannel {
            name,
            stored: input.stored,
            samples: ExrSamples::F32(&noisy[c]),
        });
    }
    for (name, stored, samples) in &input.others {
        if !noisy_names.contains(name) {
            channels.push(ExrChannel {
                name,
                stored: *stored,
                samples: ExrSamples::F32(samples),
            });
        }
    }
    let layout = ExrLayout {
        compression: ExrCompression::Zip,
        tile: None,
    };
    imageio::write_exr_channels(tmp, image.width, image.height, &channels, layout)
}
