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
//! `near / depth * sqrt(1 + s^2 + t^2)` with `(s, t)` the centre's face coordinates.
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

/// Relative depth window within which two surfaces are a tie, won by the smaller id: the
/// tracer's `2^-16`, so that coplanar duplicates resolve to the same triangle as in ray casting.
pub const DEPTH_TIE: f32 = 1.0 / 65536.0;

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
    pub x: f32,
    pub y: f32,
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

/// One face's texels (empty when not drawn).
#[derive(Clone, Debug, Default)]
struct Face {
    id: Vec<u32>,
    dist: Vec<f32>,
    /// Per [`REGION`]-square block of texels, row-major: the one triangle its texels see
    /// ([`EMPTY`] if none), or [`MIXED`] (see [`LightMap::region_id`]).
    region: Vec<u32>,
    /// The same by group of triangles ([`LightMap::build_grouped`]; empty without groups).
    region_group: Vec<u32>,
}

/// Side of the texel blocks that [`LightMap::region_id`] summarises.
///
/// Why: most pixels of a frame see, in every light's map, only their own triangle around them
/// (a wall, a floor, far from any shadow). A tile of such pixels is decided by asking whether
/// one triangle covers the map region under the tile: a few summary blocks, instead of four
/// texels per pixel. 8 keeps the summary at 1/64 of the ids and a tile's region within a few
/// blocks at the resolutions in use.
const REGION: u32 = 8;

/// [`Face::region`]: a block that sees two or more triangles.
const MIXED: u32 = EMPTY - 1;

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
/// per light (a gigabyte on the Cornell box), and huge pages for all of it made the kernel
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

/// The region summaries of a face's ids in [`BLOCK`] order, in one pass: by triangle
/// ([`Face::region`]) and by `groups[id]` ([`Face::region_group`], empty if `groups` is).
fn summarise(ids: &[u32], res: u32, groups: &[u32]) -> (Vec<u32>, Vec<u32>) {
    if ids.is_empty() {
        return (Vec::new(), Vec::new());
    }
    let blocks = res.div_ceil(REGION) as usize;
    let per = (REGION / BLOCK) as usize;
    let blocks_x = res.div_ceil(BLOCK) as usize;
    let cell = (BLOCK * BLOCK) as usize;
    // One id seen, EMPTY, or MIXED once a second one shows up.
    let see = |v: &mut u32, id: u32| {
        if id != EMPTY && id != *v {
            *v = if *v == EMPTY { id } else { MIXED };
        }
    };
    let mut both = vec![[EMPTY; 2]; blocks * blocks];
    both.par_chunks_mut(blocks).enumerate().for_each(|(ry, row)| {
        for (rx, [v, g]) in row.iter_mut().enumerate() {
            for by in ry * per..((ry + 1) * per).min(blocks_x) {
                let first = (by * blocks_x + rx * per) * cell;
                let last = (by * blocks_x + ((rx + 1) * per).min(blocks_x)) * cell;
                for &id in &ids[first..last] {
                    see(v, id);
                    if !groups.is_empty() {
                        see(g, groups.get(id as usize).copied().unwrap_or(id));
                    }
                }
            }
        }
    });
    let by_id = both.iter().map(|b| b[0]).collect();
    let by_group = if groups.is_empty() { Vec::new() } else { both.iter().map(|b| b[1]).collect() };
    (by_id, by_group)
}

/// Side of the square blocks texels are stored in: 4x4 ids are one 64-byte cache line.
///
/// Why: classifying the pixels of an image looks up, per pixel, the texel under it and its 2x2
/// neighbourhood; neighbouring pixels fall on neighbouring texels in both directions of the map,
/// and in row-major storage every step across map rows is a new cache line (of a 16 MB face at
/// 2048^2). Measured: the texel loads were 40 % of the classification time.
const BLOCK: u32 = 4;

/// Storage index of texel `(x, y)` of a `res`-square face in [`BLOCK`]-square blocks, the blocks
/// row-major, the texels of a block row-major.
#[inline]
fn texel_index(res: u32, x: u32, y: u32) -> usize {
    let blocks_x = res.div_ceil(BLOCK) as usize;
    let (bx, by) = ((x / BLOCK) as usize, (y / BLOCK) as usize);
    (by * blocks_x + bx) * (BLOCK * BLOCK) as usize + ((y % BLOCK) * BLOCK + x % BLOCK) as usize
}

/// A light's depth map: 6 cube faces or 2 paraboloid hemispheres (or 1 hemisphere, for VPLs).
#[derive(Clone, Debug)]
pub struct LightMap {
    layout: Layout,
    resolution: u32,
    light: Vec3,
    near: f32,
    drawn: Vec<bool>,
    faces: Vec<Face>,
    triangles_drawn: u64,
    /// Faces rasterized over the map's life, merges included ([`LightMap::faces_rasterized`]).
    faces_rasterized: u32,
}

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
        let mut map = LightMap {
            layout,
            resolution,
            light,
            near,
            drawn,
            faces: Vec::with_capacity(count),
            triangles_drawn: 0,
            faces_rasterized: 0,
        };

        let ropts = RasterOptions {
            reversed_z: true,
            barycentrics: false,
            cull_backfaces: false,
            depth_tie: DEPTH_TIE,
            ..RasterOptions::default()
        };
        let mut rasterizer = Rasterizer::new();
        let texels = resolution as usize * resolution as usize;
        let mut target = Target {
            depth: reserved_huge(if map.drawn.iter().any(|&d| d) { texels } else { 0 }),
            id: reserved_huge(if map.drawn.iter().any(|&d| d) { texels } else { 0 }),
            ..Target::default()
        };
        let mut cube = if layout == Layout::Cube {
            cube_triangles(tris, &valid, light, near, &map.drawn)
        } else {
            vec![]
        }
        .into_iter();
        for f in 0..count {
            let cube_face = cube.next();
            if !map.drawn[f] {
                map.faces.push(Face::default());
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
            rasterizer.rasterize_into(&clip, &ids, resolution, resolution, &ropts, &mut target);
            // The target's buffers stay with it for the next face.
            let face = map.finish_face(&target.id, &target.depth, groups);
            map.faces.push(face);
        }
        map
    }

    /// The stored face of the rasterizer's row-major ids and reversed-Z depths, in one pass:
    /// depths turned into distances, the texels outside a paraboloid's disc cleared, both
    /// stored in [`BLOCK`] order (padded with [`EMPTY`] and infinity); then the region summary
    /// ([`Face::region`]). One pass, not one per step: each of them read and wrote the whole
    /// face, and fresh buffers for each cost page faults of their own.
    ///
    /// In `f32` (so that it vectorises): `near / depth` and the square root are correctly
    /// rounded, a few ulps in all (`~3e-7` relative) on top of the depth's own rounding.
    fn finish_face(&self, ids: &[u32], depth: &[f32], groups: &[u32]) -> Face {
        let res = self.resolution as usize;
        let b = BLOCK as usize;
        let blocks_x = res.div_ceil(b);
        let near = self.near;
        let inv = 2.0 / self.resolution as f32;
        // Squared face coordinate of texel centre i (the same for rows: t = -s).
        let sq: Vec<f32> = (0..res).map(|i| ((i as f32 + 0.5) * inv - 1.0).powi(2)).collect();
        let cube = self.layout == Layout::Cube;
        let res32 = self.resolution;
        // Zeroed allocations are mapped lazily (and not advised huge: `advise_huge`): every
        // element is written below, once.
        let n = blocks_x * blocks_x * b * b;
        let (mut id, mut dist) = (vec![0u32; n], vec![0f32; n]);
        let band = blocks_x * b * b;
        id.par_chunks_mut(band).zip(dist.par_chunks_mut(band)).enumerate().for_each(
            |(by, (id_out, dist_out))| {
                for dy in 0..b {
                    let y = by * b + dy;
                    let (x0, x1) = if y >= res {
                        (0, 0)
                    } else if cube {
                        (0, res32)
                    } else {
                        disc_span(res32, y as u32)
                    };
                    for x in 0..blocks_x * b {
                        let k = (x / b) * b * b + dy * b + x % b;
                        let inside = (x0..x1).contains(&(x as u32));
                        let d = if inside { depth[y * res + x] } else { 0.0 };
                        // Reversed-Z: empty texels hold depth 0, drawn ones near / w >= 2^-21.
                        (id_out[k], dist_out[k]) = if d > 0.0 {
                            // Cube: w = near / depth along the axis; the centre's direction
                            // (1, s, t) is sqrt(1 + s^2 + t^2) times longer than its axis
                            // component.
                            let r = if cube { near / d * ((1.0 + sq[y]) + sq[x]).sqrt() } else { near / d };
                            (ids[y * res + x], r)
                        } else {
                            (EMPTY, f32::INFINITY)
                        };
                    }
                }
            },
        );
        let (region, region_group) = summarise(&id, self.resolution, groups);
        Face { id, dist, region, region_group }
    }

    /// Where direction `dir` (non-zero, from the light) falls.
    ///
    /// Coordinates are clamped into `[0, resolution)` (a direction on a cube edge or corner goes
    /// to the face [`cube_lookup`] picks, at its last texel), and for paraboloids into a texel
    /// whose centre is in the disc (module docs). NaN gives some in-range texel.
    #[inline]
    pub fn coord(&self, dir: Vec3) -> MapCoord {
        if self.layout == Layout::Cube {
            // In f32: classification calls this for every pixel and light, and the face
            // coordinates are exact to an ulp either way (one division each).
            let (face, st) = cube_lookup(dir);
            let half = self.resolution as f32 * 0.5;
            let lim = (self.resolution as f32).next_down();
            let clamp = |v: f32| v.max(0.0).min(lim);
            return MapCoord {
                face: face.index(),
                x: clamp((st.x + 1.0) * half),
                y: clamp((1.0 - st.y) * half),
            };
        }
        let d = dir.as_dvec3();
        let half = f64::from(self.resolution) * 0.5;
        let face = match self.layout {
            Layout::Dual => Self::face_of(MapKind::Paraboloid, dir),
            _ => 0,
        };
        let m = self.layout.frame(face).to_map(d);
        // Directions behind a single hemisphere go to its rim.
        let z = m.z.max(0.0);
        let w = (m.x * m.x + m.y * m.y + z * z).sqrt() + z;
        let (s, t) = (m.x / w, m.y / w);
        let (x, y) = self.clamp_to_domain((s + 1.0) * half, (1.0 - t) * half);
        MapCoord { face, x, y }
    }

    /// Continuous coordinates clamped into `[0, resolution)` and, for paraboloids, into a texel
    /// of the domain: the nearest one (by distance to its square) if the point's own is not.
    fn clamp_to_domain(&self, x: f64, y: f64) -> (f32, f32) {
        let res = self.resolution;
        // The largest f32 below `res` (`res` is at most 2^16, exact in f32): `next_down`
        // without its special cases.
        let lim = f32::from_bits((res as f32).to_bits() - 1);
        // `max` before `min` and NaN -> 0: f32::max returns the non-NaN operand.
        let (x, y) = ((x as f32).max(0.0).min(lim), (y as f32).max(0.0).min(lim));
        if self.layout == Layout::Cube {
            return (x, y);
        }
        let (ix, iy) = (x as u32, y as u32);
        if disc_contains(res, ix, iy) {
            return (x, y);
        }
        let (jx, jy) = nearest_in_disc(res, x, y).unwrap_or((res / 2, res / 2));
        let into = |v: f32, j: u32| v.max(j as f32).min(((j + 1) as f32).next_down());
        (into(x, jx), into(y, jy))
    }

    /// The unit direction (from the light) of the continuous texel position `(x, y)` on `face`.
    ///
    /// A face number out of range is taken as the last face.
    pub fn texel_dir(&self, face: u8, x: f32, y: f32) -> Vec3 {
        let inv = 2.0 / f64::from(self.resolution);
        let (s, t) = (f64::from(x) * inv - 1.0, 1.0 - f64::from(y) * inv);
        let d = match self.layout {
            Layout::Cube => {
                let (axis, sign, si, ti) = CubeFace::ALL[usize::from(face.min(5))].axes();
                let mut d = DVec3::ZERO;
                d[axis] = f64::from(sign);
                d[si] = s;
                d[ti] = t;
                d
            }
            Layout::Dual | Layout::Hemisphere(_) => {
                // Inverse of (u, v) = (x, y) / (1 + z) on the unit sphere (crate::paraboloid).
                let r2 = s * s + t * t;
                let z = (1.0 - r2) / (1.0 + r2);
                self.layout.frame(face).to_world(DVec3::new(s * (1.0 + z), t * (1.0 + z), z))
            }
        };
        d.normalize().as_vec3()
    }

    /// The face index if valid, texel index within it.
    #[inline]
    fn texel(&self, face: u8, ix: u32, iy: u32) -> Option<(&Face, usize)> {
        let res = self.resolution;
        let f = self.faces.get(usize::from(face))?;
        (ix < res && iy < res && !f.id.is_empty()).then(|| (f, texel_index(res, ix, iy)))
    }

    /// The ids of `face` in storage order (texel `(ix, iy)` at [`LightMap::texel_index`]; empty
    /// when the face was not drawn, or does not exist): for lookups in bulk.
    #[inline]
    pub fn face_ids(&self, face: u8) -> &[u32] {
        self.faces.get(usize::from(face)).map_or(&[], |f| &f.id)
    }

    /// The one triangle that the texels `[x0, x1] x [y0, y1]` of `face` see: `Some(EMPTY)` if
    /// none, `Some(id)` if every texel holds `id` or nothing, `None` if two triangles or more
    /// may be seen (the answer is conservative: it reads whole `REGION` blocks). A face that
    /// was not drawn sees nothing, as its texel lookups say.
    pub fn region_id(&self, face: u8, x0: u32, y0: u32, x1: u32, y1: u32) -> Option<u32> {
        let f = self.faces.get(usize::from(face))?;
        if f.region.is_empty() {
            return Some(EMPTY);
        }
        self.region_in(&f.region, x0, y0, x1, y1)
    }

    /// [`LightMap::region_id`] by group of triangles (`Some(g)`: every texel holds a triangle
    /// of group `g`, or nothing), for a map made by [`LightMap::build_grouped`]; `None`
    /// (cannot tell) for one made without groups.
    pub fn region_group(&self, face: u8, x0: u32, y0: u32, x1: u32, y1: u32) -> Option<u32> {
        let f = self.faces.get(usize::from(face))?;
        if f.region.is_empty() {
            return Some(EMPTY);
        }
        if f.region_group.is_empty() {
            return None;
        }
        self.region_in(&f.region_group, x0, y0, x1, y1)
    }

    fn region_in(&self, region: &[u32], x0: u32, y0: u32, x1: u32, y1: u32) -> Option<u32> {
        let blocks = self.resolution.div_ceil(REGION) as usize;
        let (bx0, bx1) = ((x0 / REGION) as usize, (x1.min(self.resolution - 1) / REGION) as usize);
        let mut seen = EMPTY;
        for by in (y0 / REGION) as usize..=(y1.min(self.resolution - 1) / REGION) as usize {
            for &v in &region[by * blocks + bx0..=by * blocks + bx1] {
                if v == MIXED || (v != EMPTY && seen != EMPTY && v != seen) {
                    return None;
                }
                if v != EMPTY {
                    seen = v;
                }
            }
        }
        Some(seen)
    }

    /// Where texel `(ix, iy)` (both below the resolution) is stored in [`LightMap::face_ids`].
    #[inline]
    pub fn texel_index(&self, ix: u32, iy: u32) -> usize {
        texel_index(self.resolution, ix, iy)
    }

    /// Id of the closest triangle at texel `(ix, iy)` of `face`, or [`EMPTY`].
    #[inline]
    pub fn id(&self, face: u8, ix: u32, iy: u32) -> u32 {
        self.texel(face, ix, iy).map_or(EMPTY, |(f, i)| f.id[i])
    }

    /// Distance from the light to the stored surface in the direction of the texel's centre
    /// (`f32::INFINITY` when empty).
    #[inline]
    pub fn depth(&self, face: u8, ix: u32, iy: u32) -> f32 {
        self.texel(face, ix, iy).map_or(f32::INFINITY, |(f, i)| f.dist[i])
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
        let inv = 2.0 / f64::from(self.resolution);
        let (s, t) = (f64::from(c.x) * inv - 1.0, 1.0 - f64::from(c.y) * inv);
        let (s2, t2) = (s * s, t * t);
        let per_unit = match self.layout {
            Layout::Cube => (1.0 + s2.max(t2)).sqrt() / (1.0 + s2 + t2),
            _ => 2.0 / (1.0 + s2 + t2),
        };
        (per_unit * inv) as f32
    }

    /// Whether a texel centre lies in the region the face covers (always for cube faces; inside
    /// the unit disc for paraboloids; texels outside it are never drawn).
    #[inline]
    pub fn texel_in_domain(&self, face: u8, ix: u32, iy: u32) -> bool {
        let res = self.resolution;
        usize::from(face) < self.faces.len()
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

    /// Texels per side of every face (the requested resolution clamped to `[1, MAX_TARGET_DIM]`).
    #[inline]
    pub fn resolution(&self) -> u32 {
        self.resolution
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
        self.faces.len()
    }

    /// Which faces were drawn.
    pub fn faces_drawn(&self) -> &[bool] {
        &self.drawn
    }

    /// Triangles rasterized, after culling per face and tessellation (summed over faces).
    pub fn triangles_drawn(&self) -> u64 {
        self.triangles_drawn
    }

    /// Faces rasterized to make this map, [`LightMap::merge`]s included: equal to the number of
    /// faces drawn when no face was ever drawn twice.
    pub fn faces_rasterized(&self) -> u32 {
        self.faces_rasterized
    }

    /// Takes the faces `other` drew and `self` did not, so that a map can gain faces (a camera
    /// that moved and sees more of the light's surroundings) without drawing its faces again.
    /// A face is the same whichever other faces a build draws (the near distance depends on
    /// the triangles and the light alone), so the result equals one build of all the faces.
    ///
    /// # Panics
    /// If `other` is not a map of the same light, layout and resolution.
    pub fn merge(&mut self, other: LightMap) {
        assert!(
            self.layout == other.layout && self.resolution == other.resolution && self.light == other.light,
            "merging maps of different lights or parameterisations"
        );
        if !self.drawn.iter().any(|&d| d) {
            self.near = other.near;
        }
        let used = other.drawn.iter().filter(|&&d| d).count() as u32;
        for (f, face) in other.faces.into_iter().enumerate() {
            if other.drawn[f] && !self.drawn[f] {
                self.faces[f] = face;
                self.drawn[f] = true;
            }
        }
        self.triangles_drawn += other.triangles_drawn;
        self.faces_rasterized += used;
    }

    /// Bytes of texel memory.
    pub fn memory_bytes(&self) -> usize {
        self.faces
            .iter()
            .map(|f| (f.id.len() + f.dist.len() + f.region.len() + f.region_group.len()) * 4)
            .sum()
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
    let far = d.iter().map(|x| x.length()).fold(0.0, f64::max);
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
    let near_vertex = d.iter().map(|x| x.length()).fold(f64::INFINITY, f64::min);
    let rel = 2f64.powi(-20);
    let edge_on_rel = |h: f64| h > near_vertex * rel || h > dist_triangle(d[0], d[1], d[2]) * rel;
    (h > edge_on_abs && edge_on_rel(h)).then_some(far)
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
                    let all = |f: &dyn Fn(&Vec4) -> bool| v.iter().all(f);
                    if all(&|c| c.w < near)
                        || all(&|c| c.x > c.w)
                        || all(&|c| c.x < -c.w)
                        || all(&|c| c.y > c.w)
                        || all(&|c| c.y < -c.w)
                    {
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
