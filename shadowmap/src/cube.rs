//! Cube-map faces: which face a direction falls on and where.

use glam::{Vec2, Vec3};

/// The six faces, named by the axis they look along.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CubeFace {
    PosX,
    NegX,
    PosY,
    NegY,
    PosZ,
    NegZ,
}

/// The face a direction falls on (its largest |component|, ties to x then y) and the
/// coordinates in `[-1, 1]^2` on that face: the other two components divided by the major one.
pub fn cube_lookup(d: Vec3) -> (CubeFace, Vec2) {
    let a = d.abs();
    if a.x >= a.y && a.x >= a.z {
        let f = if d.x >= 0.0 { CubeFace::PosX } else { CubeFace::NegX };
        (f, Vec2::new(d.y, d.z) / a.x)
    } else if a.y >= a.z {
        let f = if d.y >= 0.0 { CubeFace::PosY } else { CubeFace::NegY };
        (f, Vec2::new(d.x, d.z) / a.y)
    } else {
        let f = if d.z >= 0.0 { CubeFace::PosZ } else { CubeFace::NegZ };
        (f, Vec2::new(d.x, d.y) / a.z)
    }
}
