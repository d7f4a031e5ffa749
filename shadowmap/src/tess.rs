//! Paraboloid hemispheres: a triangle is clipped to the hemisphere, tessellated and projected to
//! clip space for `hyrt-raster`.
//!
//! # Projection
//!
//! In the map's frame (the hemisphere is `z >= 0`, the light at the origin) a point `d` goes to
//!
//! ```text
//!     clip = (d.x, d.y, near * w / |d|, w),    w = |d| + d.z
//! ```
//!
//! so NDC `(x/w, y/w) = (d.x, d.y) / (|d| + d.z)` is the paraboloid point `(u, v)` of the
//! direction of `d` (`crate::paraboloid`), and NDC depth `z/w = near / |d|` is the rasterizer's
//! reversed-Z convention (larger is closer, the near plane `z <= w` is `|d| >= near`). Since
//! `d.z >= 0` after clipping, `w >= |d| > 0`: no vertex reaches `w = 0`, and `|(u, v)| <= 1`.
//!
//! The rasterizer draws straight edges between projected vertices and interpolates `z/w`
//! linearly in screen space; the paraboloid map is not projective, so both are approximations
//! that tessellation makes small.
//!
//! # Clipping
//!
//! Against the plane `z = 0` through the light, in 3D, before projecting (Sutherland-Hodgman on
//! one plane: a triangle becomes a triangle or a quad, fanned into one or two triangles). As in
//! the rasterizer's clipper, the new vertex is computed from the inside endpoint towards the
//! outside one and put exactly on the plane (`z := 0`), so two triangles sharing an edge get the
//! same bits, and it projects onto the rim of the disc.
//!
//! # Tessellation bound
//!
//! The paraboloid map is conformal (it is the stereographic projection from `-z`): at polar
//! angle `theta` a direction at `u = tan(theta / 2)` moves by
//! `du = dtheta / (2 cos^2(theta / 2)) = dtheta / (1 + cos theta)` in any direction, at most
//! `dtheta` on the hemisphere. So a curve of angular length `a` maps to a curve of length at
//! most `a / (1 + cos theta_max)` in NDC units, i.e. `a * res / (2 (1 + cos theta_max))` texels
//! (`theta_max` its largest polar angle), and so does the chord the rasterizer draws in its
//! place. For the points of a segment or triangle, `cos theta = z / |d| >= min z_i / max |d_i|`
//! (`z` is affine and `|d|` convex along it, so both extremes are at vertices). A segment of
//! length `L` whose points are all at distance `>= dist` from the light subtends
//! `a <= L / dist` (`|d(p/|p|)| <= |dp| / |p|`). Splitting a triangle into `n x n` similar
//! sub-triangles (edges parallel to its own, `L_e / n` long, at distance `>= dist(light,
//! triangle)`) therefore keeps every sub-edge at most `tess_texels` texels long when
//!
//! ```text
//!     n >= max_e L_e / dist(light, triangle) * res / (2 tess_texels) / (1 + min z_i / max |d_i|)
//! ```
//!
//! `n` is capped at [`MAX_TESS`] `= 64` (4096 sub-triangles per triangle): triangles larger
//! than about `64 * 2 * tess_texels / res` times their distance to the light (a wall next to
//! the light) keep longer sub-edges near the light, where their image and depth are less
//! accurate. Most triangles of a detailed mesh need no subdivision; they are recognised cheaply
//! (every point is at least `min |d_i| - max L_e` from the light) and drawn as they are.
//!
//! # Crack-free stitching
//!
//! Neighbouring triangles get different `n`, and the chords of a shared edge would then differ:
//! every chord lies on the concave side of the edge's curved image, so the finer set of chords
//! leaves a sliver (a T-junction crack) that a texel centre can fall into. So each edge has its
//! own factor `m_e <= n`, from the same bound applied to the edge alone (its length and its
//! distance to the light): a function of its two endpoints only, computed from them in a
//! canonical order, as are its `m_e + 1` points. The grid vertices on the triangle's border are
//! snapped to the nearest of those points (rounding `i * m_e / n` is monotone in `i` and steps
//! by at most 1, so every edge point is used and the border strips stay a valid triangulation;
//! sub-triangles that collapse are dropped). Two triangles sharing an edge then share its
//! projected vertices bit for bit, and the rasterizer's fill rule covers each texel centre along
//! it exactly once.
//!
//! The image is not affine, so where a border strip is thin (`m_e` much smaller than `n`) the
//! chord of its long edge can cross the curved image of a neighbouring one and fold a
//! sub-triangle over. That covers a few texel centres within the chords' sag of an edge (at most
//! `c^2 / (4 res)` texels for a chord of `c` texels, the image of a straight edge being a circle
//! of radius at least `res / 2` texels) two extra times with the same triangle, and never leaves
//! one uncovered: the winding number stays 1 (the unit tests count coverage on closed meshes).
//!
//! # The rim
//!
//! Where a triangle is cut by `z = 0` (or has an edge on it), its image ends at the rim of the
//! disc, an arc; the drawn edges are its chords, which leave the circular segment between chord
//! and arc uncovered, and texel centres inside the disc can lie there. Each rim chord `PQ` (an
//! angle `alpha` of the rim) therefore gets a "skirt" triangle `P, Q, T` with `T` where the
//! tangents at `P` and `Q` meet, `T = (P + Q) / cos^2(alpha / 2) / 2 = 2 (P + Q) / |P + Q|^2`: it
//! contains the segment and lies otherwise outside the disc (texels there are never looked up,
//! and the map clears them). Its depth is the mean of `P`'s and `Q`'s. Chords of more than 120
//! degrees (only next to the light) are first split at the projection of the 3D midpoint.

use glam::{DVec2, DVec3, Vec4};

use crate::map::MAX_TESS;

/// An orthonormal frame: map coordinates are `(t . d, b . d, n . d)`, the hemisphere is around `n`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Frame {
    pub t: DVec3,
    pub b: DVec3,
    pub n: DVec3,
}

impl Frame {
    /// The world axes (the front map of a dual-paraboloid point light).
    pub const WORLD: Frame = Frame { t: DVec3::X, b: DVec3::Y, n: DVec3::Z };
    /// `z` mirrored (the back map: `(x, y, z) -> (x, y, -z)`, as in `crate::paraboloid`).
    pub const MIRRORED: Frame = Frame { t: DVec3::X, b: DVec3::Y, n: DVec3::NEG_Z };

    /// A frame around `axis` (normalised here; `+z` if it is zero or not finite), from the
    /// branchless construction of Duff et al. 2017 ("Building an orthonormal basis, revisited"),
    /// which gives the world axes for `axis = +z`.
    pub fn around(axis: DVec3) -> Frame {
        let n = axis.normalize_or_zero();
        if n == DVec3::ZERO || !n.is_finite() {
            return Frame::WORLD;
        }
        let sign = 1f64.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let t = DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let bb = DVec3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { t, b: bb, n }
    }

    /// World direction -> map coordinates. Exact for [`Frame::WORLD`] and [`Frame::MIRRORED`].
    #[inline]
    pub fn to_map(self, d: DVec3) -> DVec3 {
        DVec3::new(self.t.dot(d), self.b.dot(d), self.n.dot(d))
    }

    /// Map coordinates -> world direction.
    #[inline]
    pub fn to_world(self, m: DVec3) -> DVec3 {
        self.t * m.x + self.b * m.y + self.n * m.z
    }
}

/// Constants of one hemisphere's tessellation.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Params {
    /// Near distance (module docs of `crate::map`).
    pub near: f64,
    /// `resolution / (2 * tess_texels)`: an edge of length `L` at distance `>= dist` needs
    /// `L / dist * k` subdivisions (module docs). 0 without tessellation.
    pub k: f64,
    /// Texels per side.
    pub res: f32,
}

impl Params {
    pub fn new(near: f64, resolution: u32, tess_texels: f32) -> Params {
        // `tess_texels = inf` (or NaN) is no tessellation; 0 or negative is the finest (the cap).
        let tess = f64::from(tess_texels);
        let k = if tess.is_nan() || tess == f64::INFINITY {
            0.0
        } else if tess > 0.0 {
            f64::from(resolution) / (2.0 * tess)
        } else {
            f64::INFINITY
        };
        Params { near, k, res: resolution as f32 }
    }

    /// Whether the projected triangle `c` (clip space, `w > 0`) certainly covers no texel
    /// centre: its bounding box, widened by 1/64 texel (far more than the rasterizer's snapping
    /// to 1/256 texel and the rounding of `x / w`), holds no centre `k + 1/2` along `x` or `y`.
    ///
    /// Why: at the small resolutions of VPL maps most triangles of a large scene fall between
    /// the texel centres; dropping them here spares storing, setting up and binning them.
    #[inline]
    pub fn misses_centres(&self, c: &[Vec4; 3]) -> bool {
        let half = self.res * 0.5;
        let x = c.map(|v| (v.x / v.w + 1.0) * half);
        let y = c.map(|v| (1.0 - v.y / v.w) * half);
        let none = |v: [f32; 3]| {
            let (lo, hi) = (v[0].min(v[1]).min(v[2]) - 1.0 / 64.0, v[0].max(v[1]).max(v[2]) + 1.0 / 64.0);
            // The first centre at or above `lo` lies above `hi`. (A ceiling by truncation: the
            // front hemisphere's coordinates lie within the map, far inside the i32 range.)
            let t = lo - 0.5;
            let c = t as i32 as f32;
            let c = if c < t { c + 1.0 } else { c };
            c + 0.5 > hi
        };
        none(x) || none(y)
    }

    /// Subdivisions for a segment or triangle of longest edge `len`, at distance `>= dist` from
    /// the light, whose vertices have `z >= zmin` and `|d| <= rmax` (module docs), in
    /// `[1, MAX_TESS]`.
    #[inline]
    fn factor(&self, len: f64, dist: f64, zmin: f64, rmax: f64) -> u32 {
        let x = len / dist * self.k / (1.0 + (zmin / rmax).max(0.0));
        if x >= f64::from(MAX_TESS) {
            MAX_TESS
        } else if x > 1.0 {
            x.ceil() as u32
        } else {
            1 // also NaN: 0 * inf, 0 / 0 of a degenerate edge
        }
    }
}

/// A total order on points, so that an edge is always processed from the same end.
#[inline]
fn canonical(a: DVec3, b: DVec3) -> (DVec3, DVec3, bool) {
    let key = |p: DVec3| [p.x, p.y, p.z];
    let (ka, kb) = (key(a), key(b));
    let le = ka.iter().zip(&kb).map(|(x, y)| x.total_cmp(y)).find(|o| o.is_ne()).is_none_or(|o| o.is_lt());
    if le { (a, b, false) } else { (b, a, true) }
}

/// Distance from the origin to segment `ab`.
#[inline]
fn dist_segment(a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let l2 = ab.length_squared();
    let t = if l2 > 0.0 { (-a.dot(ab) / l2).clamp(0.0, 1.0) } else { 0.0 };
    (a + ab * t).length()
}

/// Distance from the origin to triangle `abc` (Ericson, "Real-Time Collision Detection",
/// 5.1.5, with the query point at the origin); the edges' if that is not finite (slivers).
pub(crate) fn dist_triangle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let closest = || {
        let (ab, ac) = (b - a, c - a);
        let (d1, d2) = (-ab.dot(a), -ac.dot(a));
        if d1 <= 0.0 && d2 <= 0.0 {
            return a;
        }
        let (d3, d4) = (-ab.dot(b), -ac.dot(b));
        if d3 >= 0.0 && d4 <= d3 {
            return b;
        }
        let vc = d1 * d4 - d3 * d2;
        if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            return a + ab * (d1 / (d1 - d3));
        }
        let (d5, d6) = (-ab.dot(c), -ac.dot(c));
        if d6 >= 0.0 && d5 <= d6 {
            return c;
        }
        let vb = d5 * d2 - d1 * d6;
        if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            return a + ac * (d2 / (d2 - d6));
        }
        let va = d3 * d6 - d5 * d4;
        if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
            return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
        }
        let denom = 1.0 / (va + vb + vc);
        a + ab * (vb * denom) + ac * (vc * denom)
    };
    let d = closest().length();
    if d.is_finite() { d } else { dist_segment(a, b).min(dist_segment(b, c)).min(dist_segment(c, a)) }
}

/// Clip-space position of map-frame point `d` (module docs). A point at the light gives NaN,
/// which makes the rasterizer skip the triangle.
#[inline]
fn project(d: DVec3, near: f64) -> Vec4 {
    let r = d.length();
    let w = r + d.z;
    Vec4::new(d.x as f32, d.y as f32, (near * w / r) as f32, w as f32)
}

/// An edge with its subdivision: its points are `point(k)`, `k = 0..=m`, from `a` to `b`.
#[derive(Clone, Copy, Debug)]
struct Edge {
    /// The ends in canonical order ([`canonical`]), and whether that is `b, a`.
    p: DVec3,
    q: DVec3,
    swapped: bool,
    m: u32,
}

impl Edge {
    fn new(a: DVec3, b: DVec3, prm: &Params) -> Edge {
        let (p, q, swapped) = canonical(a, b);
        let m = prm.factor((q - p).length(), dist_segment(p, q), p.z.min(q.z), p.length().max(q.length()));
        Edge { p, q, swapped, m }
    }

    /// Point `k` of `m` from `a`, computed from the canonical end so that the edge of the
    /// neighbouring triangle (traversed the other way) gets the same bits; the ends exactly.
    fn point(&self, k: u32) -> DVec3 {
        let k = if self.swapped { self.m - k } else { k };
        if k == 0 {
            self.p
        } else if k == self.m {
            self.q
        } else {
            self.p + (self.q - self.p) * (f64::from(k) / f64::from(self.m))
        }
    }

    /// The edge point a border grid vertex `i` of `n` snaps to (module docs).
    fn snapped(&self, i: u32, n: u32) -> DVec3 {
        let k = (2 * u64::from(i) * u64::from(self.m) + u64::from(n)) / (2 * u64::from(n));
        self.point(k as u32)
    }

    fn on_rim(&self) -> bool {
        self.p.z == 0.0 && self.q.z == 0.0
    }
}

/// Tessellates triangles into clip-space triangles for one hemisphere, appending to `tris` and
/// `ids`; keeps its scratch buffers between triangles.
#[derive(Default)]
pub(crate) struct Tessellator {
    pts: Vec<DVec3>,
    clip: Vec<Vec4>,
    pub tris: Vec<[Vec4; 3]>,
    pub ids: Vec<u32>,
}

impl Tessellator {
    /// Appends the clip-space triangles of the part of map-frame triangle `p` (light at the
    /// origin) with `z >= 0`, with id `id`.
    pub fn triangle(&mut self, p: [DVec3; 3], id: u32, prm: &Params) {
        if !p.iter().any(|q| q.z > 0.0) {
            return; // nothing strictly inside (at most an edge on the rim)
        }
        if p.iter().all(|q| q.z > 0.0) {
            // Fast path (module docs): no clipping, and every point at least rmin - lmax from
            // the light, far enough for n = 1 (ignoring the 1 / (1 + cos) gain); with a margin so
            // that rounding cannot make a neighbour's general path split a shared edge.
            // `lmax k 1.001 <= rmin - lmax`, squared (both sides are lengths): no square roots.
            let rmin2 = p[0].length_squared().min(p[1].length_squared()).min(p[2].length_squared());
            let lmax2 = (p[1] - p[0])
                .length_squared()
                .max((p[2] - p[1]).length_squared())
                .max((p[0] - p[2]).length_squared());
            let grow = 1.0 + prm.k * 1.001;
            if lmax2 * grow * grow <= rmin2 {
                let c = p.map(|q| project(q, prm.near));
                if !prm.misses_centres(&c) {
                    self.tris.push(c);
                    self.ids.push(id);
                }
                return;
            }
        }
        let mut poly = [DVec3::ZERO; 4];
        let mut len = 0;
        for i in 0..3 {
            let (a, b) = (p[i], p[(i + 1) % 3]);
            if a.z >= 0.0 {
                poly[len] = a;
                len += 1;
            }
            if (a.z > 0.0 && b.z < 0.0) || (a.z < 0.0 && b.z > 0.0) {
                let (pin, pout) = if a.z > 0.0 { (a, b) } else { (b, a) };
                let t = pin.z / (pin.z - pout.z);
                let mut q = pin + (pout - pin) * t;
                q.z = 0.0;
                poly[len] = q;
                len += 1;
            }
        }
        for k in 1..len.saturating_sub(1) {
            self.tessellate(poly[0], poly[k], poly[k + 1], id, prm);
        }
    }

    fn tessellate(&mut self, a: DVec3, b: DVec3, c: DVec3, id: u32, prm: &Params) {
        let (ab, bc, ca) = (Edge::new(a, b, prm), Edge::new(b, c, prm), Edge::new(a, c, prm));
        let lmax = (b - a).length().max((c - b).length()).max((a - c).length());
        let (zmin, rmax) = (a.z.min(b.z).min(c.z), a.length().max(b.length()).max(c.length()));
        let n = prm.factor(lmax, dist_triangle(a, b, c), zmin, rmax).max(ab.m).max(bc.m).max(ca.m);

        // Grid vertex (i, j), i + j <= n, is a + (b - a) i/n + (c - a) j/n; row j holds
        // n - j + 1 vertices and starts at j (n + 1) - j (j - 1) / 2.
        self.pts.clear();
        let nf = f64::from(n);
        for j in 0..=n {
            for i in 0..=n - j {
                let q = if j == 0 {
                    ab.snapped(i, n)
                } else if i == 0 {
                    ca.snapped(j, n)
                } else if i + j == n {
                    bc.snapped(j, n)
                } else {
                    a + (b - a) * (f64::from(i) / nf) + (c - a) * (f64::from(j) / nf)
                };
                self.pts.push(q);
            }
        }
        self.clip.clear();
        self.clip.extend(self.pts.iter().map(|&q| project(q, prm.near)));

        let row = |j: u32| (j * (n + 1) - j * j.saturating_sub(1) / 2) as usize;
        let idx = |i: u32, j: u32| row(j) + i as usize;
        for j in 0..n {
            for i in 0..n - j {
                self.emit([idx(i, j), idx(i + 1, j), idx(i, j + 1)], id);
                if i + j + 1 < n {
                    self.emit([idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)], id);
                }
            }
        }
        for e in [ab, bc, ca] {
            if e.on_rim() {
                for k in 0..e.m {
                    self.skirt(e.point(k), e.point(k + 1), id, prm, 0);
                }
            }
        }
    }

    /// A grid sub-triangle, unless border snapping collapsed it.
    fn emit(&mut self, v: [usize; 3], id: u32) {
        let [p0, p1, p2] = v.map(|i| self.pts[i]);
        if p0 != p1 && p1 != p2 && p2 != p0 {
            self.tris.push(v.map(|i| self.clip[i]));
            self.ids.push(id);
        }
    }

    /// Covers the circular segment between rim chord `pq` and the rim (module docs).
    fn skirt(&mut self, p: DVec3, q: DVec3, id: u32, prm: &Params, level: u32) {
        let (cp, cq) = (project(p, prm.near), project(q, prm.near));
        // On the rim (z = 0) the disc point is (x, y) / |d|, computed in f64.
        let rim = |d: DVec3| DVec2::new(d.x, d.y) / d.length();
        let s = rim(p) + rim(q);
        let s2 = s.length_squared();
        if s2 >= 1.0 {
            // alpha <= 120 degrees: the tangents meet at a finite, nearby T.
            let t = s * (2.0 / s2);
            let w = 0.5 * (f64::from(cp.w) + f64::from(cq.w));
            let depth = 0.5 * (f64::from(cp.z / cp.w) + f64::from(cq.z / cq.w));
            let ct = Vec4::new((t.x * w) as f32, (t.y * w) as f32, (depth * w) as f32, w as f32);
            self.tris.push([cp, cq, ct]);
            self.ids.push(id);
        } else if level < 8 {
            let mut mid = (p + q) * 0.5;
            mid.z = 0.0;
            self.tris.push([cp, project(mid, prm.near), cq]);
            self.ids.push(id);
            self.skirt(p, mid, id, prm, level + 1);
            self.skirt(mid, q, id, prm, level + 1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hyrt_raster::{RasterOptions, coverage_count};

    fn in_disc(res: u32, x: u32, y: u32) -> bool {
        let (r, cx, cy) = (i64::from(res), 2 * i64::from(x) + 1, 2 * i64::from(y) + 1);
        (cx - r) * (cx - r) + (cy - r) * (cy - r) < r * r
    }

    /// A closed mesh around the light (star-shaped: every ray crosses it once) covers every
    /// texel centre of the disc an odd number of times (winding number 1: no crack, the rim
    /// segments covered by the skirts; a sub-triangle folded over by the curvature of the map adds
    /// 2), and exactly once for all but a few. Returns the number covered more than once.
    fn check_watertight(tris: &[[DVec3; 3]], frame: Frame, res: u32, tess: f32) -> usize {
        let prm = Params::new(1e-6, res, tess);
        let mut t = Tessellator::default();
        for (i, tri) in tris.iter().enumerate() {
            t.triangle(tri.map(|p| frame.to_map(p)), i as u32, &prm);
        }
        let count = coverage_count(&t.tris, res, res, &RasterOptions::default());
        let (mut texels, mut folded) = (0, 0);
        for y in 0..res {
            for x in 0..res {
                if in_disc(res, x, y) {
                    let c = count[(y * res + x) as usize];
                    assert!(
                        c % 2 == 1,
                        "texel ({x}, {y}) covered {c} times (res {res}, tess {tess}, {frame:?})"
                    );
                    texels += 1;
                    folded += usize::from(c > 1);
                }
            }
        }
        assert!(folded * 200 <= texels, "{folded} of {texels} texels covered more than once");
        folded
    }

    /// An axis-aligned box `[lo, hi]` as 12 triangles with shared vertices.
    fn cuboid(lo: DVec3, hi: DVec3) -> Vec<[DVec3; 3]> {
        let v = |i: usize| {
            DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        };
        let quads = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]];
        quads.iter().flat_map(|q| [[v(q[0]), v(q[1]), v(q[2])], [v(q[0]), v(q[2]), v(q[3])]]).collect()
    }

    /// A subdivided icosahedron-like sphere (random-ish vertex radii) around the origin.
    fn bumpy_sphere(levels: u32) -> Vec<[DVec3; 3]> {
        let t = (1.0 + 5f64.sqrt()) / 2.0;
        let v = [
            [-1.0, t, 0.0],
            [1.0, t, 0.0],
            [-1.0, -t, 0.0],
            [1.0, -t, 0.0],
            [0.0, -1.0, t],
            [0.0, 1.0, t],
            [0.0, -1.0, -t],
            [0.0, 1.0, -t],
            [t, 0.0, -1.0],
            [t, 0.0, 1.0],
            [-t, 0.0, -1.0],
            [-t, 0.0, 1.0],
        ]
        .map(|p| DVec3::from_array(p).normalize());
        let f = [
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ];
        let mut tris: Vec<[DVec3; 3]> = f.iter().map(|t| t.map(|i| v[i])).collect();
        for _ in 0..levels {
            tris = tris
                .iter()
                .flat_map(|&[a, b, c]| {
                    let (ab, bc, ca) = (
                        ((a + b) * 0.5).normalize(),
                        ((b + c) * 0.5).normalize(),
                        ((c + a) * 0.5).normalize(),
                    );
                    [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
                })
                .collect();
        }
        // Deterministic bumps: radius from the position, so shared vertices stay shared.
        let bump =
            |p: DVec3| p * (1.0 + 0.15 * (3.0 * p.x + 5.0 * p.y * p.z).sin()) + DVec3::new(0.2, -0.1, 0.15);
        let tris: Vec<[DVec3; 3]> = tris.iter().map(|t| t.map(bump)).collect();
        // Star-shaped around the light (every triangle faces it from the same side), so that
        // every ray from the light crosses the surface exactly once.
        assert!(tris.iter().all(|[a, b, c]| a.dot(b.cross(*c)) > 0.0));
        tris
    }

    #[test]
    fn closed_meshes_cover_the_disc_exactly_once() {
        let boxed = cuboid(DVec3::new(-1.0, -0.7, -1.3), DVec3::new(2.0, 0.9, 0.8));
        let sphere = bumpy_sphere(2);
        let tilted = Frame::around(DVec3::new(0.3, -0.8, 0.5));
        let mut folded = 0;
        for (mesh, res) in [(&boxed, 96), (&sphere, 64), (&boxed, 7), (&sphere, 33), (&sphere, 256)] {
            for frame in [Frame::WORLD, Frame::MIRRORED, tilted] {
                for tess in [f32::INFINITY, 8.0, 2.0] {
                    folded += check_watertight(mesh, frame, res, tess);
                }
            }
        }
        eprintln!("texels covered more than once (folds): {folded}");
    }

    #[test]
    fn frames_are_orthonormal_and_right_handed() {
        assert_eq!(Frame::around(DVec3::Z), Frame::WORLD);
        for axis in [DVec3::new(0.3, -0.8, 0.5), DVec3::NEG_Z, DVec3::X, DVec3::new(1e-9, 0.0, -1.0)] {
            let f = Frame::around(axis);
            assert!((f.n - axis.normalize()).length() < 1e-15);
            assert!((f.t.cross(f.b) - f.n).length() < 1e-12, "{f:?}");
            assert!(f.t.dot(f.b).abs() < 1e-12 && f.t.dot(f.n).abs() < 1e-12);
        }
        assert_eq!(Frame::around(DVec3::ZERO), Frame::WORLD);
        assert_eq!(Frame::around(DVec3::NAN), Frame::WORLD);
    }

    #[test]
    fn tessellation_meets_the_bound_below_the_cap() {
        // A triangle at distance ~1 spanning ~0.5 rad: every drawn sub-edge, measured in texels
        // on the map, is within 1.5 tess_texels (border strips join n-grid and m_e-edge points).
        let res = 512;
        let tess = 8.0;
        let prm = Params::new(1e-6, res, tess);
        let mut t = Tessellator::default();
        t.triangle(
            [DVec3::new(-0.3, -0.2, 1.0), DVec3::new(0.4, 0.0, 0.9), DVec3::new(0.0, 0.3, 1.2)],
            0,
            &prm,
        );
        assert!(t.tris.len() > 100, "{} sub-triangles", t.tris.len());
        let texels =
            |a: Vec4, b: Vec4| ((a.x / a.w - b.x / b.w).hypot(a.y / a.w - b.y / b.w)) * res as f32 / 2.0;
        let worst = t.tris.iter().map(|v| texels(v[0], v[1]).max(texels(v[1], v[2])).max(texels(v[2], v[0])));
        let worst = worst.fold(0.0f32, f32::max);
        assert!(worst <= 1.5 * tess, "longest projected sub-edge {worst} texels");
    }
}
