//! Rendering in independent passes: progressive photon mapping, partial images, merging.
//!
//! A render in passes is a sum of pass images. Pass `k` depends only on (scene, settings,
//! seed, `k`): its pixel samples use the seed [`pass_seed`]`(seed, k)`, and with
//! progressive photon mapping (Knaus and Zwicker 2011, "Progressive photon mapping: a
//! probabilistic approach") it also traces fresh global and caustic maps with that seed, and
//! its estimates use only the photons within `s_k r_knn^2` of each lookup, where `r_knn` is
//! the k-nearest radius of the lookup (capped by `globalradius` / `causticradius`) and
//!
//! ```text
//! s_0 = 1,   s_{i+1} = s_i (i + alpha) / (i + 1)        (i = 1, 2, ...; alpha = 2/3)
//! ```
//!
//! Knaus and Zwicker's schedule with an initial radius that depends on the position (pass 0
//! is Jensen's estimate). Given `r_knn`, the photons inside the smaller disc are uniform in it,
//! so the same kernel estimate over them stays consistent; bias and variance both go to zero
//! as passes are added (the MSE falls as `N^-(1 - alpha)` or faster while pixel noise
//! dominates). Progressive passes skip the irradiance cache (its nearest-point lookup is a
//! blur that would not shrink) and the minimum photon count. With Jensen's fixed maps
//! (`progressive false`) every pass reads the same maps (traced once with `seed`).
//!
//! Pass images are added into an exact fixed-point accumulator ([`Partial`]: `i64` per channel
//! in units of 2^-24), so that the sum does not depend on how passes are grouped: any split of
//! the passes `[0, N)` over processes or machines merges to the same image, bit for bit.
//!
//! ```text
//! Integrator "photonmap" "bool progressive" [ true ] "float alpha" [ 0.6667 ]
//!     "integer passspp" [ 4 ]      # samples per pixel of each pass
//! ```
use super::photonmap::PhotonPass;
use super::{IntegratorKind, RenderOutput, RenderSettings};
use crate::accel::Accel;
use crate::film::Component;
use crate::imageio::RgbImage;
use crate::limits::MAX_PASSES;
use crate::sampling::hash;
use crate::scene::Scene;
use std::ops::Range;

/// Units of the fixed-point accumulator: a pass value `v` adds `round(v * 2^24)`.
pub const FIXED_ONE: f64 = (1u64 << 24) as f64;

/// The seed of pass `k`'s sample streams (and of its photon maps when progressive).
pub fn pass_seed(seed: u64, k: u64) -> u64 {
    hash(&[seed, k, 0x7061_7373])
}

/// Factor on the squared radii of pass `k` (pass 0: 1): the product of
/// `(i + alpha) / (i + 1)` for `i = 1..=k` (`k` at most [`MAX_PASSES`], which the command
/// line and partial files are held to: the product stops there).
pub fn radius_scale2(alpha: f64, k: u64) -> f64 {
    (1..=k.min(MAX_PASSES)).fold(1.0, |s, i| s * (i as f64 + alpha) / (i as f64 + 1.0))
}

/// The settings of pass `k`: its seed, its sample count and (progressive) its radii.
pub fn pass_settings(settings: &RenderSettings, k: u64) -> RenderSettings {
    let mut s = settings.clone();
    s.seed = pass_seed(settings.seed, k);
    s.texture_spp = Some(settings.texture_spp.unwrap_or(settings.spp));
    s.spp = settings.pass_spp.max(1);
    // VCM's merge radius goes on shrinking from the iterations of the passes before.
    s.vcm.first = k
        .saturating_mul(s.spp as u64)
        .saturating_add(settings.vcm.first as u64)
        .min(u32::MAX as u64) as u32;
    if s.photon.progressive {
        s.photon.radius_scale2 = radius_scale2(s.photon.alpha as f64, k);
    }
    s
}

/// What makes two partial images parts of one render: everything but the pass range.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PartialHeader {
    /// [`Scene::content_hash`] in hex.
    pub scene: String,
    pub seed: u64,
    pub width: usize,
    pub height: usize,
    /// Integrator, backend, samples per pass and every setting that changes the image.
    pub settings: String,
}

impl PartialHeader {
    /// The header of a render of `scene` with `settings` by `kind` on backend `backend`.
    pub fn new(
        scene: &Scene,
        settings: &RenderSettings,
        kind: IntegratorKind,
        backend: &str,
    ) -> Self {
        let mut s = settings.clone();
        s.seed = 0;
        s.spp = 0; // the pass count is in the range; the per-pass count in `pass_spp`
        s.photon.radius_scale2 = 1.0;
        PartialHeader {
            scene: format!("{:016x}", scene.content_hash()),
            seed: settings.seed,
            width: settings.image_size().0 as usize,
            height: settings.image_size().1 as usize,
            settings: format!("integrator {kind:?}, backend {backend}, {s:?}"),
        }
    }
}

/// The sum of the pass images of a range of passes, exactly (fixed point).
#[derive(Clone, Debug, PartialEq)]
pub struct Partial {
    pub header: PartialHeader,
    pub passes: Range<u64>,
    /// Per pixel: R, G, B of each of the [`Component`]s, in units of 2^-24.
    pub sums: Vec<[i64; 12]>,
    /// Values that were not finite (left out) or saturated the accumulator.
    pub rejected: u64,
}

/// A pass value in fixed point (non-finite: `None`).
fn to_fixed(v: f32) -> Option<i64> {
    let x = (v as f64 * FIXED_ONE).round();
    x.is_finite()
        .then(|| x.clamp(-(2f64.powi(62)), 2f64.powi(62)) as i64)
}

impl Partial {
    /// An empty partial image of `header`'s size, at pass `start`.
    pub fn new(header: PartialHeader, start: u64) -> Partial {
        let n = header.width * header.height;
        Partial {
            header,
            passes: start..start,
            sums: vec![[0; 12]; n],
            rejected: 0,
        }
    }

    /// Adds the image of pass `self.passes.end`.
    pub fn add_pass(&mut self, out: &RenderOutput) {
        for (c, (_, img)) in out
            .components
            .iter()
            .enumerate()
            .take(Component::NAMES.len())
        {
            for (sum, px) in self.sums.iter_mut().zip(&img.pixels) {
                for (k, &v) in px.iter().enumerate() {
                    let slot = &mut sum[3 * c + k];
                    match to_fixed(v).and_then(|q| slot.checked_add(q)) {
                        Some(s) => *slot = s,
                        None => self.rejected += 1,
                    }
                }
            }
        }
        self.passes.end += 1;
    }

    /// Adds another part of the same render (the caller checks headers and ranges). A sum
    /// that would leave the i64 range is an error naming the pixel (saturating would give a
    /// wrong image without a word).
    pub fn absorb(&mut self, other: &Partial) -> Result<(), String> {
        let w = self.header.width.max(1);
        for (i, (a, b)) in self.sums.iter_mut().zip(&other.sums).enumerate() {
            for (x, y) in a.iter_mut().zip(b) {
                *x = x.checked_add(*y).ok_or_else(|| {
                    format!(
                        "the sum at pixel ({}, {}) overflows: the parts hold more than \
                         2^39 units of radiance there",
                        i % w,
                        i / w
                    )
                })?;
            }
        }
        self.rejected = self.rejected.saturating_add(other.rejected);
        self.passes =
            self.passes.start.min(other.passes.start)..self.passes.end.max(other.passes.end);
        Ok(())
    }

    /// The mean over the passes: the total image and one image per component.
    pub fn mean(&self) -> (RgbImage, Vec<(&'static str, RgbImage)>) {
        let (w, h) = (self.header.width, self.header.height);
        let n = (self.passes.end - self.passes.start).max(1) as f64 * FIXED_ONE;
        let mut parts: Vec<(&'static str, RgbImage)> = Component::NAMES
            .iter()
            .map(|&c| (c, RgbImage::new(w, h)))
            .collect();
        let mut total = RgbImage::new(w, h);
        for (i, s) in self.sums.iter().enumerate() {
            for k in 0..3 {
                let mut t = 0i128;
                for (c, (_, img)) in parts.iter_mut().enumerate() {
                    img.pixels[i][k] = (s[3 * c + k] as f64 / n) as f32;
                    t += s[3 * c + k] as i128;
                }
                total.pixels[i][k] = (t as f64 / n) as f32;
            }
        }
        (total, parts)
    }
}

/// The `photon.format` attribute of partial images.
pub const FORMAT: &str = "photon-partial-1";

impl Partial {
    /// Writes the partial image to `path` (atomically): `R,G,B` and the component layers hold
    /// the mean so far (any EXR viewer shows the image), the `UINT` layers
    /// `sum.<component>.hi/lo` the exact sums, and string attributes `photon.*` the header and
    /// pass range.
    pub fn write(&self, path: &std::path::Path) -> Result<(), crate::imageio::ImageError> {
        let (total, parts) = self.mean();
        let words: Vec<(String, Vec<[u32; 3]>)> = Component::NAMES
            .iter()
            .enumerate()
            .flat_map(|(c, name)| {
                let half = |hi: bool| {
                    self.sums
                        .iter()
                        .map(|s| {
                            std::array::from_fn(|k| {
                                let v = s[3 * c + k] as u64;
                                if hi {
                                    (v >> 32) as u32
                                } else {
                                    v as u32
                                }
                            })
                        })
                        .collect()
                };
                [
                    (format!("sum.{name}.hi"), half(true)),
                    (format!("sum.{name}.lo"), half(false)),
                ]
            })
            .collect();
        let uint: Vec<(&str, &[[u32; 3]])> =
            words.iter().map(|(n, w)| (n.as_str(), &w[..])).collect();
        let h = &self.header;
        let attrs = [
            ("photon.format", FORMAT.to_string()),
            ("photon.scene", h.scene.clone()),
            ("photon.seed", h.seed.to_string()),
            ("photon.resolution", format!("{}x{}", h.width, h.height)),
            ("photon.settings", h.settings.clone()),
            (
                "photon.passes",
                format!("{}..{}", self.passes.start, self.passes.end),
            ),
            ("photon.rejected", self.rejected.to_string()),
        ];
        let attributes: Vec<(&str, &str)> = attrs.iter().map(|(k, v)| (*k, v.as_str())).collect();
        let layers: Vec<(&str, &RgbImage)> = parts.iter().map(|(n, i)| (*n, i)).collect();
        crate::imageio::write_exr_with(
            path,
            &total,
            &layers,
            crate::imageio::ExrPixel::Float,
            crate::imageio::ExrExtra {
                uint_layers: &uint,
                attributes: &attributes,
                ..Default::default()
            },
        )
    }

    /// Reads a partial image written by [`Partial::write`]; the error says what is missing.
    pub fn read(path: &std::path::Path) -> Result<Partial, String> {
        let shown = path.display();
        let attrs = crate::imageio::read_exr_attributes(path).map_err(|e| e.to_string())?;
        let get = |k: &str| {
            attrs
                .iter()
                .find(|(n, _)| n == k)
                .map(|(_, v)| v.clone())
                .ok_or_else(|| format!("{shown}: not a partial image of photon (no attribute {k})"))
        };
        if get("photon.format")? != FORMAT {
            return Err(format!(
                "{shown}: partial image format {:?}, expected {FORMAT}",
                get("photon.format")?
            ));
        }
        let bad = |k: &str| format!("{shown}: malformed attribute {k}");
        let (w, h) = get("photon.resolution")?
            .split_once('x')
            .and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)))
            .ok_or_else(|| bad("photon.resolution"))?;
        let passes = get("photon.passes")?
            .split_once("..")
            .and_then(|(a, b)| Some(a.parse().ok()?..b.parse().ok()?))
            .filter(|r: &Range<u64>| r.start <= r.end)
            .ok_or_else(|| bad("photon.passes"))?;
        let pixels = w as u64 * h as u64;
        if w == 0 || h == 0 || pixels > crate::limits::MAX_IMAGE_PIXELS {
            return Err(format!(
                "{shown}: photon.resolution {w}x{h} is not a size photon renders (at most {} \
                 pixels)",
                crate::limits::MAX_IMAGE_PIXELS
            ));
        }
        // The file's own data window (from its header) must be that size before any layer is
        // decoded: a forged window would make the decoder allocate for it.
        let size = crate::imageio::read_exr_size(path).map_err(|e| e.to_string())?;
        if size != (w, h) {
            return Err(format!(
                "{shown}: the image is {}x{}, photon.resolution says {w}x{h}",
                size.0, size.1
            ));
        }
        if passes.end > MAX_PASSES {
            return Err(format!(
                "{shown}: pass range {}..{} goes beyond the limit of {MAX_PASSES} passes",
                passes.start, passes.end
            ));
        }
        let header = PartialHeader {
            scene: get("photon.scene")?,
            seed: get("photon.seed")?
                .parse()
                .map_err(|_| bad("photon.seed"))?,
            width: w,
            height: h,
            settings: get("photon.settings")?,
        };
        // Allocated once the first layer has shown the file really holds w x h pixels (a
        // forged photon.resolution asked for 960 GB here).
        let mut sums: Vec<[i64; 12]> = Vec::new();
        for (c, name) in Component::NAMES.iter().enumerate() {
            let read = |half: &str| {
                let layer = format!("sum.{name}.{half}");
                let (lw, lh, words) =
                    crate::imageio::read_exr_uint_layer(path, &layer).map_err(|e| e.to_string())?;
                if (lw, lh) != (w, h) {
                    return Err(format!(
                        "{shown}: layer {layer} is {lw}x{lh}, expected {w}x{h}"
                    ));
                }
                Ok(words)
            };
            let (hi, lo) = (read("hi")?, read("lo")?);
            if sums.is_empty() {
                sums = vec![[0i64; 12]; w * h];
            }
            for (i, ((s, a), b)) in sums.iter_mut().zip(&hi).zip(&lo).enumerate() {
                for k in 0..3 {
                    let v = ((a[k] as u64) << 32 | b[k] as u64) as i64;
                    // Radiance and the pixel filters (box, triangle, Gaussian) are never
                    // negative: a negative sum was not written by photon.
                    if v < 0 {
                        return Err(format!(
                            "{shown}: sum.{name} is negative at pixel ({}, {}): not a sum \
                             photon wrote",
                            i % w,
                            i / w
                        ));
                    }
                    s[3 * c + k] = v;
                }
            }
        }
        Ok(Partial {
            header,
            passes,
            sums,
            rejected: get("photon.rejected")?
                .parse()
                .map_err(|_| bad("photon.rejected"))?,
        })
    }
}

/// Merges parts of one render: their headers must agree (the error names the first field
/// that differs and the two files) and their pass ranges must tile `[0, N)` without overlap
/// (the error lists the overlaps and the missing ranges).
pub fn merge(parts: &[(std::path::PathBuf, Partial)]) -> Result<Partial, String> {
    let Some((first_path, first)) = parts.first() else {
        return Err("nothing to merge".into());
    };
    for (path, p) in &parts[1..] {
        let (a, b) = (&first.header, &p.header);
        let field = if a.scene != b.scene {
            Some("scene")
        } else if a.seed != b.seed {
            Some("seed")
        } else if (a.width, a.height) != (b.width, b.height) {
            Some("resolution")
        } else if a.settings != b.settings {
            Some("settings")
        } else {
            None
        };
        if let Some(field) = field {
            return Err(format!(
                "{} and {} are parts of different renders: {field} differs",
                first_path.display(),
                path.display()
            ));
        }
    }
    let mut order: Vec<&(std::path::PathBuf, Partial)> = parts.iter().collect();
    order.sort_by_key(|(_, p)| (p.passes.start, p.passes.end));
    let mut problems = Vec::new();
    let mut covered = 0u64;
    let mut last: Option<&std::path::PathBuf> = None;
    for (path, p) in &order {
        if p.passes.start < covered {
            problems.push(format!(
                "passes {}..{} of {} overlap {}",
                p.passes.start,
                covered.min(p.passes.end),
                path.display(),
                last.map_or(String::new(), |l| l.display().to_string())
            ));
        } else if p.passes.start > covered {
            problems.push(format!("passes {covered}..{} are missing", p.passes.start));
        }
        if p.passes.end > covered {
            covered = p.passes.end;
            last = Some(path);
        }
    }
    if !problems.is_empty() {
        return Err(format!("cannot merge: {}", problems.join("; ")));
    }
    let mut acc = Partial::new(first.header.clone(), 0);
    for (_, p) in order {
        acc.absorb(p)?;
    }
    Ok(acc)
}

/// Renders passes `range` of `scene`, adding each into `acc` (whose range must end at
/// `range.start`), and calls `after_pass(acc)` after each; stops early when `after_pass`
/// returns false. Returns the statistics lines of the last pass (photon counts, radii).
pub fn render_passes(
    scene: &Scene,
    accel: &Accel,
    settings: &RenderSettings,
    kind: IntegratorKind,
    range: Range<u64>,
    acc: &mut Partial,
    after_pass: &mut dyn FnMut(&Partial, &RenderOutput) -> bool,
) {
    debug_assert_eq!(acc.passes.end, range.start);
    // Jensen's fixed maps: pass 1 once, with the render's own seed.
    let progressive = settings.photon.progressive;
    let shared: Option<PhotonPass> = (!progressive)
        .then(|| super::prepare(scene, accel, settings, kind))
        .flatten();
    let first = range.start;
    for k in range {
        let s = pass_settings(settings, k);
        let own = progressive
            .then(|| super::prepare(scene, accel, &s, kind))
            .flatten();
        let photons = own.as_ref().or(shared.as_ref());
        let mut out = super::render_prepared(scene, accel, &s, kind, photons, super::UNOBSERVED);
        if own.is_none() && k != first {
            // Shared maps: their pass 1 is charged to the first pass only.
            out.seconds -= out.photon_seconds + out.map_build_seconds;
            (
                out.photon_seconds,
                out.map_build_seconds,
                out.photons_emitted,
            ) = (0.0, 0.0, 0);
        }
        if crate::interrupt::requested().is_some() {
            break; // the pass was cut short: it is not added
        }
        acc.add_pass(&out);
        if !after_pass(acc, &out) {
            break;
        }
    }
}

/// Photon work (tracing and building) is kept to at most this share of a pass in
/// [`render_for_time`] by raising the pass's samples per pixel.
pub const PHOTON_SHARE: f64 = 0.25;

/// Progressive passes until `budget_s` seconds are spent, stopping before a pass that would
/// not fit. Made for a wall-clock budget, not for merging: each pass traces the configured
/// photon counts, and the samples per pixel of the next pass grow (at most 4x per pass) until
/// photon work is at most [`PHOTON_SHARE`] of a pass; when such a pass would not fit in the
/// time left, the pass takes the samples that do fit (at least 1; else the render stops);
/// pass images are averaged weighted by their samples. Returns the image and the samples per pixel it holds.
pub fn render_for_time(
    scene: &Scene,
    accel: &Accel,
    settings: &RenderSettings,
    kind: IntegratorKind,
    budget_s: f64,
    observer: &dyn super::Observer,
) -> (RenderOutput, u32) {
    let start = std::time::Instant::now();
    let (w, h) = settings.image_size();
    let (w, h) = (w as usize, h as usize);
    let mut sums = vec![[0f64; 12]; w * h];
    let mut totals = RenderOutput::empty();
    let (mut pass_spp, mut spp_done, mut k) = (settings.pass_spp.max(1), 0u32, 0u64);
    let mut last_spp = pass_spp;
    loop {
        let mut s = pass_settings(settings, k);
        s.spp = pass_spp;
        let t = std::time::Instant::now();
        let photons = super::prepare(scene, accel, &s, kind);
        let out =
            super::render_prepared(scene, accel, &s, kind, photons.as_ref(), super::UNOBSERVED);
        if crate::interrupt::requested().is_some() && spp_done > 0 {
            break; // cut short: not added
        }
        for (c, (_, img)) in out
            .components
            .iter()
            .enumerate()
            .take(Component::NAMES.len())
        {
            for (sum, px) in sums.iter_mut().zip(&img.pixels) {
                for (k, v) in px.iter().enumerate() {
                    sum[3 * c + k] += *v as f64 * pass_spp as f64;
                }
            }
        }
        totals.add_counts(&out);
        spp_done += pass_spp;
        last_spp = pass_spp;
        let (image, layers) = weighted_mean(&sums, spp_done, w, h);
        observer.image(&image, &layers, k);
        k += 1;
        // The next pass: enough samples that photon work is at most PHOTON_SHARE of it.
        let pass_s = t.elapsed().as_secs_f64();
        let photon_s = out.photon_seconds + out.map_build_seconds;
        let per_spp = ((pass_s - photon_s) / pass_spp as f64).max(1e-9);
        let want = photon_s * (1.0 - PHOTON_SHARE) / PHOTON_SHARE / per_spp;
        pass_spp = (want.ceil() as u32).clamp(pass_spp, pass_spp.saturating_mul(4));
        let elapsed = start.elapsed().as_secs_f64();
        let left = budget_s - elapsed;
        if photon_s + per_spp * pass_spp as f64 > left {
            // The grown pass does not fit: the largest that does (down to 1 spp), so that a
            // larger budget is used rather than stopping where a smaller one stopped.
            let fits = ((left - photon_s) * 0.9 / per_spp).floor();
            pass_spp = if fits >= 1.0 {
                (fits as u32).min(pass_spp)
            } else {
                0
            };
        }
        let stop = pass_spp == 0 || k >= MAX_PASSES;
        if stop || crate::interrupt::requested().is_some() {
            break;
        }
    }
    let (image, parts) = weighted_mean(&sums, spp_done, w, h);
    totals.image = image;
    totals.components = parts;
    totals.seconds = start.elapsed().as_secs_f64();
    let scale = radius_scale2(settings.photon.alpha as f64, k.saturating_sub(1)).sqrt();
    let photons = if scene.media_need_tracking.is_some() {
        format!("{} volume photons", settings.photon.volume_photons)
    } else {
        format!(
            "{} + {} photons",
            settings.photon.trace.global_photons, settings.photon.trace.caustic_photons
        )
    };
    totals.notes.push(format!(
        "progressive: {k} passes, {spp_done} spp ({} spp in the last), {photons} per pass, radii now x{scale:.3} of the first pass's",
        last_spp,
    ));
    (totals, spp_done)
}

/// The image and component images of per-pixel sums (`[component][channel]`, weighted by
/// samples) over `spp` samples, for a `w x h` image.
fn weighted_mean(
    sums: &[[f64; 12]],
    spp: u32,
    w: usize,
    h: usize,
) -> (RgbImage, Vec<(&'static str, RgbImage)>) {
    let n = spp.max(1) as f64;
    let mut parts: Vec<(&'static str, RgbImage)> = Component::NAMES
        .iter()
        .map(|&c| (c, RgbImage::new(w, h)))
        .collect();
    let mut image = RgbImage::new(w, h);
    for (i, s) in sums.iter().enumerate() {
        for c in 0..3 {
            let mut t = 0.0;
            for (j, (_, img)) in parts.iter_mut().enumerate() {
                img.pixels[i][c] = (s[3 * j + c] / n) as f32;
                t += s[3 * j + c];
            }
            image.pixels[i][c] = (t / n) as f32;
        }
    }
    (image, parts)
}

/// One statistics line: passes, samples, photons and the current radii.
pub fn progress_note(settings: &RenderSettings, acc: &Partial) -> String {
    let n = acc.passes.end - acc.passes.start;
    let p = &settings.photon;
    let mut line = format!(
        "passes {}..{} ({n} x {} spp)",
        acc.passes.start,
        acc.passes.end,
        settings.pass_spp.max(1)
    );
    if p.progressive && acc.passes.end > 0 {
        let scale = radius_scale2(p.alpha as f64, acc.passes.end - 1).sqrt();
        line += &format!(
            ", progressive (alpha {:.3}): {} + {} photons per pass, radii now {:.4} / {:.4} of the scene radius (x{:.3} of pass 0)",
            p.alpha,
            p.trace.global_photons,
            p.trace.caustic_photons,
            p.global_radius as f64 * scale,
            p.caustic_radius as f64 * scale,
            scale
        );
    }
    if acc.rejected > 0 {
        line += &format!(", {} non-finite or saturated values left out", acc.rejected);
    }
    line
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radius_schedule_follows_the_recurrence() {
        // r_{i+1}^2 = r_i^2 (i + alpha) / (i + 1), computed step by step by hand.
        let alpha = 2.0 / 3.0;
        let mut r2 = 1.0f64;
        for k in 0..50u64 {
            assert!(
                (radius_scale2(alpha, k) - r2).abs() < 1e-12 * r2,
                "pass {k}"
            );
            let i = (k + 1) as f64;
            r2 *= (i + alpha) / (i + 1.0);
        }
        // Asymptotically r^2 ~ C k^(alpha - 1): the ratio over a doubling tends to 2^(-1/3).
        let ratio = radius_scale2(alpha, 20_000) / radius_scale2(alpha, 10_000);
        assert!((ratio - 2f64.powf(alpha - 1.0)).abs() < 1e-4, "{ratio}");
    }

    #[test]
    fn fixed_point_sums_do_not_depend_on_grouping() {
        let header = PartialHeader {
            scene: "0".into(),
            seed: 1,
            width: 2,
            height: 1,
            settings: String::new(),
        };
        let pass = |k: u64| {
            let v = |c: u64| (hash(&[k, c]) >> 40) as f32 * 1e-3 + 1e-7;
            let img = RgbImage {
                width: 2,
                height: 1,
                pixels: vec![[v(0), v(1), v(2)], [v(3), 1e6 * v(4), v(5) * 1e-6]],
            };
            RenderOutput {
                image: img.clone(),
                components: Component::NAMES.iter().map(|&c| (c, img.clone())).collect(),
                seconds: 0.0,
                photon_seconds: 0.0,
                map_build_seconds: 0.0,
                photons_emitted: 0,
                counters: Default::default(),
                notes: vec![],
                variance: None,
                spp: 1,
            }
        };
        let mut whole = Partial::new(header.clone(), 0);
        (0..9).for_each(|k| whole.add_pass(&pass(k)));
        let mut a = Partial::new(header.clone(), 0);
        let mut b = Partial::new(header.clone(), 4);
        (0..4).for_each(|k| a.add_pass(&pass(k)));
        (4..9).for_each(|k| b.add_pass(&pass(k)));
        b.absorb(&a).unwrap();
        assert_eq!(b, whole);
        // The mean is the f64 mean of the passes to within the fixed-point step.
        let (total, parts) = whole.mean();
        let exact: f64 = (0..9)
            .map(|k| pass(k).image.pixels[1][1] as f64)
            .sum::<f64>()
            / 9.0;
        assert!((parts[0].1.pixels[1][1] as f64 - exact).abs() < 1e-6 * exact.max(1.0));
        assert!((total.pixels[1][1] as f64 - 4.0 * exact).abs() < 4e-6 * exact.max(1.0));
        // Non-finite values are left out and counted.
        let mut bad = pass(0);
        bad.components[0].1.pixels[0][0] = f32::NAN;
        let mut p = Partial::new(header, 0);
        p.add_pass(&bad);
        assert_eq!((p.rejected, p.sums[0][0]), (1, 0));
    }
}
