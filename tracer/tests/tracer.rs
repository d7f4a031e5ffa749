//! Tracer correctness: watertightness, tie-breaking, self-intersection, scale, bad input.

use glam::{Vec3, vec3};
use hyrt_tracer::{Ray, RayCounts, RayKind, Tracer, offset::hit_point, spawn_ray, spawn_ray_to};

/// An n x n grid of quads in the plane z = 0 over [0, n]^2, two triangles each.
fn grid(n: usize) -> Vec<[Vec3; 3]> {
    let mut t = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (i as f32, j as f32);
            let a = vec3(x, y, 0.0);
            let b = vec3(x + 1.0, y, 0.0);
            let c = vec3(x + 1.0, y + 1.0, 0.0);
            let d = vec3(x, y + 1.0, 0.0);
            t.push([a, b, c]);
            t.push([a, c, d]);
        }
    }
    t
}

#[test]
fn rays_through_shared_edges_and_vertices_never_miss() {
    let tris = grid(8);
    let tracer = Tracer::build(&tris);
    let mut counts = RayCounts::default();
    let mut misses = 0;
    let mut total = 0;
    // Points on every grid line (shared edges), every vertex, and every diagonal, from
    // oblique directions so the edges are not axis-aligned in the ray's frame.
    // Interior points only: the outer boundary is not a shared edge.
    for k in 1..64 {
        for l in 1..8 {
            let s = k as f32 / 8.0;
            let l = l as f32;
            for target in [vec3(s, l, 0.0), vec3(l, s, 0.0), vec3(s, s, 0.0)] {
                for dir in [vec3(0.3, 0.7, -1.0), vec3(-0.11, 0.05, -1.0), vec3(0.0, 0.0, -1.0)] {
                    let dir = dir.normalize();
                    let ray = Ray::new(target - dir * 10.0, dir, f32::INFINITY);
                    total += 1;
                    if tracer.closest_hit(&ray, RayKind::Primary, &mut counts).is_none() {
                        misses += 1;
                    }
                }
            }
        }
    }
    assert_eq!(misses, 0, "{misses} of {total} rays slipped through shared edges");
    assert_eq!(counts.primary, total);
}

#[test]
fn ties_at_equal_distance_go_to_the_smaller_id() {
    let a = [vec3(-1.0, -1.0, 0.0), vec3(1.0, -1.0, 0.0), vec3(0.0, 1.0, 0.0)];
    let b = [vec3(-2.0, -1.0, 0.0), vec3(2.0, -1.0, 0.0), vec3(0.0, 2.0, 0.0)];
    let mut counts = RayCounts::default();
    let ray = Ray::new(vec3(0.1, 0.0, 5.0), vec3(0.0, 0.0, -1.0), f32::INFINITY);
    // Many copies so the two coplanar triangles land in different leaves and orders.
    for order in [vec![a, b], vec![b, a]] {
        let mut tris = order.clone();
        tris.extend(grid(6).into_iter().map(|t| t.map(|p| p + vec3(20.0, 0.0, 0.0))));
        let hit = Tracer::build(&tris).closest_hit(&ray, RayKind::Primary, &mut counts).unwrap();
        assert_eq!(hit.tri, 0, "tie must go to triangle id 0");
    }
}

#[test]
fn reported_distance_and_barycentrics_match_the_geometry() {
    let tri = [vec3(0.0, 0.0, -3.0), vec3(2.0, 0.0, -3.0), vec3(0.0, 2.0, -3.0)];
    let tracer = Tracer::build(&[tri]);
    let ray = Ray::new(vec3(0.5, 0.25, 1.0), vec3(0.0, 0.0, -1.0), f32::INFINITY);
    let h = tracer.closest_hit(&ray, RayKind::Primary, &mut RayCounts::default()).unwrap();
    assert!((h.t - 4.0).abs() <= 4.0 * 1e-6, "t = {}", h.t);
    let (p, _) = hit_point(&tri, h.bary);
    assert!((p - vec3(0.5, 0.25, -3.0)).length() < 1e-6, "p = {p}");
    // tmax excludes hits at or beyond it.
    let short = Ray { tmax: 3.9, ..ray };
    assert!(!tracer.occluded(&short, RayKind::Shadow, &mut RayCounts::default()));
    assert!(tracer.occluded(&Ray { tmax: 4.1, ..ray }, RayKind::Shadow, &mut RayCounts::default()));
}

/// Rays leaving a surface (reflection and shadow rays at grazing angles) must not hit the
/// surface they leave, at any scale: zero self-hits over many points.
#[test]
fn spawned_rays_never_hit_their_own_surface_at_any_scale() {
    for scale in [1e-4f32, 1e-2, 1.0, 1e2, 1e4] {
        // A tilted, finely tessellated plane far from the origin (large coordinates are
        // where fixed epsilons fail).
        let base = grid(16);
        let offset = vec3(3.0e3, -2.0e3, 1.0e3) * scale;
        let rot = glam::Quat::from_euler(glam::EulerRot::XYZ, 0.3, -0.2, 0.1);
        let tris: Vec<[Vec3; 3]> = base.iter().map(|t| t.map(|p| rot * (p * scale) + offset)).collect();
        let tracer = Tracer::build(&tris);
        let n = rot * Vec3::Z;
        let mut counts = RayCounts::default();
        let mut self_hits = 0;
        for (i, tri) in tris.iter().enumerate().step_by(3) {
            for b in [[0.2f32, 0.3, 0.5], [0.9, 0.05, 0.05], [1.0 / 3.0; 3]] {
                let (p, err) = hit_point(tri, b);
                for d in [n + rot * vec3(50.0, 0.0, 0.0), n + rot * vec3(-7.0, 3.0, 0.0), n] {
                    let d = d.normalize();
                    let r = spawn_ray(p, err, n, d);
                    if tracer.occluded(&r, RayKind::Specular, &mut counts) {
                        self_hits += 1;
                    }
                    // The same from the back side.
                    let r = spawn_ray(p, err, n, -d);
                    if tracer.occluded(&r, RayKind::Specular, &mut counts) {
                        self_hits += 1;
                    }
                }
                // A shadow ray to a light at grazing elevation.
                let light = p + (rot * vec3(1.0, 0.0, 0.0) * 100.0 + n * 0.5) * scale;
                if tracer.occluded(&spawn_ray_to(p, err, n, light), RayKind::Shadow, &mut counts) {
                    self_hits += 1;
                }
            }
            let _ = i;
        }
        assert_eq!(self_hits, 0, "scale {scale}: {self_hits} self-intersections");
    }
}

/// Two parallel plates a tiny distance apart (relative 1e-5 of the coordinates): a ray from the
/// lower plate towards the upper must hit it, at every scale; obvhs's absolute node epsilon
/// would lose it without the tracer's internal rescaling.
#[test]
fn close_parallel_plates_are_resolved_at_every_scale() {
    for scale in [1e-6f32, 1e-3, 1.0, 1e3, 1e6] {
        let lower = [vec3(0.0, 0.0, 0.0), vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0)].map(|p| p * scale);
        let gap = 1e-5;
        let upper = [vec3(0.0, 0.0, gap), vec3(1.0, 0.0, gap), vec3(0.0, 1.0, gap)].map(|p| p * scale);
        let tracer = Tracer::build(&[lower, upper]);
        let (p, err) = hit_point(&lower, [0.4, 0.3, 0.3]);
        let r = spawn_ray(p, err, Vec3::Z, Vec3::Z);
        let h = tracer.closest_hit(&r, RayKind::Specular, &mut RayCounts::default());
        let h = h.unwrap_or_else(|| panic!("scale {scale}: the upper plate was missed"));
        assert_eq!(h.tri, 1, "scale {scale}");
        assert!((h.t / (gap * scale) - 1.0).abs() < 1e-2, "scale {scale}: t = {}", h.t);
    }
}

#[test]
fn degenerate_and_non_finite_triangles_are_never_hit_and_do_not_panic() {
    let tris = vec![
        [Vec3::ZERO, Vec3::ZERO, Vec3::ZERO],
        [vec3(-1.0, 0.0, 0.0), vec3(0.0, 0.0, 0.0), vec3(1.0, 0.0, 0.0)], // collinear
        [vec3(f32::NAN, 0.0, 0.0), vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0)],
        [vec3(f32::INFINITY, 0.0, 0.0), vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0)],
    ];
    let tracer = Tracer::build(&tris);
    let mut counts = RayCounts::default();
    for d in [vec3(0.0, 0.0, -1.0), vec3(0.0, -1.0, 0.0), vec3(1.0, 0.0, 0.0)] {
        let r = Ray::new(-d * 5.0 + vec3(0.0, 0.0, 0.0), d, f32::INFINITY);
        assert_eq!(tracer.closest_hit(&r, RayKind::Primary, &mut counts), None);
    }
    // An empty tracer answers too.
    let empty = Tracer::build(&[]);
    let r = Ray::new(Vec3::ZERO, Vec3::X, f32::INFINITY);
    assert_eq!(empty.closest_hit(&r, RayKind::Primary, &mut counts), None);
    assert!(!empty.occluded(&r, RayKind::Shadow, &mut counts));
    // Non-finite rays are counted but hit nothing.
    let bad = Ray::new(vec3(f32::NAN, 0.0, 0.0), Vec3::X, 1.0);
    assert!(!tracer.occluded(&bad, RayKind::Shadow, &mut counts));
}

/// A mesh collapsed to a point and a part pasted many times in place: 60,000 coincident boxes
/// each. Before such triangles were left out, obvhs took 2.6 s for 10,000 coincident boxes
/// (quadratic), and its recursive tree conversion overflowed the stack here (this test's
/// thread has Rust's default 2 MiB; an overflow aborts the whole test binary) and at 100,000
/// in an 8 MiB main thread.
#[test]
fn coincident_triangles_build_and_answer_as_one() {
    let p = vec3(0.25, 0.5, 0.0);
    let tri = [vec3(-1.0, -1.0, 0.0), vec3(1.0, -1.0, 0.0), vec3(0.0, 1.0, 0.0)];
    const N: usize = 60_000;
    let mut tris = grid(4).into_iter().map(|t| t.map(|q| q + vec3(10.0, 0.0, 0.0))).collect::<Vec<_>>();
    let first = tris.len() as u32;
    // Interleaved, so each repeat and each point is preceded by the first copy of the triangle.
    for _ in 0..N {
        tris.push(tri);
        tris.push([p; 3]);
    }
    // A repeat with its corners rotated is not the same sequence of operations: kept.
    let rotated = [tri[1], tri[2], tri[0]];
    tris.push(rotated);
    let tracer = Tracer::build(&tris);
    assert_eq!(tracer.triangle_count(), tris.len());
    assert_eq!(tracer.bvh_triangle_count(), 4 * 4 * 2 + 2, "grid, one copy, the rotated one");

    let mut counts = RayCounts::default();
    for (o, d) in [(vec3(0.1, 0.0, 5.0), vec3(0.0, 0.0, -1.0)), (vec3(0.1, 0.2, -3.0), vec3(0.0, 0.0, 1.0))] {
        let ray = Ray::new(o, d, f32::INFINITY);
        let hit = tracer.closest_hit(&ray, RayKind::Primary, &mut counts).unwrap();
        assert_eq!(hit.tri, first, "the first copy wins the tie");
        assert!(tracer.occluded(&ray, RayKind::Shadow, &mut counts));
    }
    // Through the point, along the plane: nothing (the point has no area).
    let ray = Ray::new(p - vec3(5.0, 0.0, 0.0), Vec3::X, 9.0);
    assert_eq!(tracer.closest_hit(&ray, RayKind::Primary, &mut counts), None);
}

#[test]
fn hint_test_matches_full_traversal() {
    let tris = grid(4);
    let tracer = Tracer::build(&tris);
    let ray = Ray::new(vec3(1.3, 2.2, 4.0), vec3(0.0, 0.0, -1.0), f32::INFINITY);
    let full = tracer.closest_hit(&ray, RayKind::Shadow, &mut RayCounts::default()).unwrap();
    let hint = tracer.hits_triangle(full.tri, &ray).unwrap();
    assert_eq!(hint, full);
    assert!(tracer.hits_triangle(full.tri ^ 1, &ray).is_none());
    assert!(tracer.hits_triangle(u32::MAX, &ray).is_none());
}

#[test]
fn counts_add_up_by_kind() {
    let mut a = RayCounts::default();
    a.add(RayKind::Primary, 3);
    a.add(RayKind::Shadow, 5);
    let mut b = RayCounts::default();
    b.add(RayKind::Specular, 7);
    b.add(RayKind::VplShadow, 11);
    let s: RayCounts = [a, b].into_iter().sum();
    assert_eq!((s.primary, s.shadow, s.specular, s.vpl_shadow, s.total()), (3, 5, 7, 11, 26));
}

#[test]
fn plane_hit_equals_triangle_hit_inside_and_extends_outside() {
    let tri = [vec3(0.0, 0.0, -3.0), vec3(2.0, 0.0, -3.5), vec3(0.0, 2.0, -2.5)];
    let tracer = Tracer::build(&[tri]);
    // Inside: bit-identical to the triangle test.
    let ray = Ray::new(vec3(0.4, 0.3, 1.0), vec3(0.05, -0.02, -1.0).normalize(), f32::INFINITY);
    assert_eq!(tracer.hit_on_plane(0, &ray), tracer.hits_triangle(0, &ray));
    assert!(tracer.hits_triangle(0, &ray).is_some());
    // Outside the triangle but on its plane: a hit with a negative barycentric whose point
    // lies on the plane.
    let ray = Ray::new(vec3(2.0, 2.0, 1.0), vec3(0.0, 0.0, -1.0), f32::INFINITY);
    assert!(tracer.hits_triangle(0, &ray).is_none());
    let h = tracer.hit_on_plane(0, &ray).unwrap();
    assert!(h.bary.iter().any(|&b| b < 0.0));
    let p = ray.origin + ray.dir * h.t;
    let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize();
    assert!((p - tri[0]).dot(n).abs() < 1e-5, "{p} is off the plane");
    // Parallel and backwards rays find nothing.
    let parallel = Ray::new(vec3(0.0, 0.0, 5.0), (tri[1] - tri[0]).normalize(), f32::INFINITY);
    assert!(tracer.hit_on_plane(0, &parallel).is_none());
    let away = Ray::new(vec3(0.4, 0.3, 1.0), vec3(0.0, 0.0, 1.0), f32::INFINITY);
    assert!(tracer.hit_on_plane(0, &away).is_none());
}

/// Two parallel triangles: the nearer wins whatever its id, down to gaps far below the f32
/// distances' resolution (ordered in f64); coplanar ones, which nothing orders, go to the
/// smaller id (both faces entered); and `nearer_hit` orders any two alike.
#[test]
fn near_surfaces_go_to_the_nearer_and_coplanar_ones_to_the_smaller_id() {
    let tri = |z: f32| [vec3(-1.0, -1.0, z), vec3(1.0, -1.0, z), vec3(0.0, 1.0, z)];
    let ray = Ray::new(vec3(0.1, 0.0, 10.0), vec3(0.0, 0.0, -1.0), f32::INFINITY);
    let mut c = RayCounts::default();
    for gap in [1e-2f32, 1e-5, 1e-6, 2e-7] {
        // Triangle 0 is the farther one, then the nearer one.
        for (tris, nearer) in [([tri(0.0), tri(gap)], 1), ([tri(gap), tri(0.0)], 0)] {
            let tracer = Tracer::build(&tris);
            assert_eq!(tracer.closest_hit(&ray, RayKind::Primary, &mut c).unwrap().tri, nearer, "gap {gap}");
            assert_eq!(tracer.nearer_hit(&ray, 0, 1).unwrap().tri, nearer, "gap {gap}");
            assert_eq!(tracer.nearer_hit(&ray, 1, 0).unwrap().tri, nearer, "gap {gap}");
        }
    }
    // The same plane, the corners in another order: a tie, to the smaller id.
    let t = tri(0.0);
    let tracer = Tracer::build(&[[t[1], t[2], t[0]], t]);
    assert_eq!(tracer.closest_hit(&ray, RayKind::Primary, &mut c).unwrap().tri, 0);
    assert_eq!(tracer.nearer_hit(&ray, 1, 0).unwrap().tri, 0);
    // Only one of the two hit: that one; neither (or an unknown id): none.
    let tracer = Tracer::build(&[tri(0.0), tri(1.0).map(|p| p + vec3(5.0, 0.0, 0.0))]);
    assert_eq!(tracer.nearer_hit(&ray, 1, 0).unwrap().tri, 0);
    assert!(tracer.nearer_hit(&ray, 1, 7).is_none());
    assert!(hyrt_tracer::depth_tie(10.0, 10.0 + 1e-4) && !hyrt_tracer::depth_tie(10.0, 10.0 + 1e-3));
}

/// The hit point's error bound holds: the computed point lies within the bound of the exact
/// (f64) point for the same barycentrics, on triangles near and far from the origin; and far
/// from the origin the bound is at most a few ulps of the coordinates (not seven).
#[test]
fn hit_point_error_bound_holds() {
    let mut worst = 0.0f64;
    for (k, offset) in [0.0f32, 1.0, 1e3, 1e5, -3e6].into_iter().enumerate() {
        for i in 0..400 {
            let f = |j: u32| ((i * 7919 + j * 104_729 + k as u32 * 31) % 1000) as f32 / 1000.0;
            let o = vec3(offset, offset * 0.37, -offset * 0.61);
            let tri = [
                o + vec3(f(1), f(2), f(3)) * 5.0,
                o + vec3(f(4), f(5), f(6)) * 5.0,
                o + vec3(f(7), f(8), f(9)) * 5.0,
            ];
            let (b1, b2) = (f(10) * 0.5, f(11) * 0.5);
            let b = [1.0 - b1 - b2, b1, b2];
            let (p, err) = hit_point(&tri, b);
            let d = |v: Vec3| v.as_dvec3();
            let exact =
                d(tri[0]) + (d(tri[1]) - d(tri[0])) * f64::from(b1) + (d(tri[2]) - d(tri[0])) * f64::from(b2);
            let off = (d(p) - exact).abs();
            for a in 0..3 {
                assert!(
                    off[a] <= f64::from(err[a]),
                    "offset {offset}, triangle {i}: axis {a} off by {} > {}",
                    off[a],
                    err[a]
                );
                if err[a] > 0.0 {
                    worst = worst.max(off[a] / f64::from(err[a]));
                }
            }
            if offset.abs() >= 1e5 {
                let ulp = |x: f32| (x.abs().next_up() - x.abs()) as f64;
                for a in 0..3 {
                    assert!(f64::from(err[a]) <= 2.0 * ulp(p[a]), "bound {} vs ulp {}", err[a], ulp(p[a]));
                }
            }
        }
    }
    assert!(worst > 0.0, "no rounding seen at all");
}

/// Axis-aligned boxes (every triangle on a face of its BVH node's box) far from the origin,
/// and shadow rays from points on them towards lights, half of them aimed exactly at a point of
/// a box's top edge and going on past it: the traversal's answer equals the brute-force answer
/// over every triangle with the same watertight test (no ray slips past a box's edge by the
/// box test's rounding), and so does the hint-first answer for any hint.
#[test]
fn traversal_agrees_with_brute_force_on_boxes_far_away() {
    for offset in [0.0f32, 3e4, 3e5, 1e6] {
        let o = vec3(1.0, 0.37, -0.61) * offset;
        let mut boxes = vec![(vec3(-2.5, -0.1, -2.5), vec3(2.5, 0.0, 2.5))];
        for k in 0..12 {
            let x = -2.0 + k as f32 * 0.35;
            boxes.push((vec3(x, 0.0, -1.0 + k as f32 * 0.1), vec3(x + 0.2, 0.3 + k as f32 * 0.05, 1.2)));
        }
        let mut tris = Vec::new();
        for &(lo, hi) in &boxes {
            let c = |i: u32| {
                o + vec3(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                )
            };
            for q in [[0, 4, 6, 2], [1, 3, 7, 5], [0, 1, 5, 4], [2, 6, 7, 3], [0, 2, 3, 1], [4, 5, 7, 6]] {
                let q = q.map(c);
                tris.push([q[0], q[1], q[2]]);
                tris.push([q[0], q[2], q[3]]);
            }
        }
        let tracer = Tracer::build(&tris);
        let mut c = RayCounts::default();
        let (mut disagree, mut blocked, mut total) = (0, 0, 0);
        let lights = [o + vec3(0.4, 2.2, 0.9), o + vec3(-1.2, 1.8, -0.7), o + vec3(2.0, 0.35, 0.1)];
        for i in 0..20_000u32 {
            let f = |j: u32| {
                (i.wrapping_mul(2_654_435_761).wrapping_add(j.wrapping_mul(40_503)) % 10_000) as f32 / 1e4
            };
            let t = &tris[(i as usize * 7) % tris.len()];
            let (b1, b2) = (f(1) * 0.5, f(2) * 0.5);
            let (p, err) = hit_point(t, [1.0 - b1 - b2, b1, b2]);
            let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
            let light = if i % 2 == 0 {
                lights[i as usize % 3]
            } else {
                let (lo, hi) = boxes[1 + (i as usize / 2) % 12];
                let q = o + vec3(lo.x, hi.y, lo.z + (hi.z - lo.z) * f(3));
                p + (q - p) * 3.0
            };
            if n.dot(light - p) <= 0.0 {
                continue;
            }
            let ray = spawn_ray_to(p, err, n, light);
            let brute = (0..tris.len() as u32).any(|k| tracer.hits_triangle(k, &ray).is_some());
            let traversed = tracer.occluded(&ray, RayKind::Shadow, &mut c);
            let hinted = tracer.occluded_with_hint(&ray, (i * 13) % tris.len() as u32, &mut c);
            // Named, with no hint and with one: a triangle that blocks the ray, or none.
            let named = [u32::MAX, (i * 13) % tris.len() as u32]
                .map(|hint| tracer.occluder_with_hint(&ray, hint, &mut c));
            let names_a_blocker = |o: Option<u32>| {
                o.is_some() == brute && o.is_none_or(|t| tracer.hits_triangle(t, &ray).is_some())
            };
            total += 1;
            blocked += usize::from(brute);
            disagree += usize::from(brute != traversed) + usize::from(brute != hinted);
            disagree += named.iter().filter(|&&o| !names_a_blocker(o)).count();
        }
        assert!(total > 5000 && blocked > 1000, "offset {offset}: {blocked} of {total} blocked");
        assert_eq!(disagree, 0, "offset {offset}: {disagree} disagreements in {total} rays");
    }
}

/// A BVH built on a thread of its own answers every query as one built at once: the same hits,
/// occlusions and counts, and the single-triangle tests work before the build is done.
#[test]
fn a_background_build_answers_as_a_build_at_once() {
    let mut tris = grid(12);
    // Repeats and a degenerate triangle, which both builds leave out alike.
    tris.push(tris[3]);
    tris.push([Vec3::ONE; 3]);
    let now = Tracer::build(&tris);
    let later = Tracer::build_in_background(&tris);
    let probe = Ray::new(vec3(0.5, 0.25, 1.0), vec3(0.0, 0.0, -1.0), f32::INFINITY);
    assert_eq!(later.hits_triangle(0, &probe), now.hits_triangle(0, &probe));
    let (mut a, mut b) = (RayCounts::default(), RayCounts::default());
    for k in 0..400 {
        let (x, y) = ((k % 20) as f32 * 0.61, (k / 20) as f32 * 0.59);
        let dir = vec3(0.2 - 0.01 * (k % 7) as f32, 0.1, -1.0).normalize();
        let ray = Ray::new(vec3(x, y, 3.0), dir, if k % 3 == 0 { 2.5 } else { f32::INFINITY });
        assert_eq!(
            later.closest_hit(&ray, RayKind::Primary, &mut a),
            now.closest_hit(&ray, RayKind::Primary, &mut b)
        );
        assert_eq!(
            later.occluded(&ray, RayKind::Shadow, &mut a),
            now.occluded(&ray, RayKind::Shadow, &mut b)
        );
    }
    assert_eq!(a, b);
    assert_eq!(later.bvh_triangle_count(), now.bvh_triangle_count());
    assert_eq!(later.bvh_triangle_count(), tris.len() - 2);
    // Ready once a query has waited for it; a build at once is ready from the start.
    assert!(later.is_ready() && now.is_ready());
    let pending = Tracer::build_in_background(&grid(300));
    while !pending.is_ready() {
        std::thread::yield_now();
    }
    assert_eq!(pending.bvh_triangle_count(), 2 * 300 * 300, "ready, and built");
}

/// Holes in the triangles of a cut-out: a point of triangle 0 or 1 is a hole where its
/// barycentric weight of corner 1 is below one half.
struct HalfHoles;

impl hyrt_tracer::Cutouts for HalfHoles {
    fn has_holes(&self, tri: u32) -> bool {
        tri < 2
    }
    fn solid(&self, _tri: u32, bary: [f32; 3]) -> bool {
        bary[1] >= 0.5
    }
}

/// Rays pass through a cut-out's holes, in every query that reports or blocks, and stop on
/// its solid parts; plane queries ignore holes; a triangle without holes is untouched.
#[test]
fn rays_pass_through_cut_out_holes_alone() {
    // A cut-out quad at z = 2 (triangles 0 and 1), a plain one at z = 1 behind it (2 and 3),
    // seen from z = 3.
    let at = |z: f32| grid(1).into_iter().map(move |t| t.map(|p| p + z * Vec3::Z));
    let tris: Vec<[Vec3; 3]> = at(2.0).chain(at(1.0)).collect();
    let plain = Tracer::build(&tris);
    let cut = Tracer::build(&tris).with_cutouts(Box::new(HalfHoles));
    let mut c = RayCounts::default();
    let down = |x: f32, y: f32, tmax: f32| Ray::new(vec3(x, y, 3.0), Vec3::NEG_Z, tmax);
    // Triangle 0 (corners (0,0), (1,0), (1,1)): corner 1's weight at (x, y) is x - y.
    let (hole, solid) = ((0.4, 0.1), (0.9, 0.1));
    let hit = |t: &Tracer, (x, y): (f32, f32)| {
        t.closest_hit(&down(x, y, f32::INFINITY), RayKind::Primary, &mut RayCounts::default())
    };
    assert_eq!(hit(&plain, hole).map(|h| h.tri), Some(0));
    assert_eq!(hit(&cut, hole).map(|h| (h.tri, h.t)), Some((2, 2.0)), "through the hole to the back quad");
    assert_eq!(hit(&cut, solid).map(|h| (h.tri, h.t)), Some((0, 1.0)));
    // Occlusion up to just before the back quad.
    let blocked = |t: &Tracer, (x, y): (f32, f32)| {
        t.occluded(&down(x, y, 1.5), RayKind::Shadow, &mut RayCounts::default())
    };
    assert!(blocked(&plain, hole) && !blocked(&cut, hole) && blocked(&cut, solid));
    // The hint: a hole in it is no hit, and the traversal then finds nothing either.
    let before = c.shadow_hint_hits;
    assert!(!cut.occluded_with_hint(&down(hole.0, hole.1, 1.5), 0, &mut c));
    assert!(cut.occluded_with_hint(&down(solid.0, solid.1, 1.5), 0, &mut c));
    assert_eq!(c.shadow_hint_hits, before + 1);
    assert_eq!(cut.occluder_with_hint(&down(hole.0, hole.1, 1.5), 0, &mut c), None);
    assert_eq!(cut.occluder_with_hint(&down(solid.0, solid.1, 1.5), u32::MAX, &mut c), Some(0));
    assert_eq!(c.shadow_hint_hits, before + 1, "no hint, or one in a hole: no hint hit");
    let ray = down(hole.0, hole.1, f32::INFINITY);
    assert!(cut.hits_triangle(0, &ray).is_none() && plain.hits_triangle(0, &ray).is_some());
    assert_eq!(cut.hit_on_plane(0, &ray), plain.hit_on_plane(0, &ray));
    // The plain quad behind has no holes, whatever its barycentrics.
    assert_eq!(cut.hits_triangle(2, &ray), plain.hits_triangle(2, &ray));
}
