//! hyrt-shadowmap: point-light and VPL depth maps drawn with `hyrt-raster`, and the image
//! operations of selective shadow ray tracing.
//!
//! - [`paraboloid`] (Heidrich and Seidel 1998; Brabec et al. 2002) and [`cube`]: the two
//!   omnidirectional parameterisations;
//! - [`map`]: building a light's depth map (per texel the closest triangle's id and distance);
//! - [`vpl_map`]: a VPL's hemisphere of occluder planes or 16-bit depths, for many fast lookups;
//! - [`classify`]: deciding a surface point lit, shadowed or undecided from a map;
//! - [`border`]: shadow-border detection on a screen-space occlusion map (the thesis's Laplace
//!   kernel) and dilation.

pub mod border;
pub mod classify;
pub mod cube;
pub mod map;
pub mod paraboloid;
mod tess;
pub mod vpl_map;

pub use cube::{CubeFace, cube_lookup};
pub use map::{EMPTY, LightMap, MapCoord, MapKind, MapOptions};
pub use paraboloid::{Hemisphere, paraboloid_project, paraboloid_unproject};
