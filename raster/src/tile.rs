//! Parallel setup and binning of triangles into screen tiles, and parallel per-tile rendering
//! straight into the caller's full-frame buffers.
//!
//! # Determinism
//!
//! The output must be byte-identical for any number of threads. Three things ensure it:
//!
//! * setup is parallel over fixed-size chunks of the input, and every chunk bins its own set-up
//!   triangles (in input order); a tile visits the chunks in input order, so every tile sees its
//!   triangles in increasing input order for any thread count;
//! * each tile is rendered by exactly one task, which alone writes the tile's pixels;
//! * what a task writes depends only on the tile and its triangle list.
//!
//! The per-pixel depth test additionally makes the z-buffer independent of triangle order (ties
//! broken by id), but the above is what makes it independent of scheduling.

use rayon::prelude::*;

use crate::TriangleSource;
use crate::edge::BLOCK;
use crate::setup::{SetupContext, SetupTri, setup_chunk};
use crate::zbuf::{Isa, Tier};

use glam::Vec4;

/// Input triangles per parallel setup task: large enough to amortise task overhead, small enough
/// that the few tens of thousands of triangles a frame's culling leaves (a dozen tasks at twice
/// this size) balance over the cores.
const SETUP_CHUNK: usize = 1024;

/// Rounds a requested tile size up to a multiple of the block size, within `[BLOCK, 4096]`.
pub(crate) fn effective_tile_size(requested: u32) -> u32 {
    requested.clamp(BLOCK, 4096).next_multiple_of(BLOCK)
}

/// Grid of `tile`-pixel square tiles covering a `width x height` target.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TileGrid {
    pub width: u32,
    pub height: u32,
    pub tile: u32,
    pub tiles_x: u32,
    pub tiles_y: u32,
    /// `ceil(2^32 / tile)`: `x / tile == (x * recip) >> 32` for every pixel coordinate (see
    /// [`TileGrid::tile_of`]). Binning divides 4 coordinates per triangle.
    recip: u64,
}

impl TileGrid {
    pub fn new(width: u32, height: u32, tile: u32) -> Self {
        Self {
            width,
            height,
            tile,
            tiles_x: width.div_ceil(tile),
            tiles_y: height.div_ceil(tile),
            recip: (1u64 << 32).div_ceil(u64::from(tile)),
        }
    }

    pub fn count(&self) -> usize {
        self.tiles_x as usize * self.tiles_y as usize
    }

    /// Pixel rectangle `[x0, y0, x1, y1)` of tile `t` (row-major tile index).
    pub fn rect(&self, t: usize) -> [u32; 4] {
        let (tx, ty) = (t as u32 % self.tiles_x, t as u32 / self.tiles_x);
        let (x0, y0) = (tx * self.tile, ty * self.tile);
        [x0, y0, (x0 + self.tile).min(self.width), (y0 + self.tile).min(self.height)]
    }

    /// Inclusive tile ranges `[tx0, ty0, tx1, ty1]` overlapped by an inclusive pixel box.
    #[inline]
    fn tiles_of(&self, [x0, y0, x1, y1]: [u32; 4]) -> [u32; 4] {
        [self.tile_of(x0), self.tile_of(y0), self.tile_of(x1), self.tile_of(y1)]
    }

    /// `x / tile` for a pixel coordinate `x < MAX_TARGET_DIM = 2^16`, without a division.
    ///
    /// With `recip = 2^32 / tile + r`, `0 <= r < 1`: `x recip / 2^32 = x / tile + x r / 2^32`,
    /// and the error `x r / 2^32 < 2^-16` cannot reach the next integer, because `x / tile` is
    /// either an integer or at least `1 / tile >= 2^-12` below one (`tile <= 4096`).
    #[inline]
    fn tile_of(&self, x: u32) -> u32 {
        ((u64::from(x) * self.recip) >> 32) as u32
    }

    /// Splits a row-major full-frame buffer into the rows of each tile: entry `t` holds the rows
    /// of tile `t`, top to bottom, each `x1 - x0` long. The slices are disjoint, so tiles can be
    /// written in parallel without synchronisation or copies.
    pub fn split<'b, T>(&self, buf: &'b mut [T]) -> Vec<Vec<&'b mut [T]>> {
        assert_eq!(buf.len(), self.width as usize * self.height as usize);
        let rows = self.tile.min(self.height) as usize;
        let mut tiles: Vec<Vec<&mut [T]>> = (0..self.count()).map(|_| Vec::with_capacity(rows)).collect();
        for (y, row) in buf.chunks_exact_mut(self.width as usize).enumerate() {
            let first = y / self.tile as usize * self.tiles_x as usize;
            for (tile, seg) in tiles[first..].iter_mut().zip(row.chunks_mut(self.tile as usize)) {
                tile.push(seg);
            }
        }
        tiles
    }
}

/// The set-up triangles of one chunk of the input, binned by tile. Its vectors are kept by a
/// [`crate::Rasterizer`] and reused frame after frame: allocating them afresh costs page faults
/// (a large part of the frame, measured) once they are large enough to be mapped and unmapped.
#[derive(Default)]
pub(crate) struct Chunk {
    tris: Vec<SetupTri>,
    /// Triangles overlapping tile `t`: `items[start[t]..start[t + 1]]`, indices into `tris` in
    /// increasing order.
    start: Vec<u32>,
    items: Vec<u32>,
    /// Scratch of the counting sort.
    fill: Vec<u32>,
}

thread_local! {
    /// A chunk's input made by a [`TriangleSource`], per thread: made and set up by the same
    /// task, in the same memory for every chunk the thread sets up, it is read back from the
    /// core's cache.
    static SOURCED: std::cell::RefCell<(Vec<[Vec4; 3]>, Vec<u32>)> = Default::default();
}

impl Chunk {
    /// Sets up `input` (ids `None`: id 0 for all) with the kernel `isa`, replacing `self.tris`.
    fn set_up(&mut self, input: &[[Vec4; 3]], ids: Option<&[u32]>, ctx: &SetupContext, isa: Isa) {
        let out = &mut self.tris;
        out.clear();
        out.reserve(input.len());
        match isa.tier() {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: an `Isa` of the AVX2 tier exists only where the CPU runs it.
            Tier::Avx2 => unsafe { crate::setup::vector::setup_chunk_avx2(input, ids, ctx, out) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: an `Isa` of the AVX-512 tier exists only where the CPU runs it.
            Tier::Avx512 => unsafe { crate::setup::vector::setup_chunk_avx512(input, ids, ctx, out) },
            _ => setup_chunk(input, ids, ctx, out),
        }
    }

    /// Bins `self.tris` with a counting sort (two passes over the tile ranges).
    fn bin(&mut self, grid: &TileGrid) {
        let start = &mut self.start;
        start.clear();
        start.resize(grid.count() + 1, 0);
        for tri in &self.tris {
            let [tx0, ty0, tx1, ty1] = grid.tiles_of(tri.bbox);
            for ty in ty0..=ty1 {
                let row = (ty * grid.tiles_x) as usize;
                for t in row + tx0 as usize..=row + tx1 as usize {
                    start[t + 1] += 1;
                }
            }
        }
        for t in 0..grid.count() {
            start[t + 1] += start[t];
        }
        self.fill.clear();
        self.fill.extend_from_slice(start);
        self.items.clear();
        self.items.resize(start[grid.count()] as usize, 0);
        for (i, tri) in self.tris.iter().enumerate() {
            let [tx0, ty0, tx1, ty1] = grid.tiles_of(tri.bbox);
            for ty in ty0..=ty1 {
                let row = (ty * grid.tiles_x) as usize;
                for t in row + tx0 as usize..=row + tx1 as usize {
                    self.items[self.fill[t] as usize] = i as u32;
                    self.fill[t] += 1;
                }
            }
        }
    }
}

/// Counts of the set-up triangles and bin entries of `chunks` (`submitted` left 0).
pub(crate) fn stats(chunks: &[Chunk]) -> crate::RasterStats {
    let tris = || chunks.iter().flat_map(|c| &c.tris);
    crate::RasterStats {
        submitted: 0,
        set_up: tris().count(),
        tiny: tris().filter(|t| t.bbox[2] - t.bbox[0] <= 1 && t.bbox[3] - t.bbox[1] <= 1).count(),
        bin_entries: chunks.iter().map(|c| c.items.len()).sum(),
    }
}

/// The triangles to set up: slices (ids `None`: id 0 for all), or made chunk by chunk.
#[derive(Clone, Copy)]
pub(crate) enum Input<'a> {
    Slice { tris: &'a [[Vec4; 3]], ids: Option<&'a [u32]> },
    Source(&'a dyn TriangleSource),
}

impl Input<'_> {
    pub(crate) fn len(&self) -> usize {
        match self {
            Input::Slice { tris, .. } => tris.len(),
            Input::Source(source) => source.len(),
        }
    }
}

/// All set-up triangles, binned into the tiles of `grid`.
pub(crate) struct Binned<'c> {
    pub grid: TileGrid,
    chunks: &'c [Chunk],
}

impl<'c> Binned<'c> {
    /// Sets up and bins all triangles of `input` in parallel, with the setup kernel `isa`, into
    /// `chunks` (grown as needed, reused otherwise). Triangles with id
    /// [`EMPTY_ID`](crate::EMPTY_ID) are dropped.
    pub fn new(
        chunks: &'c mut Vec<Chunk>,
        input: Input,
        ctx: &SetupContext,
        tile_size: u32,
        isa: Isa,
    ) -> Self {
        let grid = TileGrid::new(ctx.width, ctx.height, effective_tile_size(tile_size));
        let len = input.len();
        let n = len.div_ceil(SETUP_CHUNK);
        if chunks.len() < n {
            chunks.resize_with(n, Chunk::default);
        }
        let chunks = &mut chunks[..n];
        let set_up = |(c, chunk): (usize, &mut Chunk)| {
            let first = c * SETUP_CHUNK;
            let count = (len - first).min(SETUP_CHUNK);
            match input {
                Input::Slice { tris, ids } => {
                    chunk.set_up(&tris[first..][..count], ids.map(|ids| &ids[first..][..count]), ctx, isa)
                }
                Input::Source(source) => {
                    let mut make = |(tris, ids): &mut (Vec<[Vec4; 3]>, Vec<u32>)| {
                        // Grown, never shrunk: every entry below `count` is overwritten.
                        if tris.len() < count {
                            tris.resize(count, [Vec4::ZERO; 3]);
                            ids.resize(count, 0);
                        }
                        source.fill(first, &mut tris[..count], &mut ids[..count]);
                        chunk.set_up(&tris[..count], Some(&ids[..count]), ctx, isa);
                    };
                    SOURCED.with(|buffer| match buffer.try_borrow_mut() {
                        Ok(mut buffer) => make(&mut buffer),
                        // In use: a `fill` that runs parallel work of its own let this thread
                        // take another chunk while it waited.
                        Err(_) => make(&mut Default::default()),
                    })
                }
            }
            chunk.bin(&grid);
        };
        // One chunk (a light map's page, say): set up on this thread, with no parallel
        // machinery for a call that may hold a few dozen triangles.
        if let [chunk] = chunks {
            set_up((0, chunk));
        } else {
            chunks.par_iter_mut().enumerate().for_each(set_up);
        }
        Self { grid, chunks }
    }

    /// The triangles overlapping tile `t`, in input order.
    pub fn tile(&self, t: usize) -> impl Iterator<Item = &'c SetupTri> + use<'c> {
        self.chunks.iter().flat_map(move |c| {
            let items = &c.items[c.start[t] as usize..c.start[t + 1] as usize];
            items.iter().map(|&i| &c.tris[i as usize])
        })
    }

    /// The number of chunks holding this call's triangles.
    pub fn chunk_count(&self) -> usize {
        self.chunks.len()
    }

    /// Whether no triangle overlaps tile `t`.
    pub fn tile_is_empty(&self, t: usize) -> bool {
        self.chunks.iter().all(|c| c.start[t] == c.start[t + 1])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tile_size_is_a_block_multiple() {
        assert_eq!(effective_tile_size(0), 8);
        assert_eq!(effective_tile_size(64), 64);
        assert_eq!(effective_tile_size(65), 72);
        assert_eq!(effective_tile_size(u32::MAX), 4096);
    }

    #[test]
    fn tile_of_divides_exactly() {
        for tile in (8..=4096).step_by(8) {
            let grid = TileGrid::new(crate::MAX_TARGET_DIM, 1, tile);
            assert!((0..crate::MAX_TARGET_DIM).all(|x| grid.tile_of(x) == x / tile), "tile {tile}");
        }
    }

    #[test]
    fn tiles_cover_the_target_exactly() {
        let grid = TileGrid::new(100, 37, 16);
        let mut hits = vec![0u8; 100 * 37];
        for t in 0..grid.count() {
            let [x0, y0, x1, y1] = grid.rect(t);
            for y in y0..y1 {
                for x in x0..x1 {
                    hits[(y * 100 + x) as usize] += 1;
                }
            }
        }
        assert!(hits.iter().all(|&h| h == 1));
    }

    #[test]
    fn split_gives_each_tile_its_rows() {
        let grid = TileGrid::new(100, 37, 16);
        let mut buf: Vec<usize> = (0..100 * 37).collect();
        let tiles = grid.split(&mut buf);
        for (t, rows) in tiles.iter().enumerate() {
            let [x0, y0, x1, y1] = grid.rect(t);
            assert_eq!(rows.len(), (y1 - y0) as usize);
            for (r, row) in rows.iter().enumerate() {
                let y = y0 as usize + r;
                let expect: Vec<usize> = (x0 as usize..x1 as usize).map(|x| y * 100 + x).collect();
                assert_eq!(**row, expect[..]);
            }
        }
    }
}
