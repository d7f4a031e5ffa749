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
#[inline]
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

impl CubeFace {
    /// All faces in index order (the face numbers of a cube [`crate::LightMap`]).
    pub const ALL: [CubeFace; 6] =
        [CubeFace::PosX, CubeFace::NegX, CubeFace::PosY, CubeFace::NegY, CubeFace::PosZ, CubeFace::NegZ];

    /// The face's number in a cube [`crate::LightMap`]: `PosX = 0, NegX = 1, ..., NegZ = 5`.
    pub fn index(self) -> u8 {
        self as u8
    }

    /// The face numbered `i`, if `i < 6`.
    pub fn from_index(i: u8) -> Option<CubeFace> {
        Self::ALL.get(i as usize).copied()
    }

    /// The axis the face looks along (0, 1, 2 for x, y, z), its sign (`+1` or `-1`), and the
    /// axes of [`cube_lookup`]'s first and second coordinate on it (the other two, in order).
    pub fn axes(self) -> (usize, f32, usize, usize) {
        let i = self as usize;
        let axis = i / 2;
        let sign = if i.is_multiple_of(2) { 1.0 } else { -1.0 };
        let (s, t) = match axis {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        (axis, sign, s, t)
    }
}
