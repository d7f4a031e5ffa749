//! hyrt-shadowmap: point-light and VPL depth maps drawn with `hyrt-raster`, and the image
//! operations of selective shadow ray tracing.
//!
//! - [`paraboloid`] (Heidrich and Seidel 1998; Brabec et al. 2002) and [`cube`]: the two
//!   omnidirectional parameterisations;
//! - [`map`]: building a light's depth map (per texel the closest triangle's id and distance);
//! - [`paged`]: paged maps, drawn only where a frame's receivers fall, at the resolution they need;
//! - [`vpl_map`]: a VPL's hemisphere of occluder planes or 16-bit depths, for many fast lookups;
//! - [`classify`]: deciding a surface point lit, shadowed or undecided from a map;
//! - [`border`]: shadow-border detection on a screen-space occlusion map (the thesis's Laplace
//!   kernel) and dilation.
//!
//! ```
//! use glam::Vec3;
//! use hyrt_shadowmap::{
//!     LightMap, MapOptions,
//!     classify::{Classifier, Decision, point_error_bound, triangle_planes},
//! };
//!
//! // A floor (triangles 0, 1) at y = 0 and a small square occluder (2, 3) at y = 1, under a
//! // light at y = 2.
//! let q = |y: f32, r: f32| {
//!     let v = |x: f32, z: f32| Vec3::new(x, y, z);
//!     [[v(-r, -r), v(r, r), v(r, -r)], [v(-r, -r), v(-r, r), v(r, r)]]
//! };
//! let tris: Vec<[Vec3; 3]> = q(0.0, 4.0).into_iter().chain(q(1.0, 0.25)).collect();
//! let light = Vec3::new(0.0, 2.0, 0.0);
//! let opts = MapOptions { resolution: 256, ..MapOptions::default() };
//! // Every face of the cube map drawn.
//! let map = LightMap::build(&tris, light, &opts, &[true; 6]);
//! let planes = triangle_planes(&tris);
//! let cls = Classifier { map: &map, planes: &planes, bias: 1.0, point_error: point_error_bound(&tris), cutouts: &[] };
//! // Under the occluder: shadowed, with the occluder as the hint for a ray; far from it: lit.
//! let under = cls.classify(Vec3::new(0.0, 0.0, 0.1), 1);
//! assert_eq!(under.decision, Decision::Shadow);
//! assert!(under.hint == 2 || under.hint == 3);
//! assert_eq!(cls.classify(Vec3::new(2.0, 0.0, 1.0), 0).decision, Decision::Lit);
//! ```

pub mod border;
pub mod classify;
pub mod cube;
pub mod map;
pub mod paged;
pub mod paraboloid;
mod tess;
pub mod vpl_map;

pub use cube::{CubeFace, cube_lookup};
pub use map::{
    ABSENT, EMPTY, LightMap, MAX_LEVEL, MapCoord, MapKind, MapOptions, PAGE, PageKey, paged_memory_bound,
};
pub use paraboloid::{Hemisphere, paraboloid_project, paraboloid_unproject};
