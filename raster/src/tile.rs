//! Binning of set-up triangles into screen tiles, and parallel per-tile rasterization.
//!
//! # Determinism
//!
//! The output must be byte-identical for any number of threads. Three things ensure it:
//!
//! * setup is parallel over fixed-size chunks of the input, and the chunks' results are
//!   concatenated in input order, so the set-up triangle list is the same for any thread count;
//! * binning is sequential, so every bin lists its triangles in increasing index order;
//! * each tile is rendered by exactly one task into its own buffer, visiting its bin in order, and
//!   the tile buffers are copied into the full image in a fixed order afterwards.
//!
//! The per-pixel `shade` function additionally makes the z-buffer independent of triangle order
//! (ties broken by id), but the above is what makes it independent of scheduling.

use rayon::prelude::*;

use crate::EMPTY_ID;
use crate::clip::ClipScratch;
use crate::edge::{BLOCK, raster_rect};
use crate::setup::{SetupContext, SetupTri, setup_triangle};

use glam::Vec4;

/// Input triangles per parallel setup task: large enough to amortise task overhead, small enough
/// to balance a few hundred thousand triangles over the cores.
const SETUP_CHUNK: usize = 2048;

/// Rounds a requested tile size up to a multiple of the block size, within `[BLOCK, 4096]`.
pub(crate) fn effective_tile_size(requested: u32) -> u32 {
    requested.clamp(BLOCK, 4096).next_multiple_of(BLOCK)
}

/// Sets up all triangles in parallel. The result is a list of chunks whose concatenation is in
/// input order (it is never concatenated: bins point into the chunks). With `ids`, triangles with
/// id [`EMPTY_ID`] are dropped; `ids: None` uses id 0 for all.
pub(crate) fn setup_all(tris: &[[Vec4; 3]], ids: Option<&[u32]>, ctx: &SetupContext) -> Vec<Vec<SetupTri>> {
    tris.par_chunks(SETUP_CHUNK)
        .enumerate()
        .map(|(c, chunk)| {
            let mut out = Vec::with_capacity(chunk.len());
            let mut scratch = ClipScratch::new();
            for (k, tri) in chunk.iter().enumerate() {
                let id = ids.map_or(0, |ids| ids[c * SETUP_CHUNK + k]);
                if id != EMPTY_ID {
                    setup_triangle(tri, id, ctx, &mut scratch, &mut out);
                }
            }
            out
        })
        .collect()
}

/// Grid of `tile`-pixel square tiles covering a `width x height` target.
#[derive(Clone, Copy, Debug)]
struct TileGrid {
    width: u32,
    height: u32,
    tile: u32,
    tiles_x: u32,
    tiles_y: u32,
}

impl TileGrid {
    fn new(width: u32, height: u32, tile: u32) -> Self {
        Self { width, height, tile, tiles_x: width.div_ceil(tile), tiles_y: height.div_ceil(tile) }
    }

    fn count(&self) -> usize {
        self.tiles_x as usize * self.tiles_y as usize
    }

    /// Pixel rectangle `[x0, y0, x1, y1)` of tile `t` (row-major tile index).
    fn rect(&self, t: usize) -> [u32; 4] {
        let (tx, ty) = (t as u32 % self.tiles_x, t as u32 / self.tiles_x);
        let (x0, y0) = (tx * self.tile, ty * self.tile);
        [x0, y0, (x0 + self.tile).min(self.width), (y0 + self.tile).min(self.height)]
    }

    /// Lists, for every tile, the triangles whose pixel bounds overlap it, in input order.
    fn bin<'t>(&self, chunks: &'t [Vec<SetupTri>]) -> Vec<Vec<&'t SetupTri>> {
        let mut bins = vec![Vec::new(); self.count()];
        for tri in chunks.iter().flatten() {
            let [x0, y0, x1, y1] = tri.bbox;
            for ty in y0 / self.tile..=y1 / self.tile {
                for tx in x0 / self.tile..=x1 / self.tile {
                    bins[(ty * self.tiles_x + tx) as usize].push(tri);
                }
            }
        }
        bins
    }
}

/// Rendered tiles (`None`: no triangle touched the tile), before placement into full-frame
/// buffers.
pub(crate) struct Tiles<P> {
    grid: TileGrid,
    tiles: Vec<Option<Vec<P>>>,
}

/// Rasterizes the set-up triangles (chunks from [`setup_all`]) tile by tile, in parallel. Each
/// tile buffer starts as `empty`, and `shade(tri, pixel, e)` is called for every pixel covered by
/// `tri` with its unbiased edge functions `e`, triangles in input order. The result is
/// independent of the thread count. `width` and `height` must be non-zero.
pub(crate) fn render<P, F>(
    chunks: &[Vec<SetupTri>],
    width: u32,
    height: u32,
    tile_size: u32,
    empty: P,
    shade: F,
) -> Tiles<P>
where
    P: Copy + Send + Sync,
    F: Fn(&SetupTri, &mut P, [i64; 3]) + Sync,
{
    let grid = TileGrid::new(width, height, effective_tile_size(tile_size));
    let bins = grid.bin(chunks);
    let tiles = bins
        .par_iter()
        .enumerate()
        .map(|(t, bin)| {
            if bin.is_empty() {
                return None;
            }
            let [x0, y0, x1, y1] = grid.rect(t);
            let tw = (x1 - x0) as usize;
            let mut buf = vec![empty; tw * (y1 - y0) as usize];
            for &tri in bin {
                let [bx0, by0, bx1, by1] = tri.bbox;
                // Tile ∩ triangle bounds (bbox is inclusive, rect exclusive).
                let rect = [x0.max(bx0), y0.max(by0), x1.min(bx1 + 1), y1.min(by1 + 1)];
                raster_rect(tri, rect, |px, py, e| {
                    let k = (py - y0) as usize * tw + (px - x0) as usize;
                    shade(tri, &mut buf[k], e);
                });
            }
            Some(buf)
        })
        .collect();
    Tiles { grid, tiles }
}

impl<P: Sync> Tiles<P> {
    /// Writes `f(pixel)` for every pixel of every rendered tile into the row-major full-frame
    /// buffer `out` (`width * height` entries), leaving pixels of untouched tiles as they are.
    /// Each band of one tile row is a contiguous slice of `out`, so bands are filled in parallel
    /// without overlapping writes.
    pub fn place<T: Send>(&self, out: &mut [T], f: impl Fn(&P) -> T + Sync) {
        let grid = &self.grid;
        let width = grid.width as usize;
        assert_eq!(out.len(), width * grid.height as usize);
        out.par_chunks_mut(grid.tile as usize * width)
            .zip(self.tiles.par_chunks(grid.tiles_x as usize))
            .enumerate()
            .for_each(|(ty, (band, row_tiles))| {
                for (tx, buf) in row_tiles.iter().enumerate() {
                    let Some(buf) = buf else { continue };
                    let [x0, _, x1, _] = grid.rect(ty * grid.tiles_x as usize + tx);
                    let tw = (x1 - x0) as usize;
                    for (r, src) in buf.chunks_exact(tw).enumerate() {
                        let start = r * width + x0 as usize;
                        for (d, s) in band[start..start + tw].iter_mut().zip(src) {
                            *d = f(s);
                        }
                    }
                }
            });
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
}
