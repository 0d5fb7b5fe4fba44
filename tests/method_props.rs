//! Property tests: for thousands of seeded random configurations per method,
//! either a typed error for truly impossible input, or a matrix that keeps
//! every relevant point in front of the light, inside the map, and inside the
//! depth range together with every caster between it and the light.
//!
//! The relevant points are found independently of the solver's own convex
//! bodies: a dense random sample of the receiver box kept when the camera's
//! clip matrix and the spot cone accept it, plus the corners of the view
//! frustum and receiver box that lie in the other. The solver's bodies (and
//! PSM's hull `H`) are checked on top.

mod common;

use std::collections::BTreeMap;

use glam::{DMat4, DVec3, DVec4};
use lixel::{Aabb, Light, LightMatrix, LixelError, Parameterization, ShadowProblem};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const NDC_SLACK: f64 = 1e-6;
const DEPTH_SLACK: f64 = 1e-6;

fn in_view(problem: &ShadowProblem, p: DVec3, slack: f64) -> bool {
    let c = problem.camera().clip_from_world() * p.extend(1.0);
    let s = slack * c.w.abs();
    c.w > 0.0 && c.x.abs() <= c.w + s && c.y.abs() <= c.w + s && c.z >= -s && c.z <= c.w + s
}

fn in_light(light: &Light, p: DVec3) -> bool {
    match *light {
        Light::Spot { position, direction, outer_half_angle_radians } => {
            let d = p - position;
            d.length() > 0.0 && d.normalize().dot(direction) >= outer_half_angle_radians.cos()
        }
        _ => true,
    }
}

fn expand(b: &Aabb, by: f64) -> Aabb {
    Aabb { min: b.min - DVec3::splat(by), max: b.max + DVec3::splat(by) }
}

/// Independent sample of the points every map must hold.
fn relevant_points(problem: &ShadowProblem, rng: &mut ChaCha8Rng) -> Vec<DVec3> {
    let r = problem.bounds().receivers;
    let light = problem.light();
    let mut points = Vec::new();
    for _ in 0..600 {
        let p = DVec3::new(rng.random_range(0.0..=1.0), rng.random_range(0.0..=1.0), rng.random_range(0.0..=1.0))
            * (r.max - r.min)
            + r.min;
        if in_view(problem, p, 0.0) && in_light(light, p) {
            points.push(p);
            if points.len() == 64 {
                break;
            }
        }
    }
    points.extend(r.corners().into_iter().filter(|&p| in_view(problem, p, 0.0) && in_light(light, p)));
    points.extend(problem.camera().frustum_corners().into_iter().filter(|&p| r.contains(p) && in_light(light, p)));
    points
}

struct Checker<'a> {
    problem: &'a ShadowProblem,
    matrix: &'a LightMatrix,
}

impl Checker<'_> {
    fn clip(&self, p: DVec3) -> DVec4 {
        self.matrix.clip_from_world * p.extend(1.0)
    }

    fn depth_ok(&self, z: f64) -> bool {
        z <= 1.0 + DEPTH_SLACK && (z >= -DEPTH_SLACK || self.matrix.needs_unclipped_depth)
    }

    fn check_relevant(&self, p: DVec3, what: &str) -> Result<(), String> {
        let c = self.clip(p);
        if !(c.w > 0.0) {
            return Err(format!("{what} {p} behind the light (w = {})", c.w));
        }
        let ndc = c.truncate() / c.w;
        if !(ndc.x.abs() <= 1.0 + NDC_SLACK && ndc.y.abs() <= 1.0 + NDC_SLACK) {
            return Err(format!("{what} {p} outside the map: ndc {ndc}"));
        }
        if !self.depth_ok(ndc.z) {
            return Err(format!("{what} {p} outside the depth range: z {}", ndc.z));
        }
        self.check_casters(p, ndc.z)
    }

    /// Points between `p` and the light that lie in the caster box.
    fn check_casters(&self, p: DVec3, z_p: f64) -> Result<(), String> {
        let casters = self.problem.bounds().casters;
        let reach = self.problem.scale() * 4.0;
        for t in [1e-4, 1e-3, 0.01, 0.05, 0.1, 0.2, 0.35, 0.5, 0.65, 0.8, 0.9, 0.99] {
            let q = match *self.problem.light() {
                Light::Directional { direction } => p - direction * (t * reach),
                Light::Point { position } | Light::Spot { position, .. } => position + (p - position) * t,
            };
            if !casters.contains(q) {
                continue;
            }
            let c = self.clip(q);
            if !(c.w > 0.0) {
                return Err(format!("caster {q} (shadowing {p}) behind the light"));
            }
            let ndc = c.truncate() / c.w;
            if !self.depth_ok(ndc.z) {
                return Err(format!("caster {q} (shadowing {p}) outside the depth range: z {}", ndc.z));
            }
            if ndc.z.max(0.0) > z_p.max(0.0) + 1e-9 {
                return Err(format!("caster {q} is deeper ({}) than the point it shadows ({z_p})", ndc.z));
            }
        }
        Ok(())
    }
}

fn error_is_justified(problem: &ShadowProblem, err: &LixelError, param: &Parameterization, sample: &[DVec3]) -> bool {
    let scale = problem.scale();
    match err {
        LixelError::LightInsideFocus { .. } => {
            // Point lights only: a spot under 89° always fits its own frustum.
            let Light::Point { position: l } = *problem.light() else { return false };
            let in_receivers = expand(&problem.bounds().receivers, 1e-6 * scale).contains(l);
            // Normal and focused-snapped aim along the cone around all receivers.
            let whole = matches!(param, Parameterization::Normal | Parameterization::FocusedSnapped(_));
            in_receivers && (whole || in_view(problem, l, 1e-6))
        }
        LixelError::NothingVisible { .. } => {
            sample.is_empty()
                && matches!(*problem.light(), Light::Point { position } if problem.bounds().receivers.contains(position))
        }
        LixelError::NothingLit { .. } => matches!(problem.light(), Light::Spot { .. }) && sample.is_empty(),
        _ => false,
    }
}

/// Runs `param` over `common::cases()` general configurations and half as
/// many drawn from the hard regions ([`common::hard_config`]).
fn run(param: Parameterization, seed: u64) {
    let n = common::cases();
    let hard = n / 2;
    let mut outcomes: BTreeMap<String, usize> = BTreeMap::new();
    let mut failures = Vec::new();
    let mut checked_points = 0usize;
    for i in 0..n + hard {
        let (config, region) = if i < n {
            (common::config(seed, i), "general".to_string())
        } else {
            let (config, region) = common::hard_config(seed, i - n);
            (config, format!("{region:?}"))
        };
        let Some(problem) = config.problem() else {
            *outcomes.entry(format!("{region}: invalid input")).or_default() += 1;
            continue;
        };
        let mut rng = ChaCha8Rng::seed_from_u64(i as u64);
        let sample = relevant_points(&problem, &mut rng);
        match problem.solve(&param) {
            Ok(matrix) => {
                let key = match matrix.fallback {
                    Some(f) => format!("fallback {f:?}").split(' ').take(2).collect::<Vec<_>>().join(" "),
                    None => "ok".to_string(),
                };
                *outcomes.entry(format!("{region}: {key}")).or_default() += 1;
                if !matrix.clip_from_world.is_finite() {
                    failures.push(format!("#{i} ({region}): non-finite matrix\n{config:?}"));
                    continue;
                }
                let checker = Checker { problem: &problem, matrix: &matrix };
                let l = problem.light().position();
                let away_from_light = |p: &DVec3| l.is_none_or(|l| (*p - l).length() > 1e-6 * problem.scale());
                let mut points: Vec<(DVec3, &str)> = sample.iter().map(|&p| (p, "receiver")).collect();
                points.extend(
                    problem
                        .visible_receiver_body()
                        .vertices()
                        .iter()
                        .filter(|p| away_from_light(p))
                        .map(|&p| (p, "body vertex")),
                );
                if matches!(param, Parameterization::Psm(_)) && matrix.fallback.is_none() {
                    points.extend(
                        problem.psm_hull().vertices().iter().filter(|p| away_from_light(p)).map(|&p| (p, "H vertex")),
                    );
                }
                checked_points += points.len();
                if let Some(e) = points.iter().find_map(|&(p, what)| checker.check_relevant(p, what).err()) {
                    failures.push(format!("#{i} ({region}): {e}\n  fallback {:?}\n  {config:?}", matrix.fallback));
                }
            }
            Err(e) => {
                *outcomes
                    .entry(format!("{region}: error {e:?}").split([' ', '{']).take(3).collect::<Vec<_>>().join(" "))
                    .or_default() += 1;
                if !error_is_justified(&problem, &e, &param, &sample) {
                    failures.push(format!("#{i} ({region}): unjustified error {e}\n  {config:?}"));
                }
            }
        }
    }
    eprintln!(
        "{:?}: {n} general + {hard} hard configurations, {checked_points} relevant points checked: {outcomes:#?}",
        param.method()
    );
    assert!(
        failures.is_empty(),
        "{} of {} configurations failed; first ones:\n{}",
        failures.len(),
        n + hard,
        failures[..failures.len().min(5)].join("\n")
    );
}

#[test]
fn normal_keeps_every_relevant_point() {
    run(Parameterization::Normal, 1);
}

#[test]
fn focused_keeps_every_relevant_point() {
    run(Parameterization::Focused, 2);
}

#[test]
fn focused_snapped_keeps_every_relevant_point() {
    run(Parameterization::FocusedSnapped(Default::default()), 7);
}

#[test]
fn psm_keeps_every_relevant_point() {
    run(Parameterization::Psm(Default::default()), 3);
}

#[test]
fn lispsm_keeps_every_relevant_point() {
    run(Parameterization::LiSpsm(Default::default()), 4);
}

#[test]
fn lispsm_simple_keeps_every_relevant_point() {
    run(Parameterization::LiSpsm(lixel::LiSpsmOptions { n_opt: lixel::NOpt::Simple, ..Default::default() }), 5);
}

#[test]
fn plane_optimal_keeps_every_relevant_point() {
    run(Parameterization::PlaneOptimal(Default::default()), 6);
}

/// `m` scaled to unit Frobenius norm.
fn normalized(m: &DMat4) -> DMat4 {
    let n = m.to_cols_array().iter().map(|v| v * v).sum::<f64>().sqrt();
    *m * (1.0 / n)
}

/// Smallest relative distance between `a` and `b` over the map's harmless
/// symmetries: NDC x and y mirrored, swapped, or both (eight signed
/// permutations of the first two rows).
fn distance_modulo_rectangle(a: &DMat4, b: &DMat4) -> f64 {
    let (a, b) = (normalized(a), normalized(b));
    let mut best = f64::INFINITY;
    for swap in [false, true] {
        for sx in [1.0, -1.0] {
            for sy in [1.0, -1.0] {
                let (r0, r1) = if swap { (a.row(1), a.row(0)) } else { (a.row(0), a.row(1)) };
                let m = DMat4::from_cols(r0 * sx, r1 * sy, a.row(2), a.row(3)).transpose();
                let d = (m - b).to_cols_array().iter().map(|v| v * v).sum::<f64>().sqrt();
                best = best.min(d);
            }
        }
    }
    best
}

/// Continuity: a 1e-9 relative nudge of the light may flip the map's
/// rectangle (mirror or 90° swap, harmless) but otherwise moves the matrix by
/// a comparable amount. Counted over general configurations. Jumps where a
/// method switches branch (a fallback starts or stops) are legitimate; jumps
/// within one branch are a known gap: about 0.15% of matrices (issue 10,
/// seed 21: 7 of 4628, 6 of them PSM; the minimum-area rectangle's tie-break
/// removed 16 more). The test fails above 1%.
#[test]
fn a_tiny_light_nudge_moves_every_matrix_continuously() {
    let n = common::cases() / 4;
    let mut jumps: BTreeMap<String, usize> = BTreeMap::new();
    let mut compared = 0usize;
    let mut failures = Vec::new();
    for i in 0..n {
        let config = common::config(21, i);
        let Some(problem) = config.problem() else { continue };
        let mut nudged = config;
        nudged.light = match config.light {
            Light::Directional { direction } => Light::directional(direction + DVec3::new(1e-9, -1e-9, 0.5e-9)),
            Light::Point { position } => Light::point(position + DVec3::new(1e-9, -1e-9, 0.5e-9) * problem.scale()),
            Light::Spot { position, direction, outer_half_angle_radians } => Light::spot(
                position + DVec3::new(1e-9, -1e-9, 0.5e-9) * problem.scale(),
                direction,
                outer_half_angle_radians,
            ),
        };
        let Some(other) = nudged.problem() else { continue };
        for p in Parameterization::ALL_DEFAULT {
            let (Ok(a), Ok(b)) = (problem.solve(&p), other.solve(&p)) else { continue };
            compared += 1;
            let d = distance_modulo_rectangle(&a.clip_from_world, &b.clip_from_world);
            if d > 1e-4 {
                let same_branch = std::mem::discriminant(&a.fallback) == std::mem::discriminant(&b.fallback)
                    && a.fallback.map(|f| format!("{f:?}").split(' ').next().map(str::to_owned))
                        == b.fallback.map(|f| format!("{f:?}").split(' ').next().map(str::to_owned));
                let key = format!("{:?} {}", p.method(), if same_branch { "same branch" } else { "branch switch" });
                *jumps.entry(key).or_default() += 1;
                if same_branch {
                    failures.push(format!("#{i} {:?}: moved {d:e} for a 1e-9 nudge\n  {config:?}", p.method()));
                }
            }
        }
    }
    eprintln!("{compared} matrices compared; jumps beyond 1e-4: {jumps:#?}");
    for f in failures.iter().take(3) {
        eprintln!("{f}");
    }
    assert!(
        failures.len() * 100 <= compared,
        "{} discontinuities within one branch (more than 1 in 100); first ones:\n{}",
        failures.len(),
        failures[..failures.len().min(5)].join("\n")
    );
}
