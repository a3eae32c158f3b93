//! Reads directives and their parameter lists and keeps pbrt-v4's graphics state (CTM,
//! material, area light, `ReverseOrientation`, named coordinate systems) while building the
//! [`Scene`].
//!
//! ```text
//! LookAt 0 1 6.8  0 1 0  0 1 0          # options block: transforms, Camera, Film, Sampler,
//! Camera "perspective" "float fov" 40   # Integrator, PixelFilter
//! WorldBegin                            # CTM reset to identity
//! AttributeBegin                        # push CTM, material, area light, orientation
//!   Translate 0 1 0
//!   Material "diffuse"
//!   Shape "sphere" "float radius" 0.5
//! AttributeEnd
//! Include "more.pbrt"                   # relative to the main file's directory
//! ```
//!
//! Accepted and ignored, with a note line in [`Scene::notes`]: `Accelerator` (any type and
//! parameters; photon builds its own BVH), the parameters of another renderer's `Integrator`
//! that photon does not implement (`Integrator "sppm" "float radius" 0.01`: see
//! [`FOREIGN_INTEGRATORS`]), the `Option`s that cannot change photon's image. `ColorSpace
//! "srgb"` is photon's own space; other color spaces, curves and hair are errors.
//! `MakeNamedMedium` and `MediumInterface` build absorbing media ([`crate::medium`], which
//! lists what is not supported yet). `Texture`s are parsed and
//! stored ([`super::textures`]); materials ([`crate::material`]) and a shape's `alpha` (see
//! [`super::shapes`]) name them.
//!
//! Object instancing (`ObjectBegin "tree"` ... `ObjectEnd`, `ObjectInstance "tree"`) copies
//! the object's meshes per instance (photon's accelerators hold flat meshes), each moved by the
//! CTM at `ObjectInstance`; area lights inside a definition are ignored with a note, as pbrt-v4
//! ignores them.
//!
//! `ActiveTransform StartTime|EndTime|All` picks which of the two CTMs (shutter open, close)
//! later transforms change, as in pbrt-v4; photon renders the shutter-open one and notes once
//! when something moves (no motion blur). `NamedMaterial` may name a material that a later
//! `MakeNamedMaterial` defines (pbrt-v4 resolves names after parsing).
//!
//! Transforms post-multiply the CTM (`CTM = CTM * M`); `Transform`/`ConcatTransform` read 16
//! numbers column-major as pbrt does (`glam::Mat4::from_cols_array`). The CTM at `Camera` is
//! camera-from-world; its inverse becomes `world_from_camera` and the named system "camera".

use super::lights::{area_light, light_source, AreaSpec};
use super::params::{Param, ParamSet, ParamType, ParamValues};
use super::shapes;
use super::tokenizer::{unescape, TokKind, Token, Tokenizer};
use crate::material::{self, MaterialContext};
use crate::math::{Mat4, Vec2, Vec3};
use crate::scene::{
    CameraDesc, FilmDesc, FilterDesc, IntegratorDesc, Loc, Material, MaterialKind, Mesh,
    Projection, SamplerDesc, Scene, SceneError,
};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// How deep `Include`/`Import` may nest (a cycle stops here).
const MAX_INCLUDE_DEPTH: u32 = 32;

/// The material a shape gets: the default (diffuse 0.5, added to the scene on first use) or
/// an index into `Scene::materials`.
#[derive(Clone, Copy, Debug, PartialEq)]
enum MatRef {
    Default,
    Index(u32),
}

/// Which of the two CTMs the transform directives change (`ActiveTransform`).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Active {
    start: bool,
    end: bool,
}

/// Both: pbrt-v4's default and the state after `WorldBegin`.
const ACTIVE_ALL: Active = Active {
    start: true,
    end: true,
};

/// What `AttributeBegin` saves.
#[derive(Clone, Debug)]
struct GraphicsState {
    /// The CTM at shutter open: the one photon renders with.
    ctm: Mat4,
    /// The CTM at shutter close (differs from `ctm` only after `ActiveTransform`).
    ctm_end: Mat4,
    active: Active,
    material: MatRef,
    area: Option<AreaSpec>,
    reverse: bool,
    /// The current `MediumInterface`: inside and outside medium names ("" = vacuum) and
    /// where it was written.
    media: (String, String, Option<Loc>),
}

/// A pushed block: what it saved and where it began.
enum Saved {
    Attribute(GraphicsState),
    /// The two CTMs and the active ones.
    Transform(Mat4, Mat4, Active),
}

/// The scene under construction.
pub struct Builder {
    main_path: PathBuf,
    base_dir: PathBuf,
    gs: GraphicsState,
    stack: Vec<(Saved, Loc)>,
    /// Named coordinate systems: the CTMs at shutter open and close.
    named_coords: HashMap<String, (Mat4, Mat4)>,
    named_materials: HashMap<String, u32>,
    /// `NamedMaterial`s used before their `MakeNamedMaterial`: the index kept for the material
    /// (a placeholder until it is defined) and the first use.
    pending_materials: HashMap<String, (u32, Loc)>,
    /// Whether the note that the scene moves (no motion blur) was given.
    motion_noted: bool,
    default_material: Option<u32>,
    world_begun: bool,
    meshes: Vec<Mesh>,
    /// Where each mesh's `Shape` was written.
    mesh_locs: Vec<Loc>,
    /// Spheres waiting for their tessellation (mesh index, sphere).
    spheres: Vec<(usize, shapes::SphereSpec)>,
    materials: Vec<Material>,
    lights: Vec<crate::scene::Light>,
    camera: CameraDesc,
    film: FilmDesc,
    filter: FilterDesc,
    sampler: SamplerDesc,
    integrator: IntegratorDesc,
    /// Record errors and read on ([`super::load_collecting`]) instead of stopping.
    collect: bool,
    errors: Vec<SceneError>,
    notes: Vec<String>,
    /// How many `Texture` directives were read.
    texture_count: usize,
    textures: crate::texture::Textures,
    images: super::textures::ImageCache,
    /// Lookup work (textures evaluated, depth) of each named texture, by its `Arc`'s address.
    texture_work: std::collections::HashMap<usize, (u64, u32)>,
    /// What the data files (images, PLY meshes, instanced copies) may allocate.
    budget: super::LoadBudget,
    /// `MakeNamedMedium` media, and their indices by name.
    media: Vec<crate::medium::Medium>,
    named_media: HashMap<String, u32>,
    /// The camera's medium (the outside medium at `Camera`), when not vacuum.
    camera_medium: Option<(String, Loc)>,
    camera_medium_index: Option<u32>,
    /// Per light (as `lights`), the media around it.
    light_media: Vec<crate::medium::MediumInterface>,
    /// The first reason the scene's media need tracking (see `Scene::media_need_tracking`).
    needs_tracking: Option<String>,
    /// `ObjectBegin` definitions: world-space meshes as defined (CTM at definition).
    objects: HashMap<String, Vec<Mesh>>,
    /// The definition being read: its name, meshes and where it began.
    object: Option<(String, Vec<Mesh>, Loc)>,
}

impl Builder {
    /// A builder for the scene whose main file is `main_path` (pbrt-v4 defaults everywhere).
    pub fn new(main_path: &Path) -> Self {
        let base_dir = main_path
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default();
        Builder {
            main_path: main_path.to_path_buf(),
            base_dir,
            gs: GraphicsState {
                ctm: Mat4::IDENTITY,
                ctm_end: Mat4::IDENTITY,
                active: ACTIVE_ALL,
                material: MatRef::Default,
                area: None,
                reverse: false,
                media: Default::default(),
            },
            stack: Vec::new(),
            named_coords: HashMap::new(),
            named_materials: HashMap::new(),
            pending_materials: HashMap::new(),
            motion_noted: false,
            default_material: None,
            world_begun: false,
            meshes: Vec::new(),
            mesh_locs: Vec::new(),
            spheres: Vec::new(),
            materials: Vec::new(),
            lights: Vec::new(),
            camera: CameraDesc::pinhole(Mat4::IDENTITY, 90.0),
            film: FilmDesc::new(1280, 720),
            filter: FilterDesc::Gaussian {
                radius: Vec2::splat(1.5),
                sigma: 0.5,
            },
            sampler: SamplerDesc {
                name: "zsobol".to_string(),
                pixel_samples: 16,
            },
            integrator: IntegratorDesc {
                name: "default".to_string(),
                params: ParamSet::new(),
                loc: None,
            },
            collect: false,
            errors: Vec::new(),
            notes: Vec::new(),
            texture_count: 0,
            textures: Default::default(),
            images: Default::default(),
            texture_work: Default::default(),
            budget: super::LoadBudget::new(crate::limits::default_budget().bytes),
            media: Vec::new(),
            named_media: HashMap::new(),
            camera_medium: None,
            camera_medium_index: None,
            light_media: Vec::new(),
            needs_tracking: None,
            objects: HashMap::new(),
            object: None,
        }
    }

    /// Holds the data files' allocations to `bytes` ([`super::LoadBudget`]).
    pub fn budget(mut self, bytes: u64) -> Self {
        self.budget = super::LoadBudget::new(bytes);
        self
    }

    /// Records every error and reads on (see [`super::load_collecting`]).
    pub fn collecting(mut self) -> Self {
        self.collect = true;
        self
    }

    /// Reads the main file and everything it includes, and returns the scene.
    pub fn run(mut self) -> Result<Scene, SceneError> {
        let main = self.main_path.clone();
        let end = self.parse_file(&main, 0, None)?;
        self.check_named_materials()?;
        self.check_end(&end)?;
        Ok(self.into_scene())
    }

    /// Reads everything, recording each error (the builder must be [`Self::collecting`]).
    pub fn run_collecting(mut self) -> super::Collected {
        let main = self.main_path.clone();
        let end = self.parse_file(&main, 0, None);
        let _ = self.check_named_materials(); // collect mode: records, never fails
        if let Err(e) = end.and_then(|end| self.check_end(&end)) {
            self.errors.push(e);
        }
        super::Collected {
            errors: std::mem::take(&mut self.errors),
            textures: self.texture_count,
            scene: self.into_scene(),
        }
    }

    /// The checks at the end of the main file: every block closed, a world block read.
    fn check_end(&mut self, end: &Loc) -> Result<(), SceneError> {
        if let Some((_, _, loc)) = &self.object {
            return Err(SceneError::at(
                loc,
                "ObjectBegin without a matching ObjectEnd",
            ));
        }
        if let Some((saved, loc)) = self.stack.last() {
            let what = match saved {
                Saved::Attribute(_) => "AttributeBegin without a matching AttributeEnd",
                Saved::Transform(..) => "TransformBegin without a matching TransformEnd",
            };
            return Err(SceneError::at(loc, what));
        }
        if !self.world_begun {
            return Err(SceneError::at(end, "the scene has no WorldBegin"));
        }
        if let Some((name, loc)) = self.camera_medium.clone() {
            let Some(&i) = self.named_media.get(&name) else {
                return Err(SceneError::at(
                    &loc,
                    format!("undefined medium \"{name}\" (MediumInterface before Camera)"),
                ));
            };
            self.camera_medium_index = Some(i);
            self.track(&loc, &format!("the camera is inside medium \"{name}\""));
        }
        self.tessellate_spheres();
        self.note_media();
        super::extent::check(&self.meshes, &self.mesh_locs)
    }

    /// In collect mode records `e` and returns `Ok`; otherwise returns `Err(e)`.
    fn recover(&mut self, e: SceneError) -> Result<(), SceneError> {
        if !self.collect {
            return Err(e);
        }
        self.errors.push(e);
        Ok(())
    }

    /// The scene read so far.
    fn into_scene(self) -> Scene {
        Scene {
            meshes: self.meshes,
            materials: self.materials,
            lights: self.lights,
            media: self.media,
            light_media: self.light_media,
            camera_medium: self.camera_medium_index,
            media_need_tracking: self.needs_tracking,
            camera: self.camera,
            film: self.film,
            filter: self.filter,
            sampler: self.sampler,
            integrator: self.integrator,
            path: self.main_path,
            notes: self.notes,
            textures: self.textures,
            load_peak: self.budget.peak(),
        }
    }

    /// Parses one file; `from` is the `Include` that named it. Returns the end-of-file loc.
    fn parse_file(
        &mut self,
        path: &Path,
        depth: u32,
        from: Option<&Loc>,
    ) -> Result<Loc, SceneError> {
        let fail = |msg: String| match from {
            Some(loc) => SceneError::at(loc, msg),
            None => SceneError::new(msg),
        };
        let bytes = super::read_input(path, crate::limits::MAX_SCENE_FILE)
            .map_err(|e| fail(format!("cannot read \"{}\": {e}", path.display())))?;
        let file = Arc::new(path.to_path_buf());
        let text = String::from_utf8(bytes).map_err(|e| not_utf8(&file, e))?;
        let mut tok = Tokenizer::new(&text, file);
        let mut first = true;
        loop {
            let t = match tok.next() {
                Ok(Some(t)) => t,
                Ok(None) => break,
                Err(e) => {
                    // The rest of the file cannot be tokenized.
                    self.recover(e)?;
                    break;
                }
            };
            if first && !(t.kind == TokKind::Word && is_directive(t.text)) {
                // Do not quote a file that is not a scene (an Include of /etc/passwd).
                return Err(tok.err(
                    &t,
                    "not a pbrt-v4 scene file: it does not start with a directive",
                ));
            }
            first = false;
            let done = if t.kind == TokKind::Word {
                self.directive(&t, &mut tok, depth)
            } else {
                Err(tok.err(&t, format!("expected a directive, found {}", t.describe())))
            };
            if let Err(e) = done {
                self.recover(e)?;
                if let Err(e) = skip_arguments(&mut tok) {
                    // The rest of the file cannot be tokenized (often the error just recorded).
                    if self.errors.last() != Some(&e) {
                        self.recover(e)?;
                    }
                    break;
                }
            }
        }
        Ok(tok.end_loc())
    }

    /// Tessellates every sphere by its size in the scene and on screen
    /// ([`shapes::sphere_rings`]).
    fn tessellate_spheres(&mut self) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for p in self.meshes.iter().flat_map(|m| m.positions.iter()) {
            (lo, hi) = (lo.min(*p), hi.max(*p));
        }
        for (_, s) in &self.spheres {
            (lo, hi) = (lo.min(s.centre - s.radius), hi.max(s.centre + s.radius));
        }
        let scene_radius = 0.5 * (hi - lo).as_dvec3().length() as f32;
        for (i, spec) in std::mem::take(&mut self.spheres) {
            // An emitter's power goes with its area: always the full tessellation.
            let rings = match self.meshes[i].area_light {
                Some(_) => shapes::SPHERE_RINGS,
                None => shapes::sphere_rings(&spec, scene_radius, &self.camera, &self.film),
            };
            shapes::tessellate(&spec, rings, &mut self.meshes[i]);
        }
    }

    /// Carries out the directive `t`, reading its arguments from `tok`.
    fn directive(&mut self, t: &Token, tok: &mut Tokenizer, depth: u32) -> Result<(), SceneError> {
        let loc = tok.loc(t);
        match t.text {
            "Identity" => self.transform(|_| Mat4::IDENTITY),
            "Translate" => {
                let v = numbers(tok, 3)?;
                let m = Mat4::from_translation(Vec3::new(v[0], v[1], v[2]));
                self.transform(|c| c * m);
            }
            "Scale" => {
                let v = numbers(tok, 3)?;
                let m = Mat4::from_scale(Vec3::new(v[0], v[1], v[2]));
                self.transform(|c| c * m);
            }
            "Rotate" => {
                let v = numbers(tok, 4)?;
                let m = rotate(v[0], Vec3::new(v[1], v[2], v[3]), &loc)?;
                self.transform(|c| c * m);
            }
            "LookAt" => {
                let v = numbers(tok, 9)?;
                let m = look_at(&v, &loc)?;
                self.transform(|c| c * m);
            }
            "Transform" => {
                let m = Mat4::from_cols_array(&bracketed16(tok)?);
                self.transform(|_| m);
            }
            "ConcatTransform" => {
                let m = Mat4::from_cols_array(&bracketed16(tok)?);
                self.transform(|c| c * m);
            }
            "ActiveTransform" => self.gs.active = active_transform(tok, &loc)?,
            "CoordinateSystem" => {
                let (name, _) = string_arg(tok, "a coordinate system name")?;
                self.named_coords
                    .insert(name, (self.gs.ctm, self.gs.ctm_end));
            }
            "CoordSysTransform" => {
                let (name, at) = string_arg(tok, "a coordinate system name")?;
                match self.named_coords.get(&name) {
                    Some(&(m, e)) => (self.gs.ctm, self.gs.ctm_end) = (m, e),
                    None => {
                        return Err(SceneError::at(
                            &at,
                            format!("unknown coordinate system \"{name}\""),
                        ))
                    }
                }
            }
            "TransformBegin" => {
                let saved = Saved::Transform(self.gs.ctm, self.gs.ctm_end, self.gs.active);
                self.stack.push((saved, loc));
            }
            "TransformEnd" => {
                let want = Saved::Transform(Mat4::IDENTITY, Mat4::IDENTITY, ACTIVE_ALL);
                self.pop(want, t.text, &loc)?
            }
            "AttributeBegin" => {
                self.world_only(t.text, &loc)?;
                self.stack.push((Saved::Attribute(self.gs.clone()), loc));
            }
            "AttributeEnd" => {
                self.world_only(t.text, &loc)?;
                self.pop(Saved::Attribute(self.gs.clone()), t.text, &loc)?;
            }
            "ObjectBegin" => {
                self.world_only(t.text, &loc)?;
                let (name, _) = string_arg(tok, "an object name")?;
                if let Some((open, _, at)) = &self.object {
                    return Err(SceneError::at(
                        &loc,
                        format!(
                            "ObjectBegin inside the definition of \"{open}\" (line {})",
                            at.line
                        ),
                    ));
                }
                self.stack
                    .push((Saved::Attribute(self.gs.clone()), loc.clone()));
                self.object = Some((name, Vec::new(), loc));
            }
            "ObjectEnd" => {
                self.world_only(t.text, &loc)?;
                let Some((name, meshes, _)) = self.object.take() else {
                    return Err(SceneError::at(&loc, "ObjectEnd without ObjectBegin"));
                };
                self.pop(Saved::Attribute(self.gs.clone()), t.text, &loc)?;
                if self.objects.insert(name.clone(), meshes).is_some() {
                    return Err(SceneError::at(&loc, format!("object \"{name}\" redefined")));
                }
            }
            "ObjectInstance" => {
                self.world_only(t.text, &loc)?;
                let (name, at) = string_arg(tok, "an object name")?;
                self.instance(&name, &at)?;
            }
            "ReverseOrientation" => {
                self.world_only(t.text, &loc)?;
                self.gs.reverse = !self.gs.reverse;
            }
            "WorldBegin" => {
                if self.world_begun {
                    return Err(SceneError::at(&loc, "WorldBegin given twice"));
                }
                self.world_begun = true;
                (self.gs.ctm, self.gs.ctm_end) = (Mat4::IDENTITY, Mat4::IDENTITY);
                self.gs.active = ACTIVE_ALL;
                self.named_coords
                    .insert("world".to_string(), (Mat4::IDENTITY, Mat4::IDENTITY));
            }
            "Camera" | "Film" | "Sampler" | "Integrator" | "PixelFilter" | "Accelerator" => {
                self.option(t.text, tok, &loc)?
            }
            "ColorSpace" => {
                let (name, at) = string_arg(tok, "a color space name")?;
                if name != "srgb" {
                    return Err(SceneError::at(
                        &at,
                        format!(
                            "unsupported color space \"{name}\" (photon renders in linear sRGB)"
                        ),
                    ));
                }
            }
            "Option" => self.pbrt_option(tok)?,
            "MakeNamedMedium" => {
                let (name, at) = string_arg(tok, "a medium name")?;
                let mut params = read_params(tok)?;
                if name.is_empty() {
                    return Err(SceneError::at(&at, "a medium needs a non-empty name"));
                }
                if self.named_media.contains_key(&name) {
                    return Err(SceneError::at(
                        &at,
                        format!("medium \"{name}\" is defined twice"),
                    ));
                }
                let medium_from_world = self.gs.ctm.inverse();
                // A homogeneous or uniformgrid medium's one `Le` reads as a light's `L`
                // (rgb or blackbody); an rgbgrid's `Le` is a grid the medium reads itself.
                let ty = params
                    .peek("type")
                    .and_then(|p| p.strings())
                    .and_then(|v| v.first().cloned());
                let le = match ty.as_deref() {
                    Some("homogeneous" | "uniformgrid") => {
                        super::lights::emission_rgb(&mut params, "Le")?
                    }
                    _ => None,
                };
                let medium =
                    crate::medium::Medium::create(&name, &mut params, &loc, medium_from_world, le)?;
                if medium.scatters() {
                    self.track(&loc, &format!("medium \"{name}\" scatters"));
                }
                if !medium.is_homogeneous() {
                    self.track(&loc, &format!("medium \"{name}\" is heterogeneous"));
                }
                if medium.emits() {
                    self.track(&loc, &format!("medium \"{name}\" emits"));
                }
                self.named_media.insert(name, self.media.len() as u32);
                self.media.push(medium);
            }
            "MediumInterface" => {
                let (inside, outside) = medium_interface(tok, &loc)?;
                self.gs.media = (inside, outside, Some(loc.clone()));
            }
            "Texture" => {
                self.world_only(t.text, &loc)?;
                self.texture_count += 1;
                self.texture(tok)?;
            }
            "Material" | "MakeNamedMaterial" | "NamedMaterial" => {
                self.world_only(t.text, &loc)?;
                self.material(t.text, tok)?;
            }
            "Shape" => {
                self.world_only(t.text, &loc)?;
                self.shape(tok)?;
            }
            "AreaLightSource" => {
                self.world_only(t.text, &loc)?;
                let (ty, at) = string_arg(tok, "an area light type")?;
                let mut params = read_params(tok)?;
                self.gs.area = Some(area_light(&ty, &mut params, &at)?);
            }
            "LightSource" => {
                self.world_only(t.text, &loc)?;
                let (ty, at) = string_arg(tok, "a light type")?;
                let mut params = read_params(tok)?;
                let portal = params.loc("portal").cloned();
                if !self.gs.media.1.is_empty() {
                    let why = format!("a light is inside medium \"{}\"", self.gs.media.1);
                    self.track(&at, &why);
                }
                let light = light_source(
                    &ty,
                    &mut params,
                    &at,
                    &self.gs.ctm,
                    (&self.base_dir, &self.budget),
                )?;
                if let Some(p) = portal {
                    self.notes.push(format!(
                        "{p}: portal: light enters only through it, as in pbrt-v4, but photon \
                         samples the whole environment (rays and photons outside the portal \
                         are wasted: expect more noise than pbrt-v4)"
                    ));
                }
                self.note_motion(&at);
                let medium = self.light_medium(&at)?;
                self.lights.push(light);
                self.light_media.push(medium);
            }
            "Include" | "Import" => {
                let (name, _) = string_arg(tok, "a file name")?;
                if depth >= MAX_INCLUDE_DEPTH {
                    return Err(SceneError::at(
                        &loc,
                        format!(
                            "{} nested more than {MAX_INCLUDE_DEPTH} deep (a cycle?)",
                            t.text
                        ),
                    ));
                }
                let path = self.base_dir.join(&name);
                self.parse_file(&path, depth + 1, Some(&loc))?;
            }
            other => return Err(SceneError::at(&loc, unsupported(other))),
        }
        Ok(())
    }

    /// Applies `f` to the active CTMs (pbrt-v4's `ForActiveTransforms`).
    fn transform(&mut self, f: impl Fn(Mat4) -> Mat4) {
        if self.gs.active.start {
            self.gs.ctm = f(self.gs.ctm);
        }
        if self.gs.active.end {
            self.gs.ctm_end = f(self.gs.ctm_end);
        }
    }

    /// The note, once per scene, that something placed at `at` moves during the shutter
    /// interval: photon has no motion blur and renders the shutter-open pose.
    fn note_motion(&mut self, at: &Loc) {
        if self.motion_noted || self.gs.ctm == self.gs.ctm_end {
            return;
        }
        self.motion_noted = true;
        self.notes.push(format!(
            "{at}: the transform at shutter close differs from the one at shutter open \
             (ActiveTransform): photon has no motion blur and renders the shutter-open pose \
             (noted once, here at the first moving object)"
        ));
    }

    /// Errors unless inside the world block.
    fn world_only(&self, what: &str, loc: &Loc) -> Result<(), SceneError> {
        if self.world_begun {
            Ok(())
        } else {
            Err(SceneError::at(
                loc,
                format!("{what} is only allowed after WorldBegin"),
            ))
        }
    }

    /// Pops the innermost block, which must be of the same kind as `want`.
    fn pop(&mut self, want: Saved, what: &str, loc: &Loc) -> Result<(), SceneError> {
        let begin = what.replace("End", "Begin");
        match (self.stack.pop(), want) {
            (Some((Saved::Attribute(gs), _)), Saved::Attribute(_)) => self.gs = gs,
            (Some((Saved::Transform(m, e, a), _)), Saved::Transform(..)) => {
                (self.gs.ctm, self.gs.ctm_end, self.gs.active) = (m, e, a)
            }
            (Some((_, open)), _) => {
                return Err(SceneError::at(
                    loc,
                    format!(
                        "{what} does not match the block opened at line {}",
                        open.line
                    ),
                ))
            }
            (None, _) => return Err(SceneError::at(loc, format!("{what} without {begin}"))),
        }
        Ok(())
    }

    /// `Camera`, `Film`, `Sampler`, `Integrator`, `PixelFilter` (before `WorldBegin`).
    fn option(&mut self, what: &str, tok: &mut Tokenizer, loc: &Loc) -> Result<(), SceneError> {
        if self.world_begun {
            return Err(SceneError::at(
                loc,
                format!("{what} is not allowed after WorldBegin"),
            ));
        }
        let (ty, at) = string_arg(tok, "a type name")?;
        let mut params = read_params(tok)?;
        match what {
            "Camera" => {
                // Defined before the camera is checked (as pbrt-v4 does), so that a rejected
                // Camera does not make every later `CoordSysTransform "camera"` an error too.
                // Equal CTMs give the same matrix, not a second inverse that may differ in the
                // last bits (which would look like a moving camera).
                let start = inverse(&self.gs.ctm);
                let end = if self.gs.ctm_end == self.gs.ctm {
                    start
                } else {
                    inverse(&self.gs.ctm_end)
                };
                if start.is_finite() && end.is_finite() {
                    self.named_coords.insert("camera".to_string(), (start, end));
                }
                self.note_motion(&at);
                self.camera = camera(&ty, &mut params, &at, start)?;
                // pbrt-v4: the camera is in the outside medium current at `Camera`.
                if !self.gs.media.1.is_empty() {
                    self.camera_medium = Some((self.gs.media.1.clone(), at.clone()));
                }
            }
            "Film" => {
                self.film = film(&ty, &mut params, &at)?;
            }
            "Sampler" => self.sampler = sampler(&ty, &mut params, &at)?,
            "PixelFilter" => self.filter = filter(&ty, &mut params, &at)?,
            "Accelerator" => {
                let given = mark_all_used(&mut params);
                self.notes.push(format!(
                    "{loc}: Accelerator \"{ty}\"{given} ignored: photon builds its own BVH \
                     (--backend embree|obvhs)"
                ));
            }
            _ => {
                // Integrator: kept as written for the integrator to read, less the parameters
                // of another renderer's integrator that photon does not implement.
                if let Some(note) = ignore_foreign_params(&ty, &mut params) {
                    self.notes.push(format!("{loc}: {note}"));
                }
                self.integrator = IntegratorDesc {
                    name: ty,
                    params,
                    loc: Some(loc.clone()),
                };
                return Ok(());
            }
        }
        params.check_unused()
    }

    /// `Material`, `MakeNamedMaterial`, `NamedMaterial`.
    fn material(&mut self, what: &str, tok: &mut Tokenizer) -> Result<(), SceneError> {
        let (name, at) = string_arg(tok, "a material name")?;
        match what {
            "Material" => {
                let mut params = read_params(tok)?;
                let m = material::create(&name, &mut params, &at, &self.material_context());
                let m = self.or_default(m)?;
                self.materials.push(m);
                self.gs.material = MatRef::Index(self.materials.len() as u32 - 1);
            }
            "MakeNamedMaterial" => {
                let mut params = read_params(tok)?;
                if self.named_materials.contains_key(&name) {
                    return Err(SceneError::at(
                        &at,
                        format!("named material \"{name}\" redefined"),
                    ));
                }
                let m = named_material(&mut params, &at, &self.material_context());
                let m = self.or_default(m)?;
                let i = match self.pending_materials.remove(&name) {
                    Some((i, _)) => {
                        self.materials[i as usize] = m;
                        i
                    }
                    None => {
                        self.materials.push(m);
                        self.materials.len() as u32 - 1
                    }
                };
                self.named_materials.insert(name, i);
            }
            _ => {
                let i = match self.named_materials.get(&name) {
                    Some(&i) => i,
                    None => self.forward_material(name, at),
                };
                self.gs.material = MatRef::Index(i);
            }
        }
        Ok(())
    }

    /// The index of a named material used before its `MakeNamedMaterial` (pbrt-v4 resolves
    /// names after reading the whole scene): a placeholder that the definition replaces.
    fn forward_material(&mut self, name: String, at: Loc) -> u32 {
        if let Some((i, _)) = self.pending_materials.get(&name) {
            return *i;
        }
        self.materials.push(Material::from(MaterialKind::Diffuse(
            crate::material::DiffuseMaterial {
                reflectance: Vec3::splat(0.5).into(),
            },
        )));
        let i = self.materials.len() as u32 - 1;
        self.pending_materials.insert(name, (i, at));
        i
    }

    /// After the last file: a named material used but never defined is an error at its first
    /// use (each one in collect mode, in file order).
    fn check_named_materials(&mut self) -> Result<(), SceneError> {
        let mut missing: Vec<(String, Loc)> = self
            .pending_materials
            .drain()
            .map(|(name, (_, at))| (name, at))
            .collect();
        missing.sort_by(|a, b| (&a.1.file, a.1.line, a.1.col).cmp(&(&b.1.file, b.1.line, b.1.col)));
        for (name, at) in missing {
            let e = SceneError::at(
                &at,
                format!("unknown named material \"{name}\" (no MakeNamedMaterial defines it)"),
            );
            self.recover(e)?;
        }
        Ok(())
    }

    /// `Texture "name" "spectrum"|"float" CLASS params`: builds and names the texture.
    fn texture(&mut self, tok: &mut Tokenizer) -> Result<(), SceneError> {
        let (name, name_at) = string_arg(tok, "a texture name")?;
        let (kind, _) = string_arg(tok, "a texture type")?;
        let (class, class_at) = string_arg(tok, "a texture class")?;
        let mut params = read_params(tok)?;
        let mut cx = super::textures::TextureContext {
            textures: &self.textures,
            images: &mut self.images,
            base_dir: &self.base_dir,
            budget: &self.budget,
            notes: &mut self.notes,
        };
        let tex = super::textures::make_texture(&kind, &class, &mut params, &class_at, &mut cx)?;
        params.check_unused()?;
        let map = if kind == "float" {
            &mut self.textures.float
        } else {
            &mut self.textures.spectrum
        };
        if map.contains_key(&name) {
            return Err(SceneError::at(
                &name_at,
                format!("{kind} texture \"{name}\" redefined"),
            ));
        }
        use super::textures::{lookup_work, MAX_TEXTURE_DEPTH, MAX_TEXTURE_LOOKUPS};
        let (work, depth) = lookup_work(&tex, &self.texture_work);
        if depth > MAX_TEXTURE_DEPTH {
            return Err(SceneError::at(
                &name_at,
                format!(
                    "texture \"{name}\" nests {depth} textures deep (at most {MAX_TEXTURE_DEPTH})"
                ),
            ));
        }
        if work > MAX_TEXTURE_LOOKUPS {
            return Err(SceneError::at(
                &name_at,
                format!(
                    "texture \"{name}\": one lookup would evaluate {work} textures (at most \
                     {MAX_TEXTURE_LOOKUPS}; each texture named twice by the next doubles it)"
                ),
            ));
        }
        let tex = Arc::new(tex);
        self.texture_work
            .insert(Arc::as_ptr(&tex) as usize, (work, depth));
        map.insert(name, tex);
        Ok(())
    }

    /// What building a material may refer to: textures and named materials defined so far.
    fn material_context(&self) -> MaterialContext<'_> {
        MaterialContext {
            textures: &self.textures,
            named: &self.named_materials,
            materials: &self.materials,
        }
    }

    /// A material that failed to build: in collect mode the error is recorded and the default
    /// diffuse stands in, so that later references to the material do not fail too.
    fn or_default(&mut self, m: Result<Material, SceneError>) -> Result<Material, SceneError> {
        m.or_else(|e| {
            self.recover(e)?;
            Ok(Material::from(MaterialKind::Diffuse(
                crate::material::DiffuseMaterial {
                    reflectance: Vec3::splat(0.5).into(),
                },
            )))
        })
    }

    /// `Option "type name" value`: the options that cannot change photon's image are accepted
    /// with a note; the others are errors.
    fn pbrt_option(&mut self, tok: &mut Tokenizer) -> Result<(), SceneError> {
        const IGNORED: [&str; 8] = [
            "disablewavelengthjitter",
            "disabletexturefiltering",
            "msereferenceimage",
            "msereferenceout",
            "pixelstats",
            "rendercoordsys",
            "seed",
            "wavefront",
        ];
        let mut params = read_params(tok)?;
        let names: Vec<String> = params.iter().map(|p| p.name.clone()).collect();
        for name in &names {
            if !IGNORED.contains(&name.as_str()) {
                let p = params.peek(name).expect("listed");
                return Err(p.err("unsupported Option"));
            }
            let p = params.get_param(name).expect("listed");
            let note = format!(
                "{}: Option {} ignored (it does not change photon's image)",
                p.loc,
                p.decl()
            );
            self.notes.push(note);
        }
        Ok(())
    }

    /// `Shape`: builds the world-space mesh, gives it the current material and area light.
    fn shape(&mut self, tok: &mut Tokenizer) -> Result<(), SceneError> {
        let (ty, at) = string_arg(tok, "a shape type")?;
        let mut params = read_params(tok)?;
        let alpha_at = params.loc("alpha").cloned();
        let alpha = shapes::alpha(&mut params, &self.textures)?;
        let gs = &self.gs;
        // A sphere to tessellate once the scene is read, registered only with its mesh (the
        // shape can still fail below).
        let mut sphere = None;
        let mut mesh = match ty.as_str() {
            "trianglemesh" => {
                let obj = shapes::triangle_mesh(&mut params, &at)?;
                params.check_unused()?;
                shapes::to_world(obj, &gs.ctm, gs.reverse, &at)?
            }
            "bilinearmesh" => {
                let obj = super::bilinear::bilinear_mesh(&mut params, &at)?;
                params.check_unused()?;
                shapes::to_world(obj, &gs.ctm, gs.reverse, &at)?
            }
            "plymesh" => {
                // Check the other parameters before reading a possibly large file.
                params.get_string_opt("filename")?;
                params.check_unused()?;
                let obj = shapes::ply_mesh(&mut params, &at, &self.base_dir, &self.budget)?;
                shapes::to_world(obj, &gs.ctm, gs.reverse, &at)?
            }
            "sphere" => {
                let (spec, mut m) = shapes::sphere(&mut params, &at, &gs.ctm, gs.reverse)?;
                params.check_unused()?;
                if self.object.is_some() {
                    // An object's sphere may be instanced anywhere: the full tessellation.
                    shapes::tessellate(&spec, shapes::SPHERE_RINGS, &mut m);
                } else {
                    sphere = Some(spec);
                }
                m
            }
            "disk" | "cylinder" => {
                let obj = if ty == "disk" {
                    shapes::disk(&mut params, &at)?
                } else {
                    shapes::cylinder(&mut params, &at)?
                };
                params.check_unused()?;
                shapes::to_world(obj, &gs.ctm, gs.reverse, &at)?
            }
            "curve" => {
                return Err(SceneError::at(
                    &at,
                    "unsupported shape type \"curve\" (curves and hair are not supported)",
                ))
            }
            other => {
                return Err(SceneError::at(
                    &at,
                    format!("unsupported shape type \"{other}\""),
                ))
            }
        };
        super::extent::check_shape(&mesh, &at)?;
        mesh.interface = self.interface(&at)?;
        if let (Some(_), Some(_)) = (&mesh.interface, &self.gs.area) {
            self.track(&at, "an emitting shape lies on a medium boundary");
        }
        self.note_motion(&at);
        mesh.material = self.material_index();
        if self.materials[mesh.material as usize].interface {
            if mesh.interface.is_none() {
                return Err(SceneError::at(
                    &at,
                    "a shape with material \"interface\" needs a MediumInterface with two \
                     different media (it is only a boundary between them)",
                ));
            }
            self.track(&at, "a shape has material \"interface\"");
        }
        if let (Some(a), Some(_), Some(loc), None) =
            (&alpha, &self.gs.area, &alpha_at, &self.object)
        {
            // pbrt-v4's area light returns no light where its shape's alpha masks it, and
            // rays pass there: with a constant alpha of 0 the shape neither shows nor emits.
            if matches!(**a, crate::texture::Texture::Constant(v) if v.max_element() <= 0.0) {
                self.notes.push(format!(
                    "{loc}: an emitting shape with alpha 0 neither shows nor emits (as in \
                     pbrt-v4): left out"
                ));
                return Ok(());
            }
            return Err(SceneError::at(
                loc,
                "alpha other than 0 on an emitting shape (AreaLightSource) is not supported",
            ));
        }
        mesh.alpha = alpha;
        if let Some((name, meshes, _)) = &mut self.object {
            if self.gs.area.is_some() {
                self.notes.push(format!(
                    "{at}: area light ignored inside object \"{name}\" (pbrt-v4 ignores \
                     area lights in instances)"
                ));
            }
            meshes.push(mesh);
            return Ok(());
        }
        if let Some(spec) = &self.gs.area {
            let area = match mesh.sphere {
                Some((_, r)) => 4.0 * std::f64::consts::PI * (r as f64).powi(2),
                None => (0..mesh.indices.len() as u32)
                    .map(|t| mesh.area_f64(t))
                    .sum(),
            };
            let l = spec.radiance(area).map_err(|m| SceneError::at(&at, m))?;
            mesh.area_light = Some(self.lights.len() as u32);
            let medium = self.light_medium(&at)?;
            self.lights.push(crate::scene::Light::Area {
                mesh: self.meshes.len() as u32,
                l,
                two_sided: spec.two_sided,
            });
            self.light_media.push(medium);
        }
        if let Some(spec) = sphere {
            self.spheres.push((self.meshes.len(), spec));
        }
        self.meshes.push(mesh);
        self.mesh_locs.push(at);
        Ok(())
    }

    /// The media around a light defined now (pbrt-v4: an area light's shape's
    /// `MediumInterface`, a `LightSource`'s current outside medium on both sides).
    fn light_medium(&self, at: &Loc) -> Result<crate::medium::MediumInterface, SceneError> {
        let (inside, outside, written) = &self.gs.media;
        let written = written.as_ref().unwrap_or(at);
        let index = |name: &String| -> Result<Option<u32>, SceneError> {
            if name.is_empty() {
                return Ok(None);
            }
            self.named_media.get(name).map(|&i| Some(i)).ok_or_else(|| {
                SceneError::at(
                    written,
                    format!("undefined medium \"{name}\" (MakeNamedMedium must come first)"),
                )
            })
        };
        let outside = index(outside)?;
        let inside = match self.gs.area {
            Some(_) => index(inside)?,
            None => outside,
        };
        Ok(crate::medium::MediumInterface { inside, outside })
    }

    /// Records the first reason the scene's media need the path tracer's medium tracking.
    fn track(&mut self, at: &Loc, why: &str) {
        if self.needs_tracking.is_none() {
            self.needs_tracking = Some(SceneError::at(at, why).to_string());
        }
    }

    /// Notes naming the media (one per medium) and what every integrator does with them (one
    /// line per group of integrators), each short enough for `photon check`'s one-line notes.
    fn note_media(&mut self) {
        if self.media.is_empty() {
            return;
        }
        let boundaries = self.meshes.iter().filter(|m| m.interface.is_some()).count();
        for m in &self.media {
            let (a, s) = (m.sigma_a, m.sigma_s);
            let kind = match &m.field {
                None => "homogeneous",
                Some(crate::medium::Field::Density { .. }) => "uniformgrid",
                Some(crate::medium::Field::Rgb { .. }) => "rgbgrid (coefficients x grids)",
                Some(crate::medium::Field::Cloud { .. }) => "cloud",
            };
            let emits = if m.emits() { ", emits" } else { "" };
            self.notes.push(format!(
                "medium \"{}\": {kind}, sigma_a {} {} {}, sigma_s {} {} {}, g {}, majorant {}{emits}",
                crate::params::clip_for_message(&m.name, crate::params::MAX_TOKEN),
                a.x,
                a.y,
                a.z,
                s.x,
                s.y,
                s.z,
                m.g,
                m.majorant()
            ));
        }
        let n = self.media.len();
        let scatters = self.media.iter().any(|m| m.scatters());
        match &self.needs_tracking {
            None => self.notes.push(format!(
                "media: {n}, bounded by {boundaries} shapes, absorbing only: every integrator \
                 dims each ray segment inside them by Beer's law; no volume photon map is built"
            )),
            Some(why) => {
                let volume = if scatters {
                    "photonmap: surfaces as path, in-scattering by volume photon beams"
                } else {
                    "photonmap: as path (nothing scatters: no volume photon map)"
                };
                self.notes.push(format!(
                    "media: {n}, bounded by {boundaries} shapes, tracked: path as pbrt-v4's \
                     volpath; direct tracks them too (single scattering); {volume}"
                ));
                self.notes.push(format!(
                    "media: vcm, bdpt, bpm and lighttracer refuse the scene: {why}"
                ));
            }
        }
    }

    /// The medium boundary the current `MediumInterface` makes of a shape at `at`: `None`
    /// when both sides are vacuum.
    fn interface(
        &mut self,
        at: &Loc,
    ) -> Result<Option<crate::medium::MediumInterface>, SceneError> {
        let (inside, outside, written) = &self.gs.media.clone();
        if inside.is_empty() && outside.is_empty() {
            return Ok(None);
        }
        let written = written.as_ref().unwrap_or(at);
        if inside == outside {
            // pbrt-v4: no boundary; a ray that meets it stays in the medium it was in.
            if !self.named_media.contains_key(inside) {
                return Err(SceneError::at(
                    written,
                    format!("undefined medium \"{inside}\" (MakeNamedMedium must come first)"),
                ));
            }
            self.track(
                written,
                &format!("a surface is immersed in medium \"{inside}\""),
            );
            return Ok(None);
        }
        let index = |name: &String| -> Result<Option<u32>, SceneError> {
            if name.is_empty() {
                return Ok(None);
            }
            match self.named_media.get(name) {
                Some(&i) => Ok(Some(i)),
                None => Err(SceneError::at(
                    written,
                    format!("undefined medium \"{name}\" (MakeNamedMedium must come first)"),
                )),
            }
        };
        Ok(Some(crate::medium::MediumInterface {
            inside: index(inside)?,
            outside: index(outside)?,
        }))
    }

    /// `ObjectInstance "name"`: a copy of each mesh of the object, moved by the CTM (so the
    /// transform is the CTM here times the CTM where the shape was defined, as in pbrt-v4).
    fn instance(&mut self, name: &str, at: &Loc) -> Result<(), SceneError> {
        if let Some((open, _, _)) = &self.object {
            return Err(SceneError::at(
                at,
                format!("ObjectInstance inside the definition of \"{open}\""),
            ));
        }
        if !self.objects.contains_key(name) {
            return Err(SceneError::at(at, format!("unknown object \"{name}\"")));
        }
        let at_open = self.gs.ctm;
        self.note_motion(at);
        let meshes = &self.objects[name];
        let bytes: u64 = meshes.iter().map(Mesh::bytes).sum();
        self.budget
            .reserve(bytes, &format!("a copy of object \"{name}\""))
            .map_err(|m| SceneError::at(at, m))?;
        for m in meshes {
            let moved = shapes::transform_mesh(m, &at_open)
                .map_err(|e| SceneError::at(at, format!("object \"{name}\": {e}")))?;
            self.meshes.push(moved);
            self.mesh_locs.push(at.clone());
        }
        Ok(())
    }

    /// The current material's index, adding the default diffuse 0.5 on first use.
    fn material_index(&mut self) -> u32 {
        match self.gs.material {
            MatRef::Index(i) => i,
            MatRef::Default => *self.default_material.get_or_insert_with(|| {
                self.materials.push(Material::from(MaterialKind::Diffuse(
                    crate::material::DiffuseMaterial {
                        reflectance: Vec3::splat(0.5).into(),
                    },
                )));
                self.materials.len() as u32 - 1
            }),
        }
    }
}

/// The directives this parser reads.
const DIRECTIVES: [&str; 38] = [
    "Identity",
    "Translate",
    "Scale",
    "Rotate",
    "LookAt",
    "Transform",
    "ConcatTransform",
    "ActiveTransform",
    "CoordinateSystem",
    "CoordSysTransform",
    "TransformBegin",
    "TransformEnd",
    "AttributeBegin",
    "AttributeEnd",
    "ReverseOrientation",
    "WorldBegin",
    "Camera",
    "Film",
    "Sampler",
    "Integrator",
    "PixelFilter",
    "Material",
    "MakeNamedMaterial",
    "NamedMaterial",
    "Shape",
    "AreaLightSource",
    "LightSource",
    "Include",
    "Import",
    "Texture",
    "ObjectBegin",
    "ObjectEnd",
    "ObjectInstance",
    "MakeNamedMedium",
    "MediumInterface",
    "ColorSpace",
    "Option",
    "Accelerator",
];

/// pbrt-v4 directives photon knows but does not render.
const PBRT_V4_UNSUPPORTED: [&str; 2] = ["Attribute", "TransformTimes"];

/// Whether `name` is a pbrt directive (read or not): how a scene file starts.
fn is_directive(name: &str) -> bool {
    DIRECTIVES.contains(&name) || PBRT_V4_UNSUPPORTED.contains(&name) || name == "WorldEnd"
}

/// The error for a file that is not UTF-8: the location of the first bad byte.
fn not_utf8(file: &Arc<PathBuf>, e: std::string::FromUtf8Error) -> SceneError {
    let bytes = e.as_bytes();
    let good = e.utf8_error().valid_up_to();
    let line = 1 + bytes[..good].iter().filter(|&&b| b == b'\n').count();
    let line_start = bytes[..good]
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |i| i + 1);
    // Columns count characters, as the tokenizer's do for ASCII text.
    let col = 1 + String::from_utf8_lossy(&bytes[line_start..good])
        .chars()
        .count();
    let loc = Loc {
        file: file.clone(),
        line: line as u32,
        col: col as u32,
    };
    SceneError::at(
        &loc,
        format!(
            "invalid UTF-8 (byte 0x{:02x}): scene files are UTF-8 text",
            bytes[good]
        ),
    )
}

/// `MakeNamedMaterial`'s material, from its `"string type"`.
fn named_material(
    params: &mut ParamSet,
    at: &Loc,
    cx: &MaterialContext,
) -> Result<Material, SceneError> {
    let Some(ty) = params.get_string_opt("type")? else {
        return Err(SceneError::at(
            at,
            "MakeNamedMaterial needs \"string type\"",
        ));
    };
    let ty_loc = params.loc("type").cloned().unwrap_or_else(|| at.clone());
    material::create(&ty, params, &ty_loc, cx)
}

/// `ActiveTransform All | StartTime | EndTime` (a bare word): which CTMs later transforms change.
fn active_transform(tok: &mut Tokenizer, loc: &Loc) -> Result<Active, SceneError> {
    let t = tok.next()?;
    let (start, end) = match t.as_ref().map(|t| (t.kind, t.text)) {
        Some((TokKind::Word, "All")) => (true, true),
        Some((TokKind::Word, "StartTime")) => (true, false),
        Some((TokKind::Word, "EndTime")) => (false, true),
        _ => {
            let what = t.map_or("the end of the file".to_string(), |t| t.describe());
            return Err(SceneError::at(
                loc,
                format!("ActiveTransform takes All, StartTime or EndTime, found {what}"),
            ));
        }
    };
    Ok(Active { start, end })
}

/// Skips what is left of a directive that failed: everything up to the next directive word.
fn skip_arguments(tok: &mut Tokenizer) -> Result<(), SceneError> {
    while let Some(t) = tok.peek()? {
        if t.kind == TokKind::Word && !matches!(t.text, "true" | "false") {
            break;
        }
        tok.next()?;
    }
    Ok(())
}

/// `MediumInterface "inside" "outside"` (or one name for both): the two names ("" = vacuum,
/// pbrt-v4's default).
fn medium_interface(tok: &mut Tokenizer, loc: &Loc) -> Result<(String, String), SceneError> {
    let mut names = Vec::new();
    while let Some(t) = tok.peek()? {
        if t.kind != TokKind::Str || names.len() == 2 {
            break;
        }
        tok.next()?;
        names.push(unescape(t.text).into_owned());
    }
    if names.is_empty() {
        return Err(SceneError::at(
            loc,
            "MediumInterface needs one or two medium names",
        ));
    }
    let inside = names[0].clone();
    let outside = names.get(1).unwrap_or(&inside).clone();
    Ok((inside, outside))
}

/// Marks used the parameters whose names `keep` accepts and returns their declarations in
/// file order (for a note).
fn mark_used(params: &mut ParamSet, keep: impl Fn(&str) -> bool) -> Vec<String> {
    let names: Vec<String> = params
        .iter()
        .map(|p| p.name.clone())
        .filter(|n| keep(n))
        .collect();
    names
        .iter()
        .filter_map(|n| params.get_param(n).map(|p| p.decl()))
        .collect()
}

/// Marks every parameter used and lists them for a note (` ("float x", ...)`, or nothing).
fn mark_all_used(params: &mut ParamSet) -> String {
    let decls = mark_used(params, |_| true);
    if decls.is_empty() {
        String::new()
    } else {
        format!(" ({})", decls.join(", "))
    }
}

/// pbrt-v4's integrators other than photon's own, with their parameters besides `maxdepth`
/// (which photon reads whatever the integrator's name), from pbrt-v4's `integrators.cpp`.
pub const FOREIGN_INTEGRATORS: [(&str, &[&str]); 10] = [
    ("path", &["regularize", "lightsampler"]),
    ("volpath", &["regularize", "lightsampler"]),
    (
        "bdpt",
        &["regularize", "visualizestrategies", "visualizeweights"],
    ),
    (
        "mlt",
        &[
            "regularize",
            "bootstrapsamples",
            "chains",
            "mutationsperpixel",
            "largestepprobability",
            "sigma",
        ],
    ),
    ("sppm", &["photonsperiteration", "radius", "seed"]),
    ("simplepath", &["samplelights", "samplebsdf"]),
    ("simplevolpath", &[]),
    ("lightpath", &[]),
    ("randomwalk", &[]),
    ("ambientocclusion", &["cossample", "maxdistance"]),
];

/// Marks used the parameters of pbrt-v4 integrator `name` that photon does not implement and
/// returns the note listing them in file order (`None` when there were none). Other parameters stay unread,
/// so they are still errors.
fn ignore_foreign_params(name: &str, params: &mut ParamSet) -> Option<String> {
    let (_, foreign) = FOREIGN_INTEGRATORS.iter().find(|(n, _)| *n == name)?;
    let ignored = mark_used(params, |n| foreign.contains(&n));
    if ignored.is_empty() {
        return None;
    }
    Some(format!(
        "Integrator \"{name}\": photon renders with its own integrator and ignores {}",
        ignored.join(", ")
    ))
}

/// The message for a directive we do not read.
fn unsupported(name: &str) -> String {
    if name == "WorldEnd" {
        "unsupported directive \"WorldEnd\" (pbrt-v4 has no WorldEnd: is this a pbrt-v3 file?)"
            .to_string()
    } else if PBRT_V4_UNSUPPORTED.contains(&name) {
        format!("unsupported directive \"{name}\"")
    } else {
        let name = crate::scene::clip_for_message(name, crate::scene::MAX_TOKEN);
        format!("unknown directive \"{name}\"")
    }
}

/// A rotation by `deg` degrees about `axis` (pbrt's `Rotate`).
fn rotate(deg: f32, axis: Vec3, loc: &Loc) -> Result<Mat4, SceneError> {
    let a = axis.normalize_or_zero();
    if a == Vec3::ZERO {
        return Err(SceneError::at(loc, "Rotate about a zero axis"));
    }
    Ok(Mat4::from_axis_angle(a, deg.to_radians()))
}

/// pbrt's `LookAt eye look up`: the camera-from-world matrix.
fn look_at(v: &[f32], loc: &Loc) -> Result<Mat4, SceneError> {
    // Directions in f64: at coordinates near 1e20 an f32 length squared overflows.
    let eye = Vec3::new(v[0], v[1], v[2]);
    let look = glam::DVec3::new(v[3] as f64, v[4] as f64, v[5] as f64);
    let up = glam::DVec3::new(v[6] as f64, v[7] as f64, v[8] as f64);
    let dir = (look - eye.as_dvec3()).normalize_or_zero();
    if dir == glam::DVec3::ZERO {
        return Err(SceneError::at(
            loc,
            "LookAt: the eye and the look-at point coincide",
        ));
    }
    let right = up.normalize_or_zero().cross(dir).normalize_or_zero();
    if right == glam::DVec3::ZERO {
        return Err(SceneError::at(
            loc,
            "LookAt: the up vector is zero or along the view direction",
        ));
    }
    let new_up = dir.cross(right);
    let world_from_camera = Mat4::from_cols(
        right.as_vec3().extend(0.0),
        new_up.as_vec3().extend(0.0),
        dir.as_vec3().extend(0.0),
        eye.extend(1.0),
    );
    Ok(world_from_camera.inverse())
}

/// `n` bare numbers.
fn numbers(tok: &mut Tokenizer, n: usize) -> Result<Vec<f32>, SceneError> {
    (0..n)
        .map(|_| {
            let t = tok.next_required("a number")?;
            parse_float(tok, &t)
        })
        .collect()
}

/// `[ 16 numbers ]`.
fn bracketed16(tok: &mut Tokenizer) -> Result<[f32; 16], SceneError> {
    let open = tok.next_required("\"[\"")?;
    if open.kind != TokKind::Open {
        return Err(tok.err(&open, format!("expected \"[\", found {}", open.describe())));
    }
    let mut m = [0.0f32; 16];
    for slot in m.iter_mut() {
        let t = tok.next_required("a number")?;
        *slot = parse_float(tok, &t)?;
    }
    let close = tok.next_required("\"]\"")?;
    if close.kind != TokKind::Close {
        return Err(tok.err(
            &close,
            format!(
                "expected \"]\" after 16 numbers, found {}",
                close.describe()
            ),
        ));
    }
    Ok(m)
}

/// A quoted string argument and its location (`photon upgrade` reads its arguments so too).
pub(crate) fn string_arg(tok: &mut Tokenizer, what: &str) -> Result<(String, Loc), SceneError> {
    let t = tok.next_required(what)?;
    if t.kind != TokKind::Str {
        return Err(tok.err(
            &t,
            format!("expected {what} in quotes, found {}", t.describe()),
        ));
    }
    Ok((unescape(t.text).into_owned(), tok.loc(&t)))
}

/// A finite number.
fn parse_float(tok: &Tokenizer, t: &Token) -> Result<f32, SceneError> {
    if t.kind != TokKind::Num {
        return Err(tok.err(t, format!("expected a number, found {}", t.describe())));
    }
    match t.text.parse::<f32>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(tok.err(t, format!("\"{}\" is not a finite number", t.clipped()))),
    }
}

/// The parameter list following a directive's arguments.
pub fn read_params(tok: &mut Tokenizer) -> Result<ParamSet, SceneError> {
    let mut set = ParamSet::new();
    while let Some(t) = tok.peek()? {
        if t.kind != TokKind::Str {
            break;
        }
        tok.next()?;
        set.push(read_param(tok, &t)?)?;
    }
    Ok(set)
}

/// One `"type name" value-or-list`, `decl` being the declaration token.
fn read_param(tok: &mut Tokenizer, decl: &Token) -> Result<Param, SceneError> {
    let mut words = decl.text.split_whitespace();
    let (Some(ty_name), Some(name), None) = (words.next(), words.next(), words.next()) else {
        return Err(tok.err(
            decl,
            format!(
                "expected a parameter declaration \"type name\", found \"{}\"",
                decl.clipped()
            ),
        ));
    };
    let Some(ty) = ParamType::from_name(ty_name) else {
        return Err(tok.err(
            decl,
            format!(
                "unknown parameter type \"{}\" in \"{}\"",
                crate::scene::clip_for_message(ty_name, crate::scene::MAX_TOKEN),
                decl.clipped()
            ),
        ));
    };
    let values = read_values(tok, ty, decl)?;
    Ok(Param::new(ty, ty_name, name, values, tok.loc(decl)))
}

/// The value tokens of a parameter: one token, or everything between `[` and `]`.
fn read_values(
    tok: &mut Tokenizer,
    ty: ParamType,
    decl: &Token,
) -> Result<ParamValues, SceneError> {
    let first = tok.next_required("a parameter value")?;
    if first.kind != TokKind::Open {
        let mut vals = Values::new(ty, &first);
        vals.push(tok, &first, decl)?;
        return Ok(vals.finish());
    }
    let mut vals: Option<Values> = None;
    loop {
        let t = tok.next_required("\"]\"")?;
        match t.kind {
            TokKind::Close => return Ok(vals.unwrap_or_else(|| Values::new(ty, &first)).finish()),
            TokKind::Open => return Err(tok.err(&t, "\"[\" inside a parameter list")),
            // The storage is chosen by the first value, so a named spectrum may be bracketed.
            _ => vals
                .get_or_insert_with(|| Values::new(ty, &t))
                .push(tok, &t, decl)?,
        }
    }
}

/// Accumulates typed values.
struct Values {
    ty: ParamType,
    out: ParamValues,
}

impl Values {
    /// Chooses the storage for `ty` from its first value (spectra: strings if it is quoted).
    fn new(ty: ParamType, first: &Token) -> Self {
        let out = match ty {
            ParamType::Integer => ParamValues::Ints(Vec::new()),
            ParamType::Bool => ParamValues::Bools(Vec::new()),
            ParamType::String | ParamType::Texture => ParamValues::Strings(Vec::new()),
            ParamType::Spectrum if first.kind == TokKind::Str => ParamValues::Strings(Vec::new()),
            _ => ParamValues::Floats(Vec::new()),
        };
        Values { ty, out }
    }

    fn finish(self) -> ParamValues {
        self.out
    }

    /// Converts and appends one value token.
    fn push(&mut self, tok: &Tokenizer, t: &Token, decl: &Token) -> Result<(), SceneError> {
        let bad = |what: &str| {
            tok.err(
                t,
                format!(
                    "parameter \"{}\": expected {what}, found {}",
                    decl.clipped(),
                    t.describe()
                ),
            )
        };
        match &mut self.out {
            ParamValues::Floats(v) => {
                if t.kind != TokKind::Num {
                    return Err(bad("a number"));
                }
                v.push(parse_float(tok, t)?);
            }
            ParamValues::Ints(v) => {
                let i = (t.kind == TokKind::Num)
                    .then(|| t.text.parse::<i32>().ok())
                    .flatten();
                v.push(i.ok_or_else(|| bad("an integer"))?);
            }
            ParamValues::Bools(v) => {
                let b = match (t.kind, t.text) {
                    (TokKind::Word | TokKind::Str, "true") => true,
                    (TokKind::Word | TokKind::Str, "false") => false,
                    _ => return Err(bad("true or false")),
                };
                v.push(b);
            }
            ParamValues::Strings(v) => {
                if t.kind != TokKind::Str {
                    let what = if self.ty == ParamType::Spectrum {
                        "a spectrum name"
                    } else {
                        "a quoted string"
                    };
                    return Err(bad(what));
                }
                v.push(unescape(t.text).into_owned());
            }
        }
        Ok(())
    }
}

/// The inverse of `m` (a camera-from-world CTM), computed in f64: a camera-from-world scale
/// near 1e-20 has a determinant below f32's range. Not finite when `m` is singular.
fn inverse(m: &Mat4) -> Mat4 {
    m.as_dmat4().inverse().as_mat4()
}

/// `Camera "perspective"` (`fov`) or `"orthographic"`: `lensradius`, `focaldistance`,
/// `screenwindow`, `frameaspectratio`, `shutteropen`/`shutterclose` (their difference is the
/// exposure time of the film's imaging ratio; photon has no motion blur). An orthographic
/// camera takes no `fov` (as in pbrt-v4, it would be an unused parameter).
fn camera(
    ty: &str,
    params: &mut ParamSet,
    at: &Loc,
    world_from_camera: Mat4,
) -> Result<CameraDesc, SceneError> {
    let projection = match ty {
        "perspective" => Projection::Perspective,
        "orthographic" => Projection::Orthographic,
        _ => {
            return Err(SceneError::at(
                at,
                format!("unsupported camera type \"{ty}\" (photon renders \"perspective\" and \"orthographic\")"),
            ))
        }
    };
    let fov_deg = if projection == Projection::Perspective {
        params.get_float("fov", 90.0)?
    } else {
        90.0
    };
    if !(fov_deg > 0.0 && fov_deg < 180.0) {
        let p = params.peek("fov").expect("a bad fov came from the file");
        return Err(p.err("fov must lie in (0, 180) degrees"));
    }
    let lens_radius = params.get_float("lensradius", 0.0)?;
    if !(0.0..=super::extent::MAX_COORDINATE).contains(&lens_radius) {
        let p = params
            .peek("lensradius")
            .expect("a bad radius came from the file");
        return Err(p.err(format!(
            "must lie in [0, {:e}], got {lens_radius}",
            super::extent::MAX_COORDINATE
        )));
    }
    let focal_distance = params.get_float("focaldistance", 1e6)?;
    if !(focal_distance > 0.0 && focal_distance.is_finite()) {
        let p = params
            .peek("focaldistance")
            .expect("a bad distance came from the file");
        return Err(p.err(format!("must be positive and finite, got {focal_distance}")));
    }
    let screen_window = screen_window(params)?;
    let open = params.get_float("shutteropen", 0.0)?;
    let close = params.get_float("shutterclose", 1.0)?;
    let exposure_time = close - open;
    if !(exposure_time > 0.0 && exposure_time.is_finite()) {
        let p = params.peek("shutterclose").or(params.peek("shutteropen"));
        let msg = format!("\"shutterclose\" ({close}) must be after \"shutteropen\" ({open})");
        return Err(p.map_or_else(|| SceneError::at(at, &msg), |p| p.err(&msg)));
    }
    if !world_from_camera.is_finite() {
        return Err(SceneError::at(at, "the camera transform is singular"));
    }
    let eye = world_from_camera.transform_point3(Vec3::ZERO);
    let max = super::extent::MAX_COORDINATE;
    // The lens's rim in world space (the camera transform may scale).
    let rim = [Vec3::X, Vec3::Y]
        .map(|a| {
            world_from_camera
                .transform_vector3(a * lens_radius)
                .length()
        })
        .into_iter()
        .fold(0.0, f32::max);
    // An orthographic camera's rays start anywhere on its screen window (default: the
    // shorter side [-1, 1], the longer up to the film's aspect ratio, which the limit of the
    // resolution bounds).
    let window = match (projection, screen_window) {
        (Projection::Perspective, _) => 0.0,
        (Projection::Orthographic, Some(w)) => w.iter().fold(0.0f32, |m, v| m.max(v.abs())),
        (Projection::Orthographic, None) => crate::limits::MAX_RESOLUTION as f32,
    };
    let reach = [Vec3::X, Vec3::Y]
        .map(|a| world_from_camera.transform_vector3(a * window).length())
        .into_iter()
        .fold(0.0, f32::max);
    if eye.abs().max_element() + rim + reach > max {
        return Err(SceneError::at(
            at,
            format!("the scene is too large: the camera is at {eye} (photon supports coordinates up to {max:e}; scale the scene down)"),
        ));
    }
    Ok(CameraDesc {
        projection,
        lens_radius,
        focal_distance,
        screen_window,
        exposure_time,
        ..CameraDesc::pinhole(world_from_camera, fov_deg)
    })
}

/// The camera's `screenwindow` (four finite values, min < max on each axis), else the window
/// `frameaspectratio` implies (pbrt-v4: `[-f, f] x [-1, 1]` for f > 1, else `[-1, 1] x
/// [-1/f, 1/f]`), else `None` (the image's own aspect ratio decides).
fn screen_window(params: &mut ParamSet) -> Result<Option<[f32; 4]>, SceneError> {
    let frame = params.get_float_opt("frameaspectratio")?;
    if let Some(w) = params.get_floats("screenwindow")? {
        let p = params.peek("screenwindow").expect("given");
        let max = super::extent::MAX_COORDINATE;
        let ok = w.len() == 4 && w.iter().all(|v| v.abs() <= max) && w[0] < w[1] && w[2] < w[3];
        if !ok {
            return Err(p.err(format!(
                "expected four values xmin xmax ymin ymax within {max:e} with min < max"
            )));
        }
        return Ok(Some([w[0], w[1], w[2], w[3]]));
    }
    let Some(f) = frame else { return Ok(None) };
    if !(f > 0.0 && f.is_finite()) {
        let p = params.peek("frameaspectratio").expect("given");
        return Err(p.err(format!("must be positive and finite, got {f}")));
    }
    Ok(Some(if f > 1.0 {
        [-f, f, -1.0, 1.0]
    } else {
        [-1.0, 1.0, -1.0 / f, 1.0 / f]
    }))
}

/// `Film "rgb"` or `"gbuffer"`: `xresolution`, `yresolution`, `filename`, `iso`, `sensor`
/// (`"cie1931"` only), `whitebalance`, `maxcomponentvalue`, `cropwindow`, `pixelbounds`;
/// `gbuffer`'s `coordinatesystem` (`"camera"` or `"world"`: the space of its position and
/// normal channels, see `crate::integrator::aov`).
fn film(ty: &str, params: &mut ParamSet, at: &Loc) -> Result<FilmDesc, SceneError> {
    if ty != "rgb" && ty != "gbuffer" {
        return Err(SceneError::at(
            at,
            format!("unsupported film type \"{ty}\""),
        ));
    }
    let mut res = [0u32; 2];
    for (r, (name, default)) in res
        .iter_mut()
        .zip([("xresolution", 1280), ("yresolution", 720)])
    {
        let v = params.get_int(name, default)?;
        let max = crate::limits::MAX_RESOLUTION as i32;
        if v <= 0 || v > max {
            let msg = format!("must be positive and at most {max}, got {v}");
            return Err(params.peek(name).expect("given").err(msg));
        }
        *r = v as u32;
    }
    let mut film = FilmDesc::new(res[0], res[1]);
    film.filename = params.get_string_opt("filename")?;
    film.white_balance = sensor(params)?;
    film.iso = params.get_float("iso", 100.0)?;
    if !(film.iso > 0.0 && film.iso.is_finite()) {
        let p = params.peek("iso").expect("a bad iso came from the file");
        return Err(p.err(format!("must be positive and finite, got {}", film.iso)));
    }
    film.max_component = params.get_float("maxcomponentvalue", f32::INFINITY)?;
    if film.max_component.is_nan() || film.max_component <= 0.0 {
        let p = params.peek("maxcomponentvalue").expect("given");
        return Err(p.err(format!("must be positive, got {}", film.max_component)));
    }
    film.crop = crop_window(params, res)?;
    if ty == "gbuffer" {
        film.gbuffer = Some(gbuffer(params, &film)?);
    }
    Ok(film)
}

/// The sensor parameters photon supports: the default `cie1931` sensor, with or without white
/// balance (its temperature, 0 for none, is returned).
fn sensor(params: &mut ParamSet) -> Result<f32, SceneError> {
    let name = params.get_string("sensor", "cie1931")?;
    if name != "cie1931" {
        let p = params.peek("sensor").expect("given");
        return Err(p.err(format!(
            "sensor \"{name}\" is not supported (photon has only the default \"cie1931\")"
        )));
    }
    let t = params.get_float("whitebalance", 0.0)?;
    let min = crate::film::MIN_WHITE_BALANCE;
    if t != 0.0 && !(min..=1e5).contains(&t) {
        let p = params.peek("whitebalance").expect("given");
        return Err(p.err(format!(
            "must be 0 (none) or a daylight temperature in [{min:.0}, 100000] K, got {t} (pbrt-v4's blackbody white below it is not supported)"
        )));
    }
    Ok(t)
}

/// `cropwindow` (four fractions, each axis ordered and clamped to [0, 1] as pbrt-v4 does) or
/// `pixelbounds` (four pixel indices, half-open; it wins over `cropwindow` as in pbrt-v4); an
/// error if no pixel of the `res` image lies inside (pbrt-v4's "degenerate pixel bounds").
fn crop_window(
    params: &mut ParamSet,
    res: [u32; 2],
) -> Result<Option<crate::film::Crop>, SceneError> {
    use crate::film::Crop;
    let window = params.get_floats("cropwindow")?;
    let bounds = params.get_ints("pixelbounds")?;
    let (crop, key) = match (bounds, window) {
        (Some(b), _) => {
            let p = params.peek("pixelbounds").expect("given");
            if b.len() != 4 || b.iter().any(|&v| v < 0) {
                return Err(p.err("expected four non-negative pixel indices x0 x1 y0 y1"));
            }
            let b = [b[0] as u32, b[1] as u32, b[2] as u32, b[3] as u32];
            (Crop::Pixels(b), "pixelbounds")
        }
        (None, Some(c)) => {
            let p = params.peek("cropwindow").expect("given");
            if c.len() != 4 || c.iter().any(|v| !v.is_finite()) {
                return Err(p.err("expected four finite values x0 x1 y0 y1"));
            }
            (Crop::window([c[0], c[1], c[2], c[3]]), "cropwindow")
        }
        (None, None) => return Ok(None),
    };
    let b = crate::film::pixel_bounds(Some(crop), res[0], res[1]);
    if b[0] >= b[1] || b[2] >= b[3] {
        let p = params.peek(key).expect("given");
        return Err(p.err(format!(
            "no pixel of the {}x{} image lies inside {crop:?}",
            res[0], res[1]
        )));
    }
    Ok(Some(crop))
}

/// `Film "gbuffer"`'s own parameters: the space of its position and normal channels.
fn gbuffer(params: &mut ParamSet, film: &FilmDesc) -> Result<crate::film::Space, SceneError> {
    use crate::film::Space;
    let system = params.get_string("coordinatesystem", "camera")?;
    let space = match system.as_str() {
        "camera" => Space::Camera,
        "world" => Space::World,
        _ => {
            let p = params.peek("coordinatesystem").expect("given");
            return Err(p.err(format!(
                "unknown coordinate system \"{system}\" (expected \"camera\" or \"world\")"
            )));
        }
    };
    if let Some(name) = &film.filename {
        if !name.to_ascii_lowercase().ends_with(".exr") {
            let p = params.peek("filename").expect("given");
            return Err(p.err("Film \"gbuffer\" writes EXR only (pbrt-v4)"));
        }
    }
    Ok(space)
}

/// `Sampler`: any pbrt-v4 name; `pixelsamples`, or `xsamples` x `ysamples` (and `jitter`) for
/// `stratified`.
fn sampler(ty: &str, params: &mut ParamSet, at: &Loc) -> Result<SamplerDesc, SceneError> {
    const NAMES: [&str; 7] = [
        "independent",
        "stratified",
        "sobol",
        "zsobol",
        "halton",
        "paddedsobol",
        "pmj02bn",
    ];
    if !NAMES.contains(&ty) {
        return Err(SceneError::at(
            at,
            format!("unsupported sampler type \"{ty}\""),
        ));
    }
    let n = if ty == "stratified" {
        params.get_bool("jitter", true)?;
        let x = positive_int(params, "xsamples", 4)?;
        let y = positive_int(params, "ysamples", 4)?;
        x.checked_mul(y)
            .filter(|&n| n <= crate::limits::MAX_SPP)
            .ok_or_else(|| {
                SceneError::at(
                    at,
                    format!(
                        "xsamples * ysamples is larger than {}",
                        crate::limits::MAX_SPP
                    ),
                )
            })?
    } else {
        positive_int(params, "pixelsamples", 16)?
    };
    Ok(SamplerDesc {
        name: ty.to_string(),
        pixel_samples: n,
    })
}

/// An `integer` parameter that must be positive.
fn positive_int(params: &mut ParamSet, name: &str, default: i32) -> Result<u32, SceneError> {
    let v = params.get_int(name, default)?;
    let max = crate::limits::MAX_SPP as i32;
    if v <= 0 || v > max {
        let msg = format!("must be positive and at most {max}, got {v}");
        return Err(params.peek(name).expect("given").err(msg));
    }
    Ok(v as u32)
}

/// `PixelFilter`: `box` (radius 0.5), `triangle` (2), `gaussian` (1.5, `sigma` 0.5).
fn filter(ty: &str, params: &mut ParamSet, at: &Loc) -> Result<FilterDesc, SceneError> {
    let default = match ty {
        "box" => 0.5,
        "triangle" => 2.0,
        "gaussian" => 1.5,
        other => {
            return Err(SceneError::at(
                at,
                format!("unsupported pixel filter \"{other}\""),
            ))
        }
    };
    let mut r = [0.0f32; 2];
    for (slot, name) in r.iter_mut().zip(["xradius", "yradius"]) {
        *slot = params.get_float(name, default)?;
        if slot.is_nan() || *slot <= 0.0 {
            return Err(params.peek(name).expect("given").err("must be positive"));
        }
    }
    let radius = Vec2::new(r[0], r[1]);
    Ok(match ty {
        "box" => FilterDesc::Box { radius },
        "triangle" => FilterDesc::Triangle { radius },
        _ => {
            let sigma = params.get_float("sigma", 0.5)?;
            if sigma.is_nan() || sigma <= 0.0 {
                return Err(params.peek("sigma").expect("given").err("must be positive"));
            }
            FilterDesc::Gaussian { radius, sigma }
        }
    })
}
