//! hyrt-tracer: ray casting against triangles with an obvhs CWBVH.
//!
//! Plain slices in, plain structs out: the tracer knows nothing of scenes, materials or files.
//! It gives closest hits and occlusion tests that are
//! - **watertight** ([`triangle`]: Woop, Benthin and Wald 2013, with pbrt-v4's conservative
//!   `t > 0` bound), so rays through shared edges and vertices never slip between triangles;
//! - **nearest first, then deterministic**: of two hits, the nearer wins wherever rounding can
//!   tell them apart: by their `f32` distances beyond those distances' error bounds
//!   ([`TriHit::err`]), else by the same computation in `f64` beyond its own bounds
//!   ([`plane_distance_f64`]). Only hits closer than that (coplanar duplicates, decals) are a
//!   tie, which goes to a face the ray enters, then to the smaller original triangle id,
//!   whatever order the BVH visits them in;
//! - **free of self-intersection without magic epsilons**: hit points carry a rounding-error
//!   bound and new rays start from an origin offset just past it ([`offset`]);
//! - **counted** by kind ([`RayCounts`]), per caller, so parallel passes reduce in a fixed order.
//!
//! ```
//! use glam::Vec3;
//! use hyrt_tracer::{Ray, RayCounts, RayKind, Tracer};
//!
//! // A unit square in the z = 0 plane, as two triangles sharing the diagonal.
//! let (a, b, c, d) = (Vec3::new(0.0, 0.0, 0.0), Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y);
//! let tracer = Tracer::build(&[[a, b, c], [a, c, d]]);
//! let mut counts = RayCounts::default();
//!
//! // Straight down through the shared diagonal: watertight, so it hits, at distance 1.
//! let down = Ray::new(Vec3::new(0.5, 0.5, 1.0), Vec3::NEG_Z, f32::INFINITY);
//! let hit = tracer.closest_hit(&down, RayKind::Primary, &mut counts).expect("the square");
//! assert_eq!(hit.t, 1.0);
//! // Beside the square: nothing to hit, nothing blocks.
//! let beside = Ray::new(Vec3::new(2.0, 0.5, 1.0), Vec3::NEG_Z, f32::INFINITY);
//! assert!(!tracer.occluded(&beside, RayKind::Shadow, &mut counts));
//! assert_eq!((counts.primary, counts.shadow), (1, 1));
//! ```

pub mod batch;
pub mod counts;
pub mod offset;
pub mod orient;
pub mod triangle;

use std::sync::{Mutex, OnceLock};
use std::thread::JoinHandle;
use std::time::Duration;

use glam::{Vec3, Vec3A};
use obvhs::{
    BvhBuildParams,
    cwbvh::{CwBvh, builder::build_cwbvh},
    ray::{Ray as ObRay, RayHit},
    triangle::Triangle,
};

pub use batch::RowRays;
pub use counts::{RayCounts, RayKind};
pub use hyrt_simd::{Isa, Tier};
pub use offset::{offset_ray_origin, ray_to, spawn_ray, spawn_ray_to};
pub use orient::{PlaneSide, plane_side};
pub use triangle::{RayPrecomp, TriHit, intersect_plane, intersect_triangle, plane_distance_f64};

/// The rasterizer's relative depth window for a depth tie, `2^-16` (15 micrometres per metre),
/// and how far past its best hit a closest-hit traversal keeps looking.
///
/// Why the rasterized G-buffer needs a window: its depths are `f32` values of a plane through
/// corners projected in `f32`, good to a few ulps, so two surfaces closer than that are not
/// ordered by them. Within the window the z-buffer decides by the tie rule (a face the camera's
/// ray enters, then the smaller id), as the tracer does for its own ties, and marks the pixel
/// contested (`hyrt_raster::Target::contested`): the renderer casts that pixel's ray, which
/// orders the surfaces exactly where they can be ordered at all (module docs). 128 times the
/// f32 unit roundoff: above the rasterizer's depth error, and far below any gap between
/// surfaces meant to be distinct, so that contested pixels are few.
///
/// Why the traversal looks past its best hit: a hit farther than the best by less than their
/// error bounds may still be the nearer, or win a tie; nodes within this window are visited.
pub const DEPTH_TIE: f32 = 1.0 / 65536.0;

/// True when distances `a` and `b` lie within [`DEPTH_TIE`] of each other (the rasterizer's
/// window; the tracer orders such hits by their error bounds).
#[inline]
pub fn depth_tie(a: f32, b: f32) -> bool {
    (a - b).abs() <= DEPTH_TIE * a.max(b)
}

/// Padding of every triangle's box in the BVH, in the tracer's scaled frame (coordinates of
/// magnitude below `2^20`, see [`Tracer::build`]): 2 units, 16 to 32 ulps of the largest
/// coordinates.
///
/// Why: obvhs's ray-box test is not conservative. Its slab distances
/// `(q * extent + (node - o)) / d` are rounded (a few ulps of `|node - o| < 2^21` for a ray
/// starting inside the scene's bounds, about a quarter unit), so a ray that meets a triangle
/// lying on a face of its node's box (axis-aligned geometry: every box of a furnished room)
/// can miss the box by an ulp while the watertight triangle test hits it. Shadow rays then
/// leak through the edges of boxes, and a ray that tests its occluder hint first (which never
/// visits a box) disagrees with the same ray traversed. Boxes larger by 2 units than their
/// triangles contain every such rounding; the cost is nil (a millionth of the scene's extent).
/// Rays that start farther than the scene's bounds from it (a distant camera) are not covered
/// by this bound: the rounding of `node - o` grows with the origin's distance. Measured on a
/// grid seen head-on (`tests/hard_cases.rs`): no ray misses from up to 1e5 times the scene's
/// size away; from 1e6 the traversal loses hits that the triangle test alone finds.
const BOX_PAD: f32 = 2.0;

/// Whether a hit at distance `ta.2` (error bound `ta.3`) on triangle `ta.0` (id `ta.1`) comes
/// before one on `tb` along the ray from `o` in direction `dir` (the scaled frame), the
/// closest-hit rule (module docs): by their `f32` distances where those differ by more than
/// their error bounds; else [`near_tie`].
#[inline(always)]
fn before(o: Vec3A, dir: Vec3A, ta: (&[Vec3A; 3], u32, f32, f32), tb: (&[Vec3A; 3], u32, f32, f32)) -> bool {
    if (ta.2 - tb.2).abs() > ta.3 + tb.3 { ta.2 < tb.2 } else { near_tie(o, dir, (ta.0, ta.1), (tb.0, tb.1)) }
}

/// [`before`] for two hits that `f32` cannot order: by their `f64` distances
/// ([`plane_distance_f64`]) where those differ by more than their bounds, else by the tie key
/// (faces the ray from `o` leaves after those it enters, then the smaller id). Out of line: it
/// runs for a few hits in millions, and inlined into the traversal's loop it cost that loop
/// registers.
#[cold]
#[inline(never)]
fn near_tie(o: Vec3A, dir: Vec3A, (ta, ida): (&[Vec3A; 3], u32), (tb, idb): (&[Vec3A; 3], u32)) -> bool {
    match (plane_distance_f64(o, dir, ta), plane_distance_f64(o, dir, tb)) {
        (Some((t1, e1)), Some((t2, e2))) if (t1 - t2).abs() > e1 + e2 => t1 < t2,
        _ => {
            let key = |t: &[Vec3A; 3], id: u32| {
                (plane_side(&t.map(Vec3::from), Vec3::from(o)) != PlaneSide::Front, id)
            };
            key(ta, ida) < key(tb, idb)
        }
    }
}

/// A triangle whose BVH box is padded by [`BOX_PAD`].
struct Padded(Triangle);

impl obvhs::Boundable for Padded {
    fn aabb(&self) -> obvhs::aabb::Aabb {
        let b = self.0.aabb();
        obvhs::aabb::Aabb::new(b.min - Vec3A::splat(BOX_PAD), b.max + Vec3A::splat(BOX_PAD))
    }
}

/// Alpha cut-outs: triangles with holes (leaves, fences, grilles drawn by a texture's alpha).
///
/// The tracer knows no textures: [`Tracer::with_cutouts`] gives it this test, and a hit on a
/// triangle that [`Cutouts::has_holes`] names counts only where [`Cutouts::solid`] says so, in
/// every query that reports or blocks ([`Tracer::closest_hit`], [`Tracer::occluded`],
/// [`Tracer::occluded_with_hint`], [`Tracer::hits_triangle`]); a ray passes through the holes
/// as if the triangle were not there. Plane queries ([`Tracer::hit_on_plane`], the row hits of
/// [`batch`]) are geometric and ignore it. The test must be a pure function of its arguments:
/// every ray that meets the same point of the same triangle gets the same answer, whatever its
/// kind, which is what keeps rays and maps in agreement.
pub trait Cutouts: Send + Sync {
    /// Whether triangle `tri` (original id) may have holes; `false` skips [`Cutouts::solid`].
    fn has_holes(&self, tri: u32) -> bool;
    /// Whether the point of triangle `tri` at barycentrics `bary` (corners 0, 1, 2) is solid.
    fn solid(&self, tri: u32, bary: [f32; 3]) -> bool;
}

/// A ray with a normalised direction; hits are accepted for `0 < t < tmax`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
    pub tmax: f32,
}

impl Ray {
    pub fn new(origin: Vec3, dir: Vec3, tmax: f32) -> Self {
        Self { origin, dir, tmax }
    }
}

/// A closest hit: distance, original triangle id and barycentrics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    /// The triangle's index in the slice given to [`Tracer::build`].
    pub tri: u32,
    /// Barycentric weights of corners 0, 1, 2 (sum to 1).
    pub bary: [f32; 3],
}

/// A BVH over triangles, built once per scene.
pub struct Tracer {
    /// The BVH, once built ([`Tracer::build`], or [`Tracer::build_in_background`] when a
    /// query first needs it).
    built: OnceLock<Bvh>,
    /// [`Tracer::build_in_background`]'s build, until a query takes its result.
    pending: Mutex<Option<JoinHandle<Bvh>>>,
    /// Every triangle given to [`Tracer::build`], by original id, in the scaled frame (`p * scale`,
    /// non-finite ones included): single-triangle tests by id ([`Tracer::hits_triangle`], the
    /// plane hits of [`batch`]) read their vertices from here instead of scaling them per call.
    /// The product is the same one the BVH's copy gets, so the results are bit-identical.
    by_id: Vec<[Vec3; 3]>,
    /// Power of two applied to all coordinates (see [`Tracer::build`]).
    scale: f32,
    /// The alpha test, if any triangle has holes ([`Tracer::with_cutouts`]).
    cutouts: Option<Box<dyn Cutouts>>,
}

/// The scale of [`Tracer::build`] for `tris`, and the triangles times it, by id.
fn scaled(tris: &[[Vec3; 3]]) -> (f32, Vec<[Vec3; 3]>) {
    let max_abs =
        tris.iter().flatten().filter(|p| p.is_finite()).fold(0.0f32, |m, p| m.max(p.abs().max_element()));
    let scale = if max_abs > 0.0 {
        let e = max_abs.log2().floor() as i32;
        2f32.powi((19 - e).clamp(-120, 120))
    } else {
        1.0
    };
    (scale, tris.iter().map(|t| t.map(|p| p * scale)).collect())
}

/// The BVH of a [`Tracer`] and its triangles.
struct Bvh {
    bvh: CwBvh,
    /// Triangles in BVH leaf order, in the tracer's scaled frame.
    tris: Vec<[Vec3A; 3]>,
    /// Original id of each triangle in `tris`.
    ids: Vec<u32>,
    build_time: Duration,
}

impl Bvh {
    /// The BVH of `tris` times `scale`, less the triangles [`Tracer::build`] leaves out.
    fn build(tris: &[[Vec3; 3]], scale: f32) -> Self {
        let start = std::time::Instant::now();
        let (kept, kept_ids) = Self::kept(tris, scale);
        Self::of_kept(kept, kept_ids, start)
    }

    /// The triangles [`Tracer::build`] keeps, times `scale` and padded, with their ids, in
    /// input order. The filter's set is gone before the build (which, beside a frame's first
    /// passes, should add to their peak memory as little as it can).
    fn kept(tris: &[[Vec3; 3]], scale: f32) -> (Vec<Padded>, Vec<u32>) {
        let mut kept = Vec::with_capacity(tris.len());
        let mut kept_ids = Vec::with_capacity(tris.len());
        let mut seen = rustc_hash::FxHashSet::with_capacity_and_hasher(tris.len(), Default::default());
        let bits = |t: &[Vec3; 3]| t.map(|p| p.to_array().map(f32::to_bits));
        for (i, t) in tris.iter().enumerate() {
            let point = t[0] == t[1] && t[1] == t[2];
            if t.iter().all(|p| p.is_finite()) && !point && seen.insert(bits(t)) {
                kept.push(Padded(Triangle {
                    v0: Vec3A::from(t[0] * scale),
                    v1: Vec3A::from(t[1] * scale),
                    v2: Vec3A::from(t[2] * scale),
                }));
                kept_ids.push(i as u32);
            }
        }
        (kept, kept_ids)
    }

    /// The BVH of `kept` ([`Bvh::kept`]), its build started at `start`.
    fn of_kept(kept: Vec<Padded>, kept_ids: Vec<u32>, start: std::time::Instant) -> Self {
        let bvh = if kept.is_empty() {
            CwBvh::default()
        } else {
            build_cwbvh(&kept, BvhBuildParams::medium_build(), &mut Duration::default())
        };
        let (tris, ids) = bvh
            .primitive_indices
            .iter()
            .map(|&k| {
                let t = &kept[k as usize].0;
                ([t.v0, t.v1, t.v2], kept_ids[k as usize])
            })
            .unzip();
        Self { bvh, tris, ids, build_time: start.elapsed() }
    }
}

impl Tracer {
    /// Builds the BVH (obvhs `medium_build`, no spatial splits, so each triangle sits in
    /// exactly one leaf; the `parallel` feature is off, which the project pins so the tree is
    /// the same on every machine).
    ///
    /// Left out of the BVH, as they can never be reported (every query answers as if they were
    /// there): triangles with a non-finite coordinate; triangles whose three corners are equal
    /// (their edge functions all vanish, exactly, so `det = 0`); and repeats of an earlier
    /// triangle corner for corner (same corners in the same order): for every ray both meet
    /// the same edges with bit-identical arithmetic at the same distance, a tie that the
    /// earlier one, with the smaller id, wins. Why bother: tens of thousands of coincident
    /// boxes (a mesh collapsed to a point, a part pasted many times in place) made obvhs's
    /// build quadratic and its recursive tree conversion overflow the stack.
    ///
    /// **Scale.** obvhs culls BVH nodes whose exit distance is below an absolute `1e-4`
    /// (`cwbvh::node::EPSILON`), which would lose contact hits in a scene measured in metres
    /// and every hit in a scene a millimetre wide. We therefore multiply all coordinates by a
    /// power of two `s` chosen so that the largest coordinate magnitude lies in
    /// `[2^19, 2^20)`. Multiplying by a power of two is exact in floating point (barring
    /// overflow and subnormals, which this range avoids), so hits are unchanged; distances
    /// come back divided by the same `s`, again exactly. At that magnitude one ulp of a
    /// coordinate is at least `2^19 * 2^-23 = 1/16`, so the culling distance `1e-4` is far
    /// below anything that floating-point coordinates can distinguish.
    pub fn build(tris: &[[Vec3; 3]]) -> Self {
        let (scale, by_id) = scaled(tris);
        let built = OnceLock::from(Bvh::build(tris, scale));
        Self { built, pending: Mutex::new(None), by_id, scale, cutouts: None }
    }

    /// [`Tracer::build`], with the BVH built on a thread of its own while the caller goes on:
    /// the single-triangle tests ([`Tracer::hits_triangle`], [`Tracer::hit_on_plane`], the row
    /// hits of [`batch`]) answer at once, and the first query that traverses the BVH waits for
    /// it. The same BVH, so the same answers. Why: the build is serial, and a renderer that
    /// rasterizes its visibility and draws light maps before it casts a ray (a hybrid frame)
    /// has that time for it on the other cores.
    pub fn build_in_background(tris: &[[Vec3; 3]]) -> Self {
        let (scale, by_id) = scaled(tris);
        let owned = tris.to_vec();
        let spawned = std::thread::Builder::new().name("hyrt-bvh".into()).spawn(move || {
            let start = std::time::Instant::now();
            let (kept, ids) = Bvh::kept(&owned, scale);
            drop(owned);
            Bvh::of_kept(kept, ids, start)
        });
        match spawned {
            Ok(handle) => Self {
                built: OnceLock::new(),
                pending: Mutex::new(Some(handle)),
                by_id,
                scale,
                cutouts: None,
            },
            // No thread to be had: built here, at once.
            Err(_) => Self {
                built: OnceLock::from(Bvh::build(tris, scale)),
                pending: Mutex::new(None),
                by_id,
                scale,
                cutouts: None,
            },
        }
    }

    /// The BVH, waiting for a background build to finish.
    #[inline]
    fn bvh(&self) -> &Bvh {
        self.built.get_or_init(|| {
            let handle = self.pending.lock().unwrap_or_else(|e| e.into_inner()).take();
            match handle.expect("a tracer is built at once or in the background").join() {
                Ok(bvh) => bvh,
                Err(panic) => std::panic::resume_unwind(panic),
            }
        })
    }

    /// Whether the BVH is built, so that a query that traverses it will not wait (for a caller
    /// with other work to do meanwhile). Never waits itself.
    pub fn is_ready(&self) -> bool {
        self.built.get().is_some()
            || self.pending.lock().unwrap_or_else(|e| e.into_inner()).as_ref().is_none_or(|h| h.is_finished())
    }

    /// This tracer with alpha cut-outs: hits on `cutouts`' triangles count only where they are
    /// solid (see [`Cutouts`]).
    pub fn with_cutouts(mut self, cutouts: Box<dyn Cutouts>) -> Self {
        self.cutouts = Some(cutouts);
        self
    }

    /// Whether a hit on triangle `tri` at `bary` counts: not in a hole of a cut-out.
    #[inline]
    fn solid(&self, tri: u32, bary: [f32; 3]) -> bool {
        self.cutouts.as_ref().is_none_or(|c| !c.has_holes(tri) || c.solid(tri, bary))
    }

    /// Wall time of the BVH's build (waiting for a background build to finish).
    pub fn build_time(&self) -> Duration {
        self.bvh().build_time
    }

    /// Number of triangles given to [`Tracer::build`].
    pub fn triangle_count(&self) -> usize {
        self.by_id.len()
    }

    /// Number of those in the BVH (see [`Tracer::build`] for the ones left out).
    pub fn bvh_triangle_count(&self) -> usize {
        self.bvh().tris.len()
    }

    /// The internal power-of-two scale (exposed for tests).
    pub fn internal_scale(&self) -> f32 {
        self.scale
    }

    fn scaled(&self, ray: &Ray) -> (ObRay, RayPrecomp) {
        let o = Vec3A::from(ray.origin * self.scale);
        let d = Vec3A::from(ray.dir);
        let tmax = ray.tmax * self.scale;
        (ObRay::new(o, d, 0.0, tmax), RayPrecomp::new(o, d))
    }

    /// The nearest hit with `0 < t < ray.tmax`; hits too close for rounding to order (module
    /// docs) go to a face the ray enters, then to the smaller triangle id.
    pub fn closest_hit(&self, ray: &Ray, kind: RayKind, counts: &mut RayCounts) -> Option<Hit> {
        counts.add(kind, 1);
        // Two instances: scenes without cut-outs pay no alpha test in the traversal's loop.
        match &self.cutouts {
            None => self.closest::<false>(ray),
            Some(_) => self.closest::<true>(ray),
        }
    }

    fn closest<const CUT: bool>(&self, ray: &Ray) -> Option<Hit> {
        let Bvh { bvh, tris, ids, .. } = self.bvh();
        if bvh.nodes.is_empty() || !ray.origin.is_finite() || !ray.dir.is_finite() {
            return None;
        }
        let (ob, pre) = self.scaled(ray);
        let (o, dir) = (Vec3A::from(ray.origin * self.scale), Vec3A::from(ray.dir));
        // (t, its error bound, BVH slot, barycentrics) of the best hit so far.
        let mut best: Option<(f32, f32, usize, [f32; 3])> = None;
        bvh.ray_traverse(ob, &mut RayHit::none(), |r, i| {
            let Some(h) =
                intersect_triangle(&pre, &tris[i], r.tmax).filter(|h| !CUT || self.solid(ids[i], h.bary))
            else {
                return f32::INFINITY;
            };
            let better = match best {
                None => true,
                Some((bt, berr, j, _)) => {
                    before(o, dir, (&tris[i], ids[i], h.t, h.err), (&tris[j], ids[j], bt, berr))
                }
            };
            if better {
                best = Some((h.t, h.err, i, h.bary));
            }
            // obvhs shrinks tmax to the value returned and stops visiting nodes beyond it.
            // Returning the far end of the `DEPTH_TIE` window keeps alive every node that could
            // hold a hit too close to the best for f32 to order, unless both hits' error bounds
            // together exceed the window (grazing slivers): such a hit is then missed, the same
            // way every time. (Reaching four error bounds past the best hit as well cost the
            // primary rays more traversal for those few.)
            best.map_or(f32::INFINITY, |(bt, _, _, _)| (bt * (1.0 + DEPTH_TIE)).next_up())
        });
        best.map(|(t, _, i, bary)| Hit { t: t / self.scale, tri: ids[i], bary })
    }

    /// Of triangles `a` and `b` (original ids), the hit that [`Tracer::closest_hit`] would
    /// prefer if they were the scene: the nearer, ordered as there (by error bounds, then in
    /// `f64`, then the tie key), or the one the ray meets, or `None` (an unknown id counts as
    /// missed). No traversal and not counted as a ray: for a caller that knows the two
    /// candidates (a rasterized pixel and the rival the z-buffer recorded for it, in the
    /// renderer).
    pub fn nearer_hit(&self, ray: &Ray, a: u32, b: u32) -> Option<Hit> {
        if !ray.origin.is_finite() || !ray.dir.is_finite() {
            return None;
        }
        let (ob, pre) = self.scaled(ray);
        let hit = |id: u32| {
            let v = self.by_id.get(id as usize)?.map(Vec3A::from);
            intersect_triangle(&pre, &v, ob.tmax).filter(|h| self.solid(id, h.bary)).map(|h| (v, h))
        };
        let (o, dir) = (Vec3A::from(ray.origin * self.scale), Vec3A::from(ray.dir));
        let best = match (hit(a), hit(b)) {
            (Some((va, ha)), Some((vb, hb))) => {
                if before(o, dir, (&va, a, ha.t, ha.err), (&vb, b, hb.t, hb.err)) { (a, ha) } else { (b, hb) }
            }
            (Some((_, ha)), None) => (a, ha),
            (None, Some((_, hb))) => (b, hb),
            (None, None) => return None,
        };
        Some(Hit { t: best.1.t / self.scale, tri: best.0, bary: best.1.bary })
    }

    /// True when anything is hit with `0 < t < ray.tmax`.
    pub fn occluded(&self, ray: &Ray, kind: RayKind, counts: &mut RayCounts) -> bool {
        counts.add(kind, 1);
        match &self.cutouts {
            None => self.blocked::<false>(ray),
            Some(_) => self.blocked::<true>(ray),
        }
    }

    fn blocked<const CUT: bool>(&self, ray: &Ray) -> bool {
        let Bvh { bvh, tris, ids, .. } = self.bvh();
        if bvh.nodes.is_empty() || !ray.origin.is_finite() || !ray.dir.is_finite() {
            return false;
        }
        let (ob, pre) = self.scaled(ray);
        !bvh.ray_traverse_miss(ob, |r, i| {
            intersect_triangle(&pre, &tris[i], r.tmax)
                .filter(|h| !CUT || self.solid(ids[i], h.bary))
                .map_or(f32::INFINITY, |h| h.t)
        })
    }

    /// The original id of the first triangle the traversal finds blocking `ray`: any blocker,
    /// not the nearest, but always the same one for the same ray.
    fn blocker<const CUT: bool>(&self, ray: &Ray) -> Option<u32> {
        let Bvh { bvh, tris, ids, .. } = self.bvh();
        if bvh.nodes.is_empty() || !ray.origin.is_finite() || !ray.dir.is_finite() {
            return None;
        }
        let (ob, pre) = self.scaled(ray);
        let mut found = None;
        bvh.ray_traverse_miss(ob, |r, i| {
            let t = intersect_triangle(&pre, &tris[i], r.tmax)
                .filter(|h| !CUT || self.solid(ids[i], h.bary))
                .map_or(f32::INFINITY, |h| h.t);
            if t < r.tmax {
                found = Some(ids[i]);
            }
            t
        });
        found
    }

    /// [`Tracer::occluded_with_hint`] that also names the occluder: the hint when it blocks
    /// the ray, else the triangle the traversal found first, else `None` (unoccluded). For a
    /// caller that keeps the last occluder as the next, nearby ray's hint (a shadow cache).
    pub fn occluder_with_hint(&self, ray: &Ray, hint: u32, counts: &mut RayCounts) -> Option<u32> {
        counts.add(RayKind::Shadow, 1);
        if (hint as usize) < self.triangle_count() && self.hits_triangle(hint, ray).is_some() {
            counts.shadow_hint_hits += 1;
            return Some(hint);
        }
        match &self.cutouts {
            None => self.blocker::<false>(ray),
            Some(_) => self.blocker::<true>(ray),
        }
    }

    /// A shadow ray that first tests the occluder hint `hint` (a triangle id from a shadow map;
    /// any value that is not a triangle id means none): if the hint blocks the ray, the answer is
    /// "occluded" without a traversal. Counted as one [`RayKind::Shadow`] ray, and as a
    /// `shadow_hint_hits` when the hint answered. Same answer as [`Tracer::occluded`] (the hint
    /// is tested with the same watertight arithmetic and bounds as the traversal).
    pub fn occluded_with_hint(&self, ray: &Ray, hint: u32, counts: &mut RayCounts) -> bool {
        if (hint as usize) < self.triangle_count() && self.hits_triangle(hint, ray).is_some() {
            counts.add(RayKind::Shadow, 1);
            counts.shadow_hint_hits += 1;
            return true;
        }
        self.occluded(ray, RayKind::Shadow, counts)
    }

    /// Tests a single triangle by original id (the occluder hint of a shadow map texel):
    /// no traversal; a hit in a cut-out's hole is none. Not counted as a ray; callers count
    /// hint tests themselves.
    pub fn hits_triangle(&self, tri: u32, ray: &Ray) -> Option<Hit> {
        self.on_triangle::<true>(tri, ray)
    }

    /// Where `ray` meets the plane of triangle `tri` (original id), with barycentrics that
    /// may be negative; bit-identical to [`Tracer::hits_triangle`] where that hits. `None` for
    /// a ray parallel to the plane, a hit behind the origin or beyond `tmax`, or an unknown id.
    /// Not counted as a ray: no traversal.
    pub fn hit_on_plane(&self, tri: u32, ray: &Ray) -> Option<Hit> {
        self.on_triangle::<false>(tri, ray)
    }

    fn on_triangle<const INSIDE: bool>(&self, tri: u32, ray: &Ray) -> Option<Hit> {
        let t = self.by_id.get(tri as usize)?;
        if !ray.origin.is_finite() || !ray.dir.is_finite() {
            return None;
        }
        let (ob, pre) = self.scaled(ray);
        let v = t.map(Vec3A::from);
        let h =
            if INSIDE { intersect_triangle(&pre, &v, ob.tmax) } else { intersect_plane(&pre, &v, ob.tmax) };
        let h = h.filter(|h| !INSIDE || self.solid(tri, h.bary));
        h.map(|h| Hit { t: h.t / self.scale, tri, bary: h.bary })
    }
}
