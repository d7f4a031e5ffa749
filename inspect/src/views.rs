//! What the inspector draws, as pure functions from a frame's buffers to colour images (no
//! window, no egui context: unit-tested below).
//!
//! Colour conventions, shared by every view and its legend:
//! - occlusion maps: [`Decision::Lit`] yellow, [`Decision::Shadow`] blue, decided by a ray (undecided by the map)
//!   magenta, no decision needed (no hit, light behind the surface, mirror) near black, and with
//!   the visibility check the map decisions a ray contradicts in red;
//! - masks (borders, rays) are drawn over the frame's luminance, dimmed, so that the picture
//!   stays recognisable;
//! - heat maps (luminance error, rays per pixel) use the inferno scale, black = 0;
//! - depth maps use the viridis scale, near = dark blue, far = yellow, empty texels black.

use eframe::egui::{Color32, ColorImage};
use glam::Vec3;
use hyrt::{
    camera::CameraRays,
    film::{Film, display},
    metrics::luminance,
    render::shadows::BorderRay,
};
use hyrt_shadowmap::{
    LightMap,
    classify::{Classifier, Decision, Plane},
    vpl_map::VplMap,
};
use hyrt_tracer::RayCounts;

pub const LIT_COLOR: Color32 = Color32::from_rgb(250, 210, 80);
pub const SHADOW_COLOR: Color32 = Color32::from_rgb(45, 80, 170);
pub const UNDECIDED_COLOR: Color32 = Color32::from_rgb(235, 60, 225);
pub const NONE_COLOR: Color32 = Color32::from_rgb(22, 22, 26);
pub const WRONG_COLOR: Color32 = Color32::from_rgb(255, 30, 30);
pub const BORDER_COLOR: Color32 = Color32::from_rgb(255, 255, 255);
pub const HINT_COLOR: Color32 = Color32::from_rgb(60, 220, 90);
pub const TRAVERSAL_BLOCKED_COLOR: Color32 = Color32::from_rgb(255, 140, 20);
pub const TRAVERSAL_CLEAR_COLOR: Color32 = Color32::from_rgb(80, 200, 255);
/// Texels outside a paraboloid's disc, and faces that were not drawn.
pub const OUTSIDE_COLOR: Color32 = Color32::from_rgb(48, 48, 52);

/// The lower end of the luminance-error scale: errors below it are black.
pub const ERROR_FLOOR: f32 = 1e-3;

/// The film as displayed (exposure, clamp, sRGB), as `hyrt compare` and the PNGs see it.
pub fn film_image(film: &Film, exposure: f32) -> ColorImage {
    let pixels = film
        .pixels
        .iter()
        .map(|&p| {
            let d = display(p, exposure) * 255.0;
            Color32::from_rgb(d.x.round() as u8, d.y.round() as u8, d.z.round() as u8)
        })
        .collect();
    ColorImage::new([film.width as usize, film.height as usize], pixels)
}

/// Per pixel, the absolute difference of display luminance (sRGB values in [0, 1]): the
/// quantity whose mean square gives the PSNR.
pub fn luminance_error(a: &Film, b: &Film, exposure: f32) -> Vec<f32> {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .map(|(&p, &q)| (luminance(display(p, exposure)) - luminance(display(q, exposure))).abs() as f32)
        .collect()
}

/// Position of an error on the heat map's logarithmic scale: 0 at [`ERROR_FLOOR`] (and for
/// anything smaller), 1 at a luminance error of 1 (black against white), one third per decade.
pub fn error_scale(e: f32) -> f32 {
    if e <= ERROR_FLOOR || !e.is_finite() {
        return 0.0;
    }
    ((e.log10() - ERROR_FLOOR.log10()) / -ERROR_FLOOR.log10()).clamp(0.0, 1.0)
}

/// The luminance-error heat map: black where the images agree (to [`ERROR_FLOOR`]), inferno on a
/// log scale up to 1.
pub fn error_heat(err: &[f32], width: u32, height: u32) -> ColorImage {
    let pixels = err.iter().map(|&e| if e <= ERROR_FLOOR { Color32::BLACK } else { inferno(error_scale(e)) });
    ColorImage::new([width as usize, height as usize], pixels.collect())
}

/// The frame's display luminance, dimmed: the backdrop of the masks.
pub fn backdrop(film: &Film, exposure: f32) -> Vec<u8> {
    film.pixels.iter().map(|&p| (luminance(display(p, exposure)) * 90.0).round() as u8).collect()
}

fn gray(v: u8) -> Color32 {
    Color32::from_rgb(v, v, v)
}

/// A light's occlusion map: the final decision per pixel ([`Decision::Lit`] / [`Decision::Shadow`] / [`Decision::NotNeeded`]), with
/// the pixels a ray decided (`undecided`) in their own colour and, when given, the map
/// decisions a ray contradicts (`wrong`) in red.
pub fn occlusion_image(
    occ: &[Decision],
    undecided: &[bool],
    wrong: &[bool],
    width: u32,
    height: u32,
) -> ColorImage {
    let pixels = occ.iter().enumerate().map(|(i, &o)| {
        if wrong.get(i).copied().unwrap_or(false) {
            WRONG_COLOR
        } else if o == Decision::NotNeeded {
            NONE_COLOR
        } else if undecided.get(i).copied().unwrap_or(false) {
            UNDECIDED_COLOR
        } else if o == Decision::Shadow {
            SHADOW_COLOR
        } else {
            debug_assert_eq!(o, Decision::Lit);
            LIT_COLOR
        }
    });
    ColorImage::new([width as usize, height as usize], pixels.collect())
}

/// A mask in [`BORDER_COLOR`] over the backdrop.
pub fn mask_image(mask: &[bool], backdrop: &[u8], width: u32, height: u32) -> ColorImage {
    mask_image_in(mask, backdrop, width, height, BORDER_COLOR)
}

/// A mask in `colour` over the backdrop.
pub fn mask_image_in(mask: &[bool], backdrop: &[u8], width: u32, height: u32, colour: Color32) -> ColorImage {
    let pixels = backdrop
        .iter()
        .enumerate()
        .map(|(i, &b)| if mask.get(i).copied().unwrap_or(false) { colour } else { gray(b) });
    ColorImage::new([width as usize, height as usize], pixels.collect())
}

/// Where a light's selective shadow rays went: answered by the occluder hint (one triangle test),
/// or traversing the BVH and then blocked or reaching the light; the backdrop elsewhere.
pub fn ray_image(
    ray: &[BorderRay],
    occ: &[Decision],
    backdrop: &[u8],
    width: u32,
    height: u32,
) -> ColorImage {
    let pixels =
        backdrop.iter().enumerate().map(|(i, &b)| match ray.get(i).copied().unwrap_or(BorderRay::None) {
            BorderRay::Hint => HINT_COLOR,
            BorderRay::Traversal if occ.get(i) == Some(&Decision::Shadow) => TRAVERSAL_BLOCKED_COLOR,
            BorderRay::Traversal => TRAVERSAL_CLEAR_COLOR,
            _ => gray(b),
        });
    ColorImage::new([width as usize, height as usize], pixels.collect())
}

/// The kinds of rays shown as per-pixel heat maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayKindView {
    Primary,
    Shadow,
    ShadowTraversal,
    Specular,
    VplShadow,
    Total,
}

impl RayKindView {
    pub const ALL: [RayKindView; 6] = [
        RayKindView::Primary,
        RayKindView::Shadow,
        RayKindView::ShadowTraversal,
        RayKindView::Specular,
        RayKindView::VplShadow,
        RayKindView::Total,
    ];

    pub fn name(self) -> &'static str {
        match self {
            RayKindView::Primary => "primary",
            RayKindView::Shadow => "shadow",
            RayKindView::ShadowTraversal => "shadow traversals",
            RayKindView::Specular => "specular",
            RayKindView::VplShadow => "VPL shadow",
            RayKindView::Total => "total",
        }
    }

    pub fn count(self, c: &RayCounts) -> u64 {
        match self {
            RayKindView::Primary => c.primary,
            RayKindView::Shadow => c.shadow,
            RayKindView::ShadowTraversal => c.shadow_traversals(),
            RayKindView::Specular => c.specular,
            RayKindView::VplShadow => c.vpl_shadow,
            RayKindView::Total => c.total(),
        }
    }
}

/// Rays of one kind per pixel as a heat map (inferno, black = none, white-yellow = the image's
/// maximum), and that maximum.
pub fn ray_heat(rays: &[RayCounts], kind: RayKindView, width: u32, height: u32) -> (ColorImage, u64) {
    let max = rays.iter().map(|c| kind.count(c)).max().unwrap_or(0);
    let pixels = rays.iter().map(|c| {
        let n = kind.count(c);
        if n == 0 { Color32::BLACK } else { inferno(0.15 + 0.85 * n as f32 / max as f32) }
    });
    (ColorImage::new([width as usize, height as usize], pixels.collect()), max)
}

/// A light map's face as an image of at most `max_side` pixels a side (texels sampled at the
/// image pixels' centres), depth on a log viridis scale between `range` (near, far); `None` when
/// the face was not drawn. `planes`: the map's triangles' planes (a paged map's depths come
/// from them).
pub fn depth_face_image(
    map: &LightMap,
    planes: &[Plane],
    face: u8,
    max_side: u32,
    range: (f32, f32),
) -> Option<ColorImage> {
    if !map.faces_drawn().get(usize::from(face)).copied().unwrap_or(false) {
        return None;
    }
    if map.is_paged() {
        // Paged: each image pixel from the finest page drawn under it.
        let res = max_side.max(1);
        let at = |i: u32| (f64::from(i) + 0.5) / f64::from(res);
        return Some(depth_image(res, max_side, range, |x, y| {
            Some(paged_depth(map, planes, face, at(x), at(y)))
        }));
    }
    Some(depth_image(map.resolution(), max_side, range, |x, y| {
        map.texel_in_domain(face, x, y).then(|| map.depth(face, x, y))
    }))
}

/// A VPL's map as [`depth_face_image`] shows a light map's face.
pub fn vpl_map_image(map: &VplMap, max_side: u32, range: (f32, f32)) -> ColorImage {
    depth_image(map.resolution(), max_side, range, |x, y| map.in_domain(x, y).then(|| map.depth(x, y)))
}

/// An image of `depth(x, y)` (`None` outside the map's domain) at most `max_side` a side.
fn depth_image(
    res: u32,
    max_side: u32,
    range: (f32, f32),
    depth: impl Fn(u32, u32) -> Option<f32>,
) -> ColorImage {
    let side = res.min(max_side).max(1);
    let mut pixels = Vec::with_capacity((side * side) as usize);
    for y in 0..side {
        for x in 0..side {
            let d = depth(texel_of(x, side, res), texel_of(y, side, res));
            pixels.push(d.map_or(OUTSIDE_COLOR, |d| depth_color(d, range)));
        }
    }
    ColorImage::new([side as usize, side as usize], pixels)
}

/// The texel of a `res`-texel side under the centre of pixel `i` of a `side`-pixel image.
fn texel_of(i: u32, side: u32, res: u32) -> u32 {
    (((u64::from(i) * 2 + 1) * u64::from(res) / (2 * u64::from(side))) as u32).min(res - 1)
}

/// The depth a paged map shows at face position `(u, v)`: its finest drawn texel's there,
/// from the plane of the texel's triangle (paged maps store no depths).
fn paged_depth(map: &LightMap, planes: &[Plane], face: u8, u: f64, v: f64) -> f32 {
    let cls = Classifier { map, planes, bias: 0.0, point_error: 0.0, cutouts: &[] };
    map.finest_texel(face, u, v).map_or(f32::INFINITY, |(level, x, y)| cls.depth_at(level, face, x, y))
}

/// Nearest and farthest finite depths of the drawn faces, over the texels a `max_side` image
/// samples; `None` when nothing was drawn. `planes` as for [`depth_face_image`].
pub fn depth_range(map: &LightMap, planes: &[Plane], max_side: u32) -> Option<(f32, f32)> {
    let faces: Vec<u8> = (0..map.faces() as u8).filter(|&f| map.faces_drawn()[usize::from(f)]).collect();
    if map.is_paged() {
        let res = max_side.max(1);
        let at = |i: u32| (f64::from(i) + 0.5) / f64::from(res);
        return range_of(res, max_side, |x, y| {
            faces.iter().map(|&f| paged_depth(map, planes, f, at(x), at(y))).collect()
        });
    }
    range_of(map.resolution(), max_side, |x, y| faces.iter().map(|&f| map.depth(f, x, y)).collect())
}

/// [`depth_range`] of a VPL's plane map.
pub fn vpl_map_range(map: &VplMap, max_side: u32) -> Option<(f32, f32)> {
    range_of(map.resolution(), max_side, |x, y| vec![map.depth(x, y)])
}

fn range_of(res: u32, max_side: u32, depths: impl Fn(u32, u32) -> Vec<f32>) -> Option<(f32, f32)> {
    let side = res.min(max_side).max(1);
    let mut range: Option<(f32, f32)> = None;
    for y in 0..side {
        for x in 0..side {
            for d in depths(texel_of(x, side, res), texel_of(y, side, res)) {
                if d.is_finite() && d > 0.0 {
                    range = Some(range.map_or((d, d), |(lo, hi)| (lo.min(d), hi.max(d))));
                }
            }
        }
    }
    range
}

/// The colour of a depth on the log scale between `range`; black when empty (infinite).
pub fn depth_color(d: f32, (near, far): (f32, f32)) -> Color32 {
    if !d.is_finite() {
        return Color32::BLACK;
    }
    viridis(depth_scale(d, (near, far)))
}

/// Where `d` falls between `near` (0) and `far` (1) on a log scale.
pub fn depth_scale(d: f32, (near, far): (f32, f32)) -> f32 {
    if far <= near || near <= 0.0 {
        return 0.5;
    }
    ((d / near).ln() / (far / near).ln()).clamp(0.0, 1.0)
}

/// Film coordinates (pixel units, `(0, 0)` the image's top-left corner) of world point `p` seen
/// by `camera`, with its distance along the view axis; `None` behind the camera.
pub fn project(camera: &CameraRays, p: Vec3) -> Option<(f32, f32, f32)> {
    let d = p - camera.eye;
    let z = d.dot(camera.forward);
    if z <= 0.0 {
        return None;
    }
    let sx = d.dot(camera.right) / z * camera.inv_tan_x;
    let sy = d.dot(camera.up) / z * camera.inv_tan_y;
    let fx = (sx + 1.0) * 0.5 * camera.width as f32;
    let fy = (1.0 - sy) * 0.5 * camera.height as f32;
    Some((fx, fy, z))
}

fn lerp_table(table: &[[u8; 3]], t: f32) -> Color32 {
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 };
    let f = t * (table.len() - 1) as f32;
    let i = (f as usize).min(table.len() - 2);
    let u = f - i as f32;
    let c = |k: usize| table[i][k] as f32 * (1.0 - u) + table[i + 1][k] as f32 * u;
    Color32::from_rgb(c(0).round() as u8, c(1).round() as u8, c(2).round() as u8)
}

/// Matplotlib's inferno colour map (9 stops, linear in between): black, purple, red, yellow.
pub fn inferno(t: f32) -> Color32 {
    const T: [[u8; 3]; 9] = [
        [0, 0, 4],
        [31, 12, 72],
        [85, 15, 109],
        [136, 34, 106],
        [186, 54, 85],
        [227, 89, 51],
        [249, 140, 10],
        [249, 201, 50],
        [252, 255, 164],
    ];
    lerp_table(&T, t)
}

/// Matplotlib's viridis colour map (9 stops): dark blue, teal, green, yellow.
pub fn viridis(t: f32) -> Color32 {
    const T: [[u8; 3]; 9] = [
        [68, 1, 84],
        [71, 45, 123],
        [59, 82, 139],
        [44, 114, 142],
        [33, 145, 140],
        [40, 174, 128],
        [94, 201, 98],
        [173, 220, 48],
        [253, 231, 37],
    ];
    lerp_table(&T, t)
}

/// A horizontal legend strip of `width` pixels for a colour scale.
pub fn scale_strip(width: usize, height: usize, colour: impl Fn(f32) -> Color32) -> ColorImage {
    let row: Vec<Color32> = (0..width).map(|x| colour((x as f32 + 0.5) / width as f32)).collect();
    ColorImage::new([width, height], (0..height).flat_map(|_| row.iter().copied()).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use hyrt_shadowmap::{MapKind, MapOptions};

    fn film(pixels: Vec<Vec3>) -> Film {
        Film { width: pixels.len() as u32, height: 1, pixels }
    }

    #[test]
    fn film_image_is_the_png_display_transform() {
        let f = film(vec![Vec3::ZERO, Vec3::ONE, Vec3::new(0.5, 2.0, -1.0), Vec3::splat(f32::NAN)]);
        let img = film_image(&f, 1.0);
        let bytes = f.to_srgb8(1.0);
        for (i, p) in img.pixels.iter().enumerate() {
            assert_eq!([p.r(), p.g(), p.b(), p.a()], [bytes[3 * i], bytes[3 * i + 1], bytes[3 * i + 2], 255]);
        }
    }

    #[test]
    fn luminance_error_gives_the_psnr() {
        let a = film(vec![Vec3::ZERO, Vec3::splat(0.5), Vec3::ONE, Vec3::splat(0.2)]);
        let b = film(vec![Vec3::ZERO, Vec3::splat(0.25), Vec3::splat(0.9), Vec3::splat(0.2)]);
        let e = luminance_error(&a, &b, 1.0);
        assert_eq!((e[0], e[3]), (0.0, 0.0));
        assert!(e[1] > 0.0 && e[2] > 0.0);
        let mse = e.iter().map(|&v| f64::from(v) * f64::from(v)).sum::<f64>() / 4.0;
        let mut scene = hyrt::scene::Scene::default();
        scene.settings.exposure = 1.0;
        let psnr = hyrt::metrics::psnr(&scene, &a, &b).expect("same size");
        assert!((10.0 * (1.0 / mse).log10() - psnr).abs() < 1e-4, "{psnr}");
    }

    #[test]
    fn error_heat_is_black_where_equal_and_log_scaled() {
        assert_eq!(error_scale(0.0), 0.0);
        assert_eq!(error_scale(ERROR_FLOOR), 0.0);
        assert!((error_scale(0.01) - 1.0 / 3.0).abs() < 1e-5);
        assert!((error_scale(0.1) - 2.0 / 3.0).abs() < 1e-5);
        assert_eq!(error_scale(1.0), 1.0);
        assert_eq!(error_scale(f32::NAN), 0.0);
        let img = error_heat(&[0.0, 1e-4, 0.05, 1.0], 2, 2);
        assert_eq!(img.size, [2, 2]);
        assert_eq!(&img.pixels[..2], &[Color32::BLACK, Color32::BLACK]);
        assert_eq!(img.pixels[3], inferno(1.0));
        let brightness = |c: Color32| u32::from(c.r()) + u32::from(c.g()) + u32::from(c.b());
        assert!(brightness(img.pixels[3]) > brightness(img.pixels[2]));
        assert!(brightness(img.pixels[2]) > 0);
    }

    #[test]
    fn occlusion_colours_are_distinct_and_wrong_wins() {
        use Decision::{Lit as LIT, NotNeeded as NONE, Shadow as SHADOW};
        let occ = [LIT, SHADOW, NONE, LIT, SHADOW, LIT];
        let und = [false, false, false, true, true, false];
        let wrong = [false, false, false, false, false, true];
        let img = occlusion_image(&occ, &und, &wrong, 3, 2);
        assert_eq!(
            img.pixels,
            vec![LIT_COLOR, SHADOW_COLOR, NONE_COLOR, UNDECIDED_COLOR, UNDECIDED_COLOR, WRONG_COLOR]
        );
        // Without the check (empty buffers), nothing is red.
        let img = occlusion_image(&occ, &[], &[], 3, 2);
        assert_eq!(img.pixels[3], LIT_COLOR);
        assert_eq!(img.pixels[5], LIT_COLOR);
        let all = [LIT_COLOR, SHADOW_COLOR, UNDECIDED_COLOR, NONE_COLOR, WRONG_COLOR];
        for (i, a) in all.iter().enumerate() {
            assert!(all[i + 1..].iter().all(|b| a != b));
        }
    }

    #[test]
    fn masks_and_rays_over_the_backdrop() {
        let f = film(vec![Vec3::ONE, Vec3::ZERO, Vec3::ONE, Vec3::ONE]);
        let back = backdrop(&f, 1.0);
        assert_eq!(back, vec![90, 0, 90, 90]);
        let m = mask_image(&[true, false, false, false], &back, 4, 1);
        assert_eq!(m.pixels, vec![BORDER_COLOR, gray(0), gray(90), gray(90)]);
        let m = mask_image_in(&[false, true], &back[..2], 2, 1, WRONG_COLOR);
        assert_eq!(m.pixels, vec![gray(90), WRONG_COLOR]);
        use Decision::{Lit as LIT, Shadow as SHADOW};
        let occ = [SHADOW, LIT, SHADOW, LIT];
        let r = ray_image(
            &[BorderRay::Hint, BorderRay::Traversal, BorderRay::Traversal, BorderRay::None],
            &occ,
            &back,
            4,
            1,
        );
        assert_eq!(r.pixels, vec![HINT_COLOR, TRAVERSAL_CLEAR_COLOR, TRAVERSAL_BLOCKED_COLOR, gray(90)]);
        // Without kept ray outcomes: the backdrop alone.
        assert_eq!(ray_image(&[], &occ, &back, 4, 1).pixels[0], gray(90));
    }

    #[test]
    fn ray_heat_scales_to_the_maximum() {
        let c = |primary, shadow, hints| RayCounts {
            primary,
            shadow,
            shadow_hint_hits: hints,
            ..Default::default()
        };
        let rays = [c(1, 0, 0), c(1, 2, 1), c(1, 4, 0), c(0, 0, 0)];
        let (img, max) = ray_heat(&rays, RayKindView::Shadow, 2, 2);
        assert_eq!(max, 4);
        assert_eq!(img.pixels[0], Color32::BLACK);
        assert_eq!(img.pixels[2], inferno(1.0));
        let (_, max) = ray_heat(&rays, RayKindView::ShadowTraversal, 2, 2);
        assert_eq!(max, 4);
        let (img, max) = ray_heat(&rays, RayKindView::Total, 2, 2);
        assert_eq!(max, 5);
        assert_eq!(img.pixels[3], Color32::BLACK);
        let (img, max) = ray_heat(&rays, RayKindView::Specular, 2, 2);
        assert_eq!(max, 0);
        assert!(img.pixels.iter().all(|&p| p == Color32::BLACK));
    }

    /// A wall in front of a light: the face looking at it is drawn, its depth grows from the
    /// centre (straight at the wall) to the edges; the face looking away is empty.
    #[test]
    fn depth_maps_are_coloured_near_to_far() {
        let s = 10.0;
        let tris = vec![
            [Vec3::new(-s, -s, -1.0), Vec3::new(s, -s, -1.0), Vec3::new(s, s, -1.0)],
            [Vec3::new(-s, -s, -1.0), Vec3::new(s, s, -1.0), Vec3::new(-s, s, -1.0)],
        ];
        for kind in [MapKind::Cube, MapKind::Paraboloid] {
            let opts = MapOptions { kind, resolution: 64, ..MapOptions::default() };
            let nf = LightMap::face_count(kind);
            let map = LightMap::build(&tris, Vec3::ZERO, &opts, &vec![true; nf]);
            let range = depth_range(&map, &[], 32).expect("wall drawn");
            assert!((range.0 - 1.0).abs() < 0.05, "{kind:?} {range:?}");
            assert!(range.1 > 2.0, "{kind:?} {range:?}");
            let front = map.coord(Vec3::NEG_Z).face;
            let img = depth_face_image(&map, &[], front, 32, range).expect("drawn");
            assert_eq!(img.size, [32, 32]);
            // The centre looks straight at the wall: the nearest texels.
            let centre = img.pixels[16 * 32 + 16];
            let t = texel_of(16, 32, 64);
            assert_eq!(t, 33);
            assert_eq!(centre, depth_color(map.depth(front, t, t), range));
            assert!(depth_scale(map.depth(front, 32, 32), range) < 0.05);
            assert!(depth_scale(map.depth(front, 0, 0), range) > 0.1);
            // The face looking away is empty: black (paraboloid: grey outside its disc).
            let back = map.coord(Vec3::Z).face;
            assert_ne!(back, front);
            let img = depth_face_image(&map, &[], back, 32, range).expect("drawn");
            assert_eq!(img.pixels[16 * 32 + 16], Color32::BLACK);
            let corner = if kind == MapKind::Cube { Color32::BLACK } else { OUTSIDE_COLOR };
            assert_eq!(img.pixels[0], corner);
        }
        // A face not drawn has no image.
        let opts = MapOptions { resolution: 16, ..MapOptions::default() };
        let mut faces = vec![false; 6];
        faces[LightMap::face_of(MapKind::Cube, Vec3::NEG_Z) as usize] = true;
        let map = LightMap::build(&tris, Vec3::ZERO, &opts, &faces);
        let back = LightMap::face_of(MapKind::Cube, Vec3::Z);
        assert!(depth_face_image(&map, &[], back, 16, (1.0, 2.0)).is_none());
        assert!(
            depth_face_image(&map, &[], LightMap::face_of(MapKind::Cube, Vec3::NEG_Z), 16, (1.0, 2.0))
                .is_some()
        );
    }

    #[test]
    fn texel_sampling_covers_the_map() {
        assert_eq!(texel_of(0, 4, 4), 0);
        assert_eq!(texel_of(3, 4, 4), 3);
        assert_eq!(texel_of(0, 2, 2048), 512);
        assert_eq!(texel_of(1, 2, 2048), 1536);
        assert_eq!(texel_of(255, 256, 2048), 2044);
    }

    #[test]
    fn projection_inverts_the_camera_rays() {
        let cam =
            hyrt::scene::Camera::look_at(Vec3::new(0.0, 1.0, 5.0), Vec3::new(0.0, 1.0, 0.0), Vec3::Y, 40.0);
        let rays = CameraRays::new(&cam, 96, 72);
        for (x, y) in [(0, 0), (95, 71), (10, 60), (48, 36)] {
            let p = rays.eye + rays.direction(x, y) * 3.0;
            let (fx, fy, z) = project(&rays, p).expect("in front");
            assert!(
                (fx - (x as f32 + 0.5)).abs() < 1e-3 && (fy - (y as f32 + 0.5)).abs() < 1e-3,
                "{fx} {fy}"
            );
            assert!((z - 3.0).abs() < 1e-4);
        }
        assert!(project(&rays, Vec3::new(0.0, 1.0, 6.0)).is_none());
    }

    #[test]
    fn colour_scales_run_dark_to_bright() {
        let l = |c: Color32| luminance(Vec3::new(c.r() as f32, c.g() as f32, c.b() as f32));
        for scale in [inferno, viridis] {
            let steps: Vec<f64> = (0..=10).map(|i| l(scale(i as f32 / 10.0))).collect();
            assert!(steps.windows(2).all(|w| w[1] > w[0]), "{steps:?}");
            assert_eq!(scale(-1.0), scale(0.0));
            assert_eq!(scale(2.0), scale(1.0));
            assert_eq!(scale(f32::NAN), scale(0.0));
        }
        let strip = scale_strip(10, 2, inferno);
        assert_eq!(strip.size, [10, 2]);
        assert_eq!(strip.pixels[0], strip.pixels[10]);
    }
}
