//! `hyrt-raster`: a deterministic, tiled, fixed-point z-buffer rasterizer for clip-space
//! triangles.
//!
//! It knows nothing about scenes, cameras or lights: it takes triangles already transformed to
//! clip space (by whatever projection the caller uses: a camera, a shadow-map frustum...), in
//! slices or made on demand by the setup tasks ([`TriangleSource`]), and returns, per pixel, the
//! visible triangle's id, its depth and its perspective-correct barycentrics.
//!
//! ```
//! use glam::Vec4;
//! use hyrt_raster::{EMPTY_ID, RasterOptions, rasterize};
//!
//! // One counter-clockwise triangle in clip space (w = 1), covering the lower-left half of a
//! // 4x4 image at depth 0.5, with id 7.
//! let tri = [Vec4::new(-1.0, -1.0, 0.5, 1.0), Vec4::new(1.0, -1.0, 0.5, 1.0), Vec4::new(-1.0, 1.0, 0.5, 1.0)];
//! let target = rasterize(&[tri], &[7], 4, 4, &RasterOptions::default());
//! // Pixel (0, 3), bottom left, is covered; pixel (3, 0), top right, is not.
//! assert_eq!(target.id[target.index(0, 3)], 7);
//! assert_eq!(target.depth[target.index(0, 3)], 0.5);
//! assert_eq!(target.id[target.index(3, 0)], EMPTY_ID);
//! ```
//!
//! # Conventions
//!
//! * **Clip space** is the wgpu / D3D / Vulkan one: a point `(x, y, z, w)` is visible when
//!   `-w <= x <= w`, `-w <= y <= w` and `0 <= z <= w`. NDC is `(x, y, z) / w`; NDC `y = +1` is the
//!   top of the image: what `glam::camera::rh::proj::directx::{perspective, orthographic}` produce.
//! * **Depth** stored is NDC `z / w`, in `[0, 1]`, smaller is closer. Triangles are clipped against
//!   the near (`z = 0`) and far (`z = w`) planes, so depths outside `[0, 1]` never appear.
//! * **Pixels**: pixel `(x, y)` covers `[x, x + 1) x [y, y + 1)` in screen space, with `y` growing
//!   downwards (row 0 is the top row, buffers are row-major). Coverage and attributes are sampled at
//!   the pixel centre `(x + 1/2, y + 1/2)`.
//! * **Front faces** are counter-clockwise in NDC (the wgpu / OpenGL default). Back faces are drawn
//!   unless [`RasterOptions::cull_backfaces`] is set.
//! * **Barycentrics** `(b1, b2)` are relative to the vertices of the triangle as passed in (even
//!   when it was clipped), perspective-correct; the point is `(1 - b1 - b2) v0 + b1 v1 + b2 v2` in
//!   any space in which the triangle is affine (world, view, clip). They are interpolated over the
//!   *snapped* vertex positions (see below), so they describe the pixel centre up to the snapping
//!   (1/512 px); callers needing the exact hit point should intersect the pixel's ray with the
//!   triangle's plane.
//! * **Ties**: with [`RasterOptions::depth_tie`] `= 0` (the default), when two triangles have the
//!   same depth at a pixel a front face beats a back face, and between faces of the same facing
//!   the smaller id wins (then the earlier triangle in the slice, for equal ids), so the result
//!   does not depend on the triangle order or on the number of threads. Front first: where a
//!   thin solid's side face (which the pixel's ray enters) meets its bottom face (which it
//!   leaves) within rounding, the face seen from outside is the one shown. With a
//!   window `depth_tie > 0`, depths `d`, `d0` with `|d - d0| <= depth_tie * max(|d|, |d0|)` are a
//!   tie, won the same way, and otherwise the closer depth wins: the rule of ray casting
//!   against exact distances (for reversed-Z depths `n / w` the window is the relative distance
//!   along the ray). Ties are decided pairwise as fragments arrive, in input order, so the result
//!   is still independent of the thread count and the tile size; but the window is not transitive,
//!   so when three or more surfaces are within one window of each other the winner may depend on
//!   the input order (unlike with `depth_tie = 0`).
//!
//! # Precision and limits
//!
//! Vertices are snapped to 1/256 pixel (8 sub-pixel bits) and coverage is decided with exact `i64`
//! edge functions and the top-left fill rule: a closed or shared-edge mesh covers every pixel
//! centre exactly once.
//!
//! Depth is *not* interpolated over the snapped vertices: at a grazing angle, the tilt that
//! snapping gives the plane would cost up to ~1e-4 relative. Per triangle (or per polygon left by
//! near/far clipping) the plane `z/w = A X + B Y + C` is computed in `f64` from the unsnapped
//! screen positions, evaluated in `f64` at the pixel centre and rounded to `f32`: depth is
//! accurate to the `f32` rounding plus a few `f64` roundings (see `setup.rs`). It is then clamped
//! to the range of the polygon's vertex depths, which no point of it can leave: that bounds the
//! error where the plane is ill-conditioned (edge-on slivers). At pixel centres that the snapped
//! coverage includes but the exact triangle does not (within 1/512 px of its edges) the value is
//! the plane extended there, clamped.
//!
//! The side planes are handled with a *guard band*: triangles are clipped only where they reach
//! more than `2^19` pixels outside the image (which keeps fixed-point products in `i64`), so large
//! triangles crossing the image border are rasterized unclipped. Targets may be at most
//! [`MAX_TARGET_DIM`] pixels on a side. Triangles with a NaN or infinite coordinate, zero
//! (snapped) area, or id [`EMPTY_ID`] are skipped; no input can write outside the buffers.
//!
//! # Structure
//!
//! Each stage is one private module whose docs derive its math:
//!
//! * `affine.rs`: [`Affine`] maps to clip space, with a vector kernel for whole triangles (for
//!   callers);
//! * `clip.rs`: homogeneous clipping (near, far, guard band), barycentrics carried as attributes;
//! * `setup/mod.rs`: viewport transform, fixed-point snapping and ranges, facing, interpolation
//!   constants (the unsnapped depth plane and its clamp range, perspective-correct barycentrics);
//! * `edge.rs`: edge functions, top-left fill rule, 8x8 block rejection/acceptance;
//! * `setup/vector.rs`: the same setup for 8 triangles at a time with AVX2 or AVX-512;
//! * `tile.rs`: parallel setup and binning (of slices, or of each chunk made by a
//!   [`TriangleSource`] on the thread that sets it up), tiles as disjoint parts of the output
//!   buffers;
//! * `zbuf/mod.rs`: the per-tile depth test (with the tie window), and barycentrics computed once per
//!   pixel for the winning triangle;
//! * `zbuf/vector.rs`: the same depth test and barycentrics on 8 pixels at a time with AVX2 or
//!   AVX-512.
//!
//! The vector kernels are chosen at run time by the tier `hyrt_simd::Isa::best` detects (x86-64
//! only; the scalar ones are used elsewhere); results are bit-identical whatever the kernel
//! (tests compare them).
//!
//! # Performance notes
//!
//! The time per frame is split between setup (per input triangle: rejection, projection,
//! snapping; reading the input itself dominates for scenes with many off-screen triangles), the
//! depth test (per triangle and tile for the many small triangles of detailed meshes, per
//! fragment for large ones) and the resolve (per pixel: two divisions for the barycentrics). See
//! `benches/raster.rs` (`cargo bench -p hyrt-raster`).

mod affine;
mod clip;
mod edge;
mod setup;
mod tile;
mod zbuf;

use glam::Vec4;
use rayon::prelude::*;

pub use affine::Affine;
use setup::SetupContext;

/// Id stored in [`Target::id`] for pixels no triangle covers. Triangles with this id are skipped.
pub const EMPTY_ID: u32 = u32::MAX;

/// Depth stored in [`Target::depth`] for pixels no triangle covers.
pub const EMPTY_DEPTH: f32 = f32::INFINITY;

/// Depth stored for empty pixels with [`RasterOptions::reversed_z`] (the far plane at infinity).
pub const EMPTY_DEPTH_REVERSED: f32 = 0.0;

/// Largest supported target width or height, in pixels.
pub const MAX_TARGET_DIM: u32 = 1 << 16;

/// Number of fractional bits of the snapped screen-space vertex coordinates.
pub const SUBPIXEL_BITS: u32 = setup::SUBPIXEL_BITS;

/// Result of [`rasterize`]: row-major per-pixel buffers of `width * height` elements
/// (index `y * width + x`, row 0 at the top).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Target {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Depth `z / w` of the visible surface in `[0, 1]` (from its unsnapped plane: see the crate
    /// docs), or [`EMPTY_DEPTH`] ([`EMPTY_DEPTH_REVERSED`] with [`RasterOptions::reversed_z`]).
    /// Empty (length 0) when rasterized with [`RasterOptions::depth`] off.
    pub depth: Vec<f32>,
    /// Id of the visible triangle, or [`EMPTY_ID`].
    pub id: Vec<u32>,
    /// Perspective-correct barycentrics `(b1, b2)` of the pixel centre in the visible triangle
    /// (`b0 = 1 - b1 - b2`), relative to its original, unclipped vertices, interpolated over the
    /// snapped vertex positions (crate docs); `[0, 0]` when empty. Empty (length 0) when
    /// rasterized with [`RasterOptions::barycentrics`] off.
    pub bary: Vec<[f32; 2]>,
    /// Per pixel, the id of the triangle that last lost a depth tie there (within
    /// [`RasterOptions::depth_tie`], or of equal depth without one: decided by the tie rule
    /// rather than by depth), or [`EMPTY_ID`]: where two surfaces are too close for this
    /// rasterizer's depths to order, the other one (a caller with exact arithmetic, such as a
    /// ray's, may order the pair itself). Empty (length 0) unless rasterized with
    /// [`RasterOptions::rivals`].
    pub rival: Vec<u32>,
}

impl Target {
    /// A target with every pixel empty.
    pub fn empty(width: u32, height: u32) -> Self {
        let len = width as usize * height as usize;
        Self {
            width,
            height,
            depth: vec![EMPTY_DEPTH; len],
            id: vec![EMPTY_ID; len],
            bary: vec![[0.0; 2]; len],
            rival: Vec::new(),
        }
    }

    /// Buffer index of pixel `(x, y)`.
    #[inline]
    pub fn index(&self, x: u32, y: u32) -> usize {
        y as usize * self.width as usize + x as usize
    }
}

/// Options of [`rasterize`], [`coverage_count`] and [`for_each_fragment`].
///
/// Not `Eq`: [`RasterOptions::depth_tie`] is a float.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RasterOptions {
    /// Side of the square screen tiles rendered in parallel, in pixels. Rounded up to a multiple of
    /// 8 and clamped to `[8, 4096]`. It affects speed only, never the result. Default 64.
    pub tile_size: u32,
    /// Skip triangles that are clockwise in NDC (back faces for counter-clockwise front faces).
    /// Default `false`: surfaces are two-sided.
    pub cull_backfaces: bool,
    /// Larger depth is closer (reversed-Z), and empty pixels hold [`EMPTY_DEPTH_REVERSED`].
    ///
    /// Why: with `depth = z/w` and the usual projection, depth is `a (1 - n/w)`: every value
    /// sits near `a`, so f32 resolves only `dw/w ~ 6e-8 w/n` (0.3 % at `w = 5e4 n`). With
    /// `z_clip = n` for every vertex the stored depth is `n/w`, which f32 holds with full
    /// relative precision at any distance. The clip planes are the same (`0 <= z <= w`): `z <= w`
    /// is then the near plane `w >= n` and `z >= 0` an infinitely distant far plane. Default
    /// `false`.
    pub reversed_z: bool,
    /// Relative depth window within which two fragments are a tie, won by a front face over a
    /// back face, then by the smaller id (used by [`rasterize`] only). A fragment of depth `d`
    /// against a stored `d0`: if `|d - d0| <= depth_tie * max(|d|, |d0|)` (in `f32`) the tie rule
    /// decides, otherwise the closer depth (the smaller, or the larger with
    /// [`RasterOptions::reversed_z`]).
    ///
    /// Why: ray casting decides between surfaces by exact distances and treats hits within a
    /// relative window as a tie for the face entered, then the smaller id, so that coplanar duplicates (a surface
    /// modelled twice, decals) resolve to the same triangle everywhere instead of speckling; a
    /// rasterized G-buffer must apply the same rule to agree with it. With reversed-Z the depth
    /// `n / w` makes the window the relative distance along the pixel's ray, as in the tracer.
    /// Depth is accurate to a few `f32` ulps (crate docs), so windows of `2^-16` and above are
    /// meaningful.
    ///
    /// Ties are decided pairwise as fragments arrive, in input order: the result is the same for
    /// any thread count and tile size, but when three or more surfaces lie within one window of
    /// each other it may depend on the input order (the window is not transitive), unlike with
    /// `0`. Default `0.0`: exact comparison, equal depths go by the tie rule. Values `<= 0` and
    /// NaN mean `0`; `+inf` means every pair of fragments is a tie.
    pub depth_tie: f32,
    /// Compute [`Target::bary`] (used by [`rasterize`] only). Default `true`. Callers that
    /// recompute hit points from the ids (as the renderer does, exactly, from each pixel's ray)
    /// turn it off: the buffer is left empty, and the per-pixel divisions and the 8 bytes per
    /// pixel of writes are saved.
    pub barycentrics: bool,
    /// Write [`Target::depth`] (used by [`rasterize`] only). Default `true`. Callers that need
    /// only the ids (the renderer's visibility pass, which recomputes each hit from its ray)
    /// turn it off: the buffer is left empty and its 4 bytes per pixel are not written (a
    /// measurable part of that pass). The depth test itself is unchanged.
    pub depth: bool,
    /// Write [`Target::rival`] (used by [`rasterize`] only). Default `false`.
    pub rivals: bool,
}

impl RasterOptions {
    /// [`RasterOptions::default`], as a constant: 64-pixel tiles, both faces drawn, depth in
    /// `[0, 1]` with exact comparisons, depth and barycentrics written.
    pub const DEFAULT: Self = Self {
        tile_size: 64,
        cull_backfaces: false,
        reversed_z: false,
        depth_tie: 0.0,
        barycentrics: true,
        depth: true,
        rivals: false,
    };
}

impl Default for RasterOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// One pixel covered by a triangle, as reported by [`for_each_fragment`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fragment {
    /// Pixel column, `< width`.
    pub x: u32,
    /// Pixel row, `< height` (0 at the top).
    pub y: u32,
    /// Depth `z / w` at the pixel centre, in `[0, 1]` (from the unsnapped plane, clamped: see the
    /// crate docs).
    pub depth: f32,
    /// Perspective-correct barycentrics `(b1, b2)` in the original triangle (interpolated over
    /// the snapped vertices).
    pub bary: [f32; 2],
    /// The triangle faces away from the camera (it loses depth ties to front faces: see
    /// [`RasterOptions::depth_tie`]).
    pub back: bool,
}

fn check_dims(width: u32, height: u32) {
    assert!(
        width <= MAX_TARGET_DIM && height <= MAX_TARGET_DIM,
        "target {width}x{height} exceeds MAX_TARGET_DIM = {MAX_TARGET_DIM}"
    );
}

/// Rasterizes clip-space triangles with a z-buffer, returning the visible triangle, depth and
/// barycentrics per pixel.
///
/// `tris[i]` has id `ids[i]`; ids need not be unique or ordered, but they break depth ties (the
/// smaller wins, see [`RasterOptions::depth_tie`]) and [`EMPTY_ID`] is reserved. A `width` or
/// `height` of 0 gives empty buffers. The result is identical for any rayon thread count and
/// tile size, and with `depth_tie = 0` for any triangle order (for unique ids).
///
/// Allocates its working memory and the target on every call; to draw frame after frame, keep
/// a [`Rasterizer`] and a [`Target`] instead.
///
/// # Panics
///
/// If `tris.len() != ids.len()` or a dimension exceeds [`MAX_TARGET_DIM`].
pub fn rasterize(tris: &[[Vec4; 3]], ids: &[u32], width: u32, height: u32, opts: &RasterOptions) -> Target {
    let mut target = Target::empty(0, 0);
    Rasterizer::new().rasterize_into(tris, ids, width, height, opts, &mut target);
    target
}

/// Triangles made on demand, for [`Rasterizer::rasterize_from`]: the setup tasks ask for them a
/// chunk at a time (a few thousand triangles), each into a buffer of its own, and set them up
/// at once.
///
/// Why: a caller that transforms its triangles to clip space itself (a camera, a shadow-map
/// face; see [`Affine`]) would otherwise write them all to memory in one parallel pass, and
/// setup would read them back in the next: megabytes each way, and a wait for the slower
/// thread in between. Made by the task that sets them up, they are read back from its cache.
/// The projection stays the caller's.
pub trait TriangleSource: Sync {
    /// Number of triangles.
    fn len(&self) -> usize;

    /// Whether there are no triangles.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Writes triangles `first..first + tris.len()` (of `0..len()`), in clip space, into `tris`
    /// and their ids into `ids` (the same length). It must write the same values whenever it is
    /// asked for the same triangles, from whichever thread: then the result is the same for any
    /// thread count, and the same as [`Rasterizer::rasterize_into`] with all the triangles in
    /// slices. It may run parallel work (rayon) of its own.
    fn fill(&self, first: usize, tris: &mut [[Vec4; 3]], ids: &mut [u32]);
}

/// The working memory of [`rasterize`] (set-up triangles and tile bins), kept between frames.
///
/// Why: the bins and set-up triangles of a frame are megabytes; allocated afresh each frame, the
/// allocator maps and unmaps them and every page faults again, a large part of a frame's time
/// (measured single-threaded on a 70k-triangle scene). Results do not depend on what was drawn
/// before.
#[derive(Default)]
pub struct Rasterizer {
    chunks: Vec<tile::Chunk>,
    /// The z-buffer storage of one-tile targets.
    tile_store: zbuf::TileStore,
    /// Triangles and chunks of the last call (`stats` counts from the chunks on demand, so that
    /// frames that do not ask pay nothing).
    submitted: usize,
    used_chunks: usize,
}

/// What the last call of a [`Rasterizer`] processed: where its time goes, per item.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RasterStats {
    /// Triangles passed in (setup reads each).
    pub submitted: usize,
    /// Set-up triangles kept for drawing: triangles (or, after clipping, fan triangles) that are
    /// in view, have a non-zero snapped area and may cover a pixel centre. Those falling between
    /// the pixel centres are dropped by setup and not counted.
    pub set_up: usize,
    /// Of those, the ones whose pixel bounds span at most 2 x 2 pixels: the sub-pixel triangles
    /// of detailed meshes.
    pub tiny: usize,
    /// (set-up triangle, tile) pairs: the depth test's triangle work.
    pub bin_entries: usize,
}

impl std::fmt::Debug for Rasterizer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Rasterizer").field("chunks", &self.chunks.len()).finish_non_exhaustive()
    }
}

impl Rasterizer {
    /// A rasterizer with no memory reserved yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// What the last [`Rasterizer::rasterize_into`] processed (all zero before the first call
    /// and for an empty target).
    pub fn stats(&self) -> RasterStats {
        RasterStats { submitted: self.submitted, ..tile::stats(&self.chunks[..self.used_chunks]) }
    }

    /// [`rasterize`] into `target`, whose buffers are reused (resized to `width x height`; every
    /// element is overwritten, whatever it held). Same result as [`rasterize`].
    ///
    /// # Panics
    ///
    /// If `tris.len() != ids.len()` or a dimension exceeds [`MAX_TARGET_DIM`].
    pub fn rasterize_into(
        &mut self,
        tris: &[[Vec4; 3]],
        ids: &[u32],
        width: u32,
        height: u32,
        opts: &RasterOptions,
        target: &mut Target,
    ) {
        assert_eq!(tris.len(), ids.len(), "one id per triangle");
        self.rasterize_input(tile::Input::Slice { tris, ids: Some(ids) }, width, height, opts, target);
    }

    /// [`Rasterizer::rasterize_into`] with the triangles and ids made on demand by `source`
    /// (see [`TriangleSource`]): the same result as passing them in slices.
    ///
    /// # Panics
    ///
    /// If a dimension exceeds [`MAX_TARGET_DIM`].
    pub fn rasterize_from(
        &mut self,
        source: &dyn TriangleSource,
        width: u32,
        height: u32,
        opts: &RasterOptions,
        target: &mut Target,
    ) {
        self.rasterize_input(tile::Input::Source(source), width, height, opts, target);
    }

    fn rasterize_input(
        &mut self,
        input: tile::Input,
        width: u32,
        height: u32,
        opts: &RasterOptions,
        target: &mut Target,
    ) {
        check_dims(width, height);
        if width == 0 || height == 0 {
            *target = Target::empty(width, height);
            (self.submitted, self.used_chunks) = (0, 0);
            return;
        }
        let ctx = SetupContext::new(width, height, opts.cull_backfaces);
        let isa = zbuf::Isa::best();
        let submitted = input.len();
        let binned = tile::Binned::new(&mut self.chunks, input, &ctx, opts.tile_size, isa);
        (self.submitted, self.used_chunks) = (submitted, binned.chunk_count());
        // `+inf` as the largest finite window: `inf * 0` would be NaN, no tie, for two zero depths.
        let tie = if opts.depth_tie > 0.0 { opts.depth_tie.min(f32::MAX) } else { 0.0 };
        let out = zbuf::Outputs { depth: opts.depth, bary: opts.barycentrics, rivals: opts.rivals };
        zbuf::render(&binned, opts.reversed_z, tie, out, isa, target, &mut self.tile_store);
    }
}

/// Counts, per pixel, how many triangles cover the pixel centre (no depth test), with exactly the
/// coverage rules of [`rasterize`]. Row-major, `width * height` entries.
///
/// Meant for validation (watertightness: a closed mesh drawn with
/// [`RasterOptions::cull_backfaces`] covers each pixel of its silhouette exactly once) and overdraw
/// statistics.
///
/// # Panics
///
/// If a dimension exceeds [`MAX_TARGET_DIM`].
pub fn coverage_count(tris: &[[Vec4; 3]], width: u32, height: u32, opts: &RasterOptions) -> Vec<u32> {
    check_dims(width, height);
    if width == 0 || height == 0 {
        return Vec::new();
    }
    let ctx = SetupContext::new(width, height, opts.cull_backfaces);
    let mut chunks = Vec::new();
    let input = tile::Input::Slice { tris, ids: None };
    let binned = tile::Binned::new(&mut chunks, input, &ctx, opts.tile_size, zbuf::Isa::best());
    let grid = binned.grid;
    let mut count = vec![0u32; width as usize * height as usize];
    grid.split(&mut count).into_par_iter().enumerate().for_each(|(t, mut rows)| {
        let rect = grid.rect(t);
        for tri in binned.tile(t) {
            edge::raster_rect(tri, zbuf::clip_to_tile(rect, tri.bbox), |x, y, _| {
                let n = &mut rows[(y - rect[1]) as usize][(x - rect[0]) as usize];
                *n = n.saturating_add(1);
            });
        }
    });
    count
}

/// Calls `f` once for every pixel whose centre the triangle covers, with the depth and
/// barycentrics [`rasterize`] would store there (before the depth test). Sequential; pixels of a
/// clipped triangle may come in several runs. `opts.tile_size` and `opts.depth_tie` are ignored.
///
/// # Panics
///
/// If a dimension exceeds [`MAX_TARGET_DIM`].
pub fn for_each_fragment(
    tri: &[Vec4; 3],
    width: u32,
    height: u32,
    opts: &RasterOptions,
    mut f: impl FnMut(Fragment),
) {
    check_dims(width, height);
    if width == 0 || height == 0 {
        return;
    }
    let ctx = SetupContext::new(width, height, opts.cull_backfaces);
    let mut setup = Vec::new();
    setup::setup_triangle(tri, 0, &ctx, &mut clip::ClipScratch::new(), &mut setup);
    for t in &setup {
        let [x0, y0, x1, y1] = t.bbox;
        edge::raster_rect(t, [x0, y0, x1 + 1, y1 + 1], |x, y, e| {
            f(Fragment { x, y, depth: t.depth(e), bary: t.bary(e), back: t.back });
        });
    }
}

/// The unit tests' PRNG.
#[cfg(test)]
mod test_rng {
    pub use hyrt_testkit::Rng;
}
