//! The photon mapper's settings, each declared once: its `Integrator "photonmap"` key, its
//! `photon render` flag, its type, range and doc, in the table at the bottom of this file. The
//! table makes the file parsing ([`read_params`]), the command-line flags
//! ([`PhotonOverrides`], clap), applying them ([`PhotonOverrides::apply`]) and the README's
//! table ([`markdown_table`], checked against the README by a test); the defaults are
//! [`PhotonSettings::default`]'s.
//!
//! ```text
//! Integrator "photonmap" "integer globallookup" [ 100 ]     # photon render --global-lookup 100
//! ```
//! A value outside its range is an error at the parameter (`file:line:col`) or naming the flag,
//! with the same range either way.
use super::photonmap::{parse_kernel, PhotonSettings};
use crate::photon::Kernel;
use crate::scene::{ParamSet, SceneError};

/// The values a setting may take: `lo..=hi`, open at either end when asked.
#[derive(Clone, Copy, Debug)]
pub struct Range {
    pub lo: f64,
    pub hi: f64,
    pub open_lo: bool,
    pub open_hi: bool,
}

impl Range {
    /// `[lo, hi]`.
    pub const fn closed(lo: f64, hi: f64) -> Range {
        Range {
            lo,
            hi,
            open_lo: false,
            open_hi: false,
        }
    }

    /// `(lo, hi]`.
    pub const fn above(lo: f64, hi: f64) -> Range {
        Range {
            lo,
            hi,
            open_lo: true,
            open_hi: false,
        }
    }

    /// `(lo, hi)`.
    pub const fn open(lo: f64, hi: f64) -> Range {
        Range {
            lo,
            hi,
            open_lo: true,
            open_hi: true,
        }
    }

    /// Whether `v` lies in the range (NaN never does).
    pub fn contains(&self, v: f64) -> bool {
        let lo = if self.open_lo {
            v > self.lo
        } else {
            v >= self.lo
        };
        let hi = if self.open_hi {
            v < self.hi
        } else {
            v <= self.hi
        };
        lo && hi
    }

    /// `[0, 10]`, `(0, 4]`, `(0, 1)`, `[0, inf]`.
    pub fn describe(&self) -> String {
        format!(
            "{}{}, {}{}",
            if self.open_lo { "(" } else { "[" },
            self.lo,
            self.hi,
            if self.open_hi { ")" } else { "]" }
        )
    }
}

/// A value type of a setting: how the file and the command line spell it. Numeric types are
/// checked against the setting's range (as numbers, before any conversion), the others have
/// none.
pub trait Value: Copy + std::fmt::Debug + Send + Sync + 'static {
    /// The pbrt-v4 parameter type (`integer`, `float`, `bool`, `string`).
    const PBRT_TYPE: &'static str;
    /// Reads `key` from `params`, `default` when absent, checked against `range`.
    fn read(
        params: &mut ParamSet,
        key: &str,
        default: Self,
        range: Option<Range>,
    ) -> Result<Self, SceneError>;
    /// Parses a command-line value, checked against `range`.
    fn parse(text: &str, range: Option<Range>) -> Result<Self, String>;
    /// True for on/off settings: on the command line `--x` (on), `--no-x` (off) or
    /// `--x=BOOL`, as every on/off flag of photon is spelled.
    const SWITCH: bool = false;
}

/// The command line's number of values of a setting of type `T`: 0 or 1 for switches.
pub fn num_args<T: Value>() -> clap::builder::ValueRange {
    match T::SWITCH {
        true => (0..=1).into(),
        false => 1.into(),
    }
}

/// The value of a switch given without one (`--x`: on).
pub fn missing_value<T: Value>() -> Option<&'static str> {
    T::SWITCH.then_some("true")
}

/// `x` checked against `range` (no range: anything).
fn check(x: f64, range: Option<Range>) -> Result<(), String> {
    match range {
        Some(r) if !r.contains(x) => Err(format!("must be in {}, got {x}", r.describe())),
        _ => Ok(()),
    }
}

/// [`check`] for the file's parameter `key`: the error at the parameter.
fn check_param(
    params: &ParamSet,
    key: &str,
    x: f64,
    range: Option<Range>,
) -> Result<(), SceneError> {
    check(x, range).map_err(|m| SceneError {
        loc: params.loc(key).cloned(),
        msg: format!("\"{key}\" {m}"),
    })
}

macro_rules! integer_value {
    ($($t:ty),*) => {$(
        impl Value for $t {
            const PBRT_TYPE: &'static str = "integer";
            fn read(
                params: &mut ParamSet,
                key: &str,
                default: Self,
                range: Option<Range>,
            ) -> Result<Self, SceneError> {
                let d = (default as i64).min(i32::MAX as i64) as i32;
                let v = params.get_int(key, d)?;
                check_param(params, key, v as f64, range)?;
                Ok(v.max(0) as $t)
            }
            fn parse(text: &str, range: Option<Range>) -> Result<Self, String> {
                let v: i128 = text
                    .trim()
                    .parse()
                    .map_err(|_| format!("expected an integer, got {text:?}"))?;
                check(v as f64, range)?;
                <$t>::try_from(v).map_err(|_| format!("{v} is out of range"))
            }
        }
    )*};
}
integer_value!(u32, u64, usize);

impl Value for f32 {
    const PBRT_TYPE: &'static str = "float";
    fn read(
        params: &mut ParamSet,
        key: &str,
        default: Self,
        range: Option<Range>,
    ) -> Result<Self, SceneError> {
        let v = params.get_float(key, default)?;
        check_param(params, key, v as f64, range)?;
        Ok(v)
    }
    fn parse(text: &str, range: Option<Range>) -> Result<Self, String> {
        let v: f32 = text
            .trim()
            .parse()
            .map_err(|_| format!("expected a number, got {text:?}"))?;
        check(v as f64, range)?;
        Ok(v)
    }
}

impl Value for bool {
    const PBRT_TYPE: &'static str = "bool";
    const SWITCH: bool = true;
    fn read(
        params: &mut ParamSet,
        key: &str,
        default: Self,
        _: Option<Range>,
    ) -> Result<Self, SceneError> {
        params.get_bool(key, default)
    }
    fn parse(text: &str, _: Option<Range>) -> Result<Self, String> {
        match text.trim() {
            "true" => Ok(true),
            "false" => Ok(false),
            _ => Err(format!("expected true or false, got {text:?}")),
        }
    }
}

impl Value for Kernel {
    const PBRT_TYPE: &'static str = "string";
    fn read(
        params: &mut ParamSet,
        key: &str,
        default: Self,
        _: Option<Range>,
    ) -> Result<Self, SceneError> {
        match params.get_string_opt(key)? {
            None => Ok(default),
            Some(k) => Self::parse(&k, None).map_err(|msg| SceneError {
                loc: params.loc(key).cloned(),
                msg,
            }),
        }
    }
    fn parse(text: &str, _: Option<Range>) -> Result<Self, String> {
        parse_kernel(text.trim()).ok_or_else(|| {
            format!(
                "unknown kernel \"{}\" (box, cone, biweight, epanechnikov)",
                crate::scene::clip_for_message(text, 40)
            )
        })
    }
}

/// A clap value parser for a setting of type `T` in `range`.
pub fn parser<T: Value>(range: Option<Range>) -> impl Fn(&str) -> Result<T, String> + Clone {
    move |text| T::parse(text, range)
}

/// One row of [`SETTINGS`]: what the README's table shows.
#[derive(Clone, Copy, Debug)]
pub struct Row {
    pub key: &'static str,
    pub flag: &'static str,
    pub pbrt_type: &'static str,
    pub range: Option<Range>,
    pub doc: &'static str,
}

/// Declares every setting once (see the module docs).
macro_rules! settings {
    ($(
        $(#[doc = $doc:literal])+
        $field:ident: $ty:ty = $($path:ident).+, $key:literal, $flag:literal, $range:expr;
    )*) => {
        /// Command-line overrides of the photon mapper's settings (one flag per setting of
        /// [`SETTINGS`], with the file's range).
        #[derive(clap::Args, Clone, Debug, Default)]
        pub struct PhotonOverrides {
            $(
                $(#[doc = $doc])+
                #[arg(long = $flag, allow_negative_numbers = true,
                      value_parser = parser::<$ty>($range),
                      num_args = num_args::<$ty>(),
                      require_equals = <$ty as Value>::SWITCH,
                      default_missing_value = missing_value::<$ty>())]
                pub $field: Option<$ty>,
            )*
        }

        impl PhotonOverrides {
            /// Applies the flags that were given.
            pub fn apply(&self, s: &mut PhotonSettings) {
                $(
                    if let Some(v) = self.$field {
                        s.$($path).+ = v;
                    }
                )*
                if self.max_photon_bounces.is_some() {
                    s.bounces_given = true;
                }
            }
        }

        /// Reads every setting of [`SETTINGS`] from the file's `Integrator` parameters into
        /// `s` (each marked used), checked against its range.
        pub fn read_params(s: &mut PhotonSettings, params: &mut ParamSet) -> Result<(), SceneError> {
            $(
                s.$($path).+ = <$ty as Value>::read(params, $key, s.$($path).+, $range)?;
            )*
            s.bounces_given = params.peek("maxphotonbounces").is_some();
            Ok(())
        }

        /// Each setting's default ([`PhotonSettings::default`]), in [`SETTINGS`]' order.
        pub fn defaults() -> Vec<String> {
            let s = PhotonSettings::default();
            vec![$(format!("{:?}", s.$($path).+)),*]
        }

        /// Every setting: key, flag, type, range and doc.
        pub const SETTINGS: &[Row] = &[$(
            Row {
                key: $key,
                flag: $flag,
                pbrt_type: <$ty as Value>::PBRT_TYPE,
                range: $range,
                doc: concat!($($doc),+),
            },
        )*];
    };
}

use crate::limits::{MAX_DEPTH, MAX_GATHER_SAMPLES, MAX_LOOKUP, MAX_PHOTONS, MAX_RADIUS};

settings! {
    /// Photons emitted for the global map (0: none).
    global_photons: u64 = trace.global_photons, "globalphotons", "global-photons",
        Some(Range::closed(0.0, MAX_PHOTONS as f64));
    /// Photons emitted for the caustic map (0: none).
    caustic_photons: u64 = trace.caustic_photons, "causticphotons", "caustic-photons",
        Some(Range::closed(0.0, MAX_PHOTONS as f64));
    /// Bounces a photon is traced for (default: the render's maxdepth - 1).
    max_photon_bounces: u32 = trace.max_bounces, "maxphotonbounces", "max-photon-bounces",
        Some(Range::closed(0.0, MAX_DEPTH as f64));
    /// Photons per global-map lookup.
    global_lookup: usize = global_lookup, "globallookup", "global-lookup",
        Some(Range::closed(1.0, MAX_LOOKUP as f64));
    /// Photons per caustic-map lookup.
    caustic_lookup: usize = caustic_lookup, "causticlookup", "caustic-lookup",
        Some(Range::closed(1.0, MAX_LOOKUP as f64));
    /// Largest global lookup radius, as a fraction of the scene's bounding radius.
    global_radius: f32 = global_radius, "globalradius", "global-radius",
        Some(Range::above(0.0, MAX_RADIUS as f64));
    /// Largest caustic lookup radius, as a fraction of the scene's bounding radius.
    caustic_radius: f32 = caustic_radius, "causticradius", "caustic-radius",
        Some(Range::above(0.0, MAX_RADIUS as f64));
    /// Radiance-estimate kernel: box, cone, biweight, epanechnikov.
    kernel: Kernel = kernel, "kernel", "kernel", None;
    /// Final-gather rays per visible diffuse point.
    gather_samples: u32 = gather_samples, "gathersamples", "gather-samples",
        Some(Range::closed(1.0, MAX_GATHER_SAMPLES as f64));
    /// Final gathering on or off (off shows the global map directly).
    final_gather: bool = final_gather, "finalgather", "final-gather", None;
    /// Final-gather directions guided by the nearest photons (Jensen 1995) or cosine only.
    guided_gather: bool = guided_gather, "guidedgather", "guided-gather", None;
    /// Gather hits whose estimate's photons fill less than this share of its disc (a thin
    /// tube's, an edge's) take their light by shadow ray and one more bounce; caustic
    /// estimates at camera points weigh such photons (24 or more) over their own area instead
    /// of the disc's (0: neither).
    thin_fill: f32 = thin_fill, "thinfill", "thin-fill", Some(Range::closed(0.0, 1.0));
    /// Christensen's precomputed irradiance for the gather lookups.
    irradiance_cache: bool = irradiance_cache, "irradiancecache", "irradiance-cache", None;
    /// A global map that stored fewer than this share of its emitted photons (a scene lit
    /// mostly by a sky or the sun, whose photons leave after one bounce) is not read: gather
    /// rays go on as paths (0: always read it).
    sparse_map: f32 = sparse_map, "sparsemap", "sparse-map", Some(Range::closed(0.0, f64::INFINITY));
    /// Caustic projection maps on or off.
    projection_maps: bool = trace.projection_maps, "projectionmaps", "projection-maps", None;
    /// Distant and infinite lights aim most global photons (and the light subpaths of vcm,
    /// bdpt, bpm and lighttracer) at what the camera sees.
    aimed_photons: bool = trace.aimed, "aimedphotons", "aimed-photons", None;
    /// GGX alpha up to which a rough glossy surface receives caustic photons (inf: none).
    glossy_alpha: f32 = trace.receiver_alpha, "glossyalpha", "glossy-alpha",
        Some(Range::closed(0.0, f64::INFINITY));
    /// Photons stored in scattering media for the volume map (scenes with such media only).
    volume_photons: u64 = volume_photons, "volumephotons", "volume-photons",
        Some(Range::closed(0.0, MAX_PHOTONS as f64));
    /// Radius of the volume photons' spheres in beam estimates, as a fraction of the scene's
    /// bounding radius.
    volume_radius: f32 = volume_radius, "volumeradius", "volume-radius",
        Some(Range::above(0.0, MAX_RADIUS as f64));
}

/// The range of the progressive radius schedule's `alpha` (`"float alpha"`, `--alpha`).
pub const ALPHA: Range = Range::open(0.0, 1.0);

/// The README's table of the settings, one row each
/// (`| key | flag | default | range | what |`).
pub fn markdown_table() -> String {
    let mut s = String::from(
        "| `Integrator \"photonmap\"` parameter | `photon render` flag | default | range | what |\n\
         |---|---|---|---|---|\n",
    );
    for (r, d) in SETTINGS.iter().zip(defaults()) {
        s += &format!(
            "| `\"{} {}\"` | `--{}` | {} | {} | {} |\n",
            r.pbrt_type,
            r.key,
            r.flag,
            // It follows the render's depth unless given (PhotonSettings::follow_depth).
            if r.key == "maxphotonbounces" {
                "maxdepth - 1".to_string()
            } else {
                d.to_lowercase()
            },
            r.range.map_or("-".to_string(), |r| r.describe()),
            r.doc.trim()
        );
    }
    s
}
