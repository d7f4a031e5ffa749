//! Triangle setup: clip, project to fixed-point screen coordinates, orient, fan-triangulate, and
//! precompute the interpolation constants. Everything here runs once per input triangle; the
//! per-pixel work is in [`crate::edge`] and [`SetupTri::depth`] / [`SetupTri::bary`].
//!
//! # Viewport transform
//!
//! NDC `(x, y) = (x_c / w, y_c / w)` in `[-1, 1]^2`, y up, maps to pixels, y down:
//!
//! ```text
//!     sx = (x + 1) / 2 * width          sy = (1 - y) / 2 * height
//! ```
//!
//! so pixel `(px, py)` covers `[px, px + 1) x [py, py + 1)` and is sampled at its centre
//! `(px + 1/2, py + 1/2)`.
//!
//! # Fixed point
//!
//! Screen coordinates are rounded to `1 / 2^SUBPIXEL_BITS` pixel (`SUBPIXEL_BITS = 8`) and stored
//! as integers. Rounding happens once per vertex, so two triangles sharing a vertex share its
//! snapped position exactly, and all coverage decisions after this point are exact integer
//! arithmetic (see [`crate::edge`] for the edge functions and their bounds).
//!
//! The clipper guarantees `|sx|, |sy| <= GUARD_BAND_PX = 2^19` px, i.e. `|X| <= 2^27` in fixed
//! point; anything beyond [`MAX_FIXED`] `= 2^28` (twice that, to absorb rounding) is rejected as a
//! safety net. Sample positions are in `[0, 2^24]` (targets are at most `2^16` px wide). Hence
//! coordinate differences are below `2^29`, a 2x2 cross product below `2^59`, and an edge function
//! value at any sample below `2^60`: `i64` never overflows.
//!
//! # Orientation and culling
//!
//! With y pointing down, a triangle that is counter-clockwise in NDC (the wgpu/OpenGL default
//! front face) has a *negative* signed area `cross(v1 - v0, v2 - v0)` in screen space. The
//! orientation of a (clipped) polygon is the sign of its snapped signed area (the sum of its fan
//! triangles' areas, in `i128`), exactly as GPUs decide facing from snapped coordinates.
//! Every fan triangle is then re-ordered to positive area so that the edge functions are positive
//! inside. A fan triangle whose snapped area has the opposite sign to its polygon's is a snapping
//! artifact of a sliver and is dropped; zero-area triangles are dropped too (they cover no sample
//! and their interpolation would divide by zero), and so are tiny triangles that cover none of
//! the (at most 4) samples of their pixel bounds ([`misses_every_sample`]), which many triangles
//! of detailed meshes do.
//!
//! # Depth: the plane of the unsnapped polygon
//!
//! Depth `D = z / w` is affine in screen space on a planar polygon (the projective map sends
//! planes to planes): `D(X, Y) = A X + B Y + C`. It is evaluated at a sample from the exact
//! integer edge functions of the snapped fan triangle ([`SetupTri::depth`]):
//!
//! ```text
//!     D = z0 + e1 (z1 - z0) / area + e2 (z2 - z0) / area
//! ```
//!
//! the affine function that takes the values `z_i` at the *snapped* vertices. With `z_i = D_i`,
//! the vertices' own depths, that is the plane through the snapped positions, tilted by the
//! snapping (up to 1/512 px per coordinate): where a surface is seen at a grazing angle its depth
//! changes by percents per pixel, and the tilt costs up to ~1e-4 relative, far more than the
//! `2^-16` within which the renderer compares depths with ray casting. So `A` and `B` are
//! computed in `f64` from the *unsnapped* screen positions `(X_i, Y_i)` (the same viewport
//! transform, before rounding; in fixed-point units, so that the snapped positions `X'_i` are
//! integers), and each `z_i` is that plane's value at the snapped vertex:
//!
//! ```text
//!     z_i = D_i + A (X'_i - X_i) + B (Y'_i - Y_i)
//! ```
//!
//! its own depth corrected for the snap offset. Three values of an affine function determine
//! it, so the interpolation above *is* the unsnapped plane, evaluated at the pixel centre up to
//! `f64` rounding: a few units of `2^-53` times the largest `|z_i|` (a covered sample has
//! `0 <= e_i <= area`), far below `f32` resolution for any sample whose depth is not orders of
//! magnitude below its polygon's largest depth. What is stored is `z_0` and the differences
//! `z_k - z_0 = (D_k - D_0) + A ((X'_k - X'_0) - (X_k - X_0)) + B (...)` ([`depth_difference`]):
//! each vertex depth enters exactly as before, and the plane only through the (small)
//! corrections, so an imprecise gradient (a badly conditioned triangle) costs little. Coverage
//! does not change: it stays with the snapped vertices. The gradient comes from three vertices:
//! the triangle's, or for a clipped polygon (coplanar up to rounding) the three spanning the
//! largest screen area, the best conditioned choice; one plane serves all fan triangles of a
//! polygon, and a triangle is set up alike whether it went through the clipper or not.
//!
//! Every evaluated depth is then clamped to `[min D_i, max D_i]` over the polygon's vertices
//! (within `[0, 1]`): no point of the polygon lies outside that range. For a well-conditioned
//! plane this changes only samples that the snapped coverage includes and the exact polygon does
//! not, next to a vertex of extreme depth; for the ill-conditioned plane of an edge-on sliver it
//! bounds the damage. A plane may even be unusable: collinear vertices on screen, or a gradient
//! so steep that a correction could exceed [`MAX_DEPTH_CORRECTION`] `= 1` (the whole depth range
//! within 1/512 px along each axis, which only a polygon thinner than that has). Then the
//! corrections are dropped (`z_i = D_i`: the plane through the snapped vertices, which is what
//! GPUs interpolate), so that all values stay finite and bounded.

#[cfg(target_arch = "x86_64")]
pub(crate) mod vector;

use glam::{DVec2, DVec4, Vec4};

use crate::clip::{ClipScratch, Clipped, GuardBand, MAX_POLY_VERTS, clip_triangle};

/// Sub-pixel precision of the snapped vertex coordinates.
pub(crate) const SUBPIXEL_BITS: u32 = 8;
/// One pixel in fixed-point units.
pub(crate) const SUBPIXEL_ONE: i64 = 1 << SUBPIXEL_BITS;
/// Half a pixel: pixel centres are at `px * SUBPIXEL_ONE + HALF_PIXEL`.
pub(crate) const HALF_PIXEL: i64 = SUBPIXEL_ONE / 2;
/// Largest accepted fixed-point coordinate magnitude (see the module docs).
pub(crate) const MAX_FIXED: i64 = 1 << 28;

/// Per-target constants of the setup.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SetupContext {
    pub width: u32,
    pub height: u32,
    pub guard: GuardBand,
    pub cull_backfaces: bool,
}

impl SetupContext {
    pub fn new(width: u32, height: u32, cull_backfaces: bool) -> Self {
        Self { width, height, guard: GuardBand::for_target(width, height), cull_backfaces }
    }
}

/// A triangle ready for rasterization: positively oriented fixed-point vertices, its pixel bounds
/// within the target, and interpolation constants.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SetupTri {
    /// Fixed-point screen coordinates, ordered so that `cross(v1 - v0, v2 - v0) > 0`.
    pub v: [[i32; 2]; 3],
    /// Inclusive pixel bounds `[x0, y0, x1, y1]` of the samples that may be covered, already
    /// clamped to the target (never empty).
    pub bbox: [u32; 4],
    pub id: u32,
    /// The polygon faces away from the camera (its snapped signed area is positive): depth ties
    /// go to front faces first ([`crate::RasterOptions::depth_tie`]).
    pub back: bool,
    /// Depth plane of the unsnapped polygon (module docs): `z/w = z0 + e1 * dz[0] + e2 * dz[1]`,
    /// with `e_i` the edge functions (below).
    z0: f64,
    dz: [f64; 2],
    /// `[min, max]` of the polygon's vertex depths, within `[0, 1]`: the clamp of
    /// [`SetupTri::depth`].
    range: [f32; 2],
    /// Per vertex `i`: `[q_i, q_i * b1_i, q_i * b2_i]` where `q_i` is proportional to `1 / w_i` and
    /// `(b1_i, b2_i)` are the vertex's barycentrics in the original triangle. `f32` (relative
    /// error 6e-8 on the result) keeps the struct small; the sums are done in `f64`.
    persp: [[f32; 3]; 3],
}

impl SetupTri {
    /// A set-up triangle from its fields (see the struct), for the vector kernels of
    /// `crate::setup::vector`, which compute them as [`setup_triangle`] does.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub(crate) fn from_parts(
        v: [[i32; 2]; 3],
        bbox: [u32; 4],
        id: u32,
        back: bool,
        [z0, dz1, dz2]: [f64; 3],
        range: [f32; 2],
        persp: [[f32; 3]; 3],
    ) -> Self {
        Self { v, bbox, id, back, z0, dz: [dz1, dz2], range, persp }
    }

    /// The order of depth ties: front faces before back faces, then the smaller id (crate docs).
    #[inline(always)]
    pub(crate) fn tie_key(&self) -> (bool, u32) {
        (self.back, self.id)
    }

    /// Depth plane constants: `depth(e) = (z0 + e1 dz[0]) + e2 dz[1]` before clamping.
    #[inline]
    pub fn z0(&self) -> f64 {
        self.z0
    }

    /// See [`SetupTri::z0`].
    #[inline]
    pub fn dz(&self) -> [f64; 2] {
        self.dz
    }

    /// Perspective constants of [`SetupTri::bary`]: per vertex `i`, `[q_i, q_i b1_i, q_i b2_i]`.
    #[inline]
    pub fn persp(&self) -> &[[f32; 3]; 3] {
        &self.persp
    }

    /// `[lo, hi]` that [`SetupTri::depth`] clamps to, after rounding to `f32`.
    #[inline]
    pub fn range(&self) -> [f32; 2] {
        self.range
    }

    /// Depth `z/w` at a sample with (unbiased) edge functions `e = [e0, e1, e2]`.
    ///
    /// `e_i` is the edge function of the edge *opposite* vertex `i`, so the screen-space
    /// barycentrics are `λ_i = e_i / area` (with `e0 + e1 + e2 = area`). `z/w` is affine in screen
    /// space (the projective map sends planes to planes), so it interpolates linearly:
    /// `z = z0 + λ1 (z1 - z0) + λ2 (z2 - z0)`, with `z_i` the unsnapped polygon's plane at the
    /// snapped vertices (module docs). Computed in `f64` from exact integer `e_i`, rounded to `f32`
    /// and clamped to the polygon's depth range ([`clamp_depth`]), the result depends only on the
    /// triangle and the pixel, never on tiling or threads.
    #[inline]
    pub fn depth(&self, e: [i64; 3]) -> f32 {
        let d = self.z0 + e[1] as f64 * self.dz[0] + e[2] as f64 * self.dz[1];
        clamp_depth(d as f32, self.range)
    }

    /// Perspective-correct `(b1, b2)` of the original triangle at a sample with edge functions `e`.
    ///
    /// An attribute `a` that is linear on the triangle in 3D is *not* linear in screen space, but
    /// `a / w` and `1 / w` are. With screen barycentrics `λ_i ∝ e_i`:
    ///
    /// ```text
    ///     a = Σ λ_i a_i / w_i  /  Σ λ_i / w_i  =  Σ e_i q_i a_i  /  Σ e_i q_i
    /// ```
    ///
    /// (the `1 / area` and any common scale of `q_i ∝ 1 / w_i` cancel). The attributes are the
    /// original triangle's barycentrics carried through the clipper, so clipped triangles report
    /// barycentrics relative to the unclipped one. The result is a convex combination of the
    /// vertices' barycentrics (`e_i >= 0`, `q_i > 0`), hence inside the original triangle up to
    /// rounding.
    #[inline]
    pub fn bary(&self, e: [i64; 3]) -> [f32; 2] {
        let [p0, p1, p2] = &self.persp;
        let (e0, e1, e2) = (e[0] as f64, e[1] as f64, e[2] as f64);
        let p = |v: f32| f64::from(v);
        let den = e0 * p(p0[0]) + e1 * p(p1[0]) + e2 * p(p2[0]);
        if den <= 0.0 {
            // Unreachable for covered samples (some e_i > 0); kept so no input can divide by 0.
            return [0.0, 0.0];
        }
        let b1 = (e0 * p(p0[1]) + e1 * p(p1[1]) + e2 * p(p2[1])) / den;
        let b2 = (e0 * p(p0[2]) + e1 * p(p1[2]) + e2 * p(p2[2])) / den;
        [b1 as f32, b2 as f32]
    }
}

/// `d` clamped to `[lo, hi]` (`lo <= hi`), a NaN to `lo`.
///
/// Clamping after the rounding to `f32` gives what rounding the clamped `f64` would (rounding is
/// monotone), with half as many vector lanes. Written as the comparisons of the x86 `max` / `min`
/// instructions (`max(a, b) = a > b ? a : b`, `min(a, b) = a < b ? a : b`) with `d` first, which
/// the vector kernels use, so that every input, signed zeros and NaN included, gives the same bits
/// (`f32::clamp` would keep a NaN).
#[inline(always)]
pub(crate) fn clamp_depth(d: f32, [lo, hi]: [f32; 2]) -> f32 {
    let d = if d > lo { d } else { lo };
    if d < hi { d } else { hi }
}

/// Largest accepted bound on a vertex's depth correction `A (X' - X) + B (Y' - Y)` (module
/// docs): depths are in `[0, 1]`, so a larger correction only comes from a plane that is not
/// meaningful at the scale of the snapping.
pub(crate) const MAX_DEPTH_CORRECTION: f64 = 1.0;

/// Gradient `[A, B]` of the depth plane through three unsnapped vertices `[X, Y, D]` (screen
/// position in fixed-point units, i.e. `2^SUBPIXEL_BITS` per pixel, and depth), or `[0, 0]` if it
/// is not usable (module docs): collinear on screen (non-finite), or so steep that a correction
/// could exceed [`MAX_DEPTH_CORRECTION`].
#[inline(always)]
fn depth_gradient(pa: [f64; 3], pb: [f64; 3], pc: [f64; 3]) -> [f64; 2] {
    // Solve D - D_a = A (X - X_a) + B (Y - Y_a) at b and c (Cramer's rule).
    let [x1, y1, d1] = [pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]];
    let [x2, y2, d2] = [pc[0] - pa[0], pc[1] - pa[1], pc[2] - pa[2]];
    let inv_den = 1.0 / (x1 * y2 - x2 * y1);
    let grad = [(d1 * y2 - d2 * y1) * inv_den, (x1 * d2 - x2 * d1) * inv_den];
    // Snapping moves a coordinate by at most half a unit (rounding to the nearest), so no
    // correction exceeds (|A| + |B|) / 2. `!(x <= max)` also rejects NaN.
    let max_correction = (grad[0].abs() + grad[1].abs()) * 0.5;
    if max_correction <= MAX_DEPTH_CORRECTION { grad } else { [0.0; 2] }
}

/// `z_0`, the depth of the plane with gradient `grad` at the snapped position `f` of the vertex
/// `p = [X, Y, D]` (as in [`depth_gradient`]): `D + A (X' - X) + B (Y' - Y)`. The snapped
/// position is an integer below `2^28` in magnitude, exact in `f64`.
#[inline(always)]
fn depth_at_snapped(grad: [f64; 2], p: [f64; 3], f: [f64; 2]) -> f64 {
    // The snapped position is within half a unit of the unsnapped one: the offsets are exact
    // (Sterbenz) or nearly so.
    p[2] + (grad[0] * (f[0] - p[0]) + grad[1] * (f[1] - p[1]))
}

/// `z_k - z_0` for the vertices `p0`, `pk` (as in [`depth_at_snapped`]), as the difference of
/// their depths plus that of their corrections: `(D_k - D_0) + A (dX' - dX) + B (dY' - dY)`,
/// with `snapped = [dX', dY']`, `dX' = X'_k - X'_0` the exact integer difference (below `2^29`
/// in magnitude: exact in `f64`). Every fan triangle of a polygon shares vertex 0, so this is
/// all its interpolation needs besides `z_0` (and a triangle is the fan of one).
#[inline(always)]
fn depth_difference(grad: [f64; 2], p0: [f64; 3], pk: [f64; 3], snapped: [f64; 2]) -> f64 {
    (pk[2] - p0[2]) + (grad[0] * (snapped[0] - (pk[0] - p0[0])) + grad[1] * (snapped[1] - (pk[1] - p0[1])))
}

/// `fk - f0` as `f64` (exact: the coordinates are below `2^28` in magnitude).
#[inline(always)]
fn snapped_offset(f0: [i64; 2], fk: [i64; 2]) -> [f64; 2] {
    [(fk[0] - f0[0]) as f64, (fk[1] - f0[1]) as f64]
}

/// The clamp range of [`SetupTri::depth`]: `[min D, max D]` over the polygon's vertex depths,
/// within `[0, 1]` (they are, up to the rounding of `z * (1 / w)`), as `f32`.
#[inline(always)]
fn depth_range(d: impl Iterator<Item = f64>) -> [f32; 2] {
    let (lo, hi) = d.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| {
        (if d < lo { d } else { lo }, if d > hi { d } else { hi })
    });
    [lo.clamp(0.0, 1.0) as f32, hi.clamp(0.0, 1.0) as f32]
}

/// A polygon vertex after the viewport transform.
#[derive(Clone, Copy, Debug, Default)]
struct Projected {
    /// Fixed-point screen position.
    x: i64,
    y: i64,
    /// Unsnapped screen position, in fixed-point units (pixels times `SUBPIXEL_ONE`).
    s: [f64; 2],
    /// Depth `z / w`.
    z: f64,
    /// `1 / w` (finite, > 0).
    inv_w: f64,
    /// `(b1, b2)` in the original triangle.
    bary: DVec2,
}

/// Rounds a screen coordinate in pixels to fixed point, `None` outside `±MAX_FIXED` (or NaN).
///
/// Rounds half up, `floor(x + 1/2)`, which is translation invariant. This runs for every vertex,
/// and `f64::floor` is a library call on baseline x86-64 (and `as i64` a saturating conversion),
/// so the floor is computed with the usual magic-number rounding: for `|f| < 2^51`, adding
/// `1.5 * 2^52` rounds `f` to the nearest integer `r` (the sum's unit in the last place is 1),
/// whose bits are those of the sum minus the constant's bits, and `floor(f)` is `r` or, when
/// rounding went up, `r - 1`. Exact, and branch-free on the common path.
#[inline]
fn to_fixed(px: f64) -> Option<i64> {
    const MAGIC: f64 = 6_755_399_441_055_744.0; // 1.5 * 2^52
    let f = px * SUBPIXEL_ONE as f64 + 0.5;
    if f.is_nan() || f.abs() > MAX_FIXED as f64 {
        return None;
    }
    let m = f + MAGIC;
    let r = m.to_bits() as i64 - MAGIC.to_bits() as i64;
    Some(r - i64::from(m - MAGIC > f))
}

#[inline]
fn project(pos: DVec4, bary: DVec2, ctx: &SetupContext) -> Option<Projected> {
    // w > 0 is guaranteed by the near/far clip except for the degenerate vertex (0,0,0,0); a
    // denormal w could still make 1/w overflow, hence the finiteness check.
    if pos.w <= 0.0 {
        return None;
    }
    let inv_w = 1.0 / pos.w;
    if !inv_w.is_finite() {
        return None;
    }
    let (nx, ny) = (pos.x * inv_w, pos.y * inv_w);
    let sx = (nx + 1.0) * 0.5 * f64::from(ctx.width);
    let sy = (1.0 - ny) * 0.5 * f64::from(ctx.height);
    let s = [sx * SUBPIXEL_ONE as f64, sy * SUBPIXEL_ONE as f64];
    Some(Projected { x: to_fixed(sx)?, y: to_fixed(sy)?, s, z: pos.z * inv_w, inv_w, bary })
}

/// `cross(b - a, c - a)`: twice the signed area, positive for clockwise-on-screen (y down).
#[inline]
pub(crate) fn cross(a: [i64; 2], b: [i64; 2], c: [i64; 2]) -> i64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// `ceil(a / b)` for `b > 0`.
fn div_ceil_i64(a: i64, b: i64) -> i64 {
    -((-a).div_euclid(b))
}

/// Sets up one clip-space triangle, appending 0 or more [`SetupTri`]s (more than one only when
/// clipping turned it into a polygon).
///
/// The common cases are decided on the `f32` input before anything is converted or projected,
/// with comparisons that give exactly the answers of the `f64` plane tests in [`crate::clip`]
/// (see [`outcode`]): a triangle entirely outside one viewport plane is dropped, and one inside
/// the viewport and the depth range goes straight to [`setup_unclipped`]. Everything else takes
/// the general path through [`clip_triangle`], which repeats those tests in `f64`.
#[inline]
pub(crate) fn setup_triangle(
    tri: &[Vec4; 3],
    id: u32,
    ctx: &SetupContext,
    scratch: &mut ClipScratch,
    out: &mut Vec<SetupTri>,
) {
    match classify(tri) {
        Class::Rejected => {}
        Class::Inside => setup_unclipped(&tri.map(|v| v.as_dvec4()), id, ctx, out),
        Class::Clip => setup_clipped(tri, id, ctx, scratch, out),
    }
}

/// What [`setup_triangle`] does with a triangle, decided on the `f32` input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Class {
    /// Not finite, or entirely outside one viewport plane: nothing to draw.
    Rejected,
    /// Inside the viewport and the depth range: [`setup_unclipped`].
    Inside,
    /// Anything else: [`setup_clipped`].
    Clip,
}

/// The class of a triangle: [`Class`].
#[inline(always)]
fn classify(tri: &[Vec4; 3]) -> Class {
    if !(tri[0].is_finite() && tri[1].is_finite() && tri[2].is_finite()) {
        return Class::Rejected;
    }
    let codes = [outcode(tri[0]), outcode(tri[1]), outcode(tri[2])];
    if codes[0] & codes[1] & codes[2] != 0 {
        Class::Rejected
    } else if codes[0] | codes[1] | codes[2] == 0 {
        Class::Inside
    } else {
        Class::Clip
    }
}

/// Sets up the triangles of `tris` (`tris[k]` with id `ids[k]`, or 0 for all without `ids`;
/// those with id [`EMPTY_ID`](crate::EMPTY_ID) are skipped), appending to `out` in input order
/// exactly what [`setup_triangle`] appends for each in turn. The vector kernels
/// (`crate::setup::vector`) do the same 8 triangles at a time.
pub(crate) fn setup_chunk(
    tris: &[[Vec4; 3]],
    ids: Option<&[u32]>,
    ctx: &SetupContext,
    out: &mut Vec<SetupTri>,
) {
    let mut scratch = ClipScratch::new();
    for (k, tri) in tris.iter().enumerate() {
        if let Some(ahead) = tris.get(k + PREFETCH_AHEAD) {
            prefetch_input(ahead);
        }
        let id = ids.map_or(0, |ids| ids[k]);
        if id != crate::EMPTY_ID {
            setup_triangle(tri, id, ctx, &mut scratch, out);
        }
    }
}

/// How many input triangles ahead setup asks for: reading the input (48 bytes per triangle) is
/// a large part of the setup time of scenes with many rejected triangles, and the hardware
/// prefetcher alone leaves the core waiting.
pub(crate) const PREFETCH_AHEAD: usize = 24;

/// Starts loading an input triangle into the cache. A hint only.
#[inline(always)]
pub(crate) fn prefetch_input(tri: &[Vec4; 3]) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let p: *const i8 = (tri as *const [Vec4; 3]).cast();
        // SAFETY: prefetching has no effect on memory or on the program's state; SSE is part of
        // x86-64.
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(p);
            _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(size_of::<[Vec4; 3]>() - 1));
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = tri;
}

/// [`setup_triangle`] for triangles that reach outside the viewport or the depth range (a
/// minority: kept out of line so that the common path stays small).
#[cold]
#[inline(never)]
pub(crate) fn setup_clipped(
    tri: &[Vec4; 3],
    id: u32,
    ctx: &SetupContext,
    scratch: &mut ClipScratch,
    out: &mut Vec<SetupTri>,
) {
    let tri = tri.map(|v| v.as_dvec4());
    match clip_triangle(&tri, ctx.guard, scratch) {
        Clipped::Rejected => {}
        Clipped::Inside => setup_unclipped(&tri, id, ctx, out),
        Clipped::Polygon(poly) => {
            let poly = poly.as_slice();
            let mut pv = [Projected::default(); MAX_POLY_VERTS];
            for (p, v) in pv.iter_mut().zip(poly) {
                match project(v.pos, v.bary, ctx) {
                    Some(projected) => *p = projected,
                    None => return,
                }
            }
            setup_polygon(&pv[..poly.len()], id, ctx, out);
        }
    }
}

/// Viewport outcode of a finite vertex: a bit set for each of the planes near, far, left, right,
/// bottom, top that `v` is outside of (in some fixed bit order). Zero iff `0 <= z <= w`,
/// `|x| <= w` and `|y| <= w`.
///
/// These are exactly the outcodes of [`crate::clip`], which tests the sign of `z`, `w - z`,
/// `w + x`, `w - x`, `w + y`, `w - y` on the values widened to `f64`: for finite `a`, `b` the
/// rounded `f64` difference `a - b` cannot overflow, rounding preserves signs, and it is zero only
/// when `a == b`; so `w - z < 0` is exactly `w < z` and `w + x < 0` is exactly `x < -w` (negation
/// is exact), which `f32` compares answer without converting anything.
///
/// A triangle whose three outcodes are zero is one that [`clip_triangle`] returns `Inside` for:
/// the near and far distances are `z >= 0` and `w - z >= 0`; the guard-band side distances are
/// `fl(g w) ± x` with `g >= 15` (see [`GuardBand::for_target`](crate::clip::GuardBand::for_target))
/// and `w >= 0`, and `g w >= w` stays `>= w` after rounding (`w` is representable, rounding is
/// monotone), so `fl(g w) ± x >= w - |x| >= 0`, which rounding keeps `>= 0`.
#[inline]
fn outcode(v: Vec4) -> u32 {
    let w = Vec4::splat(v.w);
    // Lanes x, y of `v < -w`: left, bottom. Lanes x, y, z of `w < v`: right, top, far.
    let low = v.cmplt(-w).bitmask() & 0b11;
    let high = w.cmplt(v).bitmask() & 0b111;
    low | high << 2 | u32::from(v.z < 0.0) << 5
}

/// Sets up a triangle that needs no clipping: bit for bit what projecting its vertices and
/// calling [`setup_polygon`] with them gives (one fan triangle, whose area is the polygon's), but
/// in an order that drops triangles covering no sample before computing depths and perspective
/// constants, in `i64` rather than `i128` (one cross product fits, see the module docs), and
/// without the polygon's generality: this runs for nearly every triangle.
fn setup_unclipped(tri: &[DVec4; 3], id: u32, ctx: &SetupContext, out: &mut Vec<SetupTri>) {
    let (width, height) = (f64::from(ctx.width), f64::from(ctx.height));
    let mut xy = [[0i64; 2]; 3];
    let mut inv_w = [0.0f64; 3];
    // Unsnapped [X, Y, D] (D filled in once the triangle is known to cover a sample).
    let mut unsnapped = [[0.0f64; 3]; 3];
    for i in 0..3 {
        // Exactly the checks and arithmetic of `project`.
        let pos = tri[i];
        if pos.w <= 0.0 {
            return;
        }
        inv_w[i] = 1.0 / pos.w;
        if !inv_w[i].is_finite() {
            return;
        }
        let sx = (pos.x * inv_w[i] + 1.0) * 0.5 * width;
        let sy = (1.0 - pos.y * inv_w[i]) * 0.5 * height;
        let (Some(x), Some(y)) = (to_fixed(sx), to_fixed(sy)) else {
            return;
        };
        xy[i] = [x, y];
        // In fixed-point units: `to_fixed` computes the same products.
        unsnapped[i] = [sx * SUBPIXEL_ONE as f64, sy * SUBPIXEL_ONE as f64, 0.0];
    }
    let area = cross(xy[0], xy[1], xy[2]);
    if area == 0 || (ctx.cull_backfaces && area > 0) {
        return;
    }
    let Some(bbox) = pixel_bounds(&xy, ctx) else {
        return;
    };
    // `setup_polygon` swaps vertices 1 and 2 of a negatively oriented triangle.
    let (b, c) = if area < 0 { (2, 1) } else { (1, 2) };
    let inv_area = 1.0 / area.unsigned_abs() as f64;
    for i in 0..3 {
        unsnapped[i][2] = tri[i].z * inv_w[i];
    }
    // Exactly what `setup_polygon` computes for a triangle (module docs: Depth).
    let [u0, u1, u2] = unsnapped;
    let grad = depth_gradient(u0, u1, u2);
    let z0 = depth_at_snapped(grad, u0, xy[0].map(|c| c as f64));
    let dz = [0.0, depth_difference(grad, u0, u1, snapped_offset(xy[0], xy[1])), {
        depth_difference(grad, u0, u2, snapped_offset(xy[0], xy[2]))
    }];
    let range = depth_range(unsnapped.iter().map(|u| u[2]));
    // The maximum is exact and order-independent (positive, finite values): the same as `finish`.
    let scale = 1.0 / inv_w[0].max(inv_w[1]).max(inv_w[2]);
    // The barycentrics of the original vertices are (0, 0), (1, 0) and (0, 1), and q is finite
    // and positive, so `q * 1.0 == q` and `q * 0.0 == +0.0`: `finish`'s `persp`, without the
    // multiplications.
    let persp = |i: usize| {
        let q = (inv_w[i] * scale) as f32;
        [q, if i == 1 { q } else { 0.0 }, if i == 2 { q } else { 0.0 }]
    };
    let tri = SetupTri {
        // In range by the MAX_FIXED check in `to_fixed`.
        v: [xy[0], xy[b], xy[c]].map(|p| [p[0] as i32, p[1] as i32]),
        bbox,
        id,
        back: area > 0,
        z0,
        dz: [dz[b] * inv_area, dz[c] * inv_area],
        range,
        persp: [persp(0), persp(b), persp(c)],
    };
    if !misses_every_sample(&tri) {
        out.push(tri);
    }
}

/// Fixed-point extent below which a triangle can count as tiny for [`misses_every_sample`]:
/// `2^14` units (64 pixels), small enough for the vector setup to evaluate its edge functions
/// in `i32` (`crate::setup::vector`).
pub(crate) const TINY_SPAN: i32 = 1 << 14;

/// Whether a set-up triangle is tiny, its pixel bounds at most 2 x 2 pixels and its vertices
/// within [`TINY_SPAN`] of each other on both axes, and covers none of the samples of its
/// bounds (the exact edge tests of [`crate::edge`]): it can produce no fragment, and is not
/// output. Many triangles of detailed meshes fall between the pixel centres; dropping them
/// here saves binning and drawing them. Other triangles are kept whatever they cover. The
/// vector setup applies the same rule, so both output the same triangles.
#[inline]
fn misses_every_sample(tri: &SetupTri) -> bool {
    let [x0, y0, x1, y1] = tri.bbox;
    let [v0, v1, v2] = tri.v;
    let span = |c: usize| v0[c].max(v1[c]).max(v2[c]) - v0[c].min(v1[c]).min(v2[c]);
    if x1 - x0 > 1 || y1 - y0 > 1 || span(0) >= TINY_SPAN || span(1) >= TINY_SPAN {
        return false;
    }
    let ef = crate::edge::EdgeFns::new(tri);
    let covered = |x: u32, y: u32| {
        let e = ef.at_pixel(x, y);
        (0..3).all(|i| e[i] >= ef.bias[i])
    };
    !(y0..=y1).any(|y| (x0..=x1).any(|x| covered(x, y)))
}

/// Inclusive pixel bounds of the samples a triangle with these fixed-point vertices may cover,
/// clamped to the target, or `None` if no sample of the target is inside them.
#[inline]
fn pixel_bounds(xy: &[[i64; 2]; 3], ctx: &SetupContext) -> Option<[u32; 4]> {
    // Pixel px is sampled at px*ONE + HALF, so the samples inside [min_x, max_x] are px in
    // [ceil((min_x - HALF) / ONE), floor((max_x - HALF) / ONE)].
    let min_x = xy[0][0].min(xy[1][0]).min(xy[2][0]);
    let max_x = xy[0][0].max(xy[1][0]).max(xy[2][0]);
    let min_y = xy[0][1].min(xy[1][1]).min(xy[2][1]);
    let max_y = xy[0][1].max(xy[1][1]).max(xy[2][1]);
    let x0 = div_ceil_i64(min_x - HALF_PIXEL, SUBPIXEL_ONE).max(0);
    let y0 = div_ceil_i64(min_y - HALF_PIXEL, SUBPIXEL_ONE).max(0);
    let x1 = (max_x - HALF_PIXEL).div_euclid(SUBPIXEL_ONE).min(i64::from(ctx.width) - 1);
    let y1 = (max_y - HALF_PIXEL).div_euclid(SUBPIXEL_ONE).min(i64::from(ctx.height) - 1);
    // In [0, width) x [0, height) by the clamps.
    (x0 <= x1 && y0 <= y1).then_some([x0 as u32, y0 as u32, x1 as u32, y1 as u32])
}

/// The [`SetupTri`] of a positively oriented fan triangle `verts` of (snapped) area `area > 0`
/// with pixel bounds `bbox`, given its polygon's depth at the snapped vertex 0, `z0`, the
/// differences `dz = [z_1 - z_0, z_2 - z_0]` (see [`depth_difference`]) and its polygon's depth
/// range.
#[inline]
fn finish(
    verts: &[Projected; 3],
    z0: f64,
    dz: [f64; 2],
    range: [f32; 2],
    area: i64,
    bbox: [u32; 4],
    id: u32,
) -> SetupTri {
    let inv_area = 1.0 / area as f64;
    // q_i = (1 / w_i) / max_j (1 / w_j) in (0, 1]: proportional to 1 / w_i, and in range of
    // f32 whatever w is.
    let scale = 1.0 / verts.iter().map(|p| p.inv_w).fold(0.0, f64::max);
    let persp = verts.map(|p| {
        let q = p.inv_w * scale;
        [q as f32, (q * p.bary.x) as f32, (q * p.bary.y) as f32]
    });
    SetupTri {
        // In range by the MAX_FIXED check in `to_fixed`.
        v: verts.map(|p| [p.x as i32, p.y as i32]),
        bbox,
        id,
        // Set by the caller, which knows the polygon's facing.
        back: false,
        z0,
        dz: [dz[0] * inv_area, dz[1] * inv_area],
        range,
        persp,
    }
}

/// Orients, culls and fan-triangulates a projected convex polygon (at least 3 vertices).
fn setup_polygon(pv: &[Projected], id: u32, ctx: &SetupContext, out: &mut Vec<SetupTri>) {
    let xy = |p: &Projected| [p.x, p.y];
    // Signed area of the snapped polygon decides the facing (module docs). For a triangle it is
    // a single i64 cross product; a polygon sums up to 14 of them (< 2^63 each), hence i128.
    let area: i128 = if pv.len() == 3 {
        i128::from(cross(xy(&pv[0]), xy(&pv[1]), xy(&pv[2])))
    } else {
        (1..pv.len() - 1).map(|i| i128::from(cross(xy(&pv[0]), xy(&pv[i]), xy(&pv[i + 1])))).sum()
    };
    if area == 0 {
        return;
    }
    let front_facing = area < 0;
    if ctx.cull_backfaces && !front_facing {
        return;
    }

    // One depth plane for the whole polygon (module docs), from the three vertices spanning the
    // largest unsnapped area (the first such triple: deterministic). A triangle has one triple,
    // (0, 1, 2), as in `setup_unclipped`.
    let n = pv.len();
    let u = |p: &Projected| [p.s[0], p.s[1], p.z];
    let mut best = ([0, 1, 2], -1.0);
    for i in 0..n {
        for j in i + 1..n {
            for k in j + 1..n {
                let [a, b, c] = [pv[i].s, pv[j].s, pv[k].s];
                let twice_area = ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs();
                if twice_area > best.1 {
                    best = ([i, j, k], twice_area);
                }
            }
        }
    }
    let [a, b, c] = best.0;
    let grad = depth_gradient(u(&pv[a]), u(&pv[b]), u(&pv[c]));
    let z0 = depth_at_snapped(grad, u(&pv[0]), xy(&pv[0]).map(|c| c as f64));
    let mut dz = [0.0; MAX_POLY_VERTS];
    for (d, p) in dz.iter_mut().zip(pv).skip(1) {
        *d = depth_difference(grad, u(&pv[0]), u(p), snapped_offset(xy(&pv[0]), xy(p)));
    }
    let range = depth_range(pv.iter().map(|p| p.z));

    for i in 1..n - 1 {
        let (mut b, mut c) = (i, i + 1);
        let mut tri_area = cross(xy(&pv[0]), xy(&pv[b]), xy(&pv[c]));
        if tri_area == 0 || (tri_area > 0) != (area > 0) {
            continue;
        }
        if tri_area < 0 {
            std::mem::swap(&mut b, &mut c);
            tri_area = -tri_area;
        }
        let verts = [pv[0], pv[b], pv[c]];
        let Some(bbox) = pixel_bounds(&verts.map(|p| xy(&p)), ctx) else {
            continue;
        };
        let tri =
            SetupTri { back: !front_facing, ..finish(&verts, z0, [dz[b], dz[c]], range, tri_area, bbox, id) };
        if !misses_every_sample(&tri) {
            out.push(tri);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_point_bounds_hold() {
        // The largest coordinates the guard band admits, plus rounding slack, stay below
        // MAX_FIXED, and the worst edge function value fits i64 with room to spare.
        let guard_fixed = crate::clip::GUARD_BAND_PX as i64 * SUBPIXEL_ONE;
        assert!(2 * guard_fixed <= MAX_FIXED);
        let max_diff = 2 * MAX_FIXED as i128;
        let max_sample = (1i128 << 16) * SUBPIXEL_ONE as i128;
        let max_edge = 2 * max_diff * (MAX_FIXED as i128 + max_sample);
        assert!(max_edge < (1i128 << 61));
    }

    #[test]
    fn to_fixed_rounds_half_up_and_rejects_out_of_range() {
        assert_eq!(to_fixed(0.0), Some(0));
        assert_eq!(to_fixed(1.5), Some(384));
        assert_eq!(to_fixed(0.5 / 256.0), Some(1));
        assert_eq!(to_fixed(-0.5 / 256.0), Some(0));
        assert_eq!(to_fixed(-1.5 / 256.0), Some(-1));
        assert_eq!(to_fixed(-1.7 / 256.0), Some(-2));
        assert_eq!(to_fixed(1e12), None);
        assert_eq!(to_fixed(-1e12), None);
        assert_eq!(to_fixed(f64::NAN), None);
    }

    /// `setup_unclipped` is documented to give bit for bit what projecting the vertices and
    /// `setup_polygon` give (the depth plane included), for any triangle, both orientations.
    #[test]
    fn unclipped_setup_matches_the_polygon_path() {
        let ctx = SetupContext::new(97, 61, false);
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut rand = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut compared = 0;
        for i in 0..20_000 {
            // Sizes from sub-pixel to several times the target, some slivers (scale ~1e-4 in y).
            let size = [0.01, 0.1, 1.0, 5.0][i % 4];
            let squash = if i % 7 == 0 { 1e-4 } else { 1.0 };
            let (cx, cy) = (rand() * 2.0 - 1.0, rand() * 2.0 - 1.0);
            let tri: [DVec4; 3] = std::array::from_fn(|_| {
                let w = 0.5 + rand() * 10.0;
                let (x, y) = (cx + (rand() - 0.5) * size, cy + (rand() - 0.5) * size * squash);
                DVec4::new(x * w, y * w, rand() * w, w)
            });
            let mut direct = Vec::new();
            setup_unclipped(&tri, 7, &ctx, &mut direct);
            let pv = tri.map(|v| project(v, DVec2::ZERO, &ctx));
            let mut via_polygon = Vec::new();
            if let [Some(a), Some(b), Some(c)] = pv {
                // The original triangle's barycentrics, as the clipper would carry them.
                let [a, b, c] =
                    [(a, DVec2::ZERO), (b, DVec2::X), (c, DVec2::Y)].map(|(p, bary)| Projected { bary, ..p });
                setup_polygon(&[a, b, c], 7, &ctx, &mut via_polygon);
            }
            assert_eq!(format!("{direct:?}"), format!("{via_polygon:?}"), "{tri:?}");
            compared += direct.len();
        }
        assert!(compared > 10_000, "{compared}");
    }

    #[test]
    fn ccw_in_ndc_is_front_facing() {
        let ccw =
            [Vec4::new(-0.5, -0.5, 0.5, 1.0), Vec4::new(0.5, -0.5, 0.5, 1.0), Vec4::new(0.0, 0.5, 0.5, 1.0)];
        let cw = [ccw[0], ccw[2], ccw[1]];
        let ctx = SetupContext::new(16, 16, true);
        let mut scratch = ClipScratch::new();
        let mut out = Vec::new();
        setup_triangle(&ccw, 0, &ctx, &mut scratch, &mut out);
        assert_eq!(out.len(), 1);
        out.clear();
        setup_triangle(&cw, 0, &ctx, &mut scratch, &mut out);
        assert!(out.is_empty());
    }
}
