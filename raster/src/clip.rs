//! Homogeneous clipping of a clip-space triangle to a convex polygon.
//!
//! # Which planes, and why
//!
//! A point `p = (x, y, z, w)` in clip space is visible when
//!
//! ```text
//!     -w <= x <= w,    -w <= y <= w,    0 <= z <= w        (wgpu / D3D convention)
//! ```
//!
//! The rasterizer needs only two things from the clipper:
//!
//! 1. **Every vertex it projects has `w > 0`**, otherwise `x / w` flips sign and a triangle passing
//!    behind the eye would be drawn "inside out" across the screen. The near plane `z >= 0` and the
//!    far plane `z <= w` together imply `w >= z >= 0`, so clipping against both gives `w >= 0`;
//!    `w == 0` is only left for the degenerate vertex `(0, 0, 0, 0)`, which the projection rejects.
//!    Unlike a `w >= epsilon` plane, this needs no tolerance and works for any projection matrix
//!    (perspective, orthographic, oblique shadow frusta).
//! 2. **Projected coordinates fit the fixed-point range** (see [`crate::setup`]). Clipping against
//!    the real side planes `|x| <= w` would create new vertices (and thin fan triangles) for every
//!    triangle that merely crosses the screen border, which is most of the triangles of a room seen
//!    from inside. Instead the side planes are moved out to a *guard band*
//!    `|x| <= g_x w`, `|y| <= g_y w`, chosen so that the screen coordinates of anything inside it are
//!    within `±GUARD_BAND_PX` pixels. Only triangles reaching past several hundred thousand pixels
//!    off-screen are clipped there; the rest are rasterized whole and the edge functions plus the
//!    tile/bounding-box clamp discard the off-screen samples for free.
//!
//! # Watertightness across shared edges
//!
//! Two triangles sharing an edge `ab` must produce bit-identical intersection points, or the snapped
//! fixed-point edges would no longer coincide and pixels could fall into the crack. Three rules make
//! the result a pure function of the edge's endpoints (never of the triangle or its winding):
//!
//! * The intersection is always computed **from the inside endpoint towards the outside endpoint**:
//!   `t = d_in / (d_in - d_out)`, `p = p_in + t (p_out - p_in)`, regardless of the order in which
//!   the edge is visited.
//! * The new vertex is then **snapped exactly onto the plane** (e.g. `z := 0` for the near plane),
//!   which removes rounding noise and makes `|x / w| <= g_x` hold exactly.
//! * Whether a plane is processed at all is decided from the **current polygon's vertices**: if an
//!   endpoint of a shared edge is outside a plane, both polygons contain it and both clip the edge.
//!
//! Attributes (the barycentrics of the point with respect to the *original* triangle) are
//! interpolated with the same `t`: clip space is an affine image of the triangle's plane, so
//! barycentrics are linear in it, and a clipped vertex keeps its exact position in the original
//! triangle.

use glam::{DVec2, DVec4};

/// Screen coordinates (in pixels) of anything inside the guard band lie within
/// `[-GUARD_BAND_PX, GUARD_BAND_PX]`. `2^19` px: far beyond any realistic target, small enough that
/// fixed-point products fit in `i64` (see [`crate::setup::MAX_FIXED`]).
pub(crate) const GUARD_BAND_PX: f64 = (1u64 << 19) as f64;

/// At most 3 vertices plus one per plane (6) for a convex polygon; the slack covers polygons that
/// rounding made very slightly non-convex. A polygon that would exceed it is dropped.
pub(crate) const MAX_POLY_VERTS: usize = 16;

/// A polygon vertex: clip-space position and the barycentrics `(b1, b2)` of that point with respect
/// to the original (unclipped) triangle.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct ClipVertex {
    pub pos: DVec4,
    pub bary: DVec2,
}

/// A convex polygon with at most [`MAX_POLY_VERTS`] vertices, in the winding of the input triangle.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Polygon {
    verts: [ClipVertex; MAX_POLY_VERTS],
    len: usize,
}

impl Polygon {
    fn empty() -> Self {
        Self { verts: [ClipVertex::default(); MAX_POLY_VERTS], len: 0 }
    }

    /// The original triangle, with barycentrics (0,0), (1,0), (0,1) at its three vertices.
    fn triangle(tri: &[DVec4; 3]) -> Self {
        let mut p = Self::empty();
        let bary = [DVec2::ZERO, DVec2::X, DVec2::Y];
        for (pos, bary) in tri.iter().zip(bary) {
            p.verts[p.len] = ClipVertex { pos: *pos, bary };
            p.len += 1;
        }
        p
    }

    /// Appends a vertex; `false` if the polygon is full.
    fn push(&mut self, v: ClipVertex) -> bool {
        if self.len == MAX_POLY_VERTS {
            return false;
        }
        self.verts[self.len] = v;
        self.len += 1;
        true
    }

    pub fn as_slice(&self) -> &[ClipVertex] {
        &self.verts[..self.len]
    }
}

/// Half-widths of the guard band in NDC units: `|x| <= x * w`, `|y| <= y * w`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct GuardBand {
    pub x: f64,
    pub y: f64,
}

impl GuardBand {
    /// Screen x is `(x_ndc + 1) * width / 2`, so `|x_ndc| <= g` maps to
    /// `[-(g - 1) width / 2, (g + 1) width / 2]`, whose larger end is `GUARD_BAND_PX` for
    /// `g = 2 GUARD_BAND_PX / width - 1` (same for y). Since `width <= MAX_TARGET_DIM = 2^16`,
    /// `g >= 15`: the guard band is always well outside the viewport.
    pub fn for_target(width: u32, height: u32) -> Self {
        Self {
            x: 2.0 * GUARD_BAND_PX / f64::from(width.max(1)) - 1.0,
            y: 2.0 * GUARD_BAND_PX / f64::from(height.max(1)) - 1.0,
        }
    }
}

/// The six clipping planes, each written as a signed distance `d(p) >= 0` inside.
#[derive(Clone, Copy, Debug)]
enum Plane {
    Near,
    Far,
    Left,
    Right,
    Bottom,
    Top,
}

/// Near first: it is the plane that matters for correctness (w > 0), and clipping it first keeps the
/// far plane from ever seeing a vertex behind the eye.
const PLANES: [Plane; 6] = [Plane::Near, Plane::Far, Plane::Left, Plane::Right, Plane::Bottom, Plane::Top];

impl Plane {
    fn distance(self, g: GuardBand, p: DVec4) -> f64 {
        match self {
            Plane::Near => p.z,
            Plane::Far => p.w - p.z,
            Plane::Left => g.x * p.w + p.x,
            Plane::Right => g.x * p.w - p.x,
            Plane::Bottom => g.y * p.w + p.y,
            Plane::Top => g.y * p.w - p.y,
        }
    }

    /// Moves an intersection point exactly onto the plane (distance exactly 0).
    fn snap(self, g: GuardBand, p: &mut DVec4) {
        match self {
            Plane::Near => p.z = 0.0,
            Plane::Far => p.z = p.w,
            Plane::Left => p.x = -(g.x * p.w),
            Plane::Right => p.x = g.x * p.w,
            Plane::Bottom => p.y = -(g.y * p.w),
            Plane::Top => p.y = g.y * p.w,
        }
    }
}

/// Bit `i` set when `p` is outside the i-th *viewport* plane (guard band 1). Used only to reject
/// triangles that are entirely off-screen before any work is done.
fn viewport_outcode(p: DVec4) -> u8 {
    let view = GuardBand { x: 1.0, y: 1.0 };
    PLANES
        .iter()
        .enumerate()
        .fold(0, |code, (i, plane)| code | (u8::from(plane.distance(view, p) < 0.0) << i))
}

/// What [`clip_triangle`] did with a triangle.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Clipped<'s> {
    /// Nothing is left (entirely outside one viewport plane, or clipped away).
    Rejected,
    /// The triangle is entirely inside near, far and the guard band: use it as is.
    Inside,
    /// The clipped polygon, at least 3 vertices, in the triangle's winding.
    Polygon(&'s Polygon),
}

/// Two polygons that [`clip_triangle`] ping-pongs between; kept by the caller so that the
/// (rare) clipping path does not move ~800-byte polygons around for every triangle.
#[derive(Clone, Debug)]
pub(crate) struct ClipScratch {
    a: Polygon,
    b: Polygon,
}

impl ClipScratch {
    pub fn new() -> Self {
        Self { a: Polygon::empty(), b: Polygon::empty() }
    }
}

/// Clips a clip-space triangle (finite coordinates) against near, far and the guard band.
///
/// A clipped polygon lives in `scratch`. Its vertices satisfy
/// `0 <= z <= w`, `|x| <= g.x w` and `|y| <= g.y w`, up to one rounding of the interpolation for
/// planes that no vertex crossed.
pub(crate) fn clip_triangle<'s>(tri: &[DVec4; 3], g: GuardBand, scratch: &'s mut ClipScratch) -> Clipped<'s> {
    // Trivial reject: all three vertices outside the same viewport plane (e.g. all behind the eye,
    // all beyond the far plane, all left of the screen).
    let codes = tri.map(viewport_outcode);
    if codes[0] & codes[1] & codes[2] != 0 {
        return Clipped::Rejected;
    }
    // Common case: nothing reaches past near, far or the guard band (18 comparisons).
    let outside = |p: &DVec4| PLANES.iter().any(|plane| plane.distance(g, *p) < 0.0);
    if !tri.iter().any(outside) {
        return Clipped::Inside;
    }

    let (mut src, mut dst) = (&mut scratch.a, &mut scratch.b);
    *src = Polygon::triangle(tri);
    for plane in PLANES {
        // Decided on the current polygon (see the module docs for why this keeps shared edges
        // identical).
        if src.as_slice().iter().all(|v| plane.distance(g, v.pos) >= 0.0) {
            continue;
        }
        if !clip_polygon(src, plane, g, dst) || dst.len < 3 {
            return Clipped::Rejected;
        }
        std::mem::swap(&mut src, &mut dst);
    }
    Clipped::Polygon(src)
}

/// One Sutherland–Hodgman pass from `src` into `out`: keeps the inside vertices, and inserts the
/// intersection point on every edge that crosses the plane. The winding is preserved. `false` if
/// the output overflowed [`MAX_POLY_VERTS`].
fn clip_polygon(src: &Polygon, plane: Plane, g: GuardBand, out: &mut Polygon) -> bool {
    let verts = src.as_slice();
    out.len = 0;
    for (i, &a) in verts.iter().enumerate() {
        let b = verts[(i + 1) % verts.len()];
        let da = plane.distance(g, a.pos);
        let db = plane.distance(g, b.pos);
        let a_in = da >= 0.0;
        if a_in && !out.push(a) {
            return false;
        }
        if a_in != (db >= 0.0) {
            // Canonical direction: inside -> outside. d_in >= 0 > d_out, so the denominator is
            // strictly positive and t is in [0, 1).
            let (inside, outside, d_in, d_out) = if a_in { (a, b, da, db) } else { (b, a, db, da) };
            let t = d_in / (d_in - d_out);
            let mut pos = inside.pos + (outside.pos - inside.pos) * t;
            plane.snap(g, &mut pos);
            let bary = inside.bary + (outside.bary - inside.bary) * t;
            if !out.push(ClipVertex { pos, bary }) {
                return false;
            }
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    const G: GuardBand = GuardBand { x: 20.0, y: 20.0 };

    #[derive(Debug, PartialEq)]
    enum Outcome {
        Rejected,
        Inside,
        Clipped,
    }

    fn clip(tri: &[DVec4; 3]) -> (Outcome, Vec<ClipVertex>) {
        let mut scratch = ClipScratch::new();
        match clip_triangle(tri, G, &mut scratch) {
            Clipped::Rejected => (Outcome::Rejected, Vec::new()),
            Clipped::Inside => (Outcome::Inside, Vec::new()),
            Clipped::Polygon(p) => (Outcome::Clipped, p.as_slice().to_vec()),
        }
    }

    #[test]
    fn inside_triangle_is_not_clipped() {
        let tri = [
            DVec4::new(-0.5, -0.5, 0.5, 1.0),
            DVec4::new(0.5, -0.5, 0.5, 1.0),
            DVec4::new(0.0, 0.5, 0.5, 1.0),
        ];
        assert_eq!(clip(&tri).0, Outcome::Inside);
    }

    #[test]
    fn behind_the_eye_is_rejected() {
        let tri = [
            DVec4::new(-0.5, -0.5, -0.5, -1.0),
            DVec4::new(0.5, -0.5, -0.5, -1.0),
            DVec4::new(0.0, 0.5, -0.5, -1.0),
        ];
        assert_eq!(clip(&tri).0, Outcome::Rejected);
    }

    #[test]
    fn near_clip_gives_quad_on_the_plane_with_consistent_barycentrics() {
        // One vertex behind the eye (z < 0): the result is a quad whose new vertices lie on z = 0
        // and whose barycentrics reproduce their positions from the original vertices.
        let tri = [
            DVec4::new(-0.5, -0.5, 0.5, 1.0),
            DVec4::new(0.5, -0.5, 0.5, 1.0),
            DVec4::new(0.0, 0.5, -0.5, 0.2),
        ];
        let (outcome, poly) = clip(&tri);
        assert_eq!(outcome, Outcome::Clipped);
        assert_eq!(poly.len(), 4);
        for v in &poly {
            assert!(v.pos.z >= 0.0 && v.pos.z <= v.pos.w);
            let b = v.bary;
            let rebuilt = tri[0] * (1.0 - b.x - b.y) + tri[1] * b.x + tri[2] * b.y;
            assert!((rebuilt - v.pos).abs().max_element() < 1e-12, "{rebuilt} vs {}", v.pos);
        }
    }

    #[test]
    fn guard_band_clip_bounds_the_coordinates() {
        let tri = [
            DVec4::new(-1e9, -1e9, 0.5, 1.0),
            DVec4::new(1e9, -1e3, 0.5, 1.0),
            DVec4::new(0.0, 1e9, 0.5, 1.0),
        ];
        let (outcome, poly) = clip(&tri);
        assert_eq!(outcome, Outcome::Clipped);
        for v in &poly {
            assert!(v.pos.x.abs() <= G.x * v.pos.w && v.pos.y.abs() <= G.y * v.pos.w);
        }
    }

    #[test]
    fn shared_edge_is_clipped_identically_in_both_directions() {
        let a = DVec4::new(0.3, 0.1, 0.7, 1.0);
        let b = DVec4::new(-0.2, 0.4, -0.3, 0.1);
        let c1 = DVec4::new(0.9, 0.9, 0.5, 1.0);
        let c2 = DVec4::new(-0.9, -0.9, 0.5, 1.0);
        let on_plane = |tri: [DVec4; 3]| -> Vec<DVec4> {
            clip(&tri).1.iter().filter(|v| v.pos.z == 0.0).map(|v| v.pos).collect()
        };
        let mut s1 = on_plane([a, b, c1]);
        let s2 = on_plane([b, a, c2]);
        // The intersection of edge ab with z = 0 appears in both, bit for bit.
        s1.retain(|p| s2.contains(p));
        assert_eq!(s1.len(), 1);
    }
}
