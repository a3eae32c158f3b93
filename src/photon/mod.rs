//! The photon map (Jensen): compact photon records, a balanced kd-tree over their positions
//! and the radiance-estimate kernels.
//!
//! - [`stored`]: [`Photon`], 20 bytes: position, shared-exponent RGB power, octahedral
//!   direction, flags;
//! - [`kdtree`]: [`KdTree`], an implicit median-split tree with k-nearest and radius queries
//!   into a reusable [`KnnResult`];
//! - [`map`]: [`PhotonMap`], the photons in tree order beside their tree;
//! - [`estimate`]: [`Kernel`] and [`estimate::irradiance`] with leak guards (side, disc,
//!   minimum count);
//! - [`aim`]: where the distant and infinite lights aim their global photons;
//! - [`cache`]: [`IrradianceCache`], Christensen's precomputed irradiance for final gathering.
//!
//! ```
//! use photon::math::Vec3;
//! use photon::photon::{estimate, Kernel, KnnResult, Photon, PhotonMap};
//! let photons: Vec<Photon> = (0..1000)
//!     .map(|i| {
//!         let p = Vec3::new((i % 32) as f32 / 32.0, (i / 32) as f32 / 32.0, 0.0);
//!         Photon::new(p, Vec3::splat(0.001), -Vec3::Z, 0)
//!     })
//!     .collect();
//! let map = PhotonMap::new(&photons).unwrap();
//! let mut buf = KnnResult::new();
//! let (e, used, r2) =
//!     estimate::irradiance(&map, Vec3::new(0.5, 0.5, 0.0), Vec3::Z, 50, 0.04, Kernel::Box, &mut buf);
//! assert_eq!(used, 49);
//! assert!(e.x > 0.0 && r2 < 0.04);
//! ```
pub mod aim;
pub mod cache;
pub mod estimate;
pub mod guide;
pub mod kdtree;
pub mod map;
pub mod projection;
pub mod stored;
pub mod trace;
pub mod volume;

pub use cache::IrradianceCache;
pub use estimate::{EstimateParams, Kernel};
pub use kdtree::{KdTree, KnnResult, Neighbor};
pub use map::PhotonMap;
pub use stored::Photon;
