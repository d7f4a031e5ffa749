//! Deciding from a light's depth map whether a surface point is lit, shadowed, or undecided.
//!
//! # One texel: the occluder's plane, not its stored depth
//!
//! A texel records the triangle `T` closest to the light in the direction of the texel's centre.
//! The classic test compares the point's distance with the distance stored for that centre; but
//! the point's own direction differs from the centre's by up to half a texel, so on a surface
//! seen at a grazing angle the two distances differ by `footprint * tan(theta)` and the test
//! needs a bias that large (acne without it, light leaking under objects with it). Here the
//! texel's triangle id is used instead: the distance `t` at which the ray from the light towards
//! the point `p` meets `T`'s *plane* is exact for `p`'s own direction, so
//!
//! - `T` is `p`'s own triangle: lit (a planar triangle cannot shadow itself);
//! - `T` is another triangle: shadowed iff `t < |p - L| - margin`;
//! - the texel is empty: lit (nothing was drawn in that direction).
//!
//! A surface made of many coplanar triangles (a floor) then decides exactly at any angle, with a
//! margin that only has to cover rounding. What it does not cover: a point near an edge between
//! two non-coplanar triangles (a crease, a curved mesh) whose texel centre falls on the other
//! triangle, which then decides with its plane extended past the edge. Over the lateral distance
//! `s` (at most about one texel footprint `r * texel_angle`) a plane tilted by the dihedral angle
//! `a` departs from the point's surface by about `s * tan(a)`: the margin is therefore
//!
//! `margin = bias * r * texel_angle + tol + band`
//!
//! with the knob `bias` in texel footprints (1 covers dihedral angles up to 45 degrees at the
//! worst lateral distance), `tol` the rounding of the plane intersection (relative to `r`: the
//! intersection is computed relative to the light, see [`Plane`]) and `band` how far the
//! point's own rounding can move it along the ray ([`Classifier::point_error`]; it grows with
//! the distance from the origin, not with `r`, and is negligible near the origin).
//! An occluder that close to the point may also be a real one (an object resting on the
//! surface, a contact shadow), so the decision is three-way: `t < r - margin` shadowed,
//! `t >= r - tol` lit, in between *ambiguous*, which counts as shadowed and marks the point
//! undecided (a ray decides). As in the reference's shadow rays, occluders within `1e-4 r` of
//! the light do not count. Where the plane is seen edge-on (`|n . dir| < 1e-6`) its intersection
//! is meaningless and the stored depth decides instead.
//!
//! # Undecided points: the map-space border test
//!
//! Aliasing lives where texels disagree. [`Classifier::classify`] also evaluates the decision
//! against the 2x2 texels whose centres surround the point's projection (the bilinear
//! footprint); when they do not all agree, the point is near a shadow border *in the map*: an
//! occluder's silhouette, a thin occluder caught by some of the texels, a crease. This catches
//! borders that the screen-space Laplacian misses (occluders thinner than a pixel on screen, such
//! as blind slats seen from afar; points with no screen neighbours, such as mirror hits); a
//! disagreement in stored depth that does not change any decision cannot change the answer and is
//! not flagged. Footprints that leave the face (cube edges, the paraboloid rim) are undecided.
//! An occluder thinner than a texel that no texel centre of the footprint sees is missed by both
//! tests: that is what resolution buys.

use glam::Vec3;
use rayon::prelude::*;

use crate::map::{ABSENT, EMPTY, LightMap, MapCoord, MapKind};

/// What decides whether a light reaches a point: the light's map (or, on borders, a ray).
/// One byte per pixel and light in occlusion maps ([`crate::border`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Decision {
    /// The light reaches the point.
    Lit = 0,
    /// Something blocks the light.
    Shadow = 1,
    /// No decision is needed: no surface, or the light is behind it.
    #[default]
    NotNeeded = 2,
}

// A texel's three-way verdict inside [`Classifier::classify_at`]; never stored.
const LIT: u8 = 0;
const SHADOW: u8 = 1;
/// An occluder within the bias band of the point: shadowed, and a border.
const AMBIGUOUS: u8 = 3;
/// An occluder with holes (an alpha cut-out) in front of the point: shadowed, and a border
/// that nothing settles but a ray.
const CUTOUT: u8 = 4;

/// Relative margin matching the tracer's shadow rays, which stop `1e-4` of the distance short
/// of the light (`hyrt_tracer::offset::SHADOW_EPSILON`): occluders that close to the light do
/// not count.
pub const SHADOW_EPSILON: f32 = 1e-4;

/// Rounding tolerance of the plane intersection, relative to `r`, in the margins (module docs)
/// and the tile test: `1e-5` is 168 ulps of `2^-24`.
const TOLERANCE: f32 = 1e-5;

/// The rounding of the plane intersection `t = D / (n . dir)` relative to `t`, times
/// `|n . dir|`, for [`Classifier::classify`]'s test of an occluder against the point's own
/// distance. `D` is exact to `f64` rounding ([`Plane`]); `dir` (an `f32` difference, then
/// normalised) is off by a few ulps per component, `n` by one or two, and the `f32` dot
/// product adds three: `n . dir` is off by at most about `4e-7` absolute, so `t` by
/// `4e-7 / |n . dir|` relative. `1e-6` covers it with a factor 2.5. An occluder whose plane
/// the ray meets closer to the point than that cannot be told from the point's own surface
/// by the map: it is left to a ray (ambiguous), unless it lies on the point's very plane.
///
/// Why not a fixed fraction of `r`: an occluder in contact with the point (a post on a floor)
/// is within any fixed fraction of a light far enough away, which would call it the point's
/// own surface, lit, where the reference's shadow ray, offset by the point's own rounding
/// alone, is blocked.
const DIRECTION_ROUNDING: f32 = 1e-6;

/// The plane `n . x = d` of a triangle (`n` unit, `d` in `f64`), for [`Classifier`].
///
/// Why `d` in `f64`: the distance from a light `L` to the plane along a direction is
/// `(d - n . L) / (n . dir)`, and far from the origin `d` and `n . L` are both about `|L|`
/// while their difference is the light's distance to the plane: in `f32` the subtraction
/// cancels and leaves an error of about `|L| 2^-24` (a centimetre at 1e5 metres), where the
/// scene's own scale needs far less. With `d` and `n . L` in `f64` (the products of `f32`
/// factors are exact there) the difference is good to about `|L| 2^-53`, and the error of the
/// intersection is relative to the distance from the light, not to the distance from the origin.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Plane {
    pub n: Vec3,
    pub d: f64,
}

impl Plane {
    /// The plane of a degenerate or non-finite triangle: never occludes by plane (such
    /// triangles are never drawn in maps either).
    pub const ZERO: Plane = Plane { n: Vec3::ZERO, d: 0.0 };

    /// `d - n . q`, in `f64`: the signed distance from `q` to the plane, times -1.
    #[inline]
    pub fn offset_from(&self, q: Vec3) -> f64 {
        let (n, q) = (self.n.as_dvec3(), q.as_dvec3());
        self.d - (n.x * q.x + n.y * q.y + n.z * q.z)
    }
}

/// The plane of each triangle, for [`Classifier`] (see [`Plane`]).
pub fn triangle_planes(tris: &[[Vec3; 3]]) -> Vec<Plane> {
    tris.par_iter()
        .map(|t| {
            let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
            if n == Vec3::ZERO || !t.iter().all(|v| v.is_finite()) {
                Plane::ZERO
            } else {
                // The centroid is the most accurate point of the plane (rounding averages out).
                let c = (t[0].as_dvec3() + t[1].as_dvec3() + t[2].as_dvec3()) / 3.0;
                Plane { n, d: n.as_dvec3().dot(c) }
            }
        })
        .collect()
}

/// Per triangle, the first triangle with the very same plane (the same [`Plane`] to the bit):
/// coplanar triangles of a mesh (a floor, a wall) form one group, which
/// [`LightMap::build_grouped`](crate::LightMap::build_grouped) summarises as one and
/// [`Classifier::hull`] decides as one surface. Triangles without a plane are their own group.
/// Triangles with holes (`cutouts[i]`, as in [`Classifier::cutouts`]; may be empty) are
/// grouped apart from those without, so that a group's first triangle says for all of them.
pub fn plane_groups(planes: &[Plane], cutouts: &[bool]) -> Vec<u32> {
    // Sorted by the plane's bits (and then by index), equal planes are runs whose first
    // element is the group: a parallel sort, where a hash map would insert one at a time.
    let key = |i: u32| {
        let pl = &planes[i as usize];
        let n = pl.n.to_array().map(f32::to_bits);
        let holes = u64::from(cutouts.get(i as usize).is_some_and(|&c| c));
        (u64::from(n[0]) << 32 | u64::from(n[1]), u64::from(n[2]) << 1 | holes, pl.d.to_bits(), i)
    };
    let mut order: Vec<(u64, u64, u64, u32)> = (0..planes.len() as u32).into_par_iter().map(key).collect();
    order.par_sort_unstable();
    let mut groups: Vec<u32> = (0..planes.len() as u32).collect();
    let mut first = 0;
    for k in 0..order.len() {
        let same = |a: &(u64, u64, u64, u32), b: &(u64, u64, u64, u32)| (a.0, a.1, a.2) == (b.0, b.1, b.2);
        if k > 0 && !same(&order[k], &order[first]) {
            first = k;
        }
        let i = order[k].3;
        if planes[i as usize] != Plane::ZERO {
            groups[i as usize] = order[first].3;
        }
    }
    groups
}

/// A bound on the absolute rounding error, per axis, of a point interpolated on one of `tris`
/// as `hyrt_tracer::offset::hit_point` computes it, `v0 + (b1 e1 + b2 e2)`, whose bound is
/// `gamma(1) |p| + gamma(3) (|b1 e1| + |b2 e2|)`: here `gamma(1)` times the largest finite
/// coordinate plus `gamma(3)` times the largest edge component (`|b1| + |b2| <= 1` inside a
/// triangle), for [`Classifier::point_error`].
pub fn point_error_bound(tris: &[[Vec3; 3]]) -> f32 {
    let (coord, edge) = tris
        .par_iter()
        .filter(|t| t.iter().all(|v| v.is_finite()))
        .map(|t| {
            let coord = t[0].abs().max(t[1].abs()).max(t[2].abs()).max_element();
            (coord, (t[1] - t[0]).abs().max((t[2] - t[0]).abs()).max_element())
        })
        .reduce(|| (0.0f32, 0.0f32), |a, b| (a.0.max(b.0), a.1.max(b.1)));
    let gamma = |n: f32| {
        let u = f32::EPSILON * 0.5;
        n * u / (1.0 - n * u)
    };
    // Rounded up by one relative ulp each: the products themselves round.
    (coord * gamma(1.0)).next_up() + (edge * gamma(3.0)).next_up()
}

/// What [`Classifier::hull`] found for a set of points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hull {
    /// Every point is lit, with no border.
    Lit,
    /// Every point is shadowed, with no border.
    Shadowed,
    /// Classify the points one by one.
    Unknown,
}

/// The outcome of classifying one point against one light's map.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Lookup {
    /// The decision of the texel containing the point's projection: [`Decision::Lit`] or
    /// [`Decision::Shadow`].
    pub decision: Decision,
    /// The triangle of that texel when it decided shadow, else the first triangle of the 2x2
    /// footprint that decided shadow, else [`EMPTY`]: the occluder to test first if a ray is
    /// cast.
    pub hint: u32,
    /// Whether the 2x2 footprint disagrees (or leaves the face): a map-space border.
    pub map_border: bool,
    /// Whether the texel's occluder lies within the bias band of the point (the decision is
    /// then [`Decision::Shadow`] and `map_border` is set): a neighbouring triangle's plane past a crease,
    /// or a contact shadow. Lookups without rays may prefer to call it lit.
    pub ambiguous: bool,
    /// When the footprint is a border only because of occluders within the bias band (no
    /// texel decided shadow, and one or two distinct triangles were ambiguous): those
    /// triangles, else [`EMPTY`]. The map cannot tell whether they block the point (a
    /// neighbouring triangle's plane past a crease, or a contact), but the point's own shadow
    /// ray can, by testing them alone: blocked if it meets one, lit otherwise, which is the
    /// ray's answer unless an occluder no texel of the footprint holds blocks it (what
    /// resolution buys, as for every map decision).
    pub suspects: [u32; 2],
    /// For a border ([`Lookup::map_border`]): the distinct triangles of the texel and its
    /// footprint that did not decide lit, up to four, [`EMPTY`]-padded; all [`EMPTY`] when
    /// there are more, when one is a cut-out, when the footprint leaves the face, and for a
    /// lookup that is no border. The texels hold the nearest surface in their directions, so
    /// an occluder of the point that none of these is lies in no texel of the footprint:
    /// testing them alone with the point's shadow ray decides it as the map decides every
    /// point, exactly when one blocks it.
    pub occluders: [u32; 4],
    /// Face and texel of the decision (for inspection).
    pub face: u8,
    pub texel: [u32; 2],
}

/// Decides points against one light's map.
#[derive(Clone, Copy, Debug)]
pub struct Classifier<'a> {
    pub map: &'a LightMap,
    /// [`triangle_planes`] of the triangles the map was built from.
    pub planes: &'a [Plane],
    /// Margin in texel footprints (module docs).
    pub bias: f32,
    /// Absolute rounding error, per axis, of the points classified ([`point_error_bound`] for
    /// points interpolated on the map's triangles; 0 for exact points): added to the margin
    /// (module docs), so that a point moved off its surface by rounding is never shadowed by
    /// its own surface's neighbours, and an occluder that the reference's offset shadow ray
    /// might skip is left to a ray.
    pub point_error: f32,
    /// Per triangle id, whether it has holes (alpha cut-outs); empty when none has. A map that
    /// does not [resolve holes](LightMap::resolves_holes) holds such a triangle solid, so where
    /// its texel would shadow a point, the point is undecided instead: a ray, which sees the
    /// holes, decides. A map that resolves them decides as for any occluder, at its texels'
    /// centres: a footprint that straddles a hole's edge disagrees, and is a border.
    pub cutouts: &'a [bool],
}

impl Classifier<'_> {
    /// The distance from the light to the surface texel `(x, y)` of `face` at `level` holds,
    /// along the texel centre's direction: the stored depth ([`LightMap::depth_at`]) where the
    /// map has one, else (a paged map) where that direction meets the plane of the texel's
    /// triangle. `f32::INFINITY` for an empty texel or one not drawn; NaN where the plane is
    /// seen edge-on and no depth is stored.
    pub fn depth_at(&self, level: u8, face: u8, x: u32, y: u32) -> f32 {
        let d = self.map.depth_at(level, face, x, y);
        if !d.is_nan() {
            return d;
        }
        let id = self.map.id_at(level, face, x, y);
        let Some(pl) = self.planes.get(id as usize).filter(|pl| pl.n != Vec3::ZERO) else { return f32::NAN };
        let dir = self.map.texel_dir_at(face, level, f64::from(x) + 0.5, f64::from(y) + 0.5);
        let cos = pl.n.dot(dir);
        if cos.abs() < 1e-6 { f32::NAN } else { (pl.offset_from(self.map.light()) / f64::from(cos)) as f32 }
    }

    /// Classifies point `p` of triangle `own` (module docs). `p` must differ from the light.
    #[inline]
    pub fn classify(&self, p: Vec3, own: u32) -> Lookup {
        self.classify_at(p, own, self.locate(p))
    }

    /// Where `p` falls in the map: the first half of [`Classifier::classify`], for callers that
    /// pick the level themselves ([`Classifier::locate_at`]) or keep the location.
    #[inline]
    pub fn locate(&self, p: Vec3) -> MapCoord {
        self.map.coord(p - self.map.light())
    }

    /// Where `p` falls in the map at level `level` (paged maps; [`Classifier::locate`] is
    /// level 0).
    #[inline]
    pub fn locate_at(&self, p: Vec3, level: u8) -> MapCoord {
        self.map.coord_at(p - self.map.light(), level)
    }

    /// What [`Classifier::classify`] decides for every point in the convex hull of `corners`
    /// (points of `own`'s plane) that lies on `own` or on another triangle of `own`'s very
    /// [`Plane`] (see below), found from the map region under the corners alone: [`Hull::Lit`]
    /// or [`Hull::Shadowed`] (each with no border), or [`Hull::Unknown`] when it cannot tell
    /// (then classify the points one by one).
    ///
    /// Why it holds: the directions from the light that a cube face covers form a convex cone,
    /// so if every corner falls on one face, so does their hull; and within a face the map is a
    /// central projection, which takes the hull (on one plane) to the convex polygon of the
    /// corners' projections. Every point's 2x2 footprint then lies in the corners' bounding
    /// box, grown by half a texel for the footprint and by a margin for rounding: the points
    /// sit up to `sqrt(3) e` off the plane (`e` = [`Classifier::point_error`], with a factor
    /// 16 of slack for how their barycentrics were found), which seen from at least the plane's
    /// distance `h` turns their direction by up to `sqrt(3) e / h` radians, or
    /// `sqrt(3) e / h * res` texels (face coordinates move by at most 2 per radian, and there
    /// are `res / 2` texels per unit), plus one texel for the coordinates' own rounding. That
    /// box must stay inside the face ([`LightMap::region_id`] then says what it sees):
    ///
    /// - nothing, or only `own`, or only triangles whose [`Plane`] is `own`'s to the bit (its
    ///   group, in a map made by [`LightMap::build_grouped`](crate::LightMap::build_grouped)):
    ///   every footprint decides lit, as the per-point test calls a triangle of the point's
    ///   very plane lit;
    /// - other triangles: each texel of every footprint decides by its triangle's plane, and a
    ///   test of the plane at the corners (`over_hull`) finds when it decides the same for
    ///   every point of the hull (lit, or shadowed with no bias band). When every triangle
    ///   seen decides lit, or every one shadowed, so does every footprint, with no border. The
    ///   summaries say which triangles the box sees where one triangle (or one group of a
    ///   plane) fills it; otherwise its texels are read ([`LightMap::region_ids`]).
    ///
    /// At most [`HULL_CORNERS`] corners (more: [`Hull::Unknown`]).
    /// The corners are located at level `level` (0 for whole maps), and the region read there.
    /// Paraboloid maps are not central projections: always [`Hull::Unknown`].
    pub fn hull(&self, corners: &[Vec3], own: u32, level: u8) -> Hull {
        let map = self.map;
        let Some(first) = corners.first().filter(|_| corners.len() <= HULL_CORNERS) else {
            return Hull::Unknown;
        };
        let Some(pl) = self.planes.get(own as usize) else { return Hull::Unknown };
        if map.kind() != MapKind::Cube || pl.n == Vec3::ZERO {
            return Hull::Unknown;
        }
        let light = map.light();
        let e = 16.0 * 3f32.sqrt() * self.point_error;
        let h = pl.offset_from(light).abs() as f32 - e;
        let res = map.resolution_at(level) as f32;
        let margin = 1.5 + e / h * res;
        if !(h > 0.0 && margin < res) {
            return Hull::Unknown;
        }
        let margin = f64::from(margin);
        let c0 = self.locate_at(*first, level);
        let (mut lo, mut hi) = ((c0.x, c0.y), (c0.x, c0.y));
        for &p in &corners[1..] {
            let c = self.locate_at(p, level);
            if c.face != c0.face {
                return Hull::Unknown;
            }
            lo = (lo.0.min(c.x), lo.1.min(c.y));
            hi = (hi.0.max(c.x), hi.1.max(c.y));
        }
        let (x0, y0) = (floor(lo.0 - margin), floor(lo.1 - margin));
        let (x1, y1) = (floor(hi.0 + margin), floor(hi.1 + margin));
        let last = f64::from(res) - 1.0;
        if !(x0 >= 0.0 && y0 >= 0.0 && x1 <= last && y1 <= last) {
            return Hull::Unknown;
        }
        let (x0, y0, x1, y1) = (x0 as u32, y0 as u32, x1 as u32, y1 as u32);
        let far = 1.0 - (2.0 * self.bias / res + TOLERANCE + 2.0 * e / h) as f64;
        let hc = HullCorners::new(corners, light, e);
        // What every texel holding `id` decides for every point (see `Classifier::over_hull`).
        let judge = |id: u32| -> Hull {
            if id == EMPTY || id == own {
                return Hull::Lit;
            }
            match self.planes.get(id as usize) {
                // A triangle of the points' very plane cannot shadow them.
                Some(occ) if *occ == *pl => Hull::Lit,
                Some(occ) if occ.n != Vec3::ZERO && id != ABSENT => {
                    self.over_hull(occ, self.has_holes(id), &hc, far)
                }
                _ => Hull::Unknown,
            }
        };
        match map.region_id(c0.face, level, x0, y0, x1, y1) {
            Some(id) => return judge(id),
            // Several triangles: perhaps all of one plane (own's, or an occluder's), whose
            // group's first triangle has their plane, and their holes (`plane_groups`).
            None => {
                if let Some(g) = map.region_group(c0.face, level, x0, y0, x1, y1) {
                    return judge(g);
                }
            }
        }
        // Several planes: every triangle seen must decide the same for every point. Runs of
        // texels repeat ids: the last few verdicts are kept.
        let (mut lit, mut shadowed) = (false, false);
        let mut known = [(EMPTY, Hull::Lit); 8];
        let mut next = 0;
        let agreed = map.region_ids(c0.face, level, x0, y0, x1, y1, |id| {
            let verdict = match known.iter().find(|k| k.0 == id) {
                Some(k) => k.1,
                None => {
                    let v = judge(id);
                    known[next] = (id, v);
                    next = (next + 1) % known.len();
                    v
                }
            };
            lit |= verdict == Hull::Lit;
            shadowed |= verdict == Hull::Shadowed;
            verdict != Hull::Unknown && !(lit && shadowed)
        });
        match (agreed, lit, shadowed) {
            (true, true, false) => Hull::Lit,
            (true, false, true) => Hull::Shadowed,
            _ => Hull::Unknown,
        }
    }

    /// What a texel holding a triangle of plane `occ` (not the points' own; `holes` if it has
    /// holes) decides for every point of [`Classifier::hull`]'s hull of `corners` (its bounds:
    /// `e` the points' offset from the hull, `far` the margin's limit): [`Hull::Shadowed`] when
    /// every point is shadowed by it with no bias band, [`Hull::Lit`] when it blocks none
    /// (it meets every point's ray from the light beyond the point, or behind the light),
    /// else [`Hull::Unknown`].
    ///
    /// From the light `L`, the ray towards `p` meets the plane at `t = r D / g(p)`, with `r =
    /// |p - L|`, `D` the plane's offset from `L` and `g(p) = n . (p - L)`, which is linear in
    /// `p`: where `g` keeps its sign over the hull, `t / r = D / g` takes its extremes at the
    /// corners (`g` widened by the points' offsets `e`, `|n| = 1`). The per-point test calls
    /// the texel lit when `t <= SHADOW_EPSILON r` or `t >= r - 1e-6 r / |n . dir|`
    /// ([`DIRECTION_ROUNDING`]); `t / r >= 1 - 1e-7` at every corner meets the second with room
    /// for the per-point rounding of `t` and `r` (a few `1e-7 / |n . dir|` in all), and `t / r
    /// < SHADOW_EPSILON (1 - 1e-4)` the first. Shadowed: `t / r` strictly between
    /// `SHADOW_EPSILON` and `far`, each with a relative slack of `1e-4`. Either way the plane
    /// is never seen edge-on (`|g| / r` above the `1e-6` below which the per-point test reads
    /// the stored depth, with a factor 2: the smallest `|g|` over the largest `r`, `r` being
    /// convex). A cut-out shadows nothing here: its holes are not in the map.
    fn over_hull(&self, occ: &Plane, holes: bool, corners: &HullCorners, far: f64) -> Hull {
        let d = occ.offset_from(self.map.light());
        let (mut g_lo, mut g_hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in &corners.v[..corners.n] {
            let g = f64::from(occ.n.dot(*v));
            g_lo = g_lo.min(g);
            g_hi = g_hi.max(g);
        }
        let e = corners.e;
        // `g` over the hull, widened: one sign, the smallest and the largest `|g|`.
        let (near, far_g) = if g_lo - e > 0.0 {
            (g_lo - e, g_hi + e)
        } else if g_hi + e < 0.0 {
            (g_hi + e, g_lo - e)
        } else {
            return Hull::Unknown;
        };
        // (NaN-safe: a NaN bound declines.)
        if near.abs().partial_cmp(&(2e-6 * corners.r_max)) != Some(std::cmp::Ordering::Greater) {
            return Hull::Unknown;
        }
        let (a, b) = (d / near, d / far_g);
        let (lo, hi) = (a.min(b), a.max(b));
        if lo >= 1.0 - 1e-7 || hi < f64::from(SHADOW_EPSILON) * (1.0 - 1e-4) {
            Hull::Lit
        } else if !holes && lo > f64::from(SHADOW_EPSILON) * (1.0 + 1e-4) && hi < far * (1.0 - 1e-4) {
            Hull::Shadowed
        } else {
            Hull::Unknown
        }
    }

    /// Visibility from the texel under `p` alone, ambiguous occluders counted as the point's own
    /// surface: for lookups that no ray will check (VPL maps, where each VPL's share of the
    /// light is small and aliasing is diluted). Cheaper than [`Classifier::classify`]: no
    /// footprint, usually one texel load and no arithmetic.
    #[inline]
    pub fn visible(&self, p: Vec3, own: u32) -> bool {
        self.visible_at(p, own, self.locate(p))
    }

    /// [`Classifier::visible`] with `p`'s location `c` from [`Classifier::locate`].
    #[inline]
    pub fn visible_at(&self, p: Vec3, own: u32, c: MapCoord) -> bool {
        let map = self.map;
        let last = map.resolution_at(c.level).saturating_sub(1);
        let (ix, iy) = ((c.x.max(0.0) as u32).min(last), (c.y.max(0.0) as u32).min(last));
        let id = map.id_at(c.level, c.face, ix, iy);
        // A page a paged map did not draw tells nothing: visible, as an empty texel.
        if id == EMPTY || id == own || id == ABSENT {
            return true;
        }
        Occluders::new(self, p, own, c).visible(id, (ix, iy))
    }

    /// [`Classifier::visible`] filtered over the 2x2 texels whose centres surround `p`'s
    /// projection (percentage-closer filtering): the sum of the bilinear weights of the texels
    /// that [`Classifier::visible_at`]'s rule calls visible, in `[0, 1]`.
    ///
    /// Why: a lone texel decides visibility for everything within half a texel of its centre,
    /// so a shadow edge in the map becomes a staircase on the receiver, displaced by up to half
    /// a texel's footprint. Summed over many VPLs with rays, each edge is exactly where it is;
    /// the filtered value is the expected visibility over a texel-sized neighbourhood, which on
    /// average sits closer to it. Footprints that leave the face or the paraboloid's disc use
    /// the texel under `p` alone. Still lookups only: no rays.
    #[inline]
    pub fn visibility_at(&self, p: Vec3, own: u32, c: MapCoord) -> f32 {
        let map = self.map;
        let Footprint { texels: foot, in_domain, offset: (ax, ay), .. } = Footprint::of(map, c);
        if !in_domain {
            return if self.visible_at(p, own, c) { 1.0 } else { 0.0 };
        }
        let foot_ids = foot.map(|(x, y)| match map.id_at(c.level, c.face, x, y) {
            ABSENT => EMPTY,
            id => id,
        });
        if foot_ids.iter().all(|&id| id == EMPTY || id == own) {
            return 1.0;
        }
        let weights = [(1.0 - ax) * (1.0 - ay), ax * (1.0 - ay), (1.0 - ax) * ay, ax * ay];
        let occ = Occluders::new(self, p, own, c);
        let mut v = 0.0;
        for ((&id, &xy), w) in foot_ids.iter().zip(&foot).zip(weights) {
            if id == EMPTY || id == own || occ.visible(id, xy) {
                v += w;
            }
        }
        v
    }

    /// How far along the ray from the light the rounding of a point of triangle `own` can move
    /// it: `sqrt(3) e (1 + 1 / |n . dir|)` for the per-axis error `e` ([`Classifier::point_error`]).
    /// The point lies up to `|n|_1 e <= sqrt(3) e` off its plane, which along a ray meeting the
    /// plane at cosine `n . dir` is `sqrt(3) e / |n . dir|`, and its distance from the light is
    /// off by up to `sqrt(3) e`. The reference's shadow ray starts that far off the surface
    /// (`hyrt_tracer::offset`), so occluders within the band are left to a ray. Infinite (every
    /// occluder left to a ray) when `own` has no plane or is seen edge-on.
    #[inline]
    fn rounding_band(&self, own: u32, dir: Vec3) -> f32 {
        if self.point_error == 0.0 {
            return 0.0;
        }
        let e = self.point_error * 3f32.sqrt();
        let cos = self.planes.get(own as usize).map_or(0.0, |pl| pl.n.dot(dir).abs());
        if cos > 0.0 { e + e / cos } else { f32::INFINITY }
    }

    /// A likely occluder of a point of triangle `own` located at `c`, for a shadow ray to test
    /// first: the triangle the point's texel holds, else one of its 2x2 footprint's, if it is
    /// neither `own` nor of `own`'s very plane ([`EMPTY`] if none). It decides nothing (a ray
    /// is exact with any hint), so it is cheaper than [`Classifier::classify_at`]'s hint (the
    /// first texel that decides shadow): texel loads and compares, no plane intersection.
    #[inline]
    pub fn hint_at(&self, own: u32, c: MapCoord) -> u32 {
        let (_, Footprint { inside, .. }, ids) = self.texel_ids(c);
        let own_plane = self.planes.get(own as usize).copied().unwrap_or(Plane::ZERO);
        let other = |id: u32| {
            id != own
                && id != EMPTY
                && id != ABSENT
                && (own_plane == Plane::ZERO || self.planes.get(id as usize) != Some(&own_plane))
        };
        ids[..if inside { 5 } else { 1 }].iter().copied().find(|&id| other(id)).unwrap_or(EMPTY)
    }

    /// The texel under `c` (clamped to the face), its 2x2 footprint, and the ids of the texel
    /// and of the footprint's four, each page looked up once.
    #[inline]
    fn texel_ids(&self, c: MapCoord) -> ((u32, u32), Footprint, [u32; 5]) {
        let map = self.map;
        let last = map.resolution_at(c.level).saturating_sub(1);
        let (ix, iy) = ((c.x.max(0.0) as u32).min(last), (c.y.max(0.0) as u32).min(last));
        let fp = Footprint::of(map, c);
        let foot = fp.texels;
        // A footprint within the face holds the point's texel: one of its four (the column and
        // row the point falls in). Looked up in one page where it lies in one.
        let (x0, y0) = foot[0];
        if fp.inside
            && let Some(q) = map.quad_ids(c.level, c.face, x0, y0)
        {
            let centre = q[usize::from(iy != y0) * 2 + usize::from(ix != x0)];
            return ((ix, iy), fp, [centre, q[0], q[1], q[2], q[3]]);
        }
        let ids = map.ids_at(c.level, c.face, [(ix, iy), foot[0], foot[1], foot[2], foot[3]]);
        ((ix, iy), fp, ids)
    }

    /// [`Classifier::classify`] with `p`'s location `c` from [`Classifier::locate`].
    #[inline]
    pub fn classify_at(&self, p: Vec3, own: u32, c: MapCoord) -> Lookup {
        let map = self.map;
        let light = map.light();
        let v = p - light;
        let ((ix, iy), Footprint { texels: foot, inside, in_domain, .. }, ids) = self.texel_ids(c);
        let [centre, f0, f1, f2, f3] = ids;
        let foot_ids = if inside { [f0, f1, f2, f3] } else { [centre; 4] };
        let texel = [ix, iy];

        // A texel in a page that a paged map did not draw: the map cannot tell (a ray decides).
        if centre == ABSENT || foot_ids.contains(&ABSENT) {
            return Lookup {
                decision: Decision::Lit,
                hint: EMPTY,
                map_border: true,
                ambiguous: false,
                suspects: [EMPTY; 2],
                occluders: [EMPTY; 4],
                face: c.face,
                texel,
            };
        }

        // Most points see only their own triangle (or nothing) all around: lit, no border, and
        // no arithmetic. This is the rule below with every texel deciding `LIT`.
        if in_domain && foot_ids.iter().all(|&id| id == own || id == EMPTY) {
            return Lookup {
                decision: Decision::Lit,
                hint: EMPTY,
                map_border: false,
                ambiguous: false,
                suspects: [EMPTY; 2],
                occluders: [EMPTY; 4],
                face: c.face,
                texel,
            };
        }

        let r = v.length();
        let dir = v / r;
        // The reference's shadow ray from `p` ignores occluders within `SHADOW_EPSILON r` of
        // the light, and (by its origin offset) only those within rounding of `p`. Occluders
        // between `r - margin` and `r - tol` may be a neighbouring triangle's plane extended
        // past a crease, or a true contact shadow: undecided (module docs).
        let near = SHADOW_EPSILON * r;
        let tol = TOLERANCE * r;
        let margin = self.bias * map.texel_angle(c) * r + tol + self.rounding_band(own, dir);
        let own_plane = self.planes.get(own as usize).copied().unwrap_or(Plane::ZERO);
        let decide = |id: u32, (x, y): (u32, u32)| -> u8 {
            if id == EMPTY || id == own {
                return LIT;
            }
            let pl = self.planes.get(id as usize).copied().unwrap_or(Plane::ZERO);
            // A triangle of the point's very plane cannot shadow it.
            if pl == own_plane && pl != Plane::ZERO {
                return LIT;
            }
            let cos = pl.n.dot(dir);
            let (t, tol) = if cos.abs() >= 1e-6 {
                ((pl.offset_from(light) / f64::from(cos)) as f32, DIRECTION_ROUNDING * r / cos.abs())
            } else {
                match map.depth_at(c.level, c.face, x, y) {
                    // No depth stored (a paged map): a ray decides.
                    d if d.is_nan() => return AMBIGUOUS,
                    d => (d, tol),
                }
            };
            if !(t > near && t < r - tol) {
                LIT
            } else if self.has_holes(id) && !map.resolves_holes() {
                CUTOUT
            } else if t < r - margin {
                SHADOW
            } else {
                AMBIGUOUS
            }
        };
        let d = decide(centre, (ix, iy));
        let mut hint = if d != LIT { centre } else { EMPTY };
        // An ambiguous texel leans to shadow (an occluder is there, only closer than the bias
        // can tell), and is a border.
        let decision = if d == LIT { Decision::Lit } else { Decision::Shadow };
        let mut map_border = d == AMBIGUOUS || d == CUTOUT || !in_domain;
        // The ambiguous triangles (up to two; a third, or a texel deciding shadow, leaves
        // none), for `suspects`. A cut-out settles nothing: what its holes let through may
        // meet an occluder that no texel holds.
        let (mut amb, mut na) = ([centre, EMPTY], usize::from(d == AMBIGUOUS));
        let mut settles = d != SHADOW && d != CUTOUT && in_domain;
        let (mut occ, mut no) = ([EMPTY; 4], 0usize);
        let mut occ_ok = in_domain && d != CUTOUT;
        if d != LIT {
            occ[0] = centre;
            no = 1;
        }
        // (A border already, and not settled: a cut-out or a footprint off the face, which
        // names no occluders either.)
        if in_domain && (!map_border || settles) {
            // Most footprints see one or two triangles: decide each once.
            let (mut seen, mut n) = ([centre, EMPTY, EMPTY, EMPTY], 1);
            for (&id, &xy) in foot_ids.iter().zip(&foot) {
                if seen[..n].contains(&id) {
                    continue;
                }
                seen[n] = id;
                n += 1;
                let d = decide(id, xy);
                map_border |= d != decision as u8;
                if d != LIT && !occ[..no].contains(&id) {
                    if d == CUTOUT || no == 4 {
                        occ_ok = false;
                    } else {
                        occ[no] = id;
                        no += 1;
                    }
                }
                if d != LIT && hint == EMPTY {
                    hint = id;
                }
                settles &= d != SHADOW && d != CUTOUT;
                if d == AMBIGUOUS {
                    settles &= na < 2;
                    if na < 2 {
                        amb[na] = id;
                        na += 1;
                    }
                }
            }
        }
        let suspects = if map_border && settles && na > 0 { [amb[0], amb[1]] } else { [EMPTY; 2] };
        let occluders = if map_border && occ_ok { occ } else { [EMPTY; 4] };
        Lookup {
            decision,
            hint,
            map_border,
            ambiguous: d == AMBIGUOUS,
            suspects,
            occluders,
            face: c.face,
            texel,
        }
    }

    /// Whether triangle `id` has holes ([`Classifier::cutouts`]).
    #[inline]
    fn has_holes(&self, id: u32) -> bool {
        self.cutouts.get(id as usize).is_some_and(|&c| c)
    }
}

/// The corners of [`Classifier::hull`] as [`Classifier::over_hull`] reads them for every
/// plane: their offsets from the light, the points' offset `e` from the hull, and the largest
/// distance from the light (`r` is convex: largest at a corner), widened by `e`.
struct HullCorners {
    v: [Vec3; HULL_CORNERS],
    n: usize,
    e: f64,
    r_max: f64,
}

/// The most corners [`Classifier::hull`] takes.
pub const HULL_CORNERS: usize = 8;

impl HullCorners {
    /// `corners` (at most [`HULL_CORNERS`]) seen from `light`, of points up to `e` off their
    /// hull.
    fn new(corners: &[Vec3], light: Vec3, e: f32) -> Self {
        let mut v = [Vec3::ZERO; HULL_CORNERS];
        let n = corners.len().min(HULL_CORNERS);
        v.iter_mut().zip(corners).for_each(|(v, &p)| *v = p - light);
        let r_max = v[..n].iter().map(|v| f64::from(v.length())).fold(0.0, f64::max) + f64::from(e);
        Self { v, n, e: f64::from(e), r_max }
    }
}

/// `v.floor()` for texel coordinates (`|v| < 2^62`; NaN gives 0), by conversions: without
/// SSE4.1 in the target, `f64::floor` is a call into libm, in the classifier's inner loop.
#[inline]
fn floor(v: f64) -> f64 {
    let t = v as i64 as f64;
    if t > v { t - 1.0 } else { t }
}

/// The 2x2 texels whose centres surround a point's projection `c` (the texel containing it is
/// one of them).
struct Footprint {
    texels: [(u32, u32); 4],
    /// Whether all four lie within the face (else `texels` is meaningless).
    inside: bool,
    /// Whether all four are in the face's domain too (the paraboloid's disc).
    in_domain: bool,
    /// `c`'s offset from the first texel's centre, in `[0, 1)` per axis: the bilinear weights.
    offset: (f32, f32),
}

impl Footprint {
    #[inline]
    fn of(map: &LightMap, c: MapCoord) -> Self {
        let last = f64::from(map.resolution_at(c.level).saturating_sub(1));
        let (fx, fy) = (floor(c.x - 0.5), floor(c.y - 0.5));
        let inside = fx >= 0.0 && fy >= 0.0 && fx + 1.0 <= last && fy + 1.0 <= last;
        let (x0, y0) = (fx as u32, fy as u32);
        let texels = [(x0, y0), (x0 + 1, y0), (x0, y0 + 1), (x0 + 1, y0 + 1)];
        let in_domain = inside
            && (map.kind() == MapKind::Cube
                || texels.iter().all(|&(x, y)| map.texel_in_domain(c.face, x, y)));
        Self { texels, inside, in_domain, offset: ((c.x - 0.5 - fx) as f32, (c.y - 0.5 - fy) as f32) }
    }
}

/// The per-point part of [`Classifier::visible_at`]'s rule, shared by the texels of a
/// footprint: the point's distance and direction from the light and its margin.
struct Occluders<'c, 'a> {
    cls: &'c Classifier<'a>,
    face: u8,
    level: u8,
    light: Vec3,
    r: f32,
    dir: Vec3,
    margin: f32,
}

impl<'c, 'a> Occluders<'c, 'a> {
    #[inline]
    fn new(cls: &'c Classifier<'a>, p: Vec3, own: u32, c: MapCoord) -> Self {
        let light = cls.map.light();
        let v = p - light;
        let r = v.length();
        let dir = v / r;
        let margin = cls.bias * cls.map.texel_angle(c) * r + TOLERANCE * r + cls.rounding_band(own, dir);
        Self { cls, face: c.face, level: c.level, light, r, dir, margin }
    }

    /// Whether triangle `id` (not empty, not the point's own), seen at texel `(x, y)`, leaves
    /// the point visible: it meets the ray from the light beyond the margin band, or within
    /// `SHADOW_EPSILON r` of the light; an occluder within the band counts as the point's own
    /// surface, and so does one seen edge-on where the map stores no depth (a paged map).
    #[inline]
    fn visible(&self, id: u32, (x, y): (u32, u32)) -> bool {
        let pl = self.cls.planes.get(id as usize).copied().unwrap_or(Plane::ZERO);
        let cos = pl.n.dot(self.dir);
        let t = if cos.abs() >= 1e-6 {
            (pl.offset_from(self.light) / f64::from(cos)) as f32
        } else {
            self.cls.map.depth_at(self.level, self.face, x, y)
        };
        !(t > SHADOW_EPSILON * self.r && t < self.r - self.margin)
    }
}
