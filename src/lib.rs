//! photon: a two-pass photon-mapping renderer (Jensen) for pbrt-v4 scenes.
//!
//! The pipeline, in the order a render runs it:
//! - [`scene::loader`] reads a pbrt-v4 file into a [`scene::Scene`] (meshes, materials, lights,
//!   camera, film, sampler, filter, integrator settings);
//! - [`accel`] builds Embree 3 or obvhs over the triangles and answers ray queries;
//! - [`integrator`] renders: [`camera`] makes rays, [`sampling`] gives the sample streams,
//!   [`bsdf`] and [`light`] do the shading, [`film`] accumulates pixels;
//! - [`imageio`] writes EXR (OpenEXRCore) and PNG.
//!
//! [`medium`] holds the media (`MakeNamedMedium`): the path tracer tracks the medium of each
//! ray and scatters in it ([`integrator::wavefront`]); the other integrators weigh segments in
//! absorbing closed media by [`accel::transmittance`].
//!
//! [`texture`] holds the textures the loader parses (image maps, checkerboards, scale and mix),
//! which materials and shape alpha evaluate per hit.
pub mod accel;
pub mod bsdf;
pub mod camera;
pub mod film;
pub mod imageio;
pub mod integrator;
pub mod interaction;
pub mod interrupt;
pub mod light;
pub mod limits;
pub mod material;
pub mod math;
pub mod medium;
pub mod memory;
pub mod mesh;
pub mod params;
pub mod photon;
pub mod progress;
pub mod sampling;
pub mod scene;
pub mod spectrum;
pub mod texture;
pub mod tools;
