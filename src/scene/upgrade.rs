//! Translates pbrt-v3 scene text into pbrt-v4 scene text, by the rules of pbrt-v4's
//! `pbrt --upgrade` (its `FormattingParserTarget` in `src/pbrt/parser.cpp`): `photon upgrade`.
//!
//! It reads the pbrt-v3 syntax (every pbrt-v4 directive too, so a v4 file comes back
//! reformatted), with the loader's own tokenizer and parameter-list reader
//! ([`crate::scene::loader::tokenizer`], [`read_params`]) keeping the comments:
//!
//! ```text
//! TransformBegin                                  AttributeBegin
//!   Material "plastic" "color Kd" [.5 .5 .5]   ->     Material "coateddiffuse"
//!     "float roughness" 0.1                               "rgb reflectance" [ 0.5 0.5 0.5 ]
//!   Shape "sphere"                                        "float roughness" [ 0.1 ]
//! TransformEnd                                        Shape "sphere"
//! WorldEnd                                        AttributeEnd
//! ```
//!
//! Rules (those of pbrt-v4 unless said otherwise):
//! - parameter types: `point` → `point3`, `vector` → `vector3`, `color` → `rgb`; booleans
//!   written as strings become bare `true`/`false`;
//! - `TransformBegin`/`TransformEnd` → `AttributeBegin`/`AttributeEnd` (a warning each);
//!   `WorldEnd` is dropped;
//! - materials (`Material`, `MakeNamedMaterial`): `uber`/`plastic` → `coateddiffuse` (or
//!   `diffuse` when `Ks` is 0), `substrate` → `coateddiffuse`, `matte` → `diffuse` (`sigma`
//!   dropped), `metal` → `conductor`, `mirror` → `conductor` with silver's `eta`/`k` and
//!   roughness 0, `glass` → `dielectric`, `translucent` → `diffusetransmission`,
//!   `kdsubsurface` → `subsurface`, `disney` → `diffuse`, `""`/`none` → `interface`, `mix` gets
//!   `"string materials"` (in swapped order) and a float `amount`; `Kd` → `reflectance`
//!   (`transmittance` for `translucent`), `index` → `eta`, `bumpmap` → `displacement`;
//!   `Ks`/`Kr`/`Kt` that v4 has no place for are dropped (a warning unless they held the
//!   value that made them redundant); `fourier` is kept with a warning (v4 has no such material);
//! - `Texture`: `"color"` → `"spectrum"`; imagemap `gamma` → `encoding`, `trilinear` →
//!   `filter`; `scale`'s `tex1`/`tex2` → `tex`/`scale`; a texture defined twice is renamed
//!   (`NAME-renamed-N`) and later references follow;
//! - lights: an RGB `scale`, the `L` of an `infinite` light with a `mapname`, the `I` of a
//!   `projection` light with one, and the second number of a v3 `blackbody` all fold into the
//!   float `scale`; `mapname` → `filename` (for `infinite`, a note that a v3 lat-long map
//!   must be converted to pbrt-v4's equal-area square one, which pbrt-v4 does not say);
//!   `samples`/`nsamples` dropped; `AreaLightSource "area"` → `"diffuse"`;
//! - `Shape`: trianglemesh `uv`/`st` floats → `point2 uv`, `indices` [0 1 2] of a lone triangle
//!   dropped, loopsubdiv `nlevels` → `levels`, `discarddegenerateUVs`/`shadowalpha` dropped,
//!   `Kd` → `reflectance`; shapes v4 lacks (`cone`, `paraboloid`, `hyperboloid`, `heightfield`,
//!   `nurbs`) are kept with a warning;
//! - `Film "image"` → `"rgb"` (`maxsampleluminance` → `maxcomponentvalue`, `scale` → `iso`
//!   ×100); `PixelFilter` `xwidth`/`ywidth` → `xradius`/`yradius`, gaussian `alpha` → `sigma`;
//!   `Sampler` `lowdiscrepancy`/`02sequence` → `paddedsobol`, `maxmindist` → `pmj02bn`, `random`
//!   → `independent`; `Integrator "directlighting"` → `"path"` with `maxdepth` 1,
//!   `rrthreshold` dropped, `lightsamplestrategy "spatial"` → `"bvh"`, SPPM's `numiterations`
//!   and `imagewritefrequency` dropped; `Camera "environment"` → `"spherical"` with
//!   equirectangular mapping; a `heterogeneous` medium → `uniformgrid` (photon reads the
//!   medium's `"string type"`, where pbrt-v4 compares the medium's name);
//! - pbrt-v2 directives pbrt-v4 cannot read (`SurfaceIntegrator`, `VolumeIntegrator`,
//!   `Renderer`, `Volume`) are kept as comments with a warning.
//!
//! Beyond pbrt-v4: an `uber` that becomes `diffuse` loses the `eta` made from its `index`
//! (pbrt-v4 writes it, and then refuses it as unused); `NamedMaterial` follows a renamed named material the way `ObjectInstance`
//! follows a renamed object; a warning is also given for a dropped `sigma` or textured `Ks`,
//! whose loss pbrt-v4 does not mention.
//!
//! Whatever is lost is a warning with its `file:line:column` ([`Upgraded::warnings`]); the ones
//! that change what renders are also written into the output as a `# photon upgrade: ...` line
//! before the directive. What pbrt-v4 refuses to upgrade (a non-constant RGB light `scale`, a
//! non-opaque `uber`, ...) is an error, as there. `Include` and `Import` are written as they
//! are; [`Upgraded::includes`] names the files so a caller can upgrade them too.

use crate::params::{Loc, Param, ParamType, ParamValues, SceneError};
use crate::scene::loader::parser::read_params;
use crate::scene::loader::parser::string_arg;
use crate::scene::loader::tokenizer::{Comment, TokKind, Token, Tokenizer};
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

/// How the notes written into the upgraded text begin.
pub const NOTE: &str = "# photon upgrade:";

/// One upgraded file.
#[derive(Clone, Debug, Default)]
pub struct Upgraded {
    /// The pbrt-v4 text.
    pub text: String,
    /// What was changed with a loss or could not be expressed, each where it was written.
    pub warnings: Vec<SceneError>,
    /// The files named by `Include` and `Import`, as written, with where.
    pub includes: Vec<(String, Loc)>,
}

/// Names that a second definition renames (`NAME-renamed-N`, as pbrt-v4 does).
#[derive(Default)]
struct Names {
    current: HashMap<String, String>,
    renamed: u32,
}

impl Names {
    /// Defines `name`; returns the name to write and whether it had to be renamed.
    fn define(&mut self, name: &str) -> (String, bool) {
        let fresh = match self.current.contains_key(name) {
            true => {
                let n = format!("{name}-renamed-{}", self.renamed);
                self.renamed += 1;
                n
            }
            false => name.to_string(),
        };
        let renamed = fresh != name;
        self.current.insert(name.to_string(), fresh.clone());
        (fresh, renamed)
    }

    /// The name a reference to `name` now means.
    fn get(&self, name: &str) -> String {
        self.current
            .get(name)
            .cloned()
            .unwrap_or_else(|| name.to_string())
    }
}

/// The translator; its state (renamed textures, named materials and objects) carries from one
/// file to the next, so that included files are upgraded as parts of one scene.
#[derive(Default)]
pub struct Upgrader {
    textures: Names,
    materials: Names,
    objects: Names,
}

/// Types that hold a spectrum (what pbrt-v4's `RemoveSpectrum` removes).
const SPECTRA: [ParamType; 3] = [ParamType::Rgb, ParamType::Spectrum, ParamType::Blackbody];

/// A directive's parameter list being rewritten.
struct Params(Vec<Param>);

impl Params {
    fn find(&self, name: &str, types: &[ParamType]) -> Option<&Param> {
        self.0
            .iter()
            .find(|p| p.name == name && types.contains(&p.ty))
    }

    fn has(&self, name: &str, types: &[ParamType]) -> bool {
        self.find(name, types).is_some()
    }

    /// Removes every parameter `name` of one of `types`; returns the first.
    fn remove(&mut self, name: &str, types: &[ParamType]) -> Option<Param> {
        let i = self
            .0
            .iter()
            .position(|p| p.name == name && types.contains(&p.ty))?;
        let first = self.0.remove(i);
        self.0
            .retain(|p| !(p.name == name && types.contains(&p.ty)));
        Some(first)
    }

    fn rename(&mut self, from: &str, to: &str) {
        for p in self.0.iter_mut().filter(|p| p.name == from) {
            p.name = to.to_string();
        }
    }

    /// The value of an `rgb` parameter of exactly three numbers.
    fn one_rgb(&self, name: &str) -> Option<[f32; 3]> {
        match self.find(name, &[ParamType::Rgb])?.floats()? {
            &[r, g, b] => Some([r, g, b]),
            _ => None,
        }
    }

    fn floats(&self, name: &str) -> Option<Vec<f32>> {
        Some(self.find(name, &[ParamType::Float])?.floats()?.to_vec())
    }

    fn one_float(&self, name: &str) -> Option<f32> {
        self.floats(name)?.first().copied()
    }

    fn string(&self, name: &str) -> Option<String> {
        self.find(name, &[ParamType::String])?
            .strings()?
            .first()
            .cloned()
    }

    fn ints(&self, name: &str) -> Option<Vec<i32>> {
        match &self.find(name, &[ParamType::Integer])?.values {
            ParamValues::Ints(v) => Some(v.clone()),
            _ => None,
        }
    }

    fn one_bool(&self, name: &str) -> Option<bool> {
        match &self.find(name, &[ParamType::Bool])?.values {
            ParamValues::Bools(v) if v.len() == 1 => Some(v[0]),
            _ => None,
        }
    }

    /// The declaration and values of `name` as written out (for warnings).
    fn show(&self, name: &str) -> String {
        self.0
            .iter()
            .find(|p| p.name == name)
            .map(|p| param_text(p, 0).replace('\n', " "))
            .unwrap_or_default()
    }
}

/// A new parameter (one the upgrade adds).
fn param(ty: ParamType, name: &str, values: ParamValues, loc: &Loc) -> Param {
    Param::new(ty, ty.name(), name, values, loc.clone())
}

fn float_param(name: &str, v: f32, loc: &Loc) -> Param {
    param(ParamType::Float, name, ParamValues::Floats(vec![v]), loc)
}

fn string_param(name: &str, v: &[&str], loc: &Loc) -> Param {
    let v = v.iter().map(|s| s.to_string()).collect();
    param(ParamType::String, name, ParamValues::Strings(v), loc)
}

/// `s` quoted, with pbrt's escapes for what cannot stand in a string as it is.
fn quote(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            '\r' => out.push_str("\\r"),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// The column a parameter's values wrap before (a break falls only between whole values: the
/// three numbers of a point stay on one line).
const WRAP: usize = 80;

/// `"type name" [ values ]`, wrapped before column [`WRAP`] (continuation lines indented by
/// `indent + 8`).
fn param_text(p: &Param, indent: usize) -> String {
    let vals: Vec<String> = match &p.values {
        ParamValues::Floats(v) => v.iter().map(|x| x.to_string()).collect(),
        ParamValues::Ints(v) => v.iter().map(|x| x.to_string()).collect(),
        ParamValues::Bools(v) => v.iter().map(|x| x.to_string()).collect(),
        ParamValues::Strings(v) => v.iter().map(|s| quote(s)).collect(),
    };
    let group = match &p.values {
        ParamValues::Floats(_) => p.ty.arity().max(1),
        _ => 1,
    };
    let mut s = format!("{} [", quote(&format!("{} {}", p.ty.name(), p.name)));
    let mut col = indent + s.len();
    for (i, v) in vals.iter().enumerate() {
        // The whole value (and the closing bracket after the last) must fit.
        let whole: usize = vals[i..(i + group).min(vals.len())]
            .iter()
            .map(|v| v.len() + 1)
            .sum::<usize>()
            + if i + group >= vals.len() { 2 } else { 0 };
        if i > 0 && i % group == 0 && col + whole > WRAP {
            s.push('\n');
            s.push_str(&" ".repeat(indent + 4));
            col = indent + 4;
        }
        s.push(' ');
        s.push_str(v);
        col += v.len() + 1;
    }
    s.push_str(" ]");
    s
}

/// The upgraded text being written, with its indentation and the source lines (to keep the
/// blank lines between directives).
struct Out<'a> {
    text: String,
    indent: usize,
    lines: Vec<&'a str>,
    /// The source line of the last thing written (0 before the first).
    last_line: u32,
}

impl<'a> Out<'a> {
    fn new(src: &'a str) -> Self {
        Out {
            text: String::new(),
            indent: 0,
            lines: src.lines().collect(),
            last_line: 0,
        }
    }

    /// One blank line if the source had one between the last thing written and `line`.
    fn gap(&mut self, line: u32) {
        if self.last_line == 0 || line <= self.last_line + 1 {
            return;
        }
        let between = (self.last_line as usize)..(line as usize - 1);
        if self
            .lines
            .get(between)
            .unwrap_or(&[])
            .iter()
            .any(|l| l.trim().is_empty())
        {
            self.text.push('\n');
        }
    }

    fn line(&mut self, s: &str) {
        self.text.push_str(&" ".repeat(self.indent));
        self.text.push_str(s);
        self.text.push('\n');
    }

    /// Writes the comments; one on the line the last directive started on stays on its line.
    fn comments(&mut self, comments: &[Comment]) {
        for c in comments {
            if c.line == self.last_line && self.text.ends_with('\n') {
                self.text.pop();
                self.text.push_str("  ");
                self.text.push_str(c.text);
                self.text.push('\n');
                continue;
            }
            self.gap(c.line);
            self.line(c.text);
            self.last_line = c.line;
        }
    }

    /// A directive: its notes, its head line, its parameters one a line.
    fn directive(&mut self, notes: &[String], head: &str, params: &[Param]) {
        for n in notes {
            self.line(&format!("{NOTE} {n}"));
        }
        self.line(head);
        for p in params {
            let text = param_text(p, self.indent + 4);
            self.line(&format!("    {text}"));
        }
    }
}

/// A parsed directive being upgraded: what to write and what was said about it.
struct Work {
    loc: Loc,
    /// Notes written before it (`# photon upgrade: ...`), each also a warning.
    notes: Vec<String>,
    warnings: Vec<SceneError>,
}

impl Work {
    /// A warning on stderr only.
    fn warn(&mut self, loc: &Loc, msg: impl Into<String>) {
        self.warnings.push(SceneError::at(loc, msg));
    }

    /// A warning that is also written into the output before the directive.
    fn note(&mut self, loc: &Loc, msg: impl Into<String>) {
        let msg = msg.into();
        self.notes.push(msg.clone());
        self.warnings.push(SceneError::at(loc, msg));
    }

    fn error(&self, msg: impl Into<String>) -> SceneError {
        SceneError::at(&self.loc, msg)
    }
}

impl Upgrader {
    pub fn new() -> Self {
        Upgrader::default()
    }

    /// Upgrades the text `src` of the file `file` (used for locations only).
    pub fn upgrade_text(&mut self, src: &str, file: Arc<PathBuf>) -> Result<Upgraded, SceneError> {
        let mut tok = Tokenizer::new(src, file).keeping_comments();
        let mut out = Out::new(src);
        let mut done = Upgraded::default();
        while let Some(t) = tok.next()? {
            out.comments(&tok.take_comments());
            if t.kind != TokKind::Word {
                return Err(tok.err(&t, format!("expected a directive, found {}", t.describe())));
            }
            if t.text != "WorldEnd" {
                // (WorldEnd is dropped: no blank line for it.)
                out.gap(t.line);
            }
            let mut work = Work {
                loc: tok.loc(&t),
                notes: Vec::new(),
                warnings: Vec::new(),
            };
            self.directive(&t, &mut tok, &mut out, &mut work, &mut done)?;
            done.warnings.append(&mut work.warnings);
            out.last_line = t.line;
        }
        out.comments(&tok.take_comments());
        done.text = out.text;
        Ok(done)
    }

    /// Reads and writes one directive.
    fn directive(
        &mut self,
        t: &Token,
        tok: &mut Tokenizer,
        out: &mut Out,
        work: &mut Work,
        done: &mut Upgraded,
    ) -> Result<(), SceneError> {
        let loc = work.loc.clone();
        let name = t.text;
        match name {
            "AttributeBegin" | "TransformBegin" => {
                if name == "TransformBegin" {
                    work.warn(&loc, "rewriting \"TransformBegin\" to \"AttributeBegin\"");
                }
                out.line("AttributeBegin");
                out.indent += 4;
            }
            "AttributeEnd" | "TransformEnd" => {
                if name == "TransformEnd" {
                    work.warn(&loc, "rewriting \"TransformEnd\" to \"AttributeEnd\"");
                }
                out.indent = out.indent.saturating_sub(4);
                out.line("AttributeEnd");
            }
            "WorldEnd" => {}
            "WorldBegin" | "ReverseOrientation" | "ObjectEnd" | "Identity" => out.line(name),
            "Translate" | "Scale" | "Rotate" | "LookAt" | "TransformTimes" => {
                let n = match name {
                    "Rotate" => 4,
                    "LookAt" => 9,
                    "TransformTimes" => 2,
                    _ => 3,
                };
                let v = raw_numbers(tok, n)?;
                // LookAt's eye, target and up apart.
                let text = match name {
                    "LookAt" => v
                        .chunks(3)
                        .map(|g| g.join(" "))
                        .collect::<Vec<_>>()
                        .join("  "),
                    _ => v.join(" "),
                };
                out.line(&format!("{name} {text}"));
            }
            "Transform" | "ConcatTransform" => {
                let v = raw_matrix(tok)?;
                out.line(&format!("{name} [ {} ]", v.join(" ")));
            }
            "ActiveTransform" => {
                let a = tok.next_required("All, StartTime or EndTime")?;
                if !matches!(a.text, "All" | "StartTime" | "EndTime") || a.kind != TokKind::Word {
                    return Err(tok.err(
                        &a,
                        format!("expected All, StartTime or EndTime, found {}", a.describe()),
                    ));
                }
                out.line(&format!("ActiveTransform {}", a.text));
            }
            "CoordinateSystem" | "CoordSysTransform" | "ColorSpace" => {
                let (s, _) = string_arg(tok, "a name")?;
                out.line(&format!("{name} {}", quote(&s)));
            }
            "Include" | "Import" => {
                let (s, at) = string_arg(tok, "a file name")?;
                out.line(&format!("{name} {}", quote(&s)));
                done.includes.push((s, at));
            }
            "ObjectBegin" => {
                let (s, at) = string_arg(tok, "an object name")?;
                let (fresh, renamed) = self.objects.define(&s);
                if renamed {
                    work.warn(
                        &at,
                        format!("{s}: renaming multiply-defined object instance"),
                    );
                }
                out.line(&format!("ObjectBegin {}", quote(&fresh)));
            }
            "ObjectInstance" => {
                let (s, _) = string_arg(tok, "an object name")?;
                out.line(&format!("ObjectInstance {}", quote(&self.objects.get(&s))));
            }
            "NamedMaterial" => {
                let (s, _) = string_arg(tok, "a material name")?;
                out.line(&format!("NamedMaterial {}", quote(&self.materials.get(&s))));
            }
            "MediumInterface" => {
                let (a, _) = string_arg(tok, "a medium name")?;
                let mut head = format!("MediumInterface {}", quote(&a));
                if tok.peek()?.is_some_and(|t| t.kind == TokKind::Str) {
                    let (b, _) = string_arg(tok, "a medium name")?;
                    head = format!("{head} {}", quote(&b));
                }
                out.line(&head);
            }
            "Option" => {
                let ps = read_params(tok)?.into_vec();
                let text: Vec<String> = ps.iter().map(|p| param_text(p, 0)).collect();
                out.line(&format!("Option {}", text.join(" ")));
            }
            "Texture" => {
                let (tex, _) = string_arg(tok, "a texture name")?;
                let (ty, _) = string_arg(tok, "a texture type")?;
                let (class, _) = string_arg(tok, "a texture class")?;
                let mut ps = Params(read_params(tok)?.into_vec());
                let (head, extra) = self.texture(&tex, &ty, &class, &mut ps, work)?;
                out.directive(&work.notes, &head, &cat(extra, ps));
            }
            "SurfaceIntegrator" | "VolumeIntegrator" | "Renderer" | "Volume" => {
                let (ty, _) = string_arg(tok, "a type")?;
                let ps = read_params(tok)?.into_vec();
                work.note(
                    &loc,
                    format!("\"{name}\" is pbrt-v2 syntax that pbrt-v4 does not read; kept as a comment"),
                );
                for n in &work.notes {
                    out.line(&format!("{NOTE} {n}"));
                }
                out.line(&format!("# {name} {}", quote(&ty)));
                for p in &ps {
                    let text = param_text(p, out.indent + 6).replace('\n', "\n# ");
                    out.line(&format!("#     {text}"));
                }
            }
            "Shape" | "Material" | "MakeNamedMaterial" | "LightSource" | "AreaLightSource"
            | "Camera" | "Film" | "Sampler" | "PixelFilter" | "Integrator" | "Accelerator"
            | "MakeNamedMedium" | "Attribute" => {
                let (ty, _) = string_arg(tok, "a type")?;
                let mut ps = Params(read_params(tok)?.into_vec());
                let (head, extra) = self.typed(name, &ty, &mut ps, work)?;
                out.directive(&work.notes, &head, &cat(extra, ps));
            }
            _ => {
                return Err(tok.err(t, format!("unknown directive \"{}\"", t.clipped())));
            }
        }
        Ok(())
    }

    /// The directives of the form `Name "type" params...`: the head line and the parameters
    /// added in front of the rest.
    fn typed(
        &mut self,
        name: &str,
        ty: &str,
        ps: &mut Params,
        work: &mut Work,
    ) -> Result<(String, Vec<Param>), SceneError> {
        let loc = work.loc.clone();
        let mut extra = Vec::new();
        let mut ty = ty.to_string();
        match name {
            "Material" => {
                self.rename_textures(ps);
                extra = self.material(&mut ty, ps, work)?;
            }
            "MakeNamedMaterial" => {
                self.rename_textures(ps);
                let (fresh, renamed) = self.materials.define(&ty);
                if renamed {
                    work.warn(
                        &loc,
                        format!("{ty}: renaming multiply-defined named material"),
                    );
                }
                let mut mat = ps.string("type").unwrap_or_default();
                ps.remove("type", &[ParamType::String]);
                let mut more = self.material(&mut mat, ps, work)?;
                extra.push(string_param("type", &[&mat], &loc));
                extra.append(&mut more);
                ty = fresh;
            }
            "LightSource" | "AreaLightSource" => extra = light(name, &mut ty, ps, work)?,
            "Shape" => extra = shape(&ty, ps, work),
            "Film" => {
                if let Some(m) = ps.one_float("maxsampleluminance") {
                    ps.remove("maxsampleluminance", &[ParamType::Float]);
                    extra.push(float_param("maxcomponentvalue", m, &loc));
                }
                if let Some(s) = ps.one_float("scale") {
                    ps.remove("scale", &[ParamType::Float]);
                    extra.push(float_param("iso", 100.0 * s, &loc));
                }
                if ty == "image" {
                    ty = "rgb".to_string();
                }
            }
            "PixelFilter" => {
                for (from, to) in [("xwidth", "xradius"), ("ywidth", "yradius")] {
                    if let Some(&[w]) = ps.floats(from).as_deref() {
                        ps.remove(from, &[ParamType::Float]);
                        extra.push(float_param(to, w, &loc));
                    }
                }
                if ty == "gaussian" {
                    if let Some(&[a]) = ps.floats("alpha").as_deref() {
                        ps.remove("alpha", &[ParamType::Float]);
                        extra.push(float_param("sigma", 1.0 / (2.0 * a).sqrt(), &loc));
                    }
                }
            }
            "Sampler" => {
                let v4 = match ty.as_str() {
                    "lowdiscrepancy" | "02sequence" => "paddedsobol",
                    "maxmindist" => "pmj02bn",
                    "random" => "independent",
                    other => other,
                };
                ty = v4.to_string();
            }
            "Integrator" => extra = integrator(&mut ty, ps, work),
            "Camera" => {
                if ty == "environment" {
                    ty = "spherical".to_string();
                    extra.push(string_param("mapping", &["equirectangular"], &loc));
                }
                if ty == "realistic" {
                    ps.remove("simpleweighting", &[ParamType::Bool]);
                }
            }
            "MakeNamedMedium" if ps.string("type").as_deref() == Some("heterogeneous") => {
                ps.remove("type", &[ParamType::String]);
                extra.push(string_param("type", &["uniformgrid"], &loc));
            }
            _ => {}
        }
        Ok((format!("{name} {}", quote(&ty)), extra))
    }

    /// Points texture references at the textures' current names.
    fn rename_textures(&self, ps: &mut Params) {
        for p in ps.0.iter_mut().filter(|p| p.ty == ParamType::Texture) {
            if let ParamValues::Strings(v) = &mut p.values {
                for s in v.iter_mut() {
                    *s = self.textures.get(s);
                }
            }
        }
    }

    /// `Texture "name" "type" "class" params...`.
    fn texture(
        &mut self,
        tex: &str,
        ty: &str,
        class: &str,
        ps: &mut Params,
        work: &mut Work,
    ) -> Result<(String, Vec<Param>), SceneError> {
        let loc = work.loc.clone();
        // References first: a redefinition may use the texture it replaces.
        self.rename_textures(ps);
        let (fresh, renamed) = self.textures.define(tex);
        if renamed {
            work.warn(&loc, format!("{tex}: renaming multiply-defined texture"));
        }
        if class == "scale" {
            scale_texture(tex, ty, ps)?;
        }
        let mut extra = Vec::new();
        if class == "imagemap" {
            if let Some(tri) = ps.one_bool("trilinear") {
                ps.remove("trilinear", &[ParamType::Bool]);
                let f = if tri { "trilinear" } else { "bilinear" };
                extra.push(string_param("filter", &[f], &loc));
            }
        }
        if class == "imagemap" || class == "ptex" {
            match ps.one_float("gamma") {
                Some(g) if g != 0.0 => {
                    ps.remove("gamma", &[ParamType::Float]);
                    extra.push(string_param("encoding", &[&format!("gamma {g}")], &loc));
                }
                _ => {
                    if let Some(g) = ps.one_bool("gamma") {
                        ps.remove("gamma", &[ParamType::Bool]);
                        let e = if g { "sRGB" } else { "linear" };
                        extra.push(string_param("encoding", &[e], &loc));
                    }
                }
            }
        }
        let ty = if ty == "color" { "spectrum" } else { ty };
        let head = format!("Texture {} {} {}", quote(&fresh), quote(ty), quote(class));
        Ok((head, extra))
    }

    /// Upgrades a material of type `ty` (changed in place); returns the parameters to add.
    fn material(
        &self,
        ty: &mut String,
        ps: &mut Params,
        work: &mut Work,
    ) -> Result<Vec<Param>, SceneError> {
        let loc = work.loc.clone();
        let mut extra = material_index(ty, ps, work)?;
        ps.rename("bumpmap", "displacement");
        match ty.as_str() {
            "uber" => {
                *ty = "coateddiffuse".into();
                if drop_if_constant(ps, "Ks", 0.0, ty, work) {
                    *ty = "diffuse".into();
                    ps.remove("eta", &[ParamType::Float, ParamType::Texture]);
                    ps.remove("roughness", &[ParamType::Float, ParamType::Texture]);
                }
                drop_if_constant(ps, "Kr", 0.0, ty, work);
                drop_if_constant(ps, "Kt", 0.0, ty, work);
                ps.rename("Kd", "reflectance");
                if ps.has("opacity", &[ParamType::Texture]) {
                    return Err(work.error(
                        "a textured \"opacity\" in the \"uber\" material is not supported in \
                         pbrt-v4; edit the file by hand",
                    ));
                }
                if ps.has("opacity", &SPECTRA) {
                    if ps.one_rgb("opacity") != Some([1.0; 3]) {
                        return Err(work.error(
                            "a non-opaque \"opacity\" in the \"uber\" material is not supported \
                             in pbrt-v4; edit the file by hand",
                        ));
                    }
                    ps.remove("opacity", &SPECTRA);
                }
            }
            "mix" => {
                if let Some(rgb) = ps.one_rgb("amount") {
                    let avg = (rgb[0] + rgb[1] + rgb[2]) / 3.0;
                    if rgb[0] != rgb[1] || rgb[1] != rgb[2] {
                        work.note(
                            &loc,
                            format!(
                                "RGB \"amount\" ({} {} {}) changed to its average {avg}",
                                rgb[0], rgb[1], rgb[2]
                            ),
                        );
                    }
                    extra.push(float_param("amount", avg, &loc));
                } else if ps.has("amount", &SPECTRA) {
                    return Err(work.error(format!(
                        "cannot make the non-RGB spectrum \"amount\" a number: {}",
                        ps.show("amount")
                    )));
                }
                ps.remove("amount", &SPECTRA);
                let mut names = Vec::new();
                for key in ["namedmaterial1", "namedmaterial2"] {
                    let Some(m) = ps.string(key).filter(|m| !m.is_empty()) else {
                        return Err(
                            work.error(format!("no \"{key}\" parameter for the \"mix\" material"))
                        );
                    };
                    ps.remove(key, &[ParamType::String]);
                    names.push(self.materials.get(&m));
                }
                // pbrt-v4's "amount" weighs the second material: the order swaps.
                extra.push(string_param("materials", &[&names[1], &names[0]], &loc));
            }
            "substrate" => {
                *ty = "coateddiffuse".into();
                drop_if_constant(ps, "Ks", 1.0, ty, work);
                ps.rename("Kd", "reflectance");
            }
            "glass" => {
                *ty = "dielectric".into();
                drop_if_constant(ps, "Kr", 1.0, ty, work);
                drop_if_constant(ps, "Kt", 1.0, ty, work);
            }
            "plastic" => {
                *ty = "coateddiffuse".into();
                if drop_if_constant(ps, "Ks", 0.0, ty, work) {
                    *ty = "diffuse".into();
                    ps.remove("roughness", &[ParamType::Float, ParamType::Texture]);
                    ps.remove("eta", &[ParamType::Float, ParamType::Texture]);
                }
                ps.rename("Kd", "reflectance");
            }
            "fourier" => work.note(
                &loc,
                "the \"fourier\" material is not supported by pbrt-v4 (but \"measured\" is)",
            ),
            "kdsubsurface" => {
                *ty = "subsurface".into();
                ps.rename("Kd", "reflectance");
            }
            "matte" => {
                *ty = "diffuse".into();
                ps.rename("Kd", "reflectance");
                let rough = ps.has("sigma", &[ParamType::Texture])
                    || ps.one_float("sigma").is_some_and(|s| s != 0.0);
                if rough {
                    work.note(
                        &loc,
                        format!(
                            "\"diffuse\" has no Oren-Nayar roughness: {} dropped",
                            ps.show("sigma")
                        ),
                    );
                }
                ps.remove("sigma", &[ParamType::Float, ParamType::Texture]);
            }
            "metal" => {
                *ty = "conductor".into();
                drop_if_constant(ps, "Kr", 1.0, ty, work);
            }
            "translucent" => {
                *ty = "diffusetransmission".into();
                ps.rename("Kd", "transmittance");
                drop_if_constant(ps, "reflect", 0.0, ty, work);
                drop_if_constant(ps, "transmit", 1.0, ty, work);
                drop_if_constant(ps, "Ks", 0.0, ty, work);
                ps.remove("roughness", &[ParamType::Float, ParamType::Texture]);
            }
            "mirror" => {
                *ty = "conductor".into();
                extra.push(float_param("roughness", 0.0, &loc));
                let sp = |n: &str, v: &str| {
                    param(
                        ParamType::Spectrum,
                        n,
                        ParamValues::Strings(vec![v.to_string()]),
                        &loc,
                    )
                };
                extra.push(sp("eta", "metal-Ag-eta"));
                extra.push(sp("k", "metal-Ag-k"));
                drop_if_constant(ps, "Kr", 0.0, ty, work);
            }
            "disney" => {
                *ty = "diffuse".into();
                ps.rename("color", "reflectance");
            }
            "hair" => ps.rename("color", "reflectance"),
            "" | "none" => *ty = "interface".into(),
            _ => {}
        }
        if ty == "diffuse" {
            // An uber's "index" became an "eta" that diffuse has no use for.
            extra.retain(|p| p.name != "eta");
        }
        Ok(extra)
    }
}

/// A trianglemesh's or bilinear mesh's `indices` when they are 0, 1, ... n-1 over n points.
fn trivial_indices(ps: &Params, n: usize) -> bool {
    let points = ps
        .find("P", &[ParamType::Point3])
        .and_then(|p| p.floats())
        .map_or(0, |v| v.len() / 3);
    ps.ints("indices")
        .is_some_and(|v| points == n && v.iter().copied().eq(0..n as i32))
}

/// `Shape "ty"`: returns the parameters to add.
fn shape(ty: &str, ps: &mut Params, work: &mut Work) -> Vec<Param> {
    let loc = work.loc.clone();
    let mut extra = Vec::new();
    if (ty == "trianglemesh" && trivial_indices(ps, 3))
        || (ty == "bilinearmesh" && trivial_indices(ps, 4))
    {
        ps.remove("indices", &[ParamType::Integer]);
    }
    if ty == "loopsubdiv" {
        if let Some(&[n, ..]) = ps.ints("nlevels").as_deref() {
            ps.remove("nlevels", &[ParamType::Integer]);
            extra.push(param(
                ParamType::Integer,
                "levels",
                ParamValues::Ints(vec![n]),
                &loc,
            ));
        }
    }
    if ty == "trianglemesh" || ty == "plymesh" {
        ps.remove("discarddegenerateUVs", &[ParamType::Bool]);
        if let Some(p) = ps.remove("shadowalpha", &[ParamType::Texture, ParamType::Float]) {
            work.warn(
                &p.loc,
                "\"shadowalpha\" dropped: pbrt-v4 has no such parameter",
            );
        }
    }
    if ty == "trianglemesh" {
        // A point2 "st" wins; else float "uv" or "st" pairs.
        let uv = match ps.remove("st", &[ParamType::Point2]) {
            Some(p) => p.floats().map(|v| v.to_vec()),
            None => ["uv", "st"].iter().fold(None, |got, name| {
                match ps.remove(name, &[ParamType::Float]) {
                    Some(p) => p.floats().map(|v| v[..v.len() / 2 * 2].to_vec()),
                    None => got,
                }
            }),
        };
        if let Some(uv) = uv {
            extra.push(param(
                ParamType::Point2,
                "uv",
                ParamValues::Floats(uv),
                &loc,
            ));
        }
    }
    if matches!(
        ty,
        "cone" | "paraboloid" | "hyperboloid" | "heightfield" | "nurbs"
    ) {
        work.note(
            &loc,
            format!("pbrt-v4 has no \"{ty}\" shape; kept as written"),
        );
    }
    ps.rename("Kd", "reflectance");
    extra
}

/// `LightSource`/`AreaLightSource "ty"`: folds RGB scales into the float `scale`.
fn light(
    name: &str,
    ty: &mut String,
    ps: &mut Params,
    work: &mut Work,
) -> Result<Vec<Param>, SceneError> {
    let loc = work.loc.clone();
    let mut extra = Vec::new();
    let mut total = 1.0f32;
    // An RGB "scale" (or L/I beside a map) must be grey: its value joins the scale.
    let fold = |ps: &mut Params, key: &str, total: &mut f32| -> bool {
        if !ps.has(key, &SPECTRA) {
            return true;
        }
        match ps.one_rgb(key) {
            Some([r, g, b]) if r == g && g == b => {
                *total *= r;
                ps.remove(key, &SPECTRA);
                true
            }
            _ => false,
        }
    };
    if !fold(ps, "scale", &mut total) {
        let at = ps
            .find("scale", &SPECTRA)
            .map_or(loc.clone(), |p| p.loc.clone());
        return Err(SceneError::at(
            &at,
            "in pbrt-v4 \"scale\" is a \"float\" parameter of lights; this RGB scale is not \
             grey: edit the file by hand",
        ));
    }
    if name == "LightSource" {
        ps.remove("samples", &[ParamType::Integer]);
        if ps.string("mapname").is_some_and(|m| !m.is_empty()) {
            for (light, key) in [("infinite", "L"), ("projection", "I")] {
                if ty == light && !fold(ps, key, &mut total) {
                    let at = ps
                        .find(key, &SPECTRA)
                        .map_or(loc.clone(), |p| p.loc.clone());
                    return Err(SceneError::at(
                        &at,
                        format!(
                            "a non-grey \"{key}\" with a \"mapname\" is not supported by the \
                             \"{light}\" light in pbrt-v4: edit the file by hand"
                        ),
                    ));
                }
            }
        }
    } else {
        if ty == "area" {
            *ty = "diffuse".into();
        }
        ps.remove("nsamples", &[ParamType::Integer]);
        ps.remove("samples", &[ParamType::Integer]);
    }
    for key in ["I", "L"] {
        for p in ps.0.iter_mut() {
            if p.name != key || p.ty != ParamType::Blackbody {
                continue;
            }
            if let ParamValues::Floats(v) = &mut p.values {
                match v.len() {
                    1 => {}
                    2 => total *= v.pop().unwrap_or(1.0),
                    _ => {
                        return Err(p.err("expected two values for a pbrt-v3 \"blackbody\""));
                    }
                }
            }
        }
    }
    if let Some(m) = ps.string("mapname").filter(|m| !m.is_empty()) {
        if ty == "infinite" {
            work.note(
                &loc,
                format!(
                    "pbrt-v4 reads \"{m}\" as an equal-area (square) map; a pbrt-v3 \
                     latitude-longitude map needs converting (pbrt-v4's `imgtool makeequiarea`)"
                ),
            );
        }
        ps.remove("mapname", &[ParamType::String]);
        extra.push(string_param("filename", &[&m], &loc));
    }
    if total != 1.0 {
        total *= ps.one_float("scale").unwrap_or(1.0);
        ps.remove("scale", &[ParamType::Float]);
        extra.insert(0, float_param("scale", total, &loc));
    }
    Ok(extra)
}

/// `Integrator "ty"`.
fn integrator(ty: &mut String, ps: &mut Params, work: &mut Work) -> Vec<Param> {
    let loc = work.loc.clone();
    let mut extra = Vec::new();
    ps.remove("rrthreshold", &[ParamType::Float]);
    if ty == "sppm" {
        ps.remove("imagewritefrequency", &[ParamType::Integer]);
        if let Some(p) = ps.remove("numiterations", &[ParamType::Integer]) {
            work.note(
                &p.loc,
                "the SPPM integrator no longer takes \"numiterations\": it is the Sampler's \
                 pixel samples now",
            );
        }
    }
    if ps.string("lightsamplestrategy").as_deref() == Some("spatial") {
        ps.remove("lightsamplestrategy", &[ParamType::String]);
        extra.push(string_param("lightsamplestrategy", &["bvh"], &loc));
    }
    if ty == "directlighting" {
        *ty = "path".into();
        for key in ["maxdepth", "strategy"] {
            if let Some(p) = ps.remove(key, &[ParamType::Integer, ParamType::String]) {
                let shown = param_text(&p, 0).replace('\n', " ");
                work.note(&p.loc, format!("dropped {shown} of \"directlighting\""));
            }
        }
        extra.push(param(
            ParamType::Integer,
            "maxdepth",
            ParamValues::Ints(vec![1]),
            &loc,
        ));
    }
    extra
}

/// `index` → `eta` for `glass` and `uber`.
fn material_index(ty: &str, ps: &mut Params, work: &Work) -> Result<Vec<Param>, SceneError> {
    if ty != "glass" && ty != "uber" {
        return Ok(Vec::new());
    }
    let both = || {
        work.error(format!(
            "material \"{ty}\" has both \"index\" and \"eta\" parameters"
        ))
    };
    if let Some(mut p) = ps.remove("index", &[ParamType::Texture]) {
        if ps.has("eta", &[ParamType::Texture]) {
            return Err(both());
        }
        p.name = "eta".into();
        return Ok(vec![p]);
    }
    let Some(index) = ps.floats("index") else {
        return Ok(Vec::new());
    };
    if index.len() != 1 {
        return Err(work.error("more than one value for the \"index\" parameter"));
    }
    if ps.has("eta", &[ParamType::Float]) {
        return Err(both());
    }
    ps.remove("index", &[ParamType::Float]);
    Ok(vec![float_param("eta", index[0], &work.loc)])
}

/// Removes the spectrum or texture parameter `key`; true when it was the constant `value` (a
/// warning, with a note in the output, when something else was dropped).
fn drop_if_constant(ps: &mut Params, key: &str, value: f32, ty: &str, work: &mut Work) -> bool {
    let matches = ps.one_rgb(key) == Some([value; 3]);
    if !matches && (ps.has(key, &SPECTRA) || ps.has(key, &[ParamType::Texture])) {
        let loc = ps
            .find(key, &SPECTRA)
            .or(ps.find(key, &[ParamType::Texture]));
        let at = loc.map_or(work.loc.clone(), |p| p.loc.clone());
        let shown = ps.show(key);
        work.note(
            &at,
            format!("parameter dropped in the conversion to \"{ty}\": {shown}"),
        );
    }
    ps.remove(key, &SPECTRA);
    ps.remove(key, &[ParamType::Texture]);
    matches
}

/// `"scale"` textures: `tex1`/`tex2` → `tex`/`scale` (of a spectrum texture, the grey RGB one
/// becomes the float `scale`).
fn scale_texture(tex: &str, ty: &str, ps: &mut Params) -> Result<(), SceneError> {
    if ty == "float" {
        ps.rename("tex1", "tex");
        ps.rename("tex2", "scale");
        return Ok(());
    }
    let (mut rgb, mut texture) = (false, false);
    for p in ps.0.iter_mut() {
        if p.name != "tex1" && p.name != "tex2" {
            continue;
        }
        if p.ty == ParamType::Rgb {
            if rgb {
                return Err(p.err(format!(
                    "two \"rgb\" values for the \"scale\" texture \"{tex}\": edit the file by hand"
                )));
            }
            let Some(&[r, g, b]) = p.floats() else {
                return Err(p.err("expected 3 values"));
            };
            if r != g || g != b {
                return Err(p.err(format!(
                    "a non-grey \"rgb\" for the \"scale\" texture \"{tex}\": edit the file by hand"
                )));
            }
            rgb = true;
            p.ty = ParamType::Float;
            p.ty_name = "float".into();
            p.name = "scale".into();
            p.values = ParamValues::Floats(vec![r]);
        } else {
            if texture {
                return Err(p.err(format!(
                    "two textures for the \"scale\" texture \"{tex}\": edit the file by hand"
                )));
            }
            p.name = "tex".into();
            texture = true;
        }
    }
    Ok(())
}

/// `extra` followed by what is left of `ps`.
fn cat(mut extra: Vec<Param>, ps: Params) -> Vec<Param> {
    extra.extend(ps.0);
    extra
}

/// `n` numbers, as written.
fn raw_numbers(tok: &mut Tokenizer, n: usize) -> Result<Vec<String>, SceneError> {
    (0..n).map(|_| raw_number(tok)).collect()
}

fn raw_number(tok: &mut Tokenizer) -> Result<String, SceneError> {
    let t = tok.next_required("a number")?;
    if t.kind != TokKind::Num || !t.text.parse::<f32>().is_ok_and(f32::is_finite) {
        return Err(tok.err(&t, format!("expected a number, found {}", t.describe())));
    }
    Ok(t.text.to_string())
}

/// `[ 16 numbers ]`, as written.
fn raw_matrix(tok: &mut Tokenizer) -> Result<Vec<String>, SceneError> {
    let open = tok.next_required("\"[\"")?;
    if open.kind != TokKind::Open {
        return Err(tok.err(&open, format!("expected \"[\", found {}", open.describe())));
    }
    let v = raw_numbers(tok, 16)?;
    let close = tok.next_required("\"]\"")?;
    if close.kind != TokKind::Close {
        return Err(tok.err(
            &close,
            format!("expected \"]\", found {}", close.describe()),
        ));
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn up(src: &str) -> Upgraded {
        Upgrader::new()
            .upgrade_text(src, Arc::new(PathBuf::from("t.pbrt")))
            .unwrap()
    }

    #[test]
    fn long_arrays_wrap_between_whole_points() {
        let p: Vec<String> = (0..42).map(|i| format!("{i}.5")).collect();
        let src = format!("Shape \"trianglemesh\" \"point P\" [ {} ]", p.join(" "));
        let text = up(&src).text;
        assert!(text.lines().count() > 3, "{text}");
        for line in text.lines().skip(1) {
            let numbers = (line.split_whitespace())
                .filter(|w| w.parse::<f32>().is_ok())
                .count();
            assert_eq!(numbers % 3, 0, "{text}");
        }
        assert!(text.lines().all(|l| l.len() <= WRAP), "{text}");
    }

    #[test]
    fn strings_are_quoted_back() {
        assert_eq!(quote("a\"b\\c"), r#""a\"b\\c""#);
    }

    #[test]
    fn trailing_comment_stays_on_its_line() {
        let text = up("WorldBegin # start\n# next\nAttributeBegin\nAttributeEnd\n").text;
        assert_eq!(
            text,
            "WorldBegin  # start\n# next\nAttributeBegin\nAttributeEnd\n"
        );
    }
}
