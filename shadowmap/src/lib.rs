//! hyrt-shadowmap: point-light and VPL depth maps drawn with `hyrt-raster`.
//!
//! So far: the two omnidirectional parameterisations, [`paraboloid`] (Heidrich and Seidel
//! 1998; Brabec et al. 2002) and [`cube`]. Map building, occlusion classification and
//! shadow-border detection follow.

pub mod cube;
pub mod paraboloid;

pub use cube::{CubeFace, cube_lookup};
pub use paraboloid::{Hemisphere, paraboloid_project, paraboloid_unproject};
