//! The z-buffer of [`crate::rasterize`]: per tile, a depth test over every covered pixel, then one
//! *resolve* pass that computes the barycentrics of the surviving fragments only.
//!
//! # Deferred barycentrics
//!
//! The depth test needs only the depth and the id of a fragment; its barycentrics matter only if
//! it is still visible at the end. So the tile keeps, per pixel, the depth and the index of the
//! winning set-up triangle in the tile's triangle list, and [`ZBuffer::resolve`] evaluates the
//! winner's edge functions at the pixel (exact integers: the values the traversal had) and its
//! barycentrics with [`SetupTri::bary`]. The stored result is bit-identical to computing them for
//! every fragment, with one evaluation per pixel instead of one per fragment (scenes have 1.5-3.5
//! fragments per covered pixel). A triangle rather than an id, because a clipped triangle is
//! several set-up triangles with one id, and ids need not be unique.
//!
//! The resolve writes the tile's rows straight into the caller's full-frame buffers (see
//! [`crate::tile::TileGrid::split`]): no per-tile output buffers, no copies.
//!
//! # Vector kernel
//!
//! On x86-64 CPUs with AVX2 or AVX-512 (detected at run time), the coverage tests and the depth
//! test work on 8 pixels at once (`vector`), computing exactly what the scalar kernel
//! [`ZBuffer::draw_scalar`] computes, and so does the resolve. The vector resolve also empties
//! the z-buffer as it reads it ([`ZBuffer::clean`]), so that the worker's next tile starts
//! without a fill.
//!
//! # Depth test and ties
//!
//! With a tie window `t = depth_tie > 0` ([`crate::RasterOptions::depth_tie`]), fragments whose
//! depths are within `t` relative of each other are a tie, won by a front face, then by the
//! smaller id ([`wins`]). This needs the tie key of the current winner, a load through its triangle index; the kernels
//! therefore decide the (rare) ties separately, lane by lane, and the rest with vector
//! comparisons. `depth_tie = 0` keeps the exact comparison, as a separate instance of every
//! kernel (the const parameter `TIE`), so that it pays nothing for the window.

#[cfg(target_arch = "x86_64")]
pub(crate) mod vector;

use rayon::prelude::*;

use crate::edge::{EdgeFns, cover_rect, row_mask};
use crate::setup::SetupTri;
use crate::tile::Binned;
use crate::{EMPTY_DEPTH, EMPTY_DEPTH_REVERSED, EMPTY_ID, Target};

/// Tile-list index of an empty z-buffer entry.
pub(crate) const NONE: u32 = u32::MAX;

/// Slack after the last row of the tile buffers, beyond one spare row, so that an 8-pixel row
/// access starting at any pixel of the tile, or a 4-pixel access on the row below it, stays
/// inside the buffer.
const PAD: usize = 8;

/// The part of an inclusive pixel box inside a tile rectangle, as a half-open rectangle.
#[inline]
pub(crate) fn clip_to_tile([x0, y0, x1, y1]: [u32; 4], [bx0, by0, bx1, by1]: [u32; 4]) -> [u32; 4] {
    [x0.max(bx0), y0.max(by0), x1.min(bx1 + 1), y1.min(by1 + 1)]
}

pub(crate) use hyrt_simd::{Isa, Tier};

/// The z-buffer of one tile. Kept per worker and reused across tiles.
#[derive(Default)]
pub(crate) struct ZBuffer<'a> {
    /// Tile rectangle `[x0, y0, x1, y1)`.
    pub rect: [u32; 4],
    /// Tile width: the row stride of `depth` and `win`.
    pub w: usize,
    /// Row-major depth of the closest fragment so far, or the empty depth; `w + PAD` extra
    /// entries.
    pub depth: Vec<f32>,
    /// Index in `tris` of the triangle of the closest fragment so far, or [`NONE`]; `w + PAD`
    /// extra.
    pub win: Vec<u32>,
    /// The tile's triangles, in input order.
    pub tris: Vec<&'a SetupTri>,
    /// With `track` ([`crate::RasterOptions::rivals`]): per entry, the id of the triangle that
    /// last lost a depth tie there (within the tie window, or of equal depth without one: decided
    /// by [`wins`]'s tie rule), or [`EMPTY_ID`]; reset as the tile is resolved. A `Cell` so that
    /// the tie paths, which read the z-buffer through a shared reference, can mark it.
    pub rival: Vec<std::cell::Cell<u32>>,
    /// Whether to mark `rival`.
    pub track: bool,
    /// The relative tie window, `> 0` (used by the kernels instantiated with `TIE = true` only).
    pub tie: f32,
    /// Whether every entry of `depth` (all equal to `empty`) and `win` is empty, as the vector
    /// kernels leave them after resolving a tile: then the next tile needs no fill.
    pub clean: bool,
    /// The bits of the empty depth of `depth`.
    empty: u32,
}

/// A tile z-buffer's storage, kept between calls by a [`crate::Rasterizer`] for targets of one
/// tile: a new one would fill both buffers again, every call.
#[derive(Default)]
pub(crate) struct TileStore {
    depth: Vec<f32>,
    win: Vec<u32>,
    clean: bool,
    empty: u32,
}

impl ZBuffer<'_> {
    fn from_store(s: TileStore) -> Self {
        Self { depth: s.depth, win: s.win, clean: s.clean, empty: s.empty, ..Default::default() }
    }

    fn into_store(self) -> TileStore {
        TileStore { depth: self.depth, win: self.win, clean: self.clean, empty: self.empty }
    }
}

/// Whether fragment `(depth d, triangle tri)` replaces the z-buffer entry `(cur, win)`.
///
/// Without `TIE`: lexicographic (depth, back face, id), a total order on fragments, so the surviving
/// fragment is the same whatever order they arrive in. NaN never wins (comparisons are false).
/// Equal (depth, id) keeps the earlier fragment: triangles arrive in input order.
///
/// With `TIE` (window `tie > 0`): depths with `|d - cur| <= tie * max(|d|, |cur|)` (evaluated
/// in `f32`, which [`in_tie_window`] and the vector kernels do identically) are a tie, won by the
/// smaller tie key (front faces first, then the smaller id); otherwise the closer depth wins. Equal depths are always a tie, so this is the
/// rule above with a wider notion of equality; but "within the window" is not transitive, so the
/// survivor of three or more mutually close fragments can depend on their order (which is the
/// input order, for any tiling and thread count).
///
/// An empty entry has the key `(back, EMPTY_ID)`, above any set-up triangle's, and depth `+inf` or `0`
/// (reversed), so every fragment that is not NaN beats it, with either rule: it is closer, or a
/// tie won on the id.
#[inline(always)]
pub(crate) fn wins<const REVERSED: bool, const TIE: bool>(
    d: f32,
    tri: &SetupTri,
    cur: f32,
    win: u32,
    tris: &[&SetupTri],
    tie: f32,
) -> bool {
    let closer = if REVERSED { d > cur } else { d < cur };
    // The empty entry's key is above every triangle's (ids are below `EMPTY_ID`).
    let cur_key = || if win == NONE { (true, EMPTY_ID) } else { tris[win as usize].tie_key() };
    if TIE {
        if in_tie_window(d, cur, tie) { tri.tie_key() < cur_key() } else { closer }
    } else {
        closer || (d == cur && tri.tie_key() < cur_key())
    }
}

/// Whether [`wins`] decides depths `d` and `cur` by the tie rule: within the window with
/// `TIE`, equal without.
#[inline(always)]
pub(crate) fn is_tie<const TIE: bool>(d: f32, cur: f32, tie: f32) -> bool {
    if TIE { in_tie_window(d, cur, tie) } else { d == cur }
}

/// `|d - cur| <= tie * max(|d|, |cur|)`: whether two depths are a tie for the window `tie`.
///
/// For reversed-Z depths `n / w` this is `|w - w'| <= tie * max(w, w')`, the relative distance
/// along any ray, i.e. the tracer's tie rule. The vector kernels compute the same `f32`
/// operations; only the boolean matters, so the choice between equal maxima (`+0` / `-0` cannot
/// occur after `abs`) is irrelevant, and no operand is NaN (depths are clamped, see
/// [`crate::setup::clamp_depth`]).
#[inline(always)]
pub(crate) fn in_tie_window(d: f32, cur: f32, tie: f32) -> bool {
    (d - cur).abs() <= tie * d.abs().max(cur.abs())
}

impl<'a> ZBuffer<'a> {
    /// The bits of the empty depth of the z-buffer.
    #[inline]
    pub fn empty_bits(&self) -> u32 {
        self.empty
    }

    fn reset(
        &mut self,
        rect: [u32; 4],
        empty_depth: f32,
        (tie, track): (f32, bool),
        tris: impl Iterator<Item = &'a SetupTri>,
    ) {
        self.rect = rect;
        self.tie = tie;
        self.w = (rect[2] - rect[0]) as usize;
        let len = self.w * (rect[3] - rect[1] + 1) as usize + PAD;
        self.track = track;
        if track && self.rival.len() < len {
            self.rival.resize(len, std::cell::Cell::new(EMPTY_ID));
        }
        if !(self.clean && self.depth.len() >= len && self.empty == empty_depth.to_bits()) {
            self.depth.clear();
            self.depth.resize(len, empty_depth);
            self.win.clear();
            self.win.resize(len, NONE);
            self.empty = empty_depth.to_bits();
        }
        self.clean = false;
        self.tris.clear();
        self.tris.extend(tris);
        // Indices must stay below NONE. Far beyond anything that fits in memory (a SetupTri is
        // ~100 bytes), but checked: a wrong index would be a silent wrong answer.
        assert!(self.tris.len() < NONE as usize, "too many triangles in one tile");
    }

    /// Depth-tests every triangle of the tile.
    fn draw_all<const REVERSED: bool, const TIE: bool>(&mut self, isa: Isa) {
        match isa.tier() {
            Tier::Scalar => (0..self.tris.len() as u32).for_each(|i| self.draw_scalar::<REVERSED, TIE>(i)),
            #[cfg(target_arch = "x86_64")]
            // SAFETY: an `Isa` of the AVX2 tier exists only where the CPU runs it.
            Tier::Avx2 => unsafe { crate::zbuf::vector::draw_all_avx2::<REVERSED, TIE>(self) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: an `Isa` of the AVX-512 tier exists only where the CPU runs it.
            Tier::Avx512 => unsafe { crate::zbuf::vector::draw_all_avx512::<REVERSED, TIE>(self) },
        }
    }

    /// Depth-tests every pixel of the tile covered by triangle `idx` of the tile list.
    #[inline(always)]
    pub(crate) fn draw_scalar<const REVERSED: bool, const TIE: bool>(&mut self, idx: u32) {
        let tri = self.tris[idx as usize];
        let [tx0, ty0, ..] = self.rect;
        let ef = EdgeFns::new(tri);
        let (sx1, sx2) = (ef.sx[1], ef.sx[2]);
        let (w, tie, track) = (self.w, self.tie, self.track);
        let (depth, win, tris, rival) = (&mut self.depth, &mut self.win, &self.tris, &self.rival);
        let rect = clip_to_tile(self.rect, tri.bbox);
        cover_rect(
            &ef,
            rect,
            |row, n| row_mask(row, &ef.sx, n),
            |x, y, mask, e| {
                let k = (y - ty0) as usize * w + (x - tx0) as usize;
                let n = (u32::BITS - mask.leading_zeros()) as usize;
                let (depth, win) = (&mut depth[k..k + n], &mut win[k..k + n]);
                let (mut e1, mut e2) = (e[1], e[2]);
                for j in 0..n {
                    if mask >> j & 1 != 0 {
                        let d = tri.depth([0, e1, e2]);
                        let won = wins::<REVERSED, TIE>(d, tri, depth[j], win[j], tris, tie);
                        if track && win[j] != NONE && is_tie::<TIE>(d, depth[j], tie) {
                            rival[k + j].set(if won { tris[win[j] as usize].id } else { tri.id });
                        }
                        if won {
                            depth[j] = d;
                            win[j] = idx;
                        }
                    }
                    e1 += sx1;
                    e2 += sx2;
                }
            },
        );
    }

    /// Writes the tile's depth, id and barycentrics into its rows of the full-frame buffers:
    /// every element of every row, with the kernel `isa`.
    ///
    /// The vector kernels also empty the z-buffer as they go (see [`ZBuffer::clean`]).
    fn resolve(&mut self, depth: Rows<f32>, id: Rows<u32>, bary: Rows<[f32; 2]>, isa: Isa) {
        match isa.tier() {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: an `Isa` of the AVX2 tier exists only where the CPU runs it.
            Tier::Avx2 => unsafe { crate::zbuf::vector::resolve_avx2(self, depth, id, bary) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: an `Isa` of the AVX-512 tier exists only where the CPU runs it.
            Tier::Avx512 => unsafe { crate::zbuf::vector::resolve_avx512(self, depth, id, bary) },
            _ => {
                let w = self.w;
                for (r, d_row) in depth.into_iter().enumerate() {
                    d_row.copy_from_slice(&self.depth[r * w..(r + 1) * w]);
                }
                self.resolve_scalar(id, bary);
            }
        }
    }

    /// [`ZBuffer::resolve`] without barycentrics: the tile's ids and, if asked, depths, emptying
    /// the z-buffer as it goes (every entry of the tile's rows; the spare row and padding are
    /// never changed by the kernels), so that it is [`ZBuffer::clean`] afterwards.
    fn resolve_ids(&mut self, depth: Option<Rows<f32>>, id: Rows<u32>) {
        let w = self.w;
        let empty = f32::from_bits(self.empty);
        let mut depth = depth.map(Vec::into_iter);
        for (r, i_row) in id.into_iter().enumerate() {
            let (zd, zw) = (&mut self.depth[r * w..(r + 1) * w], &mut self.win[r * w..(r + 1) * w]);
            if let Some(d_row) = depth.as_mut().and_then(Iterator::next) {
                d_row.copy_from_slice(zd);
            }
            for (o, &win) in i_row.iter_mut().zip(&*zw) {
                *o = if win == NONE { EMPTY_ID } else { self.tris[win as usize].id };
            }
            zd.fill(empty);
            zw.fill(NONE);
        }
        self.clean = true;
    }

    /// The ids and barycentrics of [`ZBuffer::resolve`], one pixel at a time.
    fn resolve_scalar(&self, id: Rows<u32>, bary: Rows<[f32; 2]>) {
        let [tx0, ty0, ..] = self.rect;
        let w = self.w;
        for (r, (i_row, b_row)) in id.into_iter().zip(bary).enumerate() {
            // Runs of pixels with the same winner (long for large triangles): one edge setup per
            // run, then edge values stepped along it. The runs cover the row.
            let wins = &self.win[r * w..(r + 1) * w];
            let mut c = 0;
            while c < w {
                let win = wins[c];
                let end = c + wins[c..].iter().take_while(|&&v| v == win).count();
                if win == NONE {
                    i_row[c..end].fill(EMPTY_ID);
                    b_row[c..end].fill([0.0; 2]);
                } else {
                    let tri = self.tris[win as usize];
                    i_row[c..end].fill(tri.id);
                    let ef = EdgeFns::new(tri);
                    let e = ef.at_pixel(tx0 + c as u32, ty0 + r as u32);
                    bary_run(tri, &ef, e, &mut b_row[c..end]);
                }
                c = end;
            }
        }
    }
}

/// The rows of one tile in a full-frame output buffer, not yet initialised.
pub(crate) type Rows<'o, T> = Vec<&'o mut [T]>;

/// `out[j] = tri.bary(e + j * ef.sx)`: the barycentrics of a run of covered pixels of one triangle,
/// `e` the edge functions at the first.
///
/// Scalar, and inlined into the resolve loop: the pixels are independent, so the out-of-order
/// core overlaps their divisions, which bound the cost. (A vector version, called per run, was no
/// faster: most runs are a few pixels long.)
#[inline(always)]
fn bary_run(tri: &SetupTri, ef: &EdgeFns, mut e: [i64; 3], out: &mut [[f32; 2]]) {
    for b in out {
        *b = tri.bary(e);
        e = [e[0] + ef.sx[0], e[1] + ef.sx[1], e[2] + ef.sx[2]];
    }
}

/// Which of the optional buffers of a [`Target`] to write.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Outputs {
    pub depth: bool,
    pub bary: bool,
    pub rivals: bool,
}

/// Renders the binned triangles into `target` (its buffers reused) with the given kernel and
/// relative depth tie window (`<= 0` or NaN: exact comparisons); the buffers `out` leaves out
/// (`target.depth`, `target.bary`) are left empty, and no barycentrics are computed without
/// `out.bary`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn render(
    binned: &Binned,
    reversed: bool,
    tie: f32,
    out: Outputs,
    isa: Isa,
    target: &mut Target,
    store: &mut TileStore,
) {
    let grid = binned.grid;
    let len = grid.width as usize * grid.height as usize;
    let empty_depth = if reversed { EMPTY_DEPTH_REVERSED } else { EMPTY_DEPTH };
    target.width = grid.width;
    target.height = grid.height;
    let Target { depth, id, bary: bary_buf, rival, .. } = target;
    // The tile that owns a pixel writes it (every one, once), so the buffers need no clearing
    // first: a fill of 16 bytes per pixel would be a measurable part of the frame. A buffer
    // reused at the same size keeps its old values until overwritten; a new one comes zeroed
    // from the allocator ([`fit`]).
    let (depth_len, bary_len) = (if out.depth { len } else { 0 }, if out.bary { len } else { 0 });
    fit(depth, depth_len, 0.0);
    fit(id, len, 0);
    fit(bary_buf, bary_len, [0.0; 2]);
    fit(rival, if out.rivals { len } else { 0 }, EMPTY_ID);
    let rival_tiles: Vec<Option<Rows<u32>>> = if out.rivals {
        grid.split(&mut rival[..]).into_iter().map(Some).collect()
    } else {
        (0..grid.count()).map(|_| None).collect()
    };
    let depth_tiles: Vec<Option<Rows<f32>>> = if out.depth {
        grid.split(&mut depth[..]).into_iter().map(Some).collect()
    } else {
        (0..grid.count()).map(|_| None).collect()
    };
    let id_tiles = grid.split(&mut id[..]);
    let bary_tiles: Vec<Option<Rows<[f32; 2]>>> = if out.bary {
        grid.split(&mut bary_buf[..]).into_iter().map(Some).collect()
    } else {
        (0..grid.count()).map(|_| None).collect()
    };
    let how = (reversed, tie, empty_depth, isa);
    if grid.count() == 1 {
        // One tile (a light map's page): drawn on this thread, in the z-buffer it keeps, with no
        // parallel machinery to set up for a call that may hold a few dozen triangles.
        let (depth, id, bary) =
            (depth_tiles.into_iter().next(), id_tiles.into_iter().next(), bary_tiles.into_iter().next());
        let mut zb = ZBuffer::from_store(std::mem::take(store));
        let rival = rival_tiles.into_iter().next().flatten();
        let buffers = (depth.flatten(), id.expect("one tile"), bary.flatten(), rival);
        draw_tile(binned, how, &mut zb, &mut Vec::new(), 0, buffers);
        *store = zb.into_store();
        return;
    }
    depth_tiles.into_par_iter().zip(id_tiles).zip(bary_tiles).zip(rival_tiles).enumerate().for_each_init(
        || (ZBuffer::default(), Vec::new()),
        |(zb, scratch), (t, (((depth, id), bary), rival))| {
            draw_tile(binned, how, zb, scratch, t, (depth, id, bary, rival))
        },
    );
}

/// A tile's rows of the target's buffers: depth (if kept), ids, barycentrics (if kept),
/// rivals (if kept).
type TileRows<'b> = (Option<Rows<'b, f32>>, Rows<'b, u32>, Option<Rows<'b, [f32; 2]>>, Option<Rows<'b, u32>>);

/// Draws tile `t` of `binned` with z-buffer `zb` into its rows of the target's buffers.
fn draw_tile<'c>(
    binned: &Binned<'c>,
    (reversed, tie, empty_depth, isa): (bool, f32, f32, Isa),
    zb: &mut ZBuffer<'c>,
    scratch: &mut Vec<f32>,
    t: usize,
    (depth, id, bary, rival): TileRows,
) {
    let grid = binned.grid;
    if binned.tile_is_empty(t) {
        depth.into_iter().flatten().for_each(|d| d.fill(empty_depth));
        id.into_iter().for_each(|i| i.fill(EMPTY_ID));
        bary.into_iter().flatten().for_each(|b| b.fill([0.0; 2]));
        rival.into_iter().flatten().for_each(|c| c.fill(EMPTY_ID));
        return;
    }
    zb.reset(grid.rect(t), empty_depth, (tie, rival.is_some()), binned.tile(t));
    // `!(tie > 0)` includes NaN.
    match (reversed, tie > 0.0) {
        (false, false) => zb.draw_all::<false, false>(isa),
        (false, true) => zb.draw_all::<false, true>(isa),
        (true, false) => zb.draw_all::<true, false>(isa),
        (true, true) => zb.draw_all::<true, true>(isa),
    }
    match bary {
        Some(bary) => {
            // The barycentric kernels write depths too: without a depth buffer, into
            // a tile of scratch that stays in this thread's cache.
            let depth = depth.unwrap_or_else(|| {
                let [x0, y0, x1, y1] = grid.rect(t);
                let w = (x1 - x0) as usize;
                scratch.resize(w * (y1 - y0) as usize, 0.0);
                scratch.chunks_mut(w).collect()
            });
            zb.resolve(depth, id, bary, isa)
        }
        None => zb.resolve_ids(depth, id),
    }
    // The tile's marks, cleared for its next use.
    if let Some(rows) = rival {
        let w = zb.w;
        for (r, row) in rows.into_iter().enumerate() {
            for (o, c) in row.iter_mut().zip(&zb.rival[r * w..(r + 1) * w]) {
                *o = c.replace(EMPTY_ID);
            }
        }
    }
}

/// Gives `buf` exactly `len` elements, with no pass over those it already has: a reused buffer
/// of the same size is left as it is, and an empty one is allocated zeroed (`vec!` of a zero
/// value asks the allocator for zeroed pages instead of writing them).
fn fit<T: Copy>(buf: &mut Vec<T>, len: usize, zero: T) {
    if buf.is_empty() {
        *buf = vec![zero; len];
    } else {
        buf.resize(len, zero);
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec4;

    use super::*;
    use crate::setup::SetupContext;

    use crate::test_rng::Rng;

    /// Triangles of every size class the kernels treat differently: sub-pixel, a few pixels, 8x8
    /// blocks, tile-filling, guard-band sized (thousands of screens across), crossing the near plane,
    /// plus exact duplicates and coplanar overlaps with other ids (depth ties), and copies moved
    /// by ~1e-6 relative in depth (ties within a window only).
    fn scene() -> (Vec<[Vec4; 3]>, Vec<u32>) {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let mut tris = Vec::new();
        for i in 0..3000 {
            let size = [0.005, 0.03, 0.2, 1.5, 4000.0][i % 5];
            let (cx, cy) = (rng.f32() * 2.4 - 1.2, rng.f32() * 2.4 - 1.2);
            let w = 0.5 + rng.f32() * 4.0;
            let mut v = |_| {
                let z = if i % 97 == 0 { rng.f32() * 2.0 - 1.0 } else { rng.f32() * 0.9 + 0.05 };
                let (x, y) = (cx + (rng.f32() - 0.5) * size, cy + (rng.f32() - 0.5) * size);
                Vec4::new(x * w, y * w, z * w, w)
            };
            tris.push([v(0), v(1), v(2)]);
        }
        // Ties: duplicates (same and other ids), and a coplanar overlapping pair.
        for i in (0..600).step_by(7) {
            tris.push(tris[i]);
            tris.push([tris[i][1], tris[i][2], tris[i][0]]);
        }
        let quad = |x0: f32, x1: f32| {
            let p = |x: f32, y: f32| Vec4::new(x, y, 0.5, 1.0);
            [p(x0, -0.8), p(x1, -0.8), p(x0, 0.8)]
        };
        tris.extend([quad(-0.9, 0.3), quad(-0.5, 0.9)]);
        for i in (3..1000).step_by(25) {
            let moved = tris[i].map(|v| Vec4::new(v.x, v.y, v.z * (1.0 + 1e-6 * (1.0 + rng.f32())), v.w));
            tris.push(moved);
        }
        // Ids in scrambled order (so that ties go either way) and a few repeated ones.
        let n = tris.len() as u64;
        let ids = (0..n).map(|i| if i % 11 == 3 { 5 } else { (i * 7919 % n) as u32 }).collect();
        (tris, ids)
    }

    fn render_with(isa: Isa, tris: &[[Vec4; 3]], ids: &[u32], reversed: bool, tie: f32, tile: u32) -> Target {
        let mut t = Target::empty(0, 0);
        render_into(isa, tris, ids, reversed, tie, tile, ALL, &mut t);
        t
    }

    const ALL: Outputs = Outputs { depth: true, bary: true, rivals: true };

    #[allow(clippy::too_many_arguments)]
    fn render_into(
        isa: Isa,
        tris: &[[Vec4; 3]],
        ids: &[u32],
        reversed: bool,
        tie: f32,
        tile: u32,
        out: Outputs,
        target: &mut Target,
    ) {
        let (width, height) = (203, 157);
        let ctx = SetupContext::new(width, height, false);
        let mut chunks = Vec::new();
        let binned =
            Binned::new(&mut chunks, crate::tile::Input::Slice { tris, ids: Some(ids) }, &ctx, tile, isa);
        render(&binned, reversed, tie, out, isa, target, &mut TileStore::default());
    }

    fn bits(t: &Target) -> (Vec<u32>, Vec<u32>, Vec<[u32; 2]>) {
        (
            t.depth.iter().map(|d| d.to_bits()).collect(),
            t.id.clone(),
            t.bary.iter().map(|b| b.map(f32::to_bits)).collect(),
        )
    }

    /// Every kernel records the same rivals (the losers of ties decided by the tie rule), in
    /// both depth conventions, with and without a window: at the duplicates and coplanar
    /// overlaps of [`scene`] (and, with a wide window, many more); never the winner itself.
    #[test]
    fn every_kernel_records_the_same_rivals() {
        let (tris, ids) = scene();
        for reversed in [false, true] {
            let mut counts = Vec::new();
            for tie in [0.0, 1.0 / 65536.0, 1e-2] {
                let reference = render_with(Isa::SCALAR, &tris, &ids, reversed, tie, 64);
                let n = reference.rival.iter().filter(|&&r| r != EMPTY_ID).count();
                assert!(n > 10, "tie {tie}: {n} rivals");
                // A pixel with a rival has a winner, another triangle (the scene's ids are
                // unique but for its duplicates, which share them).
                assert!(
                    reference
                        .rival
                        .iter()
                        .zip(&reference.id)
                        .all(|(&r, &id)| r == EMPTY_ID || id != EMPTY_ID)
                );
                for isa in Isa::for_tests("z-buffer kernels") {
                    for tile in [8, 64] {
                        let t = render_with(isa, &tris, &ids, reversed, tie, tile);
                        assert!(t.rival == reference.rival, "{isa:?} tie {tie} tile {tile}");
                    }
                }
                counts.push(n);
            }
            // A wider window calls more pairs ties.
            assert!(counts[0] <= counts[1] && counts[1] < counts[2], "{counts:?}");
        }
        // Not asked: not written.
        let mut t = Target::default();
        let out = Outputs { depth: true, bary: false, rivals: false };
        render_into(Isa::best(), &tris, &ids, true, 1e-2, 64, out, &mut t);
        assert!(t.rival.is_empty());
    }

    /// Two triangles far larger than the screen, intersecting along `x = 0`, behind and in front
    /// of small ones: every kernel gives the scalar kernel's buffers bit for bit. Their edge
    /// values exceed `2^51` at every pixel, where the AVX2 kernels must take their exact
    /// `i64 -> f64` conversion, in the depth test and in the resolve.
    #[test]
    fn screen_filling_guard_band_triangles_give_identical_buffers() {
        // Vertices 4000 NDC units out (406k pixels across the 203-pixel width, inside the
        // guard band: not clipped). Every pixel lies more than 1700 units (over 1.3e5 pixels)
        // from each edge, of length over 8000 units (6.2e5 pixels): the edge function, the
        // product of the two in 1/256 pixel units, exceeds `1.3e5 * 6.2e5 * 2^16 > 2^52`.
        let big = |z: [f32; 3]| {
            let p = |x: f32, y: f32, z: f32| Vec4::new(x, y, z, 1.0);
            [p(-4000.0, -4000.0, z[0]), p(4000.0, -4000.0, z[1]), p(0.0, 4000.0, z[2])]
        };
        let (small, small_ids) = scene();
        let mut tris = vec![big([0.2, 0.8, 0.5]), big([0.8, 0.2, 0.5])];
        tris.extend(small.iter().step_by(5).take(300));
        let mut ids: Vec<u32> = vec![1_000_001, 1_000_002];
        ids.extend(small_ids.iter().step_by(5).take(300));
        for reversed in [false, true] {
            for tie in [0.0, 1.0 / 65536.0] {
                for tile in [8, 64] {
                    let reference = render_with(Isa::SCALAR, &tris, &ids, reversed, tie, tile);
                    // Not vacuous: both large triangles win pixels.
                    for big_id in [1_000_001, 1_000_002] {
                        assert!(reference.id.iter().filter(|&&id| id == big_id).count() > 1000);
                    }
                    let reference = bits(&reference);
                    for isa in Isa::for_tests("z-buffer kernels") {
                        let t = render_with(isa, &tris, &ids, reversed, tie, tile);
                        assert!(
                            bits(&t) == reference,
                            "{isa:?}, reversed {reversed}, tie {tie}, tile {tile}"
                        );
                    }
                }
            }
        }
    }

    /// Every kernel gives the scalar kernel's buffers bit for bit, in both depth conventions,
    /// for three tile sizes (the last taller than the 203 x 157 target), without a tie window,
    /// with the renderer's `2^-16` and with a wide one (`1e-2`: many random overlaps become
    /// ties, so the per-lane tie path runs a lot).
    #[test]
    fn every_kernel_gives_identical_buffers() {
        let (tris, ids) = scene();
        let isas = Isa::for_tests("z-buffer kernels");
        assert_eq!(isas.last().copied(), Some(Isa::best()));
        for reversed in [false, true] {
            let exact = bits(&render_with(Isa::SCALAR, &tris, &ids, reversed, 0.0, 64));
            for tie in [0.0, 1.0 / 65536.0, 1e-2] {
                for tile in [8, 64, 200] {
                    let reference = render_with(Isa::SCALAR, &tris, &ids, reversed, tie, tile);
                    assert!(reference.id.iter().filter(|&&id| id != EMPTY_ID).count() > 10_000);
                    let reference = bits(&reference);
                    // Not vacuous: the window changes some winners.
                    assert_eq!(tie == 0.0, reference.1 == exact.1, "tie {tie}, reversed {reversed}");
                    for &isa in &isas {
                        let mut t = render_with(isa, &tris, &ids, reversed, tie, tile);
                        assert!(
                            bits(&t) == reference,
                            "{isa:?}, reversed {reversed}, tie {tie}, tile {tile}"
                        );
                        // Without barycentrics, into the buffers of another frame (the other
                        // depth convention: every stale value differs): the same depths and ids.
                        render_into(isa, &tris, &ids, !reversed, tie, tile, ALL, &mut t);
                        let no_bary = Outputs { depth: true, bary: false, rivals: true };
                        render_into(isa, &tris, &ids, reversed, tie, tile, no_bary, &mut t);
                        let (d, i, b) = bits(&t);
                        assert!(
                            (&d, &i) == (&reference.0, &reference.1) && b.is_empty(),
                            "no barycentrics: {isa:?}, reversed {reversed}, tie {tie}, tile {tile}"
                        );
                        // Without depths (the barycentric kernels then write theirs to scratch
                        // rows), after a frame with them: the same ids and barycentrics.
                        for bary in [true, false] {
                            render_into(isa, &tris, &ids, !reversed, tie, tile, ALL, &mut t);
                            render_into(
                                isa,
                                &tris,
                                &ids,
                                reversed,
                                tie,
                                tile,
                                Outputs { depth: false, bary, rivals: false },
                                &mut t,
                            );
                            let (d, i, b) = bits(&t);
                            let expected_bary = if bary { &reference.2[..] } else { &[] };
                            assert!(
                                d.is_empty() && i == reference.1 && b == expected_bary,
                                "no depths, barycentrics {bary}: {isa:?}, reversed {reversed}, tie {tie}, tile {tile}"
                            );
                        }
                    }
                }
            }
        }
    }
}
