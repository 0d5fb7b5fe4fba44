//! Cascaded suns in the frame loop: [`LoopPolicy::Cascaded`](super::LoopPolicy::Cascaded).
//!
//! A cascaded sun is `K` consecutive lights of the renderer's frame (`K`
//! layers of the map array, [`Renderer::set_cascades`]). The loop keeps the
//! order that is easy to get wrong in one place: take the readback that has
//! arrived, fold each sun's cascade bits into one bit per sun, re-place the
//! splits from the readback's visible depths (SDSM, with hysteresis),
//! optimize every cascade from the same readback (its own hysteresis), then
//! solve the frame's cascades, mark them on the renderer and render.
//!
//! **One shadow bit per light.** The renderer looks a cascade up only where
//! the pixel's view depth lies in the range it owns, so at most one of a
//! sun's `K` bits is set per pixel: the one of the cascade chosen per pixel
//! ([`Splits::choose`](crate::cascade::Splits::choose)). The loop ORs the
//! `K` shadow bits and the `K` facing bits of each sun into the sun's bit
//! ([`sun_bits`]), so the optimizer sees one bit per light as for an
//! uncascaded light: "not lit by the sun" as the cascade that shaded the
//! pixel found it.

use crate::cascade::{visible_depth_range, CascadeOptimizer, CascadeProblems, CascadeSplits, SplitScheme};
use crate::cascade::{SplitTracker, Splits};
use crate::mesh::ShadowMasks;
use crate::optimize::{OptimizeOptions, SampleOptions};
use crate::{Light, LightMatrix, LixelError, Parameterization, ShadowProblem};
use glam::DVec3;

use super::{AnalysisReadback, Renderer};

/// Where a cascaded loop places its split boundaries.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum SplitPlacement {
    /// Each frame, over the camera's depth range limited to the scene
    /// ([`CascadeSplits::for_problem`]): the engines' fixed splits.
    Fixed,
    /// Sample-distribution shadow maps: over the visible depth range of the
    /// latest analysis readback, through a [`SplitTracker`] with this
    /// hysteresis (for example 0.05); fixed splits until the first readback.
    Sdsm {
        /// The tracker's padding and tolerance ([`SplitTracker::new`]).
        hysteresis: f64,
    },
}

/// How a cascaded loop fits each cascade's matrix.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum CascadeMatrices {
    /// Each cascade's slice solved with one parameterization every frame
    /// (focused, focused-snapped, LiSPSM, ...).
    Fixed(Parameterization),
    /// Each cascade scene-optimized from the analysis readback
    /// ([`CascadeOptimizer`], one per sun); focused until its first
    /// optimization, and again whenever the splits are re-placed.
    Optimized,
}

/// The cascade policy of a [`ShadowLoop`](super::ShadowLoop): every
/// directional light of the view gets `splits.count` cascades; point and
/// spot lights keep one focused map each (the cascade methods, snapped
/// focused maps included, are the sun's).
#[derive(Clone, Debug, PartialEq)]
pub struct CascadePolicy {
    /// How many cascades, the split scheme and the blend band.
    pub splits: CascadeSplits,
    /// Where the splits go.
    pub placement: SplitPlacement,
    /// How each cascade's matrix is fitted.
    pub matrices: CascadeMatrices,
}

impl CascadePolicy {
    /// The engines' default (Bevy-style): practical (λ = 0.75) splits of the
    /// camera range, texel-snapped focused maps.
    #[must_use]
    pub fn csm(count: usize) -> Self {
        Self {
            splits: CascadeSplits { count, scheme: SplitScheme::Practical { lambda: 0.75 }, overlap: 0.1 },
            placement: SplitPlacement::Fixed,
            matrices: CascadeMatrices::Fixed(Parameterization::FocusedSnapped(Default::default())),
        }
    }

    /// SDSM: logarithmic splits inside the visible depth range, each slice
    /// solved with `parameterization` (focused for the paper's method).
    #[must_use]
    pub fn sdsm(count: usize, parameterization: Parameterization) -> Self {
        Self {
            splits: CascadeSplits { count, scheme: SplitScheme::Logarithmic, overlap: 0.1 },
            placement: SplitPlacement::Sdsm { hysteresis: 0.05 },
            matrices: CascadeMatrices::Fixed(parameterization),
        }
    }

    /// SDSM splits with every cascade scene-optimized from the readback.
    #[must_use]
    pub fn optimized(count: usize) -> Self {
        Self { matrices: CascadeMatrices::Optimized, ..Self::sdsm(count, Parameterization::Focused) }
    }

    /// Whether the loop needs analysis passes (SDSM splits or optimized
    /// cascades).
    #[must_use]
    pub fn analyses(&self) -> bool {
        matches!(self.placement, SplitPlacement::Sdsm { .. }) || self.matrices == CascadeMatrices::Optimized
    }

    /// The map slots (renderer lights) of `lights`: light `i` takes
    /// `slots[i]..slots[i + 1]`.
    fn slots(&self, lights: &[Light]) -> Vec<usize> {
        let mut slots = vec![0];
        for light in lights {
            let n = if matches!(light, Light::Directional { .. }) { self.splits.count } else { 1 };
            slots.push(slots.last().copied().unwrap_or(0) + n);
        }
        slots
    }
}

/// A cascaded loop's state: the split tracker and one optimizer per light.
#[derive(Clone, Debug)]
pub(super) struct CascadeState {
    tracker: Option<SplitTracker>,
    optimizers: Vec<CascadeOptimizer>,
    /// Per light: world points of the last readback's pixels it shadows.
    seen: Vec<Vec<DVec3>>,
    /// Per light: the slice cameras (one per cascade) of the last readback
    /// its cascades were optimized from.
    fitted: Vec<Vec<crate::Camera>>,
    optimize: OptimizeOptions,
}

/// What the readback step of a cascaded frame did (bits per light).
#[derive(Debug, Default)]
pub(super) struct CascadeUpdate {
    pub optimized: u32,
    pub failed: u32,
    pub fallbacks: Vec<(usize, crate::Fallback)>,
    pub boundary_samples: Vec<Vec<glam::DVec3>>,
    /// Whether some cascade's optimizer accepted a new matrix.
    pub moved: bool,
}

/// Per pixel of an analysis pass's masks, bit `i` set where light `i`
/// (map slots `slots[i]..slots[i + 1]`) does not light the
/// pixel: shadowed or facing away in the map slot(s) that shaded it (for a
/// cascaded sun, the OR of its cascades' shadow bits and of their facing
/// bits; a pixel no cascade owns counts as unlit). Background pixels are 0.
#[must_use]
pub fn sun_bits(masks: &ShadowMasks, slots: &[usize]) -> Vec<u32> {
    (0..masks.depth.len())
        .map(|p| {
            if !masks.visible(p) {
                return 0;
            }
            let (s, f) = (masks.shadow[p], masks.facing[p]);
            slots.windows(2).enumerate().fold(0u32, |bits, (i, w)| {
                let range = ((1u64 << w[1]) - (1u64 << w[0])) as u32;
                let unlit = s & range != 0 || f & range == 0;
                bits | (u32::from(unlit) << i)
            })
        })
        .collect()
}

/// Whether `matrix` still holds the surfaces the last readback saw in the
/// sun's shadow (`seen`, world points; lit surfaces may fall outside a map,
/// which reads as lit, as the optimizer's relevant samples) that now lie in view depths
/// `[lo, hi]` of `camera` (the cascade's slice, blend band included), with
/// 1% of the map's half-width to spare. An optimized cascade was fitted to
/// the readback's camera; once the camera has moved further than the fit
/// allows (easily, for a near cascade a few units deep), the cascade falls
/// back to its focused matrix until the next readback rather than drop what
/// was seen. Surfaces no readback has seen yet are the analysis cadence's
/// to find, as for an uncascaded light.
fn holds(matrix: &LightMatrix, camera: &crate::Camera, (lo, hi): (f64, f64), seen: &[DVec3]) -> bool {
    const SLACK: f64 = 0.01;
    seen.iter().all(|&p| {
        let d = camera.view_depth(p);
        !(lo..=hi).contains(&d) || matrix.covers(p, SLACK)
    })
}

/// Whether an optimized cascade can still stand for the cascade's slice
/// now: the slice's visible receivers (`body`, the vertices of `V_k ∩ R`
/// of the frame's slice `k`) lie in its map, or all of them lay inside the
/// slice the readback it was fitted to sampled (`fitted`, that slice's
/// camera). Otherwise the camera has moved (or turned) onto receivers no
/// readback has seen in this slice — walking up to an object puts its
/// near side in cascade 0 — and the optimizer, which fits what was seen,
/// may have left them out of the map: the cascade falls back to its
/// focused matrix until a readback from the new view. Both tests are of
/// convex bodies (the map's coverage and a slice frustum), so the vertices
/// decide; `SLACK` (2% of the map's or the frustum's half-width, of its
/// depth range) absorbs a frame's worth of drift.
fn still_fits(matrix: &LightMatrix, body: &[DVec3], fitted: Option<&crate::Camera>) -> bool {
    const SLACK: f64 = 0.02;
    let inside = |camera: &crate::Camera, p: DVec3| {
        let c = camera.clip_from_world() * p.extend(1.0);
        c.w > 0.0 && {
            let n = c.truncate() / c.w;
            n.x.abs() <= 1.0 + SLACK && n.y.abs() <= 1.0 + SLACK && (-SLACK..=1.0 + SLACK).contains(&n.z)
        }
    };
    body.iter().all(|&p| matrix.covers(p, SLACK)) || fitted.is_some_and(|c| body.iter().all(|&p| inside(c, p)))
}

impl CascadeState {
    pub(super) fn new(policy: &CascadePolicy, lights: usize, optimize: OptimizeOptions) -> crate::Result<Self> {
        policy.splits.validate()?;
        let tracker = match policy.placement {
            SplitPlacement::Fixed => None,
            SplitPlacement::Sdsm { hysteresis } => Some(SplitTracker::new(policy.splits, hysteresis)?),
        };
        let optimizers = (0..lights).map(|_| CascadeOptimizer::new(policy.splits.count, &optimize)).collect();
        Ok(Self { tracker, optimizers, seen: vec![Vec::new(); lights], fitted: vec![Vec::new(); lights], optimize })
    }

    fn reset_optimizers(&mut self, count: usize) {
        for o in &mut self.optimizers {
            *o = CascadeOptimizer::new(count, &self.optimize);
        }
    }

    /// The splits of a frame whose (full) problem is `problem`: the
    /// tracker's, or the fixed ones of its range.
    fn splits(&mut self, policy: &CascadePolicy, problem: &ShadowProblem) -> crate::Result<Splits> {
        match &mut self.tracker {
            Some(tracker) => match tracker.splits() {
                Some(s) => Ok(s.clone()),
                None => tracker.update(problem, None).cloned(),
            },
            None => policy.splits.for_problem(problem),
        }
    }

    /// Consumes a readback: re-places SDSM splits from its visible depths
    /// and optimizes every cascade of every sun from its samples.
    pub(super) fn take_readback(
        &mut self,
        policy: &CascadePolicy,
        readback: &AnalysisReadback,
        view: &super::LoopView<'_>,
    ) -> crate::Result<CascadeUpdate> {
        let slots = policy.slots(view.lights);
        let bits = sun_bits(&readback.masks, &slots);
        let input = readback.optimizer_input(&bits);
        let mut update =
            CascadeUpdate { boundary_samples: vec![Vec::new(); view.lights.len()], ..CascadeUpdate::default() };
        let Some(sun) = view.lights.iter().position(|l| matches!(l, Light::Directional { .. })) else {
            return Ok(update);
        };
        if let Some(tracker) = &mut self.tracker {
            let visible = visible_depth_range(&readback.camera, &input)?;
            let problem = ShadowProblem::new(*view.camera, view.lights[sun], view.bounds, view.map)?;
            let before = tracker.replacements();
            tracker.update(&problem, visible)?;
            if tracker.replacements() != before {
                self.reset_optimizers(policy.splits.count);
            }
        }
        if policy.matrices != CascadeMatrices::Optimized {
            return Ok(update);
        }
        let options = SampleOptions::default();
        let world_from_screen = readback.camera.screen_from_world().inverse();
        for (i, &light) in view.lights.iter().enumerate() {
            if !matches!(light, Light::Directional { .. }) {
                continue;
            }
            let range = ((1u64 << slots[i + 1]) - (1u64 << slots[i])) as u32;
            let masks = &readback.masks;
            self.seen[i] = (0..masks.height)
                .flat_map(|y| (0..masks.width).map(move |x| (x, y)))
                .filter(|&(x, y)| {
                    let p = (y * masks.width + x) as usize;
                    masks.visible(p) && masks.facing[p] & range != 0 && masks.shadow[p] & range != 0
                })
                .map(|(x, y)| world_from_screen.project_point3(readback.screen_point(x, y)))
                .collect();
            // The samples belong to the camera the pass was rendered with.
            let mut fitted = Vec::new();
            let samples = ShadowProblem::new(readback.camera, light, view.bounds, view.map).and_then(|problem| {
                let splits = self.splits(policy, &problem)?;
                let cascades = CascadeProblems::new(&problem, splits)?;
                fitted = cascades.problems().iter().map(|p| *p.camera()).collect();
                CascadeOptimizer::samples(&cascades, &input, i as u32, &options)
            });
            let Ok(samples) = samples else {
                update.failed |= 1 << i;
                continue;
            };
            update.boundary_samples[i] = samples.iter().flat_map(|s| s.boundary_world().iter().copied()).collect();
            let mut ok = true;
            for result in self.optimizers[i].optimize(&samples)? {
                match result {
                    Ok(o) => {
                        update.moved |= o.report.accepted && o.report.fallback.is_none();
                        update.fallbacks.extend(o.report.fallback.map(|f| (i, f)));
                    }
                    Err(_) => ok = false,
                }
            }
            // A cascade whose optimization failed keeps a matrix of an older
            // readback: then only its map's own coverage can vouch for it.
            self.fitted[i] = if ok { fitted } else { Vec::new() };
            if ok {
                update.optimized |= 1 << i;
            } else {
                update.failed |= 1 << i;
            }
        }
        Ok(update)
    }

    /// The frame's matrices (one per map slot) and splits, with the
    /// renderer's cascades marked.
    pub(super) fn solve(
        &mut self,
        policy: &CascadePolicy,
        renderer: &mut Renderer,
        view: &super::LoopView<'_>,
    ) -> crate::Result<(Vec<LightMatrix>, Option<Splits>)> {
        let slots = policy.slots(view.lights);
        if slots.last().copied().unwrap_or(0) > crate::MAX_LIGHTS {
            return Err(LixelError::InvalidCascades { reason: "more cascade maps than the renderer has lights" });
        }
        let fixed = match &policy.matrices {
            CascadeMatrices::Fixed(p) => *p,
            CascadeMatrices::Optimized => Parameterization::Focused,
        };
        let mut splits = None;
        let mut matrices = Vec::with_capacity(slots.last().copied().unwrap_or(0));
        renderer.set_cascades(0, None);
        for (i, &light) in view.lights.iter().enumerate() {
            let problem = ShadowProblem::new(*view.camera, light, view.bounds, view.map)?;
            if !matches!(light, Light::Directional { .. }) {
                matrices.push(problem.solve(&Parameterization::Focused)?);
                continue;
            }
            let s = match &splits {
                Some(s) => Splits::clone(s),
                None => self.splits(policy, &problem)?,
            };
            let cascades = CascadeProblems::new(&problem, s.clone())?;
            for (k, slice) in cascades.problems().iter().enumerate() {
                let seen = &self.seen[i];
                let fits = |m: &LightMatrix| {
                    holds(m, view.camera, s.slice(k), seen)
                        && still_fits(m, slice.visible_receiver_body().vertices(), self.fitted[i].get(k))
                };
                matrices.push(match (&policy.matrices, self.optimizers[i].matrix(k)) {
                    (CascadeMatrices::Optimized, Some(m)) if fits(m) => *m,
                    _ => slice.solve(&fixed)?,
                });
            }
            renderer.set_cascades(slots[i], Some(&s));
            splits = Some(s);
        }
        Ok((matrices, splits))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_optimized_cascade_stands_only_for_receivers_its_map_or_its_readback_covered() {
        use crate::{Aabb, Camera, SceneBounds, ShadowMapSize};
        use glam::UVec2;
        let camera = |z: f64| {
            let eye = DVec3::new(0.0, 2.0, z);
            Camera::look_at(eye, eye + DVec3::new(0.0, -0.1, -1.0), DVec3::Y, 1.0, UVec2::splat(64), 0.1, 200.0)
                .unwrap()
        };
        let bounds =
            SceneBounds::uniform(Aabb::from_corners(DVec3::new(-100.0, 0.0, -100.0), DVec3::new(100.0, 5.0, 100.0)));
        let sun = Light::directional(DVec3::new(0.3, -1.0, 0.2));
        let problem = |z| ShadowProblem::new(camera(z), sun, bounds, ShadowMapSize::square(256)).unwrap();
        let slice = problem(0.0).depth_slice(1.0, 10.0).unwrap();
        let body = slice.visible_receiver_body().vertices().to_vec();
        assert!(!body.is_empty());
        // Its own focused map holds the slice.
        let own = slice.solve(&Parameterization::Focused).unwrap();
        assert!(still_fits(&own, &body, None));
        // A map of a far slice does not; it stands only while the readback's
        // slice held the receivers (the same view), not after walking 5
        // units forward or back.
        let other = problem(0.0).depth_slice(40.0, 80.0).unwrap().solve(&Parameterization::Focused).unwrap();
        assert!(!still_fits(&other, &body, None));
        assert!(still_fits(&other, &body, Some(slice.camera())));
        for z in [-5.0, 5.0] {
            let moved = problem(z).depth_slice(1.0, 10.0).unwrap().visible_receiver_body().vertices().to_vec();
            assert!(!still_fits(&other, &moved, Some(slice.camera())), "camera at z = {z}");
        }
    }

    // The binary literals are grouped by light slot (second sun | point | first sun).
    #[allow(clippy::unusual_byte_groupings)]
    #[test]
    fn a_suns_bit_is_the_or_of_its_cascades() {
        // Slots: a sun in 0..3, a point light in 3, a sun in 4..6.
        let slots = [0, 3, 4, 6];
        let pixel = |shadow: u32, facing: u32| (shadow, facing);
        let pixels = [
            pixel(0, 0b00_0_010), // first sun lit by cascade 1; point facing away; second sun no cascade
            pixel(0b00_0_100, 0b10_1_100), // first sun shadowed in cascade 2; point lit; second lit
            pixel(0b10_0_000, 0b10_0_001), // second sun shadowed in its cascade 1; point facing away
        ];
        let masks = ShadowMasks {
            width: 4,
            height: 1,
            depth: vec![0.5, 0.5, 0.5, 1.0],
            shadow: pixels.iter().map(|p| p.0).chain([7]).collect(),
            facing: pixels.iter().map(|p| p.1).chain([7]).collect(),
        };
        assert_eq!(sun_bits(&masks, &slots), vec![0b110, 0b001, 0b110, 0]);
    }
}
