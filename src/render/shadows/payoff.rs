//! Which lights get a map: those whose maps make the frames of the horizon cheapest
//! ([`ShadowOptions::map_horizon`](crate::render::ShadowOptions::map_horizon)).
//!
//! A map is bought once and then decides each (pixel, light) pair for the price of a lookup; a
//! ray is paid for every pair of every frame. Light `l` with `P_l` pages and `R_l` receivers
//! (pairs per frame) costs `B_l = P_l t_page` to build, and saves `R_l (t_ray - t_decision)` a
//! frame. Over a horizon of `H` frames, with the set `S` of lights given maps, the predicted time
//! on [`CORES`] cores is
//!
//! `T(S) = F(S) + H (sum_{l not in S} R_l t_ray + sum_{l in S} R_l t_decision) / CORES`
//!
//! where the build `F(S)` is `sum_S B_l / CORES`. `T` is evaluated for the sets made of the `k`
//! lights whose maps save rays most cheaply (the smallest `B_l / (R_l (t_ray - t_decision))`
//! first), `k = 0 ..= L`, and the cheapest is kept (the fewest maps on a tie).
//!
//! A renderer's first frame differs: the BVH is then still being built in the background
//! (`Renderer::new`), mostly on one core, while the passes that need no BVH run on the other
//! (visibility by raster, marking, map building, map decisions), and rays wait for it:
//!
//! `T(S) = max(N t_bvh, n t_prep + sum_S (B_l + R_l t_decision)) + sum_{l not in S} R_l t_ray / CORES`
//!
//! (`N` triangles, `n` pixels; the reference pays the first term as well): maps built within
//! the BVH's time cost nothing. Only all the lights' maps or none are weighed then: with some
//! lights left to rays, the frame waits for the BVH all the same, and a few maps measured no
//! faster than none (docs/results.md: the conference with 3 of its 4 maps, the 64-light
//! conference with 6 of 64), which this prediction, blind to how much each light's rays
//! cost, does not see.
//!
//! The decision is made from counts alone, so that images are the same for any thread count;
//! that is also why `CORES` is fixed rather than the thread count.
//!
//! The unit costs are CPU times measured on this project's machine kind (2 cores, AVX2 and
//! AVX-512; `hyrt bench` per unit and `hyrt render --stats` per pass on the thesis scenes and
//! the 64-light conference, docs/results.md). What matters is their ratios, which set where a
//! map starts to pay: a machine whose rays are cheaper relative to its rasterization moves that
//! point, not the rule.

/// The measured unit costs of [`choose`], in nanoseconds of CPU.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UnitCosts {
    /// Drawing one page: binning, clipping and rasterizing its triangles, summarising it (its
    /// marking included; a page of a detailed mesh costs more).
    pub page: f64,
    /// One map decision (classify, shading included).
    pub decision: f64,
    /// One shadow ray, its pixel's shading included.
    pub ray: f64,
    /// The BVH build, per triangle, on one core.
    pub bvh_per_triangle: f64,
    /// Raster visibility and marking, per pixel (what else fills the BVH build's time).
    pub prep_per_pixel: f64,
}

/// The unit costs the renderer plans with (module docs).
pub const COSTS: UnitCosts = UnitCosts {
    page: 45_000.0,
    decision: 80.0,
    ray: 220.0,
    bvh_per_triangle: 1_000.0,
    prep_per_pixel: 100.0,
};

/// Cores the prediction assumes (module docs): this project's machine kind.
pub const CORES: f64 = 2.0;

/// A light's counts for [`choose`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LightLoad {
    /// Pages its receivers need.
    pub pages: u64,
    /// Its receivers: (pixel, light) pairs per frame.
    pub receivers: u64,
}

/// What [`choose`] found for one light.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Payoff {
    /// Whether it gets a map.
    pub map: bool,
    /// Its map's build, in ms of CPU.
    pub build_ms: f64,
    /// The CPU time its map saves over the horizon (rays less decisions), in ms.
    pub saves_ms: f64,
    /// Lights given maps, of how many.
    pub maps: usize,
    pub lights: usize,
    /// Whether the counts are the sparse estimate's (its pages a lower bound).
    pub at_least: bool,
}

impl Payoff {
    /// The decision's reason, for `horizon` frames.
    pub fn why(&self, horizon: f32) -> String {
        let frames = if horizon == 1.0 { "1 frame".to_string() } else { format!("{horizon} frames") };
        let least = if self.at_least { "at least " } else { "" };
        format!(
            "its build {least}~{:.0} ms against ~{:.0} ms of rays it saves over {frames}; the frame is predicted fastest with {} of {} maps",
            self.build_ms, self.saves_ms, self.maps, self.lights
        )
    }
}

/// Per light of `loads`, whether it gets a map over `horizon` frames (module docs), and why;
/// `first_frame`: the triangles and pixels of a first frame (the BVH is being built).
pub fn choose(
    loads: &[LightLoad],
    horizon: f64,
    first_frame: Option<(usize, usize)>,
    c: &UnitCosts,
) -> Vec<Payoff> {
    let build = |l: &LightLoad| l.pages as f64 * c.page;
    let saves = |l: &LightLoad| horizon * l.receivers as f64 * (c.ray - c.decision);
    // Cheapest savers first (then by index: the same order every run); lights that nothing
    // faces save nothing and get no map.
    let mut order: Vec<usize> = (0..loads.len()).filter(|&l| loads[l].receivers > 0).collect();
    let ratio = |l: usize| build(&loads[l]) / saves(&loads[l]).max(f64::MIN_POSITIVE);
    order.sort_by(|&a, &b| ratio(a).total_cmp(&ratio(b)).then(a.cmp(&b)));
    // T for the first k of `order`, in ns, from the running sums of their builds, their rays
    // and their decisions.
    let rays: f64 = loads.iter().map(|l| horizon * l.receivers as f64 * c.ray).sum();
    let time = |built: f64, their_rays: f64, decided: f64| match first_frame {
        Some((triangles, pixels)) => {
            let bvh = triangles as f64 * c.bvh_per_triangle;
            bvh.max(pixels as f64 * c.prep_per_pixel + built + decided) + (rays - their_rays) / CORES
        }
        None => (built + rays - their_rays + decided) / CORES,
    };
    let (mut sums, mut best, mut best_k) = ((0.0, 0.0, 0.0), time(0.0, 0.0, 0.0), 0);
    for (k, &l) in order.iter().enumerate() {
        let r = horizon * loads[l].receivers as f64;
        sums = (sums.0 + build(&loads[l]), sums.1 + r * c.ray, sums.2 + r * c.decision);
        // A first frame weighs all or none (module docs).
        if first_frame.is_some() && k + 1 < order.len() {
            continue;
        }
        let t = time(sums.0, sums.1, sums.2);
        if t < best {
            (best, best_k) = (t, k + 1);
        }
    }
    let mut out: Vec<Payoff> = loads
        .iter()
        .map(|l| Payoff {
            map: false,
            build_ms: build(l) * 1e-6,
            saves_ms: saves(l) * 1e-6,
            maps: best_k,
            lights: loads.len(),
            at_least: false,
        })
        .collect();
    order[..best_k].iter().for_each(|&l| out[l].map = true);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const C: UnitCosts =
        UnitCosts { page: 1000.0, decision: 10.0, ray: 110.0, bvh_per_triangle: 100.0, prep_per_pixel: 0.0 };

    #[test]
    fn a_map_pays_once_its_build_costs_less_than_the_rays_it_saves() {
        // 100 pages = 100 us to build; 1000 receivers save 100 ns each per frame.
        let l = [LightLoad { pages: 100, receivers: 1000 }];
        assert!(!choose(&l, 0.9, None, &C)[0].map, "0.9 frames save 90 us of 100");
        assert!(choose(&l, 1.1, None, &C)[0].map, "1.1 frames save 110 us of 100");
        let p = choose(&l, 1.0, None, &C)[0];
        assert!((p.build_ms - 0.1).abs() < 1e-12 && (p.saves_ms - 0.1).abs() < 1e-12, "{p:?}");
    }

    #[test]
    fn a_first_frame_gives_every_map_or_none_as_the_bvh_build_hides_them() {
        // Two builds of 100 us and their decisions (10 us over half a frame) are 210 us of work
        // for the BVH's time to hide: 250 us of it does (250 us, against 250 + 55 with rays
        // alone), 150 us does not (210 us, against 150 + 55).
        let l = [LightLoad { pages: 100, receivers: 1000 }, LightLoad { pages: 100, receivers: 1000 }];
        let both = choose(&l, 0.5, Some((2500, 0)), &C);
        assert!(both.iter().all(|p| p.map && p.maps == 2 && p.lights == 2), "{both:?}");
        assert!(choose(&l, 0.5, Some((1500, 0)), &C).iter().all(|p| !p.map));
        // Without the first frame's BVH, neither pays in half a frame.
        assert!(choose(&l, 0.5, None, &C).iter().all(|p| !p.map));
    }

    #[test]
    fn later_frames_give_maps_to_the_cheapest_savers_first() {
        // Over two frames light 1 (100 pages for 1000 receivers) pays and light 0 (300 pages)
        // does not.
        let l = [LightLoad { pages: 300, receivers: 1000 }, LightLoad { pages: 100, receivers: 1000 }];
        let p = choose(&l, 2.0, None, &C);
        assert_eq!(p.iter().map(|p| p.map).collect::<Vec<_>>(), [false, true], "{p:?}");
        assert_eq!(p[0].maps, 1);
    }

    #[test]
    fn a_light_no_pixel_faces_gets_no_map() {
        let p = choose(&[LightLoad::default()], 1.0, Some((10, 0)), &C)[0];
        assert!(!p.map && p.maps == 0, "{p:?}");
    }
}
