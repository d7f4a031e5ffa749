//! Omnidirectional depth maps of a point light (or one hemisphere of a VPL): per texel, the id of
//! the triangle closest to the light in that texel's direction and its distance.
//!
//! API contract (the renderer is written against it):
//! - texel `(ix, iy)` of a face covers `[ix, ix + 1) x [iy, iy + 1)` in continuous texel
//!   coordinates, its centre at `(ix + 0.5, iy + 0.5)`; faces are `resolution` texels square,
//!   row-major, row 0 first;
//! - [`LightMap::coord`] and [`LightMap::texel_dir`] are inverse to each other (up to rounding);
//! - a face that was not asked for is not drawn: all its texels are [`EMPTY`];
//! - building is deterministic (same bytes for any thread count).
//!
//! # Faces
//!
//! **Cube** maps have six 90-degree perspective faces numbered as [`CubeFace::index`]
//! (`+x, -x, +y, -y, +z, -z`). A direction falls on the face of its largest `|component|` (ties
//! to x, then y: [`cube_lookup`]), at face coordinates `(s, t)` = the other two components, in
//! order, divided by the major one's magnitude; texel coordinates are
//! `x = (s + 1) res / 2`, `y = (1 - t) res / 2` (the rasterizer's viewport: NDC `y = +1` is row 0).
//! A face is drawn in clip space `(d_s, d_t, near, ±d_axis)` with `d = p - light`, so NDC is
//! `(s, t)` and the rasterizer's reversed-Z depth is `near / w`, `w` the distance along the face
//! axis; the texel stores the distance along its centre's direction,
//! `near / depth * sqrt(1 + s^2 + t^2)` with `(s, t)` the centre's face coordinates. A paged
//! map ([`LightMap::build_pages`]) stores ids only, half the memory: decisions use the
//! triangles' planes, and the stored depth only where a plane is seen edge-on, which for a
//! paged map is left to a ray; its distances come from the planes
//! ([`Classifier::depth_at`](crate::classify::Classifier::depth_at)).
//! Each face draws only the triangles that can reach its frustum: a triangle with all three
//! vertices beyond the same side plane (`d_s > w`, `d_s < -w`, `d_t > w` or `d_t < -w`) or all
//! closer than the near plane along the axis (`w < near`: behind the light) is skipped.
//!
//! **Paraboloid** maps have two hemispheres back to back in the world frame: face 0 is `z >= 0`
//! at `(u, v) = (x, y) / (|d| + z)`, face 1 is `z < 0` at `(x, y) / (|d| - z)` (as
//! [`paraboloid_project`](crate::paraboloid_project); a direction with `z = 0` goes to face 0),
//! and [`LightMap::build_hemisphere`] draws one hemisphere around any axis. Texel coordinates are
//! `x = (u + 1) res / 2`, `y = (1 - v) res / 2`. Triangles are clipped to the hemisphere in 3D,
//! tessellated and projected as derived in `tess.rs`; the texel stores `near / depth`. Only
//! texel centres inside the unit disc belong to the map ([`LightMap::texel_in_domain`]); the
//! others are cleared to [`EMPTY`], and [`LightMap::coord`] never returns a position in one: a
//! direction whose texel's centre lies outside the disc (in the outermost ring, within one
//! texel of the rim) is moved into the nearest texel whose centre is inside (by less than a
//! texel), so that lookups near the seam find the surfaces drawn there.
//!
//! # Near plane and input
//!
//! The near distance is `2^-20` ([`NEAR_FRACTION`]) times the distance from the light to the
//! farthest vertex of the usable triangles (1 if there are none; for a single hemisphere, of the
//! usable triangles with a vertex in front of it): relative to the scene, so that
//! geometry very close to the light is still drawn, and a power of two so the scale is exact.
//! Surfaces closer than that to the light are clipped away.
//!
//! A triangle is skipped (never drawn, on no face) if a coordinate or the light is NaN or
//! infinite, a vertex is farther than `2^100` from the light, it has zero area, or it is seen
//! edge-on: its plane passes closer to the light than `2^-40` times the distance to its farthest
//! vertex (the light lies on it up to `f64` rounding), or than `2^-20` times the distance to its
//! closest point (every point of it is seen within `2^-20` radian of its plane: its image is far
//! thinner than a texel at any resolution, and rays from the light only graze it). Ids are the indices into
//! `tris`; triangles from index `u32::MAX` on (the empty id) are ignored. `resolution` is clamped
//! to `[1, MAX_TARGET_DIM]` (`0` is treated as `1`). Faces missing from `faces` are not drawn.
//!
//! # Accuracy
//!
//! Ids follow the rasterizer's rules (vertices snapped to 1/256 texel, top-left fill rule, depth
//! ties within [`DEPTH_TIE`] to the smaller id). Measured against `f64` ray casting of the texel
//! centres (`tests/maps.rs`, random overlapping triangles; a paraboloid at resolution 256 with
//! `tess_texels = 4`):
//!
//! | | ids agreeing | disagreements within | depth error (relative) |
//! |---|---:|---:|---:|
//! | cube | 99.99 % | 0.0006 texel of an edge | max `2.0e-7` |
//! | paraboloid, tessellated | 99.98 % | 0.011 texel of an edge | max `7.1e-4`, median `1.2e-4` |
//! | paraboloid, not tessellated | 94.2 % | | max `0.12` |
//!
//! Cube depths are the rasterizer's `near / w` (exact plane, `f32`-rounded) converted in `f32`:
//! a few roundings. Paraboloid depths are approximate: the rasterizer interpolates `near / |d|`
//! linearly across each projected sub-triangle, but on a plane `1 / |d| = n . dir / h` is linear
//! in the unit direction, which is quadratic in `(u, v)`. The error grows as the square of the
//! projected sub-triangle size and as `1 / cos` of the angle of incidence, so tessellation
//! reduces it: on a triangle 3 units wide 0.5 from the light (resolution 64) the largest error is
//! 2.7 (270 %) untessellated, 2.0 % at `tess_texels = 8` and 0.58 % at 4. Where the tessellation
//! cap binds (a surface much closer to the light than its triangles are large) sub-triangles
//! near the light stay large and so does the error there: for a light `1e-4` from a unit wall
//! the ids are still all right but the median depth error is 48 % (cube maps: `1.4e-7`).
//!
use glam::{DVec3, Vec3, Vec4};
use hyrt_raster::{EMPTY_ID, MAX_TARGET_DIM, RasterOptions, Rasterizer, Target};
use rayon::prelude::*;

use crate::cube::{CubeFace, cube_lookup};
use crate::tess::{Frame, Params, Tessellator, dist_triangle};

/// Id of a texel no triangle covers (the rasterizer's empty id).
pub const EMPTY: u32 = hyrt_raster::EMPTY_ID;

/// The near distance as a fraction of the distance to the farthest vertex (module docs).
pub const NEAR_FRACTION: f32 = 1.0 / (1u32 << 20) as f32;

/// Relative depth window within which two surfaces are a tie in a map, won by the smaller id:
/// `2^-22`, a few ulps of the `f32` depths (each its plane's, exact to half an ulp), enough for
/// coplanar triangles to tie. Not the tracer's `2^-16`, which must absorb the ray-triangle
/// test's error: at a light `r` away a `2^-16 r` window would tie an occluder with the surface
/// it stands on over its whole base (a post on the ground, under a light a thousand scene sizes
/// away, lost its contact shadow to the ground's smaller id). Which of two coplanar triangles a
/// texel records does not change a decision: both have the same plane.
pub const DEPTH_TIE: f32 = 1.0 / (1u32 << 22) as f32;

/// Largest number of subdivisions of a triangle edge in paraboloid maps (`n x n` sub-triangles;
/// see the tessellation bound in `tess.rs`).
pub const MAX_TESS: u32 = 64;

/// Vertices farther than this from the light are skipped (keeps clip coordinates far from the
/// `f32` range).
const MAX_DISTANCE: f64 = 1.2676506002282294e30; // 2^100

/// Clip-space triangles and their ids, for one face.
type FaceTris = (Vec<[Vec4; 3]>, Vec<u32>);

/// Input triangles per parallel job.
const CHUNK: usize = 2048;

/// Triangles per cluster that [`bin_pages`] culls at once by their bounding box (consecutive
/// triangles of a mesh lie close together).
const CLUSTER: usize = 256;

/// The parameterisation of a point light's map.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MapKind {
    /// Six perspective faces of 90 degrees.
    #[default]
    Cube,
    /// Two paraboloid hemispheres, back to back (triangles tessellated before projection).
    Paraboloid,
}

impl MapKind {
    /// The kind's name on the command line and in statistics.
    pub const fn name(self) -> &'static str {
        match self {
            MapKind::Cube => "cube",
            MapKind::Paraboloid => "paraboloid",
        }
    }
}

/// How to build a map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapOptions {
    pub kind: MapKind,
    /// Texels per side of every face (cube face, or the square around a paraboloid's disc).
    pub resolution: u32,
    /// Paraboloid maps: triangles are subdivided before projection until each projected edge is
    /// at most about this many texels long (see the tessellation docs for the exact bound);
    /// `f32::INFINITY` turns tessellation off. Ignored by cube maps.
    pub tess_texels: f32,
}

impl Default for MapOptions {
    fn default() -> Self {
        Self { kind: MapKind::Cube, resolution: 1024, tess_texels: 8.0 }
    }
}

/// Where a direction falls in a map: the face and continuous texel coordinates on it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapCoord {
    pub face: u8,
    /// The level (0 for whole maps).
    pub level: u8,
    /// Continuous texel coordinates at that level (`f64`: a paged map's fine levels have more
    /// texels per side than `f32` has steps below one texel).
    pub x: f64,
    pub y: f64,
}

/// How the faces of a map are laid out.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Layout {
    Cube,
    /// Two paraboloid hemispheres: [`Frame::WORLD`] and [`Frame::MIRRORED`].
    Dual,
    /// One paraboloid hemisphere in this frame.
    Hemisphere(Frame),
}

impl Layout {
    fn face_count(self) -> usize {
        match self {
            Layout::Cube => 6,
            Layout::Dual => 2,
            Layout::Hemisphere(_) => 1,
        }
    }

    /// The paraboloid frame of face `face` (clamped to the last face).
    fn frame(self, face: u8) -> Frame {
        match self {
            Layout::Hemisphere(f) => f,
            _ if face == 0 => Frame::WORLD,
            _ => Frame::MIRRORED,
        }
    }
}

/// Side of a page: a face's texels are stored, and paged maps drawn, in squares of this many
/// texels per side.
///
/// Why 32: a page is then 4 KB of ids (and, in a whole map, 4 KB of depths). A frame's
/// receivers touch the pages around them, and the smaller the page, the fewer texels it holds
/// that no receiver reads (memory the budget would rather spend on finer levels); smaller pages
/// cost more per-page work (binning, setting up the triangles that straddle pages).
pub const PAGE: u32 = 32;

/// Texels of one page.
const PAGE_TEXELS: usize = (PAGE * PAGE) as usize;

/// Region summaries ([`REGION`] blocks) of one page.
const PAGE_REGIONS: usize = ((PAGE / REGION) * (PAGE / REGION)) as usize;

/// Finest level of a paged map ([`LightMap::build_pages`]): level `k` has `PAGE << k` texels
/// per face side, so the finest is `2^22`.
///
/// Why `2^22`: face coordinates are computed in `f32` (a relative error of `2^-24`), which at
/// `2^22` texels per side is a sixteenth of a texel on the face's rim; a finer grid would place
/// points by their rounding. It is also what a light a thousand scene sizes away needs for
/// receivers seen at one texel per pixel (the resolution guide in [`crate::paged`]).
pub const MAX_LEVEL: u8 = 17;

/// Id returned by texel lookups in a page that was not drawn, and held by a texel whose centre
/// sees a cut-out's hole with another cut-out along its ray
/// ([`LightMap::build_pages_with_holes`]): the map cannot tell, so the classifier leaves the
/// point to a ray. Distinct from every triangle id a map draws (ids from `ABSENT` on are not
/// drawn).
pub const ABSENT: u32 = EMPTY - 2;

/// One page of a map: which level, face and page of it.
///
/// Pages order by level, then face, then row, then column: the order [`LightMap::build_pages`]
/// stores them in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct PageKey {
    pub level: u8,
    pub face: u8,
    /// Page row (texel rows `py * PAGE ..`).
    pub py: u32,
    /// Page column (texel columns `px * PAGE ..`).
    pub px: u32,
}

impl PageKey {
    /// The key in one `u64` that orders as the key does (level, face, row, column; rows and
    /// columns below `2^24`): for sorting many keys fast.
    #[inline]
    pub fn pack(self) -> u64 {
        u64::from(self.level) << 56
            | u64::from(self.face) << 48
            | u64::from(self.py) << 24
            | u64::from(self.px)
    }

    /// The key [`PageKey::pack`] made.
    #[inline]
    pub fn unpack(k: u64) -> Self {
        let m = (1u64 << 24) - 1;
        PageKey {
            level: (k >> 56) as u8,
            face: (k >> 48) as u8,
            py: ((k >> 24) & m) as u32,
            px: (k & m) as u32,
        }
    }
}

/// Page tables with at most this many entries are dense arrays; larger ones (the fine levels
/// of paged maps, where a frame draws a few pages of millions) are hash maps.
const DENSE_PAGES: usize = 1 << 12;

/// The most memory ([`LightMap::memory_bytes`]) that a paged cube map of `pages` pages can
/// take, wherever they lie: per page its ids (a paged map stores no depths), both region
/// summaries and its page-table entry, plus the dense page tables of the coarse levels
/// (allocated whole once a level of a face holds a page). For sizing maps under a memory
/// budget.
pub fn paged_memory_bound(pages: usize) -> usize {
    let per_page = PAGE_TEXELS * 4 + PAGE_REGIONS * 8 + 8;
    let dense_levels = (0..=MAX_LEVEL).filter(|&k| (1usize << (2 * k)) <= DENSE_PAGES).count();
    pages * per_page + dense_levels * 6 * DENSE_PAGES * 4
}

/// No page in a dense page table.
const NO_PAGE: u32 = u32::MAX;

/// Where a texel's id is: at an index of its face's `id`, or known (its page's one id, or
/// read through its page's palette).
#[derive(Clone, Copy, Debug)]
enum Stored {
    At(usize),
    Id(u32),
}

/// How a paged map's slot keeps its page's ids.
#[derive(Clone, Copy, Debug)]
enum Kept {
    /// Every texel holds this id (most pages: a wall, a floor, the sky); nothing is stored.
    One(u32),
    /// Texel `t`'s id is `palette[at + index[page * PAGE_TEXELS + t]]`, of a palette `len` long.
    Palette { at: u32, len: u16, page: u32 },
    /// Texel `t`'s id is `id[page * PAGE_TEXELS + t]`.
    Ids { page: u32 },
}

/// How a drawn page's ids are kept ([`PageIds::of`]).
enum PageIds {
    /// Every texel holds this id.
    One(u32),
    /// The page's distinct ids (at most 256), and each texel's index among them.
    Palette(Vec<u32>, Box<[u8; PAGE_TEXELS]>),
    /// Four bytes a texel.
    Ids,
}

impl PageIds {
    /// The least storage for a page's ids `ids` (row-major): most pages see one triangle or
    /// none, most others a few (the palette is searched on a change of id only: runs are long).
    fn of(ids: &[u32]) -> Self {
        let first = ids[0];
        if ids.iter().all(|&t| t == first) {
            return PageIds::One(first);
        }
        let (mut palette, mut index) = (vec![first], Box::new([0u8; PAGE_TEXELS]));
        // Each id's place in the palette, by open addressing (at most half full): `MIXED` is
        // never a texel's id.
        const SLOTS: usize = 512;
        let mut table = [(MIXED, 0u8); SLOTS];
        let hash = |id: u32| (id.wrapping_mul(0x9e37_79b9) >> 23) as usize;
        table[hash(first)] = (first, 0);
        let mut last = (first, 0u8);
        for (k, &id) in ids.iter().enumerate() {
            if id != last.0 {
                let mut h = hash(id);
                while table[h].0 != id && table[h].0 != MIXED {
                    h = (h + 1) % SLOTS;
                }
                if table[h].0 == MIXED {
                    if palette.len() == 256 {
                        return PageIds::Ids;
                    }
                    table[h] = (id, palette.len() as u8);
                    palette.push(id);
                }
                last = (id, table[h].1);
            }
            index[k] = last.1;
        }
        PageIds::Palette(palette, index)
    }
}

/// One face's texels at one level: the pages drawn, each [`PAGE`] texels square (empty when
/// none was drawn).
#[derive(Clone, Debug, Default)]
struct Face {
    /// Pages per side.
    n: u32,
    /// Pages in the table.
    slots: u32,
    /// Page `py * n + px` to its slot in the arrays below, for small faces ([`DENSE_PAGES`]).
    dense: Vec<u32>,
    /// The same for large faces.
    sparse: rustc_hash::FxHashMap<u32, u32>,
    /// Per page stored four bytes a texel, [`PAGE_TEXELS`] ids, row-major.
    id: Vec<u32>,
    /// Paged maps: per slot, how its ids are kept ([`Kept`]). Empty in whole maps, whose slot
    /// `s` is page `s` of `id`.
    kept: Vec<Kept>,
    /// The palettes of [`Kept::Palette`] slots, and their texels' indices, a page after another.
    palette: Vec<u32>,
    index: Vec<u8>,
    /// Per slot, the rasterizer's reversed-Z depths `near / w` (0 where empty), row-major:
    /// distances are made from them only when asked for ([`LightMap::depth_at`]), which the
    /// classifier does only for planes seen edge-on. Empty in a paged map (a ray decides those
    /// planes; its texels' distances come from their triangles' planes,
    /// [`Classifier::depth_at`](crate::classify::Classifier::depth_at)).
    depth: Vec<f32>,
    /// Per slot, [`PAGE_REGIONS`] [`REGION`]-square blocks, row-major: the one triangle its
    /// texels see ([`EMPTY`] if none), or [`MIXED`] (see [`LightMap::region_id`]).
    region: Vec<u32>,
    /// The same by group of triangles ([`LightMap::build_grouped`]; empty without groups).
    region_group: Vec<u32>,
}

impl Face {
    /// An empty face of `res` texels per side.
    fn new(res: u32) -> Self {
        let n = res.div_ceil(PAGE);
        let pages = n as usize * n as usize;
        Face {
            n,
            dense: if pages <= DENSE_PAGES { vec![NO_PAGE; pages] } else { Vec::new() },
            ..Face::default()
        }
    }

    fn is_empty(&self) -> bool {
        self.slots == 0
    }

    /// Pages in the page table (the storage may be sized after the table is filled).
    fn pages(&self) -> usize {
        self.slots as usize
    }

    /// The slot of page `(px, py)` (both below `n`), if it was drawn.
    #[inline]
    fn slot(&self, px: u32, py: u32) -> Option<usize> {
        let k = py * self.n + px;
        if self.dense.is_empty() {
            self.sparse.get(&k).map(|&s| s as usize)
        } else {
            let s = self.dense[k as usize];
            (s != NO_PAGE).then_some(s as usize)
        }
    }

    /// Appends a page's slot for page `(px, py)`; its texels are pushed by the caller.
    fn insert(&mut self, px: u32, py: u32) -> usize {
        let s = self.pages();
        self.slots += 1;
        let k = py * self.n + px;
        if self.dense.is_empty() {
            self.sparse.insert(k, s as u32);
        } else {
            self.dense[k as usize] = s as u32;
        }
        s
    }

    /// Texel `(x, y)`, if its page was drawn: where its id is stored, or its page's one id.
    #[inline]
    fn index(&self, x: u32, y: u32) -> Option<Stored> {
        let s = self.slot(x / PAGE, y / PAGE)?;
        Some(self.texel_of(s, ((y % PAGE) * PAGE + x % PAGE) as usize))
    }

    /// How slot `s` keeps its ids.
    #[inline]
    fn kept(&self, s: usize) -> Kept {
        self.kept.get(s).copied().unwrap_or(Kept::Ids { page: s as u32 })
    }

    /// Texel `t` (row-major in the page) of slot `s`.
    #[inline]
    fn texel_of(&self, s: usize, t: usize) -> Stored {
        match self.kept(s) {
            Kept::One(id) => Stored::Id(id),
            Kept::Palette { at, page, .. } => {
                let i = self.index[page as usize * PAGE_TEXELS + t];
                Stored::Id(self.palette[at as usize + usize::from(i)])
            }
            Kept::Ids { page } => Stored::At(page as usize * PAGE_TEXELS + t),
        }
    }

    /// The ids of the 2x2 texels from texel `t` of slot `s` (all four in the page).
    #[inline]
    fn quad(&self, s: usize, t: usize) -> [u32; 4] {
        let p = PAGE as usize;
        match self.kept(s) {
            Kept::One(id) => [id; 4],
            Kept::Palette { at, page, .. } => {
                let i = page as usize * PAGE_TEXELS + t;
                let (index, palette) = (&self.index[i..i + p + 2], &self.palette[at as usize..]);
                let id = |k: usize| palette[usize::from(index[k])];
                [id(0), id(1), id(p), id(p + 1)]
            }
            Kept::Ids { page } => {
                let i = page as usize * PAGE_TEXELS + t;
                let ids = &self.id[i..i + p + 2];
                [ids[0], ids[1], ids[p], ids[p + 1]]
            }
        }
    }

    /// Appends a page's ids for its next slot (the slot itself is inserted by the caller):
    /// `stored` holds a [`PageIds::Ids`] page's texels.
    fn push_ids(&mut self, ids: PageIds, stored: &[u32]) {
        let kept = match ids {
            PageIds::One(id) => Kept::One(id),
            PageIds::Palette(palette, index) => self.push_palette(&palette, &index[..]),
            PageIds::Ids => self.push_stored(stored),
        };
        self.kept.push(kept);
    }

    fn push_palette(&mut self, palette: &[u32], index: &[u8]) -> Kept {
        let (at, page) = (self.palette.len() as u32, (self.index.len() / PAGE_TEXELS) as u32);
        self.palette.extend_from_slice(palette);
        self.index.extend_from_slice(index);
        Kept::Palette { at, len: palette.len() as u16, page }
    }

    fn push_stored(&mut self, ids: &[u32]) -> Kept {
        let page = (self.id.len() / PAGE_TEXELS) as u32;
        self.id.extend_from_slice(ids);
        Kept::Ids { page }
    }

    /// Appends slot `s` of `from` (a paged face) as page `(px, py)`: its ids (as `from` keeps
    /// them) and its region summaries.
    fn push_page(&mut self, from: &Face, s: usize, (px, py): (u32, u32), groups: bool) {
        self.insert(px, py);
        let kept = match from.kept(s) {
            Kept::One(id) => Kept::One(id),
            Kept::Palette { at, len, page } => {
                let (at, i) = (at as usize, page as usize * PAGE_TEXELS);
                self.push_palette(&from.palette[at..at + usize::from(len)], &from.index[i..i + PAGE_TEXELS])
            }
            Kept::Ids { page } => {
                let i = page as usize * PAGE_TEXELS;
                self.push_stored(&from.id[i..i + PAGE_TEXELS])
            }
        };
        self.kept.push(kept);
        self.region.extend_from_slice(&from.region[s * PAGE_REGIONS..][..PAGE_REGIONS]);
        if groups {
            self.region_group.extend_from_slice(&from.region_group[s * PAGE_REGIONS..][..PAGE_REGIONS]);
        }
    }

    /// Paged maps: keeps each slot's ids as `kept` says ([`PageIds`]), the pages of four
    /// bytes a texel packed in slot order. `id` holds every slot's texels in slot order
    /// before, only those of [`PageIds::Ids`] pages written (the others never mapped in).
    fn pack_pages(&mut self, kept: Vec<PageIds>) {
        let mut id = std::mem::take(&mut self.id);
        let mut stored = 0;
        self.kept = Vec::with_capacity(kept.len());
        for (s, ids) in kept.into_iter().enumerate() {
            if matches!(ids, PageIds::Ids) {
                if stored != s {
                    id.copy_within(s * PAGE_TEXELS..(s + 1) * PAGE_TEXELS, stored * PAGE_TEXELS);
                }
                self.kept.push(Kept::Ids { page: stored as u32 });
                stored += 1;
            } else {
                self.push_ids(ids, &[]);
            }
        }
        id.truncate(stored * PAGE_TEXELS);
        id.shrink_to_fit();
        self.id = id;
        self.palette.shrink_to_fit();
        self.index.shrink_to_fit();
    }

    /// The pages drawn, by `(px, py)`.
    fn keys(&self) -> Vec<(u32, u32)> {
        let mut k: Vec<(u32, u32, u32)> = if self.dense.is_empty() {
            self.sparse.iter().map(|(&k, &s)| (s, k % self.n, k / self.n)).collect()
        } else {
            self.dense
                .iter()
                .enumerate()
                .filter(|(_, s)| **s != NO_PAGE)
                .map(|(k, &s)| (s, k as u32 % self.n, k as u32 / self.n))
                .collect()
        };
        k.sort_unstable();
        k.into_iter().map(|(_, x, y)| (x, y)).collect()
    }

    fn memory_bytes(&self) -> usize {
        if self.is_empty() {
            return 0;
        }
        self.index.len()
            + self.kept.len() * std::mem::size_of::<Kept>()
            + (self.id.len()
                + self.palette.len()
                + self.depth.len()
                + self.region.len()
                + self.region_group.len()
                + self.dense.len())
                * 4
            + self.sparse.len() * 8
    }
}

/// Side of the texel blocks that [`LightMap::region_id`] summarises.
///
/// Why: most pixels of a frame see, in every light's map, only their own triangle around them
/// (a wall, a floor, far from any shadow). A tile of such pixels is decided by asking whether
/// one triangle covers the map region under the tile: a few summary blocks, instead of four
/// texels per pixel. 8 keeps the summary at 1/64 of the ids and a tile's region within a few
/// blocks at the resolutions in use.
const REGION: u32 = 8;

/// [`Face::region`]: a block that sees two or more triangles, or a triangle and nothing.
const MIXED: u32 = EMPTY - 1;

/// A region summary before its block's first texel (never left in a summary: every block has
/// texels).
const UNSEEN: u32 = EMPTY - 3;

/// An empty vector with room for `n` elements, in memory the kernel is asked to back with huge
/// pages ([`advise_huge`]): for the rasterizer's target, which writes into its capacity.
fn reserved_huge<T>(n: usize) -> Vec<T> {
    let v = Vec::with_capacity(n);
    advise_huge(&v);
    v
}

/// Asks the kernel to back `v`'s buffer (its whole capacity) with huge pages.
///
/// Why: the rasterizer's depth and id buffers for a 2048x2048 face are 16 MB each, fresh for
/// every map; first touching them in 4 KB pages (a fault and a zeroed page each) was a large
/// part of drawing the first face. With transparent huge pages in `madvise` mode (the usual
/// Linux default) they fault in 2 MB pages. Not used for the stored faces: a frame keeps a map
/// per light, and huge pages for all of it made the kernel
/// compact memory at fault time, which made the first frame slower and erratic. A hint only:
/// nothing changes if the kernel declines, or elsewhere than Linux.
fn advise_huge<T>(v: &Vec<T>) {
    #[cfg(target_os = "linux")]
    {
        const HUGE: usize = 2 << 20;
        let start = v.as_ptr() as usize;
        let (first, end) = (start.next_multiple_of(HUGE), start + v.capacity() * std::mem::size_of::<T>());
        if end >= first + HUGE {
            let len = (end - first) / HUGE * HUGE;
            // SAFETY: `[first, first + len)` lies within `v`'s allocation, which outlives the
            // call; MADV_HUGEPAGE changes how its pages are backed, never their contents.
            unsafe { libc::madvise(first as *mut libc::c_void, len, libc::MADV_HUGEPAGE) };
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = v;
}

/// The region summaries of one page's ids (row-major), appended to `by_id` and (if `groups`
/// is not empty) `by_group`: by triangle ([`Face::region`]) and by `groups[id]`
/// ([`Face::region_group`]).
fn summarise(ids: &[u32], groups: &[u32], by_id: &mut Vec<u32>, by_group: &mut Vec<u32>) {
    let (p, r) = (PAGE as usize, REGION as usize);
    let side = p / r;
    // The one value seen (an id, or EMPTY), or MIXED once a second one shows up: a block of
    // one triangle and empty texels is mixed, since a point whose footprint holds an empty
    // texel decides otherwise than one under the triangle.
    let see = |v: &mut u32, id: u32| {
        if id != *v {
            *v = if *v == UNSEEN { id } else { MIXED };
        }
    };
    let first = by_id.len();
    by_id.resize(first + side * side, UNSEEN);
    let gfirst = by_group.len();
    if !groups.is_empty() {
        by_group.resize(gfirst + side * side, UNSEEN);
    }
    for (y, row) in ids.chunks_exact(p).enumerate() {
        for (rx, run) in row.chunks_exact(r).enumerate() {
            let k = (y / r) * side + rx;
            let v = &mut by_id[first + k];
            let group = |id: u32| groups.get(id as usize).copied().unwrap_or(id);
            // Most runs hold one id: see it (and its group) once.
            let uniform = run.iter().all(|&id| id == run[0]);
            if uniform {
                see(v, run[0]);
            } else {
                run.iter().for_each(|&id| see(v, id));
            }
            if !groups.is_empty() {
                let g = &mut by_group[gfirst + k];
                if uniform {
                    see(g, group(run[0]));
                } else {
                    run.iter().for_each(|&id| see(g, group(id)));
                }
            }
        }
    }
}

/// A light's depth map: 6 cube faces or 2 paraboloid hemispheres (or 1 hemisphere, for VPLs),
/// stored in pages ([`PAGE`]), at one level (whole maps) or several (paged maps).
#[derive(Clone, Debug)]
pub struct LightMap {
    layout: Layout,
    /// Texels per face side at level 0; level `k` has `base << k`.
    base: u32,
    light: Vec3,
    near: f32,
    /// Per face, whether any page of it was drawn (at any level).
    drawn: Vec<bool>,
    /// Per level and face (`level * face_count + face`), the pages drawn.
    faces: Vec<Face>,
    triangles_drawn: u64,
    /// Faces rasterized over the map's life, merges included ([`LightMap::faces_rasterized`]).
    faces_rasterized: u32,
    /// Pages rasterized over the map's life (a whole face counts its pages).
    pages_rasterized: u64,
    /// Made by [`LightMap::build_pages`].
    paged: bool,
    /// Made with [`Holes`]: a texel of a triangle with holes is solid at its centre, and a texel
    /// whose centre sees a hole holds what lies behind it ([`LightMap::resolves_holes`]).
    holes: bool,
}

/// Triangles with holes (alpha cut-outs) for maps that resolve them texel by texel
/// ([`LightMap::build_pages_with_holes`], [`crate::vpl_map::VplMap::build_with_holes`]): the map
/// knows no textures, so the caller says where a texel's centre meets a hole.
pub struct Holes<'a> {
    /// Per triangle id, whether it has holes.
    pub cutouts: &'a [bool],
    /// The triangles with those that have holes left out (a non-finite corner), for maps drawn
    /// in one piece (VPL maps); paged maps leave them out of each page's triangles instead and
    /// may be given an empty slice.
    pub solid: &'a [[Vec3; 3]],
    /// Whether the ray from the map's origin in unit direction `dir` meets triangle `id` (one
    /// with holes) in a hole.
    pub hole: &'a (dyn Fn(u32, Vec3) -> bool + Sync),
}

impl Holes<'_> {
    /// Whether the texel holding `id`, whose centre lies in direction `dir`, sees a hole.
    #[inline]
    pub fn sees_hole(&self, id: u32, dir: Vec3) -> bool {
        self.cutouts.get(id as usize).is_some_and(|&c| c) && (self.hole)(id, dir)
    }
}

/// The rasterizer's options for light maps: reversed-Z, ids only, no culling, the tracer's tie.
const MAP_RASTER: RasterOptions = RasterOptions {
    reversed_z: true,
    barycentrics: false,
    cull_backfaces: false,
    depth_tie: DEPTH_TIE,
    ..RasterOptions::DEFAULT
};

/// [`MAP_RASTER`] for the pages of paged maps: ids only (the depth test runs all the same).
const PAGE_RASTER: RasterOptions = RasterOptions { depth: false, ..MAP_RASTER };

impl LightMap {
    /// Number of faces of a point-light map of this kind (6 or 2).
    pub fn face_count(kind: MapKind) -> usize {
        match kind {
            MapKind::Cube => 6,
            MapKind::Paraboloid => 2,
        }
    }

    /// The face of a point-light map of kind `kind` that direction `dir` (non-zero) falls on,
    /// the same as `coord(dir).face` of a built map, without building one (to decide which
    /// faces to draw).
    pub fn face_of(kind: MapKind, dir: Vec3) -> u8 {
        match kind {
            MapKind::Cube => cube_lookup(dir).0.index(),
            // `-0.0 >= 0.0`: the seam and its signed zero go to the front; NaN to the back.
            MapKind::Paraboloid => {
                if dir.z >= 0.0 {
                    0
                } else {
                    1
                }
            }
        }
    }

    /// Draws the map of the point light at `light` over the triangles `tris` (triangle `i` has
    /// id `i`), drawing only the faces `i` with `faces[i]` (`faces.len() == face_count`).
    /// Degenerate, NaN or infinite triangles are skipped.
    pub fn build(tris: &[[Vec3; 3]], light: Vec3, opts: &MapOptions, faces: &[bool]) -> Self {
        Self::build_grouped(tris, light, opts, faces, &[])
    }

    /// [`LightMap::build`], with a second region summary ([`LightMap::region_group`]) made of
    /// `groups[id]` instead of triangle ids (for example
    /// [`plane_groups`](crate::classify::plane_groups): coplanar triangles then summarise as
    /// one). An empty `groups` means each triangle is its own group.
    pub fn build_grouped(
        tris: &[[Vec3; 3]],
        light: Vec3,
        opts: &MapOptions,
        faces: &[bool],
        groups: &[u32],
    ) -> Self {
        let layout = match opts.kind {
            MapKind::Cube => Layout::Cube,
            MapKind::Paraboloid => Layout::Dual,
        };
        Self::build_layout(tris, light, opts, layout, faces, groups)
    }

    /// One paraboloid hemisphere centred on unit `axis`, seen from `origin` (a VPL's map):
    /// one face. `opts.kind` is ignored.
    ///
    /// The map frame is `(t, b, axis)` with `t, b` from Duff et al.'s orthonormal basis (the
    /// world axes for `axis = +z`); `axis` is normalised, and a zero or non-finite one means
    /// `+z`. [`LightMap::coord`] puts directions behind the hemisphere on its rim.
    pub fn build_hemisphere(tris: &[[Vec3; 3]], origin: Vec3, axis: Vec3, opts: &MapOptions) -> Self {
        let frame = Frame::around(axis.as_dvec3());
        Self::build_layout(tris, origin, opts, Layout::Hemisphere(frame), &[true], &[])
    }

    /// A map with nothing drawn yet.
    fn empty(layout: Layout, base: u32, light: Vec3, near: f32, paged: bool) -> Self {
        LightMap {
            layout,
            base,
            light,
            near,
            drawn: vec![false; layout.face_count()],
            faces: (0..layout.face_count()).map(|_| Face::new(base)).collect(),
            triangles_drawn: 0,
            faces_rasterized: 0,
            pages_rasterized: 0,
            paged,
            holes: false,
        }
    }

    fn build_layout(
        tris: &[[Vec3; 3]],
        light: Vec3,
        opts: &MapOptions,
        layout: Layout,
        faces: &[bool],
        groups: &[u32],
    ) -> Self {
        let resolution = opts.resolution.clamp(1, MAX_TARGET_DIM);
        let count = layout.face_count();
        let drawn: Vec<bool> = (0..count).map(|i| faces.get(i).copied().unwrap_or(false)).collect();
        let (valid, near) =
            if drawn.iter().any(|&d| d) { usable_triangles(tris, light, layout) } else { (Vec::new(), 1.0) };
        let mut map = Self::empty(layout, resolution, light, near, false);
        let mut rasterizer = Rasterizer::new();
        let texels = resolution as usize * resolution as usize;
        let mut target = Target {
            depth: reserved_huge(if drawn.iter().any(|&d| d) { texels } else { 0 }),
            id: reserved_huge(if drawn.iter().any(|&d| d) { texels } else { 0 }),
            ..Target::default()
        };
        let mut cube =
            if layout == Layout::Cube { cube_triangles(tris, &valid, light, near, &drawn) } else { vec![] }
                .into_iter();
        for (f, &draw) in drawn.iter().enumerate() {
            let cube_face = cube.next();
            if !draw {
                continue;
            }
            let (clip, ids) = match layout {
                Layout::Cube => cube_face.unwrap_or_default(),
                Layout::Dual | Layout::Hemisphere(_) => {
                    let prm = Params::new(f64::from(near), resolution, opts.tess_texels);
                    hemisphere_triangles(tris, &valid, light, layout.frame(f as u8), &prm)
                }
            };
            map.triangles_drawn += clip.len() as u64;
            map.faces_rasterized += 1;
            rasterizer.rasterize_into(&clip, &ids, resolution, resolution, &MAP_RASTER, &mut target);
            // The target's buffers stay with it for the next face.
            map.store_face(f, &target.id, &target.depth, groups);
        }
        map
    }

    /// Draws the pages `pages` (at most [`MAX_LEVEL`]; duplicates are drawn once) of the cube
    /// map of the point light at `light`: a paged map, whose level `k` has `PAGE << k` texels
    /// per face side and holds only the pages asked for. Each page is drawn as its own small
    /// target through a projection that maps the page's square of the face to the whole
    /// target (see `page_clip_all`), so the virtual resolution is not bounded by the rasterizer's
    /// target size. `opts.resolution` is ignored; `opts.kind` must be [`MapKind::Cube`] (a
    /// paraboloid's tessellation would have to follow the page's resolution: see the crate's
    /// `paged` docs). Otherwise as [`LightMap::build_grouped`].
    ///
    /// # Panics
    /// If `opts.kind` is not [`MapKind::Cube`].
    pub fn build_pages(
        tris: &[[Vec3; 3]],
        light: Vec3,
        opts: &MapOptions,
        pages: &[PageKey],
        groups: &[u32],
    ) -> Self {
        Self::build_pages_with_holes(tris, light, opts, pages, groups, None)
    }

    /// [`LightMap::build_pages`], resolving cut-outs' holes texel by texel: a texel whose
    /// centre meets a triangle with holes in a hole holds what the same texel sees with those
    /// triangles left out (the page drawn again without them, where it has such a texel). The
    /// map then [`resolves_holes`](LightMap::resolves_holes), as an alpha-tested shadow map
    /// does at its texels' centres.
    ///
    /// # Panics
    /// If `opts.kind` is not [`MapKind::Cube`].
    pub fn build_pages_with_holes(
        tris: &[[Vec3; 3]],
        light: Vec3,
        opts: &MapOptions,
        pages: &[PageKey],
        groups: &[u32],
        holes: Option<&Holes>,
    ) -> Self {
        assert_eq!(opts.kind, MapKind::Cube, "paged maps are cube maps");
        let mut pages: Vec<PageKey> = pages
            .iter()
            .copied()
            .filter(|k| {
                k.level <= MAX_LEVEL && usize::from(k.face) < 6 && {
                    let n = PAGE << k.level;
                    k.px < n / PAGE && k.py < n / PAGE
                }
            })
            .collect();
        pages.sort_unstable();
        pages.dedup();
        let mut faces = [false; 6];
        pages.iter().for_each(|k| faces[usize::from(k.face)] = true);
        let (valid, near) =
            if pages.is_empty() { (Vec::new(), 1.0) } else { usable_triangles(tris, light, Layout::Cube) };
        let mut map = Self::empty(Layout::Cube, PAGE, light, near, true);
        map.holes = holes.is_some();
        if pages.is_empty() {
            return map;
        }
        // Per page, the triangles of its face whose image may reach it.
        let (offsets, binned) = bin_pages(tris, &valid, light, near, &pages);
        let l = light.as_dvec3();
        let levels = usize::from(pages.last().map_or(0, |k| k.level)) + 1;
        for lv in 1..levels {
            for _ in 0..6 {
                map.faces.push(Face::new(PAGE << lv));
            }
        }
        // Every face's storage sized once (growing it page by page reallocated and faulted in
        // its memory several times), its pages in `pages` order; then each page drawn straight
        // into its slot.
        let with_groups = !groups.is_empty();
        for key in &pages {
            let face = &mut map.faces[usize::from(key.level) * 6 + usize::from(key.face)];
            face.insert(key.px, key.py);
        }
        for face in map.faces.iter_mut().filter(|f| !f.is_empty()) {
            let n = face.pages();
            face.id = vec![0; n * PAGE_TEXELS];
            face.region = vec![0; n * PAGE_REGIONS];
            face.region_group = if with_groups { vec![0; n * PAGE_REGIONS] } else { Vec::new() };
        }
        let mut slots: Vec<PageSlot> = Vec::with_capacity(pages.len());
        for face in map.faces.iter_mut() {
            let groups_out: Vec<&mut [u32]> = if with_groups {
                face.region_group.chunks_mut(PAGE_REGIONS).collect()
            } else {
                (0..face.id.len() / PAGE_TEXELS).map(|_| Default::default()).collect()
            };
            slots.extend(
                face.id
                    .chunks_mut(PAGE_TEXELS)
                    .zip(face.region.chunks_mut(PAGE_REGIONS))
                    .zip(groups_out)
                    .map(|((a, c), d)| (a, c, d)),
            );
        }
        // Faces are in (level, face) order and their slots in `pages` order: so is `slots`.
        let drawn: Vec<(u64, PageIds)> = pages
            .par_iter()
            .zip(slots.into_par_iter())
            .enumerate()
            .map_init(
                || (Rasterizer::new(), Target::default(), Vec::new(), Vec::new(), Vec::new()),
                |(rasterizer, target, tris_out, region, region_group), (i, (key, (id, reg, reg_g)))| {
                    let bin = &binned[offsets[i]..offsets[i + 1]];
                    let (axis, sign, s, t) = CubeFace::ALL[usize::from(key.face)].axes();
                    tris_out.clear();
                    page_clip_all(tris, bin, l, near, key, (axis, sign, s, t), tris_out);
                    rasterizer.rasterize_into(tris_out, bin, PAGE, PAGE, &PAGE_RASTER, target);
                    if let Some(h) = holes {
                        see_through_holes(h, key, bin, (tris, l, near), rasterizer, target);
                    }
                    // The page is the target itself: a cube face at a paged level is a whole
                    // number of pages, and empty texels already hold EMPTY. A page of one id,
                    // or of a few, is kept as that id or a palette (`Face::pack_pages`): its
                    // slot is not written.
                    let kept = PageIds::of(&target.id);
                    if matches!(kept, PageIds::Ids) {
                        id.copy_from_slice(&target.id);
                    }
                    region.clear();
                    region_group.clear();
                    summarise(&target.id, groups, region, region_group);
                    reg.copy_from_slice(region);
                    reg_g.copy_from_slice(region_group);
                    (bin.len() as u64, kept)
                },
            )
            .collect();
        let triangles: u64 = drawn.iter().map(|d| d.0).sum();
        // How each page's ids are kept, in slot order face by face, as `slots` was.
        let mut kept = drawn.into_iter().map(|d| d.1);
        for face in map.faces.iter_mut().filter(|f| !f.is_empty()) {
            let pages: Vec<PageIds> = kept.by_ref().take(face.pages()).collect();
            face.pack_pages(pages);
        }
        for key in &pages {
            map.drawn[usize::from(key.face)] = true;
        }
        map.pages_rasterized += pages.len() as u64;
        map.triangles_drawn += triangles;
        map.faces_rasterized += faces.iter().filter(|&&f| f).count() as u32;
        map
    }

    /// Whether the map resolves cut-outs' holes at its texels' centres
    /// ([`LightMap::build_pages_with_holes`]); otherwise a texel of a triangle with holes holds it
    /// solid.
    pub fn resolves_holes(&self) -> bool {
        self.holes
    }

    /// Stores a whole face from the rasterizer's row-major ids and reversed-Z depths: every
    /// page of it, in row-major page order ([`finish_page`] for each, in parallel), then the
    /// region summaries.
    fn store_face(&mut self, f: usize, ids: &[u32], depth: &[f32], groups: &[u32]) {
        let res = self.base;
        let n = res.div_ceil(PAGE);
        let layout = self.layout;
        let pages = n as usize * n as usize;
        // Zeroed allocations are mapped lazily (and not advised huge: `advise_huge`): every
        // element is written below, once.
        let (mut id, mut dep) = (vec![0u32; pages * PAGE_TEXELS], vec![0f32; pages * PAGE_TEXELS]);
        id.par_chunks_mut(PAGE_TEXELS).zip(dep.par_chunks_mut(PAGE_TEXELS)).enumerate().for_each(
            |(k, (id, dep))| {
                let origin = ((k as u32 % n) * PAGE, (k as u32 / n) * PAGE);
                finish_page(layout, res, origin, (ids, depth, res as usize), id, dep);
            },
        );
        let mut face = Face::new(res);
        let side = PAGE_REGIONS * pages;
        face.region.reserve(side);
        let regions: Vec<(Vec<u32>, Vec<u32>)> = id
            .par_chunks(PAGE_TEXELS)
            .map(|page| {
                let (mut a, mut b) = (Vec::with_capacity(PAGE_REGIONS), Vec::new());
                summarise(page, groups, &mut a, &mut b);
                (a, b)
            })
            .collect();
        for (a, b) in regions {
            face.region.extend(a);
            face.region_group.extend(b);
        }
        // Slots in row-major page order: page k in slot k.
        face.slots = pages as u32;
        for k in 0..pages as u32 {
            if face.dense.is_empty() {
                face.sparse.insert(k, k);
            } else {
                face.dense[k as usize] = k;
            }
        }
        face.id = id;
        face.depth = dep;
        self.faces[f] = face;
        self.drawn[f] = true;
        self.pages_rasterized += pages as u64;
    }

    /// Where direction `dir` (non-zero, from the light) falls, at level 0 ([`LightMap::coord_at`]).
    #[inline]
    pub fn coord(&self, dir: Vec3) -> MapCoord {
        self.coord_at(dir, 0)
    }

    /// Where direction `dir` (non-zero, from the light) falls at level `level`.
    ///
    /// Coordinates are clamped into `[0, resolution)` (a direction on a cube edge or corner goes
    /// to the face [`cube_lookup`] picks, at its last texel), and for paraboloids into a texel
    /// whose centre is in the disc (module docs). NaN gives some in-range texel.
    // Always inlined: a cube map's path is a few instructions, called per point and light by
    // the classify pass, where the compiler's own choice varied with the caller's size and
    // out of line measured slower.
    #[inline(always)]
    pub fn coord_at(&self, dir: Vec3, level: u8) -> MapCoord {
        let res = self.resolution_at(level);
        if self.layout == Layout::Cube {
            return cube_coord(dir, res, level);
        }
        let d = dir.as_dvec3();
        let half = f64::from(res) * 0.5;
        let face = match self.layout {
            Layout::Dual => Self::face_of(MapKind::Paraboloid, dir),
            _ => 0,
        };
        let m = self.layout.frame(face).to_map(d);
        // Directions behind a single hemisphere go to its rim.
        let z = m.z.max(0.0);
        let w = (m.x * m.x + m.y * m.y + z * z).sqrt() + z;
        let (s, t) = (m.x / w, m.y / w);
        let (x, y) = self.clamp_to_domain(res, (s + 1.0) * half, (1.0 - t) * half);
        MapCoord { face, level, x: f64::from(x), y: f64::from(y) }
    }

    /// Continuous coordinates clamped into `[0, res)` and, for paraboloids, into a texel
    /// of the domain: the nearest one (by distance to its square) if the point's own is not.
    fn clamp_to_domain(&self, res: u32, x: f64, y: f64) -> (f32, f32) {
        // The largest f32 below `res` (`res` is at most 2^16, exact in f32): `next_down`
        // without its special cases.
        let lim = f32::from_bits((res as f32).to_bits() - 1);
        // `max` before `min` and NaN -> 0: f32::max returns the non-NaN operand.
        let (x, y) = ((x as f32).max(0.0).min(lim), (y as f32).max(0.0).min(lim));
        let (ix, iy) = (x as u32, y as u32);
        if disc_contains(res, ix, iy) {
            return (x, y);
        }
        let (jx, jy) = nearest_in_disc(res, x, y).unwrap_or((res / 2, res / 2));
        let into = |v: f32, j: u32| v.max(j as f32).min(((j + 1) as f32).next_down());
        (into(x, jx), into(y, jy))
    }

    /// The unit direction (from the light) of the continuous texel position `(x, y)` on `face`
    /// at level 0 ([`LightMap::texel_dir_at`]).
    ///
    /// A face number out of range is taken as the last face.
    pub fn texel_dir(&self, face: u8, x: f32, y: f32) -> Vec3 {
        self.texel_dir_at(face, 0, f64::from(x), f64::from(y))
    }

    /// The unit direction (from the light) of the continuous texel position `(x, y)` on `face`
    /// at level `level`.
    pub fn texel_dir_at(&self, face: u8, level: u8, x: f64, y: f64) -> Vec3 {
        if self.layout == Layout::Cube {
            return cube_texel_dir(face, self.resolution_at(level), x, y);
        }
        let inv = 2.0 / f64::from(self.resolution_at(level));
        let (s, t) = (x * inv - 1.0, 1.0 - y * inv);
        let d = match self.layout {
            Layout::Cube => unreachable!("returned above"),
            Layout::Dual | Layout::Hemisphere(_) => {
                // Inverse of (u, v) = (x, y) / (1 + z) on the unit sphere (crate::paraboloid).
                let r2 = s * s + t * t;
                let z = (1.0 - r2) / (1.0 + r2);
                self.layout.frame(face).to_world(DVec3::new(s * (1.0 + z), t * (1.0 + z), z))
            }
        };
        d.normalize().as_vec3()
    }

    /// The face at `level`, if the map has that level and face.
    #[inline]
    fn face_at(&self, level: u8, face: u8) -> Option<&Face> {
        let nf = self.layout.face_count();
        if usize::from(face) >= nf {
            return None;
        }
        self.faces.get(usize::from(level) * nf + usize::from(face))
    }

    /// The face and storage index of texel `(ix, iy)`: `Err(EMPTY)` outside the face or on a
    /// face of a whole map that was not drawn, `Err(ABSENT)` in a page of a paged map that was
    /// not drawn.
    #[inline]
    fn texel(&self, level: u8, face: u8, ix: u32, iy: u32) -> Result<(&Face, Stored), u32> {
        let res = self.resolution_at(level);
        if ix >= res || iy >= res {
            return Err(EMPTY);
        }
        let f = match self.face_at(level, face) {
            Some(f) => f,
            None if self.paged && usize::from(face) < self.layout.face_count() => return Err(ABSENT),
            None => return Err(EMPTY),
        };
        match f.index(ix, iy) {
            Some(i) => Ok((f, i)),
            None if self.is_paged() => Err(ABSENT),
            None => Err(EMPTY),
        }
    }

    /// [`LightMap::id_at`] of several texels of `face` at `level`, looking each page up once:
    /// the texels of a footprint mostly share one (a page table lookup is a hash at the fine
    /// levels of a paged map).
    #[inline]
    pub fn ids_at<const N: usize>(&self, level: u8, face: u8, texels: [(u32, u32); N]) -> [u32; N] {
        let res = self.resolution_at(level);
        let Some(f) = self.face_at(level, face) else {
            let missing =
                if self.paged && usize::from(face) < self.layout.face_count() { ABSENT } else { EMPTY };
            return texels.map(|(x, y)| if x >= res || y >= res { EMPTY } else { missing });
        };
        let none = if self.paged { ABSENT } else { EMPTY };
        let mut last: Option<((u32, u32), Option<usize>)> = None;
        texels.map(|(x, y)| {
            if x >= res || y >= res {
                return EMPTY;
            }
            let page = (x / PAGE, y / PAGE);
            let slot = match last {
                Some((p, s)) if p == page => s,
                _ => {
                    let s = f.slot(page.0, page.1);
                    last = Some((page, s));
                    s
                }
            };
            match slot.map(|s| f.texel_of(s, ((y % PAGE) * PAGE + x % PAGE) as usize)) {
                Some(Stored::At(i)) => f.id[i],
                Some(Stored::Id(id)) => id,
                None => none,
            }
        })
    }

    /// The ids of the 2x2 texels from `(x0, y0)` (row-major: `(x0, y0)`, `(x0 + 1, y0)`, `(x0,
    /// y0 + 1)`, `(x0 + 1, y0 + 1)`), as [`LightMap::ids_at`] gives them, when all four lie in
    /// one page of the face (most footprints: one page table lookup, four neighbouring
    /// loads); `None` otherwise.
    #[inline]
    pub fn quad_ids(&self, level: u8, face: u8, x0: u32, y0: u32) -> Option<[u32; 4]> {
        let (cx, cy) = (x0 % PAGE, y0 % PAGE);
        if cx == PAGE - 1
            || cy == PAGE - 1
            || x0 + 1 >= self.resolution_at(level)
            || y0 + 1 >= self.resolution_at(level)
        {
            return None;
        }
        let Some(f) = self.face_at(level, face) else {
            return (self.paged && usize::from(face) < self.layout.face_count()).then_some([ABSENT; 4]);
        };
        let Some(s) = f.slot(x0 / PAGE, y0 / PAGE) else {
            return Some([if self.paged { ABSENT } else { EMPTY }; 4]);
        };
        Some(f.quad(s, (cy * PAGE + cx) as usize))
    }

    /// Whether the map is paged ([`LightMap::build_pages`]): a page not drawn is then
    /// [`ABSENT`], not empty.
    #[inline]
    pub fn is_paged(&self) -> bool {
        self.paged
    }

    /// Id of the closest triangle at texel `(ix, iy)` of `face` at `level`: [`EMPTY`] if none
    /// (or outside the face), [`ABSENT`] if the texel's page was not drawn in a paged map.
    #[inline]
    pub fn id_at(&self, level: u8, face: u8, ix: u32, iy: u32) -> u32 {
        match self.texel(level, face, ix, iy) {
            Ok((f, Stored::At(i))) => f.id[i],
            Ok((_, Stored::Id(id))) => id,
            Err(e) => e,
        }
    }

    /// The one triangle that the texels `[x0, x1] x [y0, y1]` of `face` at `level` see:
    /// `Some(EMPTY)` if none, `Some(id)` if every texel holds `id`, `None` if two triangles or
    /// more, or a triangle and nothing, may be seen, or a page of the box was not drawn (the answer is
    /// conservative: it reads whole `REGION` blocks). A face of a whole map that was not drawn
    /// sees nothing, as its texel lookups say.
    pub fn region_id(&self, face: u8, level: u8, x0: u32, y0: u32, x1: u32, y1: u32) -> Option<u32> {
        let f = self.face_at(level, face)?;
        if f.is_empty() && !self.is_paged() {
            return Some(EMPTY);
        }
        self.region_in(f, level, false, x0, y0, x1, y1)
    }

    /// [`LightMap::region_id`] by group of triangles (`Some(g)`: every texel holds a triangle
    /// of group `g`), for a map made by [`LightMap::build_grouped`]; `None`
    /// (cannot tell) for one made without groups.
    pub fn region_group(&self, face: u8, level: u8, x0: u32, y0: u32, x1: u32, y1: u32) -> Option<u32> {
        let f = self.face_at(level, face)?;
        if f.is_empty() && !self.is_paged() {
            return Some(EMPTY);
        }
        if f.region_group.is_empty() {
            return None;
        }
        self.region_in(f, level, true, x0, y0, x1, y1)
    }

    #[allow(clippy::too_many_arguments)]
    fn region_in(&self, f: &Face, level: u8, group: bool, x0: u32, y0: u32, x1: u32, y1: u32) -> Option<u32> {
        let last = self.resolution_at(level) - 1;
        let side = PAGE / REGION;
        let region = if group { &f.region_group } else { &f.region };
        let mut seen = UNSEEN;
        for by in y0 / REGION..=y1.min(last) / REGION {
            for bx in x0 / REGION..=x1.min(last) / REGION {
                let slot = f.slot(bx / side, by / side)?;
                let v = region[slot * PAGE_REGIONS + ((by % side) * side + bx % side) as usize];
                if v == MIXED || (seen != UNSEEN && v != seen) {
                    return None;
                }
                seen = v;
            }
        }
        Some(if seen == UNSEEN { EMPTY } else { seen })
    }

    /// Calls `seen` with the ids that the texels `[x0, x1] x [y0, y1]` of `face` at `level`
    /// hold, every one at least once (some more than once), as [`LightMap::id_at`] gives
    /// them ([`ABSENT`] for a page a paged map did not draw), until it returns `false`;
    /// whether it never did. For the tile test where [`LightMap::region_id`] sees several
    /// triangles: a block its summary says holds one triangle is seen once, a mixed block of a
    /// palette page each of its palette entries once, of other pages texel by texel (runs of
    /// one id once).
    #[allow(clippy::too_many_arguments)]
    pub fn region_ids(
        &self,
        face: u8,
        level: u8,
        x0: u32,
        y0: u32,
        x1: u32,
        y1: u32,
        mut seen: impl FnMut(u32) -> bool,
    ) -> bool {
        let none = if self.paged { ABSENT } else { EMPTY };
        let Some(f) = self.face_at(level, face) else {
            return usize::from(face) >= self.layout.face_count() || seen(none);
        };
        if f.is_empty() && !self.paged {
            return seen(EMPTY);
        }
        let last = self.resolution_at(level) - 1;
        let (x1, y1) = (x1.min(last), y1.min(last));
        let side = PAGE / REGION;
        for by in y0 / REGION..=y1 / REGION {
            for bx in x0 / REGION..=x1 / REGION {
                let Some(slot) = f.slot(bx / side, by / side) else {
                    if !seen(none) {
                        return false;
                    }
                    continue;
                };
                let v = f.region[slot * PAGE_REGIONS + ((by % side) * side + bx % side) as usize];
                if v != MIXED {
                    if !seen(v) {
                        return false;
                    }
                    continue;
                }
                let (tx0, tx1) = (x0.max(bx * REGION), x1.min(bx * REGION + REGION - 1));
                let (ty0, ty1) = (y0.max(by * REGION), y1.min(by * REGION + REGION - 1));
                // The block's rows within the box, each a run of texels of one page row.
                let rows = (ty0..=ty1).map(|y| ((y % PAGE) * PAGE + tx0 % PAGE) as usize);
                let width = (tx1 - tx0 + 1) as usize;
                let mut run = UNSEEN;
                let mut see = |id: u32| {
                    if id == run {
                        return true;
                    }
                    run = id;
                    seen(id)
                };
                let all = match f.kept(slot) {
                    Kept::One(id) => see(id),
                    Kept::Palette { at, page, .. } => {
                        // The palette entries the block's texels use, a bit each, then each
                        // entry's id once: a block holds few distinct ids in many texels.
                        let (index, palette) =
                            (&f.index[page as usize * PAGE_TEXELS..], &f.palette[at as usize..]);
                        let mut used = [0u64; 4];
                        for t in rows {
                            for &i in &index[t..t + width] {
                                used[usize::from(i >> 6)] |= 1 << (i & 63);
                            }
                        }
                        used.iter().enumerate().all(|(w, &bits)| {
                            let mut bits = bits;
                            while bits != 0 {
                                let i = w * 64 + bits.trailing_zeros() as usize;
                                bits &= bits - 1;
                                if !see(palette[i]) {
                                    return false;
                                }
                            }
                            true
                        })
                    }
                    Kept::Ids { page } => {
                        let ids = &f.id[page as usize * PAGE_TEXELS..];
                        rows.into_iter().all(|t| ids[t..t + width].iter().all(|&id| see(id)))
                    }
                };
                if !all {
                    return false;
                }
            }
        }
        true
    }

    /// Id of the closest triangle at texel `(ix, iy)` of `face` at level 0, or [`EMPTY`]
    /// ([`LightMap::id_at`]).
    #[inline]
    pub fn id(&self, face: u8, ix: u32, iy: u32) -> u32 {
        self.id_at(0, face, ix, iy)
    }

    /// Distance from the light to the stored surface in the direction of the texel's centre
    /// at level 0 (`f32::INFINITY` when empty or not drawn; NaN where a paged map, which
    /// stores no depths, holds a triangle: see
    /// [`Classifier::depth_at`](crate::classify::Classifier::depth_at)).
    #[inline]
    pub fn depth(&self, face: u8, ix: u32, iy: u32) -> f32 {
        self.depth_at(0, face, ix, iy)
    }

    /// [`LightMap::depth`] at `level`.
    #[inline]
    pub fn depth_at(&self, level: u8, face: u8, ix: u32, iy: u32) -> f32 {
        if self.paged {
            let id = self.id_at(level, face, ix, iy);
            return if id == EMPTY || id == ABSENT { f32::INFINITY } else { f32::NAN };
        }
        let Ok((f, Stored::At(i))) = self.texel(level, face, ix, iy) else { return f32::INFINITY };
        let d = f.depth[i];
        // Reversed-Z: empty texels hold depth 0, drawn ones near / w >= 2^-21.
        if d.is_nan() || d <= 0.0 {
            return f32::INFINITY;
        }
        if self.layout != Layout::Cube {
            return self.near / d;
        }
        // Cube: w = near / depth along the axis; the centre's direction (1, s, t) is
        // sqrt(1 + s^2 + t^2) times longer than its axis component. In f32 (correctly rounded
        // division and root, a few ulps in all) from the centre's exact face coordinates.
        let inv = 2.0 / f64::from(self.resolution_at(level));
        let sq = |i: u32| ((f64::from(i) + 0.5) * inv - 1.0).powi(2) as f32;
        self.near / d * ((1.0 + sq(iy)) + sq(ix)).sqrt()
    }

    /// The texel `(level, x, y)` at face position `(u, v)` (fractions of the face's side,
    /// `[0, 1)`) of the finest level whose page there was drawn, if any: for showing a paged
    /// map's face whole. For a whole map, the level-0 texel there.
    pub fn finest_texel(&self, face: u8, u: f64, v: f64) -> Option<(u8, u32, u32)> {
        (0..self.levels()).rev().find_map(|level| {
            let res = f64::from(self.resolution_at(level));
            let (x, y) = ((u * res).max(0.0) as u32, (v * res).max(0.0) as u32);
            self.texel(level, face, x, y).is_ok().then_some((level, x, y))
        })
    }

    /// Angle in radians subtended by one texel at `c` (the largest of its two sides): the
    /// footprint of a texel at distance `r` is about `r * texel_angle`.
    ///
    /// A texel is `2 / res` wide in face coordinates `(s, t)`. Cube: the unit direction of
    /// `(1, s, t)` moves by `sqrt(1 + t^2) / (1 + s^2 + t^2)` per unit of `s` (and symmetrically),
    /// from `2 / res` at the face centre down to `0.94 / res` at a corner. Paraboloid: the map is
    /// conformal with `dtheta = 2 / (1 + u^2 + v^2) du`, from `4 / res` at the centre to `2 / res`
    /// at the rim.
    #[inline]
    pub fn texel_angle(&self, c: MapCoord) -> f32 {
        let inv = 2.0 / f64::from(self.resolution_at(c.level));
        let (s, t) = (c.x * inv - 1.0, 1.0 - c.y * inv);
        let (s2, t2) = (s * s, t * t);
        let per_unit = match self.layout {
            Layout::Cube => (1.0 + s2.max(t2)).sqrt() / (1.0 + s2 + t2),
            _ => 2.0 / (1.0 + s2 + t2),
        };
        (per_unit * inv) as f32
    }

    /// Whether a texel centre at level 0 lies in the region the face covers (always for cube
    /// faces; inside the unit disc for paraboloids; texels outside it are never drawn).
    #[inline]
    pub fn texel_in_domain(&self, face: u8, ix: u32, iy: u32) -> bool {
        let res = self.base;
        usize::from(face) < self.layout.face_count()
            && ix < res
            && iy < res
            && (self.layout == Layout::Cube || disc_contains(res, ix, iy))
    }

    #[inline]
    pub fn kind(&self) -> MapKind {
        match self.layout {
            Layout::Cube => MapKind::Cube,
            Layout::Dual | Layout::Hemisphere(_) => MapKind::Paraboloid,
        }
    }

    /// Texels per side of every face at level 0 (for a whole map, its only level: the
    /// requested resolution clamped to `[1, MAX_TARGET_DIM]`; for a paged map, [`PAGE`]).
    #[inline]
    pub fn resolution(&self) -> u32 {
        self.base
    }

    /// Texels per side of every face at `level`: `resolution() << level`.
    #[inline]
    pub fn resolution_at(&self, level: u8) -> u32 {
        self.base << level.min(MAX_LEVEL)
    }

    /// Levels the map has (1 for a whole map).
    pub fn levels(&self) -> u8 {
        (self.faces.len() / self.layout.face_count()) as u8
    }

    #[inline]
    pub fn light(&self) -> Vec3 {
        self.light
    }

    /// The near distance the map was drawn with (module docs): surfaces closer to the light are
    /// not in the map.
    pub fn near(&self) -> f32 {
        self.near
    }

    /// Number of faces of this map (6, 2, or 1 for [`LightMap::build_hemisphere`]).
    pub fn faces(&self) -> usize {
        self.layout.face_count()
    }

    /// Which faces were drawn (any page of them, at any level).
    pub fn faces_drawn(&self) -> &[bool] {
        &self.drawn
    }

    /// Whether page `key` was drawn.
    pub fn has_page(&self, key: PageKey) -> bool {
        self.face_at(key.level, key.face)
            .is_some_and(|f| key.px < f.n && key.py < f.n && f.slot(key.px, key.py).is_some())
    }

    /// The pages drawn, in [`PageKey`] order.
    pub fn pages(&self) -> Vec<PageKey> {
        let nf = self.layout.face_count();
        let mut out = Vec::new();
        for (i, f) in self.faces.iter().enumerate() {
            let (level, face) = ((i / nf) as u8, (i % nf) as u8);
            out.extend(f.keys().into_iter().map(|(px, py)| PageKey { level, face, py, px }));
        }
        out.sort_unstable();
        out
    }

    /// Number of pages drawn (held now).
    pub fn page_count(&self) -> usize {
        self.faces.iter().map(Face::pages).sum()
    }

    /// Triangles rasterized, after culling per face (per page, for paged maps) and
    /// tessellation, summed.
    pub fn triangles_drawn(&self) -> u64 {
        self.triangles_drawn
    }

    /// Faces rasterized to make this map, [`LightMap::merge`]s included: equal to the number of
    /// faces drawn when no face was ever drawn twice. (A paged map counts the faces of each
    /// build that drew pages on them.)
    pub fn faces_rasterized(&self) -> u32 {
        self.faces_rasterized
    }

    /// Pages rasterized to make this map, merges included (a whole face counts all its pages).
    pub fn pages_rasterized(&self) -> u64 {
        self.pages_rasterized
    }

    /// Takes the faces (for whole maps) or pages (for paged maps) that `other` drew and `self`
    /// did not, so that a map can gain them (a camera that moved and sees more of the light's
    /// surroundings) without drawing its own again. A face or page is the same whichever
    /// others a build draws (the near distance depends on the triangles and the light alone),
    /// so the result equals one build of all of them.
    ///
    /// # Panics
    /// If `other` is not a map of the same light, layout and resolution.
    pub fn merge(&mut self, other: LightMap) {
        assert!(
            self.layout == other.layout
                && self.base == other.base
                && self.light == other.light
                && self.paged == other.paged,
            "merging maps of different lights or parameterisations"
        );
        if !self.drawn.iter().any(|&d| d) {
            self.near = other.near;
            self.holes = other.holes;
        }
        // Resolved only if every part is.
        self.holes &= other.holes;
        let nf = self.layout.face_count();
        self.triangles_drawn += other.triangles_drawn;
        self.faces_rasterized += other.faces_rasterized;
        if !self.paged {
            for (f, face) in other.faces.into_iter().enumerate() {
                if other.drawn[f] && !self.drawn[f] {
                    self.pages_rasterized += face.pages() as u64;
                    self.faces[f] = face;
                    self.drawn[f] = true;
                }
            }
            return;
        }
        let groups = !other.faces.iter().all(|f| f.region_group.is_empty());
        while self.faces.len() < other.faces.len() {
            let level = (self.faces.len() / nf) as u32;
            self.faces.push(Face::new(self.base << level));
        }
        for key in other.pages() {
            if self.has_page(key) {
                continue;
            }
            let f = &other.faces[usize::from(key.level) * nf + usize::from(key.face)];
            let s = f.slot(key.px, key.py).expect("listed page");
            let face = &mut self.faces[usize::from(key.level) * nf + usize::from(key.face)];
            face.push_page(f, s, (key.px, key.py), groups);
            self.drawn[usize::from(key.face)] = true;
            self.pages_rasterized += 1;
        }
    }

    /// Drops the pages of a paged map for which `keep` is false (a memory budget's eviction:
    /// the pages a new view no longer reads), keeping the others as they are. Whole maps are
    /// left unchanged.
    pub fn retain_pages(&mut self, keep: impl Fn(PageKey) -> bool) {
        if !self.paged {
            return;
        }
        let nf = self.layout.face_count();
        for (i, face) in self.faces.iter_mut().enumerate() {
            let (level, f) = ((i / nf) as u8, (i % nf) as u8);
            let keys = face.keys();
            if keys.iter().all(|&(px, py)| keep(PageKey { level, face: f, py, px })) {
                continue;
            }
            let mut out = Face::new(face.n * PAGE);
            let groups = !face.region_group.is_empty();
            for (px, py) in keys {
                if !keep(PageKey { level, face: f, py, px }) {
                    continue;
                }
                let s = face.slot(px, py).expect("listed page");
                out.push_page(face, s, (px, py), groups);
            }
            *face = out;
        }
        for f in 0..nf {
            self.drawn[f] = self.faces.iter().skip(f).step_by(nf).any(|x| !x.is_empty());
        }
    }

    /// Bytes of texel memory (ids, distances, region summaries and page tables).
    pub fn memory_bytes(&self) -> usize {
        self.faces.iter().map(Face::memory_bytes).sum()
    }
}

/// Where direction `dir` falls on a cube map of `res` texels per side, at `level`.
///
/// Face coordinates in f32: classification calls this for every pixel and light, and they are
/// exact to an ulp either way (one division each). Texel coordinates in f64: `(s + 1) res / 2`
/// is then exact (a power of two times a sum of two f32).
#[inline]
pub(crate) fn cube_coord(dir: Vec3, res: u32, level: u8) -> MapCoord {
    let (face, st) = cube_lookup(dir);
    let half = f64::from(res) * 0.5;
    let lim = f64::from(res).next_down();
    // `max` before `min` and NaN -> 0: f64::max returns the non-NaN operand.
    let clamp = |v: f64| v.max(0.0).min(lim);
    MapCoord {
        face: face.index(),
        level,
        x: clamp((f64::from(st.x) + 1.0) * half),
        y: clamp((1.0 - f64::from(st.y)) * half),
    }
}

/// Whether texel `(x, y)`'s centre is strictly inside the disc inscribed in a `res`-texel square:
/// `|centre - res/2| < res/2`, times 2 in integers: `(2x + 1 - res)^2 + (2y + 1 - res)^2 < res^2`.
/// (A sum of two odd squares is 2 mod 8 and `res^2` is 0, 1 or 4 mod 8: no centre lies exactly
/// on the circle.)
pub(crate) fn disc_contains(res: u32, x: u32, y: u32) -> bool {
    let r = i64::from(res);
    let (cx, cy) = (2 * i64::from(x) + 1 - r, 2 * i64::from(y) + 1 - r);
    cx * cx + cy * cy < r * r
}

/// The columns `[x0, x1)` of row `y` whose texel centres are in the disc ([`disc_contains`]).
fn disc_span(res: u32, y: u32) -> (u32, u32) {
    let r = i64::from(res);
    let cy = 2 * i64::from(y) + 1 - r;
    let room = r * r - cy * cy; // (2x + 1 - res)^2 < room
    if room <= 0 {
        return (0, 0);
    }
    // Largest odd-or-even c = |2x + 1 - res| with c^2 < room, from the integer square root.
    let mut c = (room as f64).sqrt() as i64;
    while c * c >= room {
        c -= 1;
    }
    while (c + 1) * (c + 1) < room {
        c += 1;
    }
    // 2x + 1 - res in [-c, c]  <=>  x in [(res - 1 - c) / 2, (res - 1 + c) / 2].
    let lo = (r - 1 - c + 1).div_euclid(2).max(0); // ceil((res - 1 - c) / 2)
    let hi = (r - 1 + c).div_euclid(2).min(r - 1); // floor((res - 1 + c) / 2)
    if lo > hi { (0, 0) } else { (lo as u32, hi as u32 + 1) }
}

/// The texel of the disc nearest to point `(x, y)` (distance to its square) among the 3x3 around
/// the point's texel, the first in row-major order on ties.
pub(crate) fn nearest_in_disc(res: u32, x: f32, y: f32) -> Option<(u32, u32)> {
    let (ix, iy) = (x as u32, y as u32);
    let mut best: Option<(f32, u32, u32)> = None;
    for jy in iy.saturating_sub(1)..=(iy + 1).min(res - 1) {
        for jx in ix.saturating_sub(1)..=(ix + 1).min(res - 1) {
            if !disc_contains(res, jx, jy) {
                continue;
            }
            let gap = |v: f32, j: u32| (j as f32 - v).max(v - (j + 1) as f32).max(0.0);
            let d2 = gap(x, jx).powi(2) + gap(y, jy).powi(2);
            if best.is_none_or(|(b, _, _)| d2 < b) {
                best = Some((d2, jx, jy));
            }
        }
    }
    best.map(|(_, jx, jy)| (jx, jy))
}

/// The indices of the triangles that can be drawn (module docs) and the near distance.
///
/// For a single hemisphere, triangles with no vertex strictly in front of it are left out
/// first, by the very test (and arithmetic) the tessellator would drop them with: the cheap
/// test saves the usability test's distances for half of the scene.
fn usable_triangles(tris: &[[Vec3; 3]], light: Vec3, layout: Layout) -> (Vec<u32>, f32) {
    let tris = &tris[..tris.len().min(EMPTY_ID as usize)];
    let l = light.as_dvec3();
    let front = |t: &[Vec3; 3]| match layout {
        Layout::Hemisphere(f) => t.iter().any(|p| f.to_map(p.as_dvec3() - l).z > 0.0),
        _ => true,
    };
    let parts: Vec<(Vec<u32>, f64)> = tris
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(c, chunk)| {
            let mut ids = Vec::with_capacity(chunk.len());
            let mut far = 0.0f64;
            for (k, t) in chunk.iter().enumerate() {
                if let Some(r) = front(t).then(|| usable(t, l)).flatten() {
                    ids.push((c * CHUNK + k) as u32);
                    far = far.max(r);
                }
            }
            (ids, far)
        })
        .collect();
    let far = parts.iter().map(|p| p.1).fold(0.0, f64::max);
    let ids = parts.into_iter().flat_map(|p| p.0).collect();
    // Exact: far * 2^-20 rounded once to f32; at least the smallest normal f32.
    let near = if far > 0.0 { ((far * f64::from(NEAR_FRACTION)) as f32).max(f32::MIN_POSITIVE) } else { 1.0 };
    (ids, near)
}

/// The distance from the light to the triangle's farthest vertex, if it can be drawn.
fn usable(t: &[Vec3; 3], l: DVec3) -> Option<f64> {
    if !l.is_finite() || !t.iter().all(|v| v.is_finite()) {
        return None;
    }
    // f32 - f32 in f64 is exact unless the exponents differ by more than 29.
    let d = t.map(|v| v.as_dvec3() - l);
    // The farthest and nearest vertex's distances, one square root each: `length()` is
    // `length_squared().sqrt()`, and a correctly rounded square root keeps the order.
    let d2 = d.map(|x| x.length_squared());
    let far = d2.iter().copied().fold(0.0, f64::max).sqrt();
    if far.is_nan() || far > MAX_DISTANCE {
        return None;
    }
    let n = (d[1] - d[0]).cross(d[2] - d[0]);
    let len = n.length();
    if len.is_nan() || len <= 0.0 {
        return None; // zero area
    }
    // Distance from the light to the triangle's plane, against the edge-on thresholds.
    let h = n.dot(d[0]).abs() / len;
    let edge_on_abs = far * 2f64.powi(-40);
    // The distance to the triangle is at most the nearest vertex's: when `h` clears the
    // threshold with that distance, it clears it with the exact one, which is then not needed
    // (it is for few triangles, and it is the costly part of this test).
    let near_vertex = d2.iter().copied().fold(f64::INFINITY, f64::min).sqrt();
    let rel = 2f64.powi(-20);
    let edge_on_rel = |h: f64| h > near_vertex * rel || h > dist_triangle(d[0], d[1], d[2]) * rel;
    (h > edge_on_abs && edge_on_rel(h)).then_some(far)
}

/// One page of a whole face from the rasterizer's row-major ids and reversed-Z depths, `src`
/// = `(ids, depths, row stride)`: texels outside a paraboloid's disc or beyond the face cleared
/// ([`EMPTY`], depth 0), row-major. `origin` is the page's first texel on a face of `res`
/// texels per side.
fn finish_page(
    layout: Layout,
    res: u32,
    origin: (u32, u32),
    src: (&[u32], &[f32], usize),
    id_out: &mut [u32],
    depth_out: &mut [f32],
) {
    let (ids, depth, stride) = src;
    let p = PAGE as usize;
    let cube = layout == Layout::Cube;
    for y in 0..p {
        let gy = origin.1 + y as u32;
        let (x0, x1) = if gy >= res {
            (0, 0)
        } else if cube {
            (0, res)
        } else {
            disc_span(res, gy)
        };
        let row = gy as usize * stride + origin.0 as usize;
        for x in 0..p {
            let gx = origin.0 + x as u32;
            let k = y * p + x;
            (id_out[k], depth_out[k]) =
                if (x0..x1).contains(&gx) { (ids[row + x], depth[row + x]) } else { (EMPTY, 0.0) };
        }
    }
}

/// The texels of page `key` (drawn into `target` from the triangles `bin`) whose centre meets
/// a triangle with holes in a hole: given the id that the page drawn without those triangles
/// has there (`LightMap::build_pages_with_holes`).
fn see_through_holes(
    h: &Holes,
    key: &PageKey,
    bin: &[u32],
    (tris, light, near): (&[[Vec3; 3]], DVec3, f32),
    rasterizer: &mut Rasterizer,
    target: &mut Target,
) {
    let res = PAGE << key.level;
    let (x0, y0) = (key.px * PAGE, key.py * PAGE);
    let holes: Vec<usize> = (0..target.id.len())
        .filter(|&i| {
            let id = target.id[i];
            h.cutouts.get(id as usize).is_some_and(|&c| c) && {
                let (x, y) = (x0 + i as u32 % PAGE, y0 + i as u32 / PAGE);
                h.sees_hole(id, cube_texel_dir(key.face, res, f64::from(x) + 0.5, f64::from(y) + 0.5))
            }
        })
        .collect();
    if holes.is_empty() {
        return;
    }
    let (cut, solid): (Vec<u32>, Vec<u32>) =
        bin.iter().partition(|&&t| h.cutouts.get(t as usize).is_some_and(|&c| c));
    let axes = CubeFace::ALL[usize::from(key.face)].axes();
    let mut clipped = Vec::new();
    page_clip_all(tris, &solid, light, near, key, axes, &mut clipped);
    let mut behind = Target::default();
    rasterizer.rasterize_into(&clipped, &solid, PAGE, PAGE, &PAGE_RASTER, &mut behind);
    // Where the texel's ray crosses another cut-out too (before or after the hole), what lies
    // behind the hole is not the map without cut-outs: the texel cannot tell (a ray decides).
    clipped.clear();
    page_clip_all(tris, &cut, light, near, key, axes, &mut clipped);
    let crossings = hyrt_raster::coverage_count(&clipped, PAGE, PAGE, &PAGE_RASTER);
    for i in holes {
        target.id[i] = if crossings[i] > 1 { ABSENT } else { behind.id[i] };
    }
}

/// The unit direction (from the light) of the continuous texel position `(x, y)` of cube face
/// `face` at `res` texels a side.
fn cube_texel_dir(face: u8, res: u32, x: f64, y: f64) -> Vec3 {
    let inv = 2.0 / f64::from(res);
    let (s, t) = (x * inv - 1.0, 1.0 - y * inv);
    let (axis, sign, si, ti) = CubeFace::ALL[usize::from(face.min(5))].axes();
    let mut d = DVec3::ZERO;
    d[axis] = f64::from(sign);
    d[si] = s;
    d[ti] = t;
    d.normalize().as_vec3()
}

/// [`page_clip_all`] of one triangle.
#[cfg(test)]
fn page_clip(
    tri: [Vec3; 3],
    light: DVec3,
    near: f32,
    key: &PageKey,
    axes: (usize, f32, usize, usize),
) -> [Vec4; 3] {
    let mut out = Vec::with_capacity(1);
    page_clip_all(&[tri], &[0], light, near, key, axes, &mut out);
    out[0]
}

/// The clip-space positions of triangles `ids` of `tris`, appended to `out`, for drawing page
/// `key` alone into a [`PAGE`]-square target (face axes `(axis, sign, s, t)` of
/// [`CubeFace::axes`]).
///
/// The face's clip space is `(d_s, d_t, near, w = sign d_axis)` with NDC `(s, t) = (d_s, d_t) /
/// w`. At level `k` a face has `n = 2^k` pages per side ([`PAGE`] `<< k` texels); page
/// `(px, py)` covers NDC `s` in `[-1 + 2 px / n, -1 + 2 (px + 1) / n]` and, since texel row 0 is
/// NDC `t = +1`, `t` in `[1 - 2 (py + 1) / n, 1 - 2 py / n]`. The affine map
///
/// `s' = n s - (2 px + 1 - n)`,  `t' = n t + (2 py + 1 - n)`
///
/// takes that square to `[-1, 1]^2`; in clip space (times `w`) it is linear, so the page's
/// clip position is `(n d_s - (2 px + 1 - n) w, n d_t + (2 py + 1 - n) w, near, w)`, and depth
/// (`near / w`) is unchanged. It is computed in `f64` from the vertex's exact offset from the
/// light and rounded once: the page-relative coordinates keep `f32`'s relative precision, which
/// a face-wide `s` would not at fine levels.
///
/// One branch on the face's axes, outside the loop, so that every component is picked at
/// compile time: this runs for every (page, triangle) pair.
fn page_clip_all(
    tris: &[[Vec3; 3]],
    ids: &[u32],
    light: DVec3,
    near: f32,
    key: &PageKey,
    (axis, sign, s, t): (usize, f32, usize, usize),
    out: &mut Vec<[Vec4; 3]>,
) {
    #[inline(always)]
    fn run<const AXIS: usize, const S: usize, const T: usize>(
        tris: &[[Vec3; 3]],
        ids: &[u32],
        light: DVec3,
        (near, sign, n, ox, oy): (f32, f64, f64, f64, f64),
        out: &mut Vec<[Vec4; 3]>,
    ) {
        let clip = |p: Vec3| {
            let d = p.as_dvec3() - light;
            let w = sign * d[AXIS];
            Vec4::new((n * d[S] - ox * w) as f32, (n * d[T] + oy * w) as f32, near, w as f32)
        };
        out.extend(ids.iter().map(|&id| {
            let tri = &tris[id as usize];
            [clip(tri[0]), clip(tri[1]), clip(tri[2])]
        }));
    }
    let n = f64::from(1u32 << key.level);
    let (ox, oy) = (2.0 * f64::from(key.px) + 1.0 - n, 2.0 * f64::from(key.py) + 1.0 - n);
    let k = (near, f64::from(sign), n, ox, oy);
    match (axis, s, t) {
        (0, 1, 2) => run::<0, 1, 2>(tris, ids, light, k, out),
        (1, 0, 2) => run::<1, 0, 2>(tris, ids, light, k, out),
        (2, 0, 1) => run::<2, 0, 1>(tris, ids, light, k, out),
        _ => unreachable!("a cube face's axes are (0, 1, 2), (1, 0, 2) or (2, 0, 1)"),
    }
}

/// The NDC bounds `(lo, hi)` of a projected triangle or box, and whether a point of it is
/// behind the light (its image is then unbounded).
type NdcBounds = ((f64, f64), (f64, f64), bool);

/// One page's storage: ids, and region summaries by triangle and by group.
type PageSlot<'a> = (&'a mut [u32], &'a mut [u32], &'a mut [u32]);

/// A cube face that a cluster of triangles may reach, for [`bin_pages`]: its axes
/// ([`CubeFace::axes`]) and its groups with a marked page under the cluster's image.
struct LiveFace<'g> {
    axes: (usize, f32, usize, usize),
    groups: Vec<&'g PageGroup>,
}

/// The marked pages of one level of one face, for [`bin_pages`].
struct PageGroup {
    level: u8,
    /// The rectangle `[x0, x1] x [y0, y1]` of pages that holds them all.
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
    /// Page `(x, y)` of the rectangle to its index in the page list: dense (row-major over the
    /// rectangle, `u32::MAX` for none) or, for a large rectangle, hashed.
    dense: Vec<u32>,
    sparse: rustc_hash::FxHashMap<(u32, u32), u32>,
    /// The pages, by `(x, y, index)`.
    list: Vec<(u32, u32, u32)>,
    /// With `dense`: the marked pages' summed-area table over the rectangle, `(w + 1) x (h +
    /// 1)`, entry `(x, y)` counting the pages left of `x` and above `y`.
    counts: Vec<u32>,
}

impl PageGroup {
    /// The group of `list`'s pages (`(x, y, index)`, distinct) at `level`.
    fn new(level: u8, list: Vec<(u32, u32, u32)>) -> Self {
        let (x0, x1) =
            (list.iter().map(|p| p.0).min().unwrap_or(0), list.iter().map(|p| p.0).max().unwrap_or(0));
        let (y0, y1) =
            (list.iter().map(|p| p.1).min().unwrap_or(0), list.iter().map(|p| p.1).max().unwrap_or(0));
        let area = u64::from(x1 - x0 + 1) * u64::from(y1 - y0 + 1);
        let mut g = PageGroup {
            level,
            x0,
            y0,
            x1,
            y1,
            dense: Vec::new(),
            sparse: Default::default(),
            list,
            counts: Vec::new(),
        };
        if area <= 1 << 16 {
            g.dense = vec![u32::MAX; area as usize];
            let w = x1 - x0 + 1;
            for &(x, y, i) in &g.list {
                g.dense[((y - y0) * w + (x - x0)) as usize] = i;
            }
            let (w, h) = (w as usize, (y1 - y0 + 1) as usize);
            g.counts = vec![0; (w + 1) * (h + 1)];
            for y in 0..h {
                let mut row = 0;
                for x in 0..w {
                    row += u32::from(g.dense[y * w + x] != u32::MAX);
                    g.counts[(y + 1) * (w + 1) + x + 1] = g.counts[y * (w + 1) + x + 1] + row;
                }
            }
        } else {
            g.sparse = g.list.iter().map(|&(x, y, i)| ((x, y), i)).collect();
        }
        g
    }

    /// Whether a marked page lies in pages `[x0, x1] x [y0, y1]` (within the rectangle): from
    /// the summed-area table, four loads; `true` without one (a large, sparse group).
    #[inline]
    fn any_in(&self, x0: u32, x1: u32, y0: u32, y1: u32) -> bool {
        if self.counts.is_empty() {
            return true;
        }
        let w = (self.x1 - self.x0 + 2) as usize;
        let (a, b) = ((x0 - self.x0) as usize, (x1 - self.x0 + 1) as usize);
        let (c, d) = ((y0 - self.y0) as usize, (y1 - self.y0 + 1) as usize);
        let at = |x: usize, y: usize| self.counts[y * w + x];
        at(b, d) + at(a, c) != at(a, d) + at(b, c)
    }

    #[inline]
    fn index(&self, x: u32, y: u32) -> Option<u32> {
        if self.dense.is_empty() {
            self.sparse.get(&(x, y)).copied()
        } else {
            let w = self.x1 - self.x0 + 1;
            let i = self.dense[((y - self.y0) * w + (x - self.x0)) as usize];
            (i != u32::MAX).then_some(i)
        }
    }
}

/// Per page of `pages` (sorted), the ids (in input order) of the usable triangles `valid` of its
/// face whose image may reach it, as one list with offsets: each triangle is culled per face as
/// [`cube_triangles`] does, then binned by its projected bounding box, grown by a texel of the
/// page's level (rounding), into the marked pages it overlaps, at the levels where those bounds
/// hold a texel centre ([`holds_centre`]); a triangle with a vertex behind
/// the light's plane of the face (an unbounded image) goes to every marked page of the face.
/// One pass over the triangles for every face and level, in parallel chunks whose
/// (page, triangle) pairs are then sorted by page, stably: the same bins for any thread count.
fn bin_pages(
    tris: &[[Vec3; 3]],
    valid: &[u32],
    light: Vec3,
    near: f32,
    pages: &[PageKey],
) -> (Vec<usize>, Vec<u32>) {
    // The groups of each face.
    let mut faces: [Vec<PageGroup>; 6] = Default::default();
    let mut start = 0;
    while start < pages.len() {
        let (level, face) = (pages[start].level, pages[start].face);
        let end = start + pages[start..].iter().take_while(|k| (k.level, k.face) == (level, face)).count();
        let list: Vec<(u32, u32, u32)> = (start..end).map(|i| (pages[i].px, pages[i].py, i as u32)).collect();
        faces[usize::from(face)].push(PageGroup::new(level, list));
        start = end;
    }
    let axes: Vec<(usize, (usize, f32, usize, usize))> =
        (0..6).filter(|&f| !faces[f].is_empty()).map(|f| (f, CubeFace::ALL[f].axes())).collect();
    // The marked pages of group `g` that an image with NDC bounds `lo..hi` (or, if `behind`,
    // an unbounded one) may reach: a rectangle of pages, empty if `x0 > x1` or `y0 > y1`.
    let range = |g: &PageGroup, lo: (f64, f64), hi: (f64, f64), behind: bool| -> (u32, u32, u32, u32) {
        if behind {
            return (g.x0, g.x1, g.y0, g.y1);
        }
        // NDC to pages: page px covers [px, px + 1) of (s + 1) n / 2; row 0 is t = +1. Grown
        // by a texel of the level. Truncation is the floor of the clamped value (NaN gives 0).
        let n = 1u32 << g.level;
        let half = f64::from(n) * 0.5;
        let grow = 2.0 / f64::from(PAGE << g.level);
        let page = |v: f64| (((v + 1.0) * half).max(0.0) as u32).min(n - 1);
        let (x0, x1) = (page(lo.0 - grow), page(hi.0 + grow));
        let (y0, y1) = (page(-hi.1 - grow), page(-lo.1 + grow));
        (x0.max(g.x0), x1.min(g.x1), y0.max(g.y0), y1.min(g.y1))
    };
    // Clip-space points of a face (`(d_s, d_t, near, sign d_axis)`): whether all lie beyond one
    // of its planes (the face culling of `cube_triangles`), else their NDC bounds and whether
    // one is behind the light.
    let project = |v: &[Vec4]| -> Option<NdcBounds> {
        if beyond_face(v, near) {
            return None;
        }
        let behind = v.iter().any(|c| c.w <= 0.0);
        let (mut lo, mut hi) = ((f64::INFINITY, f64::INFINITY), (f64::NEG_INFINITY, f64::NEG_INFINITY));
        for c in v {
            let (x, y) = (f64::from(c.x) / f64::from(c.w), f64::from(c.y) / f64::from(c.w));
            lo = (lo.0.min(x), lo.1.min(y));
            hi = (hi.0.max(x), hi.1.max(y));
        }
        Some((lo, hi, behind))
    };
    let clip =
        |d: Vec3, (axis, sign, s, t): (usize, f32, usize, usize)| Vec4::new(d[s], d[t], near, sign * d[axis]);
    let l = light.as_dvec3();
    let parts: Vec<Vec<(u32, u32)>> = valid
        .par_chunks(CLUSTER)
        .map(|cluster| {
            let mut out = Vec::new();
            // The faces whose marked pages the cluster's bounding box may reach: the box is
            // convex, so is its image, so what culls all 8 corners culls every triangle in it.
            let (mut bmin, mut bmax) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
            for &id in cluster {
                for p in tris[id as usize] {
                    (bmin, bmax) = (bmin.min(p - light), bmax.max(p - light));
                }
            }
            let corners: [Vec3; 8] = std::array::from_fn(|i| {
                Vec3::new(
                    if i & 1 == 0 { bmin.x } else { bmax.x },
                    if i & 2 == 0 { bmin.y } else { bmax.y },
                    if i & 4 == 0 { bmin.z } else { bmax.z },
                )
            });
            // Per face, the groups with a marked page under the cluster's image.
            let live: Vec<LiveFace> = axes
                .iter()
                .copied()
                .filter_map(|(f, ax)| {
                    let v = corners.map(|d| clip(d, ax));
                    let (lo, hi, behind) = project(&v)?;
                    let groups: Vec<&PageGroup> = faces[f]
                        .iter()
                        .filter(|g| {
                            let (x0, x1, y0, y1) = range(g, lo, hi, behind);
                            x0 <= x1 && y0 <= y1 && g.any_in(x0, x1, y0, y1)
                        })
                        .collect();
                    (!groups.is_empty()).then_some(LiveFace { axes: ax, groups })
                })
                .collect();
            if live.is_empty() {
                return out;
            }
            for &id in cluster {
                let d = tris[id as usize].map(|p| p - light);
                // The exact offsets, for the bounds of the image (f32's would be a texel off at
                // the finest levels, and would need a margin that culls nothing there).
                let e = tris[id as usize].map(|p| p.as_dvec3() - l);
                for &LiveFace { axes: ax, ref groups } in &live {
                    let v = d.map(|d| clip(d, ax));
                    if beyond_face(&v, near) {
                        continue;
                    }
                    let behind = v.iter().any(|c| c.w <= 0.0);
                    let (lo, hi) = image_bounds(&e, ax);
                    let image = ImageBox::of(lo, hi);
                    for &g in groups {
                        let (x0, x1, y0, y1) = if behind {
                            (g.x0, g.x1, g.y0, g.y1)
                        } else {
                            match image.at(g.level) {
                                Some((x0, x1, y0, y1)) => {
                                    (x0.max(g.x0), x1.min(g.x1), y0.max(g.y0), y1.min(g.y1))
                                }
                                None => continue,
                            }
                        };
                        if x0 > x1 || y0 > y1 || !g.any_in(x0, x1, y0, y1) {
                            continue;
                        }
                        let span = u64::from(x1 - x0 + 1) * u64::from(y1 - y0 + 1);
                        if span <= g.list.len() as u64 {
                            for py in y0..=y1 {
                                for px in x0..=x1 {
                                    if let Some(i) = g.index(px, py) {
                                        out.push((i, id));
                                    }
                                }
                            }
                        } else {
                            for &(px, py, i) in &g.list {
                                if (x0..=x1).contains(&px) && (y0..=y1).contains(&py) {
                                    out.push((i, id));
                                }
                            }
                        }
                    }
                }
            }
            out
        })
        .collect();
    // Counting sort by page, stable.
    let mut offsets = vec![0usize; pages.len() + 1];
    for &(i, _) in parts.iter().flatten() {
        offsets[i as usize + 1] += 1;
    }
    for i in 0..pages.len() {
        offsets[i + 1] += offsets[i];
    }
    let mut next = offsets.clone();
    let mut ids = vec![0u32; offsets[pages.len()]];
    for &(i, id) in parts.iter().flatten() {
        ids[next[i as usize]] = id;
        next[i as usize] += 1;
    }
    (offsets, ids)
}

/// The face NDC bounds `(lo, hi)` of the image of points `e` (offsets from the light, in front
/// of it) on the face of axes `(axis, sign, s, t)` ([`CubeFace::axes`]).
#[inline]
fn image_bounds(e: &[DVec3], (axis, sign, s, t): (usize, f32, usize, usize)) -> ((f64, f64), (f64, f64)) {
    let (mut lo, mut hi) = ((f64::INFINITY, f64::INFINITY), (f64::NEG_INFINITY, f64::NEG_INFINITY));
    for c in e {
        let w = f64::from(sign) * c[axis];
        let (x, y) = (c[s] / w, c[t] / w);
        lo = (lo.0.min(x), lo.1.min(y));
        hi = (hi.0.max(x), hi.1.max(y));
    }
    (lo, hi)
}

/// The bounds of a triangle's image on a face (all in front of the light), as fractions of the
/// face's side: `u` from `s`, `v` from `t` (row 0 at `t = +1`), for [`ImageBox::at`] at every
/// level of the face's marked pages (a level's texel coordinates are these times its
/// resolution, a power of two: exact).
#[derive(Clone, Copy, Debug)]
struct ImageBox {
    u: (f64, f64),
    v: (f64, f64),
}

impl ImageBox {
    /// The box of an image with face NDC bounds `lo..hi`.
    #[inline]
    fn of(lo: (f64, f64), hi: (f64, f64)) -> Self {
        Self { u: ((lo.0 + 1.0) * 0.5, (hi.0 + 1.0) * 0.5), v: ((1.0 - hi.1) * 0.5, (1.0 - lo.1) * 0.5) }
    }

    /// At `level`: the pages `(x0, x1, y0, y1)` the image's bounds, grown by a texel
    /// (rounding), overlap, clamped to the face; `None` if the bounds hold no texel centre in
    /// one axis, so that the image covers none.
    ///
    /// Texel `i` spans `[i, i + 1)` of `u res`, its centre at `i + 1/2`: bounds `[a, b]`
    /// (texels) hold one if `floor(b - 1/2 + m) >= a - 1/2 - m`, `m` = [`CENTRE_MARGIN`].
    #[inline]
    fn at(&self, level: u8) -> Option<(u32, u32, u32, u32)> {
        let res = f64::from(PAGE << level);
        let n = 1u32 << level;
        let (u0, u1, v0, v1) = (self.u.0 * res, self.u.1 * res, self.v.0 * res, self.v.1 * res);
        if !(holds_centre(u0, u1) && holds_centre(v0, v1)) {
            return None;
        }
        // Truncation is the floor of the clamped value (NaN gives 0).
        let page = |t: f64| ((t * (1.0 / f64::from(PAGE))).max(0.0) as u32).min(n - 1);
        Some((page(u0 - 1.0), page(u1 + 1.0), page(v0 - 1.0), page(v1 + 1.0)))
    }
}

/// Whether texel bounds `[a, b]` (texel units), grown by [`CENTRE_MARGIN`], hold a texel
/// centre: an image that holds none in one axis covers none, and is not drawn (a small
/// triangle far from the light, at a coarse level, where most of a dense mesh's triangles fall
/// between texel centres). NaN bounds (a degenerate image) hold one: the rasterizer decides.
#[inline]
fn holds_centre(a: f64, b: f64) -> bool {
    // Whether an integer lies in `[a', b']`: `floor(b') >= a'`. Clamped to where `i64` holds
    // every integer exactly (a clamped bound keeps an integer in the interval if there was
    // one, and faces are far smaller). Not `f64::floor`, which is a library call without
    // SSE4.1.
    const BIG: f64 = (1u64 << 52) as f64;
    let (a, b) = (a - 0.5 - CENTRE_MARGIN, b - 0.5 + CENTRE_MARGIN);
    if a.is_nan() || b.is_nan() {
        return true;
    }
    let b = b.clamp(-BIG, BIG);
    let t = b as i64;
    let floor = t - i64::from(b < t as f64);
    floor as f64 >= a
}

/// How far, in texels, [`holds_centre`] grows an image's bounds: they come from the exact offsets
/// of the vertices from the light, in `f64`, so within about 2^-50 of a texel (face NDC within a
/// few ulps, a face at most 2^22 texels); the rasterizer moves each vertex by at most half its
/// subpixel step (2^-9 texel) when it snaps it, and `page_clip_all`'s rounding to `f32` moves it by
/// less than 2^-17 texel where the image is this small (page-relative coordinates within a
/// page or two of 0, rounded once). 2^-6 texel clears their sum four times over.
const CENTRE_MARGIN: f64 = 1.0 / 64.0;

/// Whether the clip-space points `v` of a cube face (`(d_s, d_t, near, sign d_axis)`) all lie
/// beyond one of its planes, or all closer than the near plane (module docs): then nothing
/// they bound reaches the face.
#[inline]
fn beyond_face(v: &[Vec4], near: f32) -> bool {
    // One outcode per point, its bits the planes it lies beyond; all beyond one plane if their
    // AND is not zero. Branch-free: this runs for every triangle and face while binning.
    let outcode = |c: &Vec4| {
        u8::from(c.w < near)
            | u8::from(c.x > c.w) << 1
            | u8::from(c.x < -c.w) << 2
            | u8::from(c.y > c.w) << 3
            | u8::from(c.y < -c.w) << 4
    };
    v.iter().fold(0x1f, |all, c| all & outcode(c)) != 0
}

/// Clip-space triangles and ids of each drawn cube face (module docs), in input order: one pass
/// over the triangles for all faces.
fn cube_triangles(
    tris: &[[Vec3; 3]],
    valid: &[u32],
    light: Vec3,
    near: f32,
    drawn: &[bool],
) -> Vec<FaceTris> {
    let faces: Vec<(usize, (usize, f32, usize, usize))> = CubeFace::ALL
        .iter()
        .enumerate()
        .filter(|(f, _)| drawn[*f])
        .map(|(f, face)| (f, face.axes()))
        .collect();
    let parts: Vec<Vec<FaceTris>> = valid
        .par_chunks(CHUNK)
        .map(|chunk| {
            let mut out = vec![FaceTris::default(); 6];
            for &id in chunk {
                let d = tris[id as usize].map(|p| p - light);
                for &(f, (axis, sign, s, t)) in &faces {
                    let v = d.map(|d| Vec4::new(d[s], d[t], near, sign * d[axis]));
                    if beyond_face(&v, near) {
                        continue;
                    }
                    out[f].0.push(v);
                    out[f].1.push(id);
                }
            }
            out
        })
        .collect();
    (0..6)
        .map(|f| {
            let mut face = FaceTris::default();
            face.0.reserve(parts.iter().map(|p| p[f].0.len()).sum());
            face.1.reserve(face.0.capacity());
            for p in &parts {
                face.0.extend_from_slice(&p[f].0);
                face.1.extend_from_slice(&p[f].1);
            }
            face
        })
        .collect()
}

/// Clip-space triangles of one paraboloid hemisphere (clipped and tessellated), in input order.
fn hemisphere_triangles(
    tris: &[[Vec3; 3]],
    valid: &[u32],
    light: Vec3,
    frame: Frame,
    prm: &Params,
) -> FaceTris {
    let l = light.as_dvec3();
    let parts: Vec<Tessellator> = valid
        .par_chunks(CHUNK / 4)
        .map(|chunk| {
            let mut tess = Tessellator::default();
            for &id in chunk {
                tess.triangle(tris[id as usize].map(|p| frame.to_map(p.as_dvec3() - l)), id, prm);
            }
            tess
        })
        .collect();
    let mut face = FaceTris::default();
    face.0.reserve(parts.iter().map(|t| t.tris.len()).sum());
    face.1.reserve(face.0.capacity());
    for t in parts {
        face.0.extend_from_slice(&t.tris);
        face.1.extend_from_slice(&t.ids);
    }
    face
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn disc_domain_and_nearest_texel() {
        // Every point of the closed disc (and a little beyond) finds a texel of the domain in
        // its 3x3 neighbourhood, less than a texel away.
        let mut worst = 0.0f32;
        for res in 1..=160u32 {
            let r = res as f32 * 0.5;
            for k in 0..2000 {
                let a = k as f32 * 0.0031416;
                for rho in [r, r * (1.0 + 1e-6), r - 0.3, r - 0.7] {
                    let (x, y) = (r + rho * a.cos(), r + rho * a.sin());
                    let lim = (res as f32).next_down();
                    let (x, y) = (x.max(0.0).min(lim), y.max(0.0).min(lim));
                    if disc_contains(res, x as u32, y as u32) {
                        continue;
                    }
                    let (jx, jy) =
                        nearest_in_disc(res, x, y).unwrap_or_else(|| panic!("res {res} at ({x}, {y})"));
                    let gap = |v: f32, j: u32| (j as f32 - v).max(v - (j + 1) as f32).max(0.0);
                    worst = worst.max(gap(x, jx).hypot(gap(y, jy)));
                }
            }
        }
        assert!(worst < 1.0, "moved by {worst} texels");
        // The centre texel is always in the disc, and the row spans are the disc's rows.
        for res in 1..=200 {
            assert!(disc_contains(res, res / 2, res / 2));
            for y in 0..res {
                let (x0, x1) = disc_span(res, y);
                for x in 0..res {
                    assert_eq!((x0..x1).contains(&x), disc_contains(res, x, y), "res {res} ({x}, {y})");
                }
            }
        }
    }

    /// A page group's summed-area table says whether a rectangle holds a marked page, as a
    /// brute-force scan does (pseudo-random page sets on small grids, every rectangle).
    #[test]
    fn a_page_group_knows_which_rectangles_hold_a_marked_page() {
        let mut seed = 0x9e37_79b9_u32;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            seed
        };
        for case in 0..40 {
            let (w, h) = (1 + next() % 9, 1 + next() % 7);
            let (ox, oy) = (next() % 50, next() % 50);
            let mut list: Vec<(u32, u32, u32)> = Vec::new();
            for y in 0..h {
                for x in 0..w {
                    if next() % 4 == 0 || (case % 5 == 0 && x == w / 2) {
                        list.push((ox + x, oy + y, list.len() as u32));
                    }
                }
            }
            if list.is_empty() {
                list.push((ox, oy, 0));
            }
            let g = PageGroup::new(3, list.clone());
            assert!(!g.counts.is_empty());
            for y0 in g.y0..=g.y1 {
                for y1 in y0..=g.y1 {
                    for x0 in g.x0..=g.x1 {
                        for x1 in x0..=g.x1 {
                            let brute = list
                                .iter()
                                .any(|&(x, y, _)| (x0..=x1).contains(&x) && (y0..=y1).contains(&y));
                            assert_eq!(
                                g.any_in(x0, x1, y0, y1),
                                brute,
                                "case {case}: [{x0}, {x1}] x [{y0}, {y1}]"
                            );
                        }
                    }
                }
            }
        }
        // A group too large for a dense grid cannot tell, and says so.
        let g = PageGroup::new(10, vec![(0, 0, 0), (1000, 1000, 1)]);
        assert!(g.counts.is_empty() && g.any_in(5, 6, 5, 6));
    }

    /// A page's ids are kept as one id, a palette of up to 256 ids with an index per texel,
    /// or four bytes a texel beyond that, and read back as they were.
    #[test]
    fn a_page_keeps_its_ids_in_the_least_storage() {
        let read = |kept: &PageIds, ids: &[u32]| match kept {
            PageIds::One(id) => assert!(ids.iter().all(|t| t == id)),
            PageIds::Palette(palette, index) => {
                assert!(palette.len() <= 256);
                assert!(ids.iter().zip(index.iter()).all(|(&t, &i)| palette[usize::from(i)] == t));
            }
            PageIds::Ids => {}
        };
        for distinct in [1usize, 2, 16, 255, 256, 257, 1024] {
            // Runs of ids, the last ones repeating earlier ones: the palette's search by
            // hashing meets ids again after other ids.
            let ids: Vec<u32> =
                (0..PAGE_TEXELS).map(|k| ((k * distinct / PAGE_TEXELS) * 7919 % 100_003) as u32).collect();
            let ids: Vec<u32> =
                ids.iter().zip(ids.iter().rev()).map(|(&a, &b)| if a % 3 == 0 { b } else { a }).collect();
            let n = {
                let mut v = ids.clone();
                v.sort_unstable();
                v.dedup();
                v.len()
            };
            let kept = PageIds::of(&ids);
            match n {
                1 => assert!(matches!(kept, PageIds::One(_)), "{n}"),
                2..=256 => assert!(matches!(kept, PageIds::Palette(..)), "{n}"),
                _ => assert!(matches!(kept, PageIds::Ids), "{n}"),
            }
            read(&kept, &ids);
        }
        // EMPTY and ids next to MIXED are ids like any other.
        let ids: Vec<u32> = (0..PAGE_TEXELS).map(|k| if k % 5 == 0 { EMPTY } else { ABSENT - 1 }).collect();
        let kept = PageIds::of(&ids);
        assert!(matches!(kept, PageIds::Palette(ref p, _) if p.len() == 2));
        read(&kept, &ids);
    }

    #[test]
    fn an_image_that_covers_a_texel_centre_is_never_culled() {
        // Small triangles about page corners and edges at every level: wherever drawing the
        // page (as `build_pages` does) covers a texel, `ImageBox::at` must bin it there.
        let mut rng = hyrt_testkit::Rng(0x5eed);
        let mut rasterizer = Rasterizer::new();
        let mut target = Target::default();
        let (mut covered, mut culled) = (0, 0);
        for i in 0..20_000u32 {
            let level = (i % (u32::from(MAX_LEVEL) + 1)) as u8;
            let n = 1u32 << level;
            let face = (i % 6) as u8;
            let (px, py) = (rng.below(n as usize) as u32, rng.below(n as usize) as u32);
            let key = PageKey { level, face, py, px };
            let ax = CubeFace::ALL[usize::from(face)].axes();
            let (axis, sign, s, t) = ax;
            // A point on the page, then a triangle about it a texel or so across.
            let res = f64::from(PAGE << level);
            let texel = |u: f64| u / res * 2.0 - 1.0;
            let (u, v) = (
                f64::from(px * PAGE) + rng.f64() * f64::from(PAGE),
                f64::from(py * PAGE) + rng.f64() * f64::from(PAGE),
            );
            let dist = 0.5 + rng.f64() * 100.0;
            let size = [0.3, 1.0, 3.0][i as usize % 3] / res * 2.0;
            let mut vertex = || {
                let (a, b) = (texel(u) + (rng.f64() - 0.5) * size, -texel(v) + (rng.f64() - 0.5) * size);
                let mut d = DVec3::ZERO;
                d[axis] = f64::from(sign) * dist;
                (d[s], d[t]) = (a * dist, b * dist);
                d.as_vec3()
            };
            let tri = [vertex(), vertex(), vertex()];
            let e = tri.map(|p| p.as_dvec3());
            let near = 1e-3;
            rasterizer.rasterize_into(
                &[page_clip(tri, DVec3::ZERO, near, &key, ax)],
                &[0],
                PAGE,
                PAGE,
                &MAP_RASTER,
                &mut target,
            );
            let hits = target.id.contains(&0);
            let (lo, hi) = image_bounds(&e, ax);
            let at = ImageBox::of(lo, hi).at(level);
            let holds = at.is_some();
            assert!(holds || !hits, "triangle {i} at level {level} covers a texel but was culled: {tri:?}");
            // And the page it covers a texel of is among the pages it is binned to.
            if let (true, Some((x0, x1, y0, y1))) = (hits, at) {
                assert!(
                    (x0..=x1).contains(&px) && (y0..=y1).contains(&py),
                    "triangle {i}: {at:?} vs page ({px}, {py})"
                );
            }
            covered += u32::from(hits);
            culled += u32::from(!holds);
        }
        // The test means something: both kinds occur.
        println!("{covered} covering, {culled} culled");
        assert!(covered > 2_000 && culled > 2_000, "{covered} covering, {culled} culled");
    }

    #[test]
    fn edge_on_and_degenerate_triangles_are_unusable() {
        let l = DVec3::ZERO;
        let ok = [Vec3::new(-1.0, -1.0, 1.0), Vec3::new(1.0, -1.0, 1.0), Vec3::new(0.0, 1.0, 1.0)];
        assert!(usable(&ok, l).is_some());
        // The light in the triangle's plane (inside it, and outside it).
        assert!(
            usable(&[Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)], l)
                .is_none()
        );
        assert!(
            usable(&[Vec3::new(1.0, 1.0, 0.0), Vec3::new(2.0, 1.0, 0.0), Vec3::new(1.0, 2.0, 0.0)], l)
                .is_none()
        );
        // Just above the plane inside the triangle: a huge image, drawn.
        let above = ok.map(|v| v - Vec3::new(0.0, 0.0, 1.0 - 1e-4));
        assert!(usable(&above, l).is_some());
        assert!(usable(&[ok[0], ok[0], ok[1]], l).is_none());
        assert!(usable(&[ok[0], ok[1], Vec3::new(f32::NAN, 0.0, 1.0)], l).is_none());
        assert!(usable(&ok, DVec3::new(f64::INFINITY, 0.0, 0.0)).is_none());
    }
}
