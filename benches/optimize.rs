//! Scene optimization per light from seeded synthetic readbacks: building the
//! samples from the readback plus `Optimizer::optimize`, the work an engine
//! does per light every few frames. The readbacks (CPU ray casts) are made
//! once, outside the timed loop.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::{DVec3, UVec2};
use lixel::optimize::{self, OptimizeOptions, Optimizer, SampleOptions};
use lixel::synthetic::{Sphere, SyntheticReadback, SyntheticScene};
use lixel::{Aabb, Camera, Light, Samples, ShadowMapSize, ShadowProblem};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The paper's walkthrough: a viewer just above a floor with a few dozen objects.
fn scene() -> SyntheticScene {
    let mut rng = ChaCha8Rng::seed_from_u64(2006);
    let mut s = SyntheticScene { floor: Some((0.0, 40.0)), ..Default::default() };
    for _ in 0..36 {
        let at = DVec3::new(rng.random_range(-30.0..30.0), 0.0, rng.random_range(-35.0..5.0));
        if rng.random_bool(0.5) {
            let r = rng.random_range(0.4..2.0);
            s.spheres.push(Sphere { center: at + DVec3::Y * rng.random_range(r..r + 2.0), radius: r });
        } else {
            let size = DVec3::new(rng.random_range(0.4..3.0), rng.random_range(0.5..5.0), rng.random_range(0.4..3.0));
            s.boxes
                .push(Aabb::from_corners(at - size * DVec3::new(0.5, 0.0, 0.5), at + size * DVec3::new(0.5, 1.0, 0.5)));
        }
    }
    s
}

fn lights(count: usize) -> Vec<Light> {
    (0..count)
        .map(|k| {
            let a = k as f64 * 2.399;
            Light::directional(DVec3::new(a.cos(), -1.3 - 0.1 * (k % 3) as f64, a.sin()))
        })
        .collect()
}

struct Setup {
    problems: Vec<ShadowProblem>,
    readback: SyntheticReadback,
}

fn setup(size: u32, light_count: usize) -> Setup {
    let camera = Camera::look_at(
        DVec3::new(0.0, 1.7, 10.0),
        DVec3::new(0.0, 1.0, -10.0),
        DVec3::Y,
        60f64.to_radians(),
        UVec2::new(1150, 1150),
        0.1,
        150.0,
    )
    .expect("camera");
    let scene = scene();
    let lights = lights(light_count);
    let bounds = scene.bounds().expect("bounds");
    let problems = lights
        .iter()
        .map(|&l| ShadowProblem::new(camera, l, bounds, ShadowMapSize::square(1024)).expect("problem"))
        .collect();
    Setup { problems, readback: scene.render(&camera, &lights, size, size) }
}

fn optimize_lights(setup: &Setup, optimizer: &mut Optimizer) -> usize {
    let readback = setup.readback.as_readback(false);
    let mut boundary = 0;
    for (bit, problem) in setup.problems.iter().enumerate() {
        let samples =
            Samples::from_readback(problem, &readback, bit as u32, &SampleOptions::default()).expect("samples");
        boundary += samples.boundary().len();
        let result = optimizer.optimize(&samples, None).expect("optimize");
        std::hint::black_box(result);
    }
    boundary
}

fn by_resolution(c: &mut Criterion) {
    let mut group = c.benchmark_group("optimize/one_light");
    for size in [64u32, 128, 180, 256, 512] {
        let setup = setup(size, 1);
        let mut optimizer = Optimizer::new(OptimizeOptions::default());
        let boundary = optimize_lights(&setup, &mut optimizer);
        eprintln!("{size}x{size}: {boundary} boundary samples");
        group.throughput(Throughput::Elements(u64::from(size * size)));
        group.bench_with_input(BenchmarkId::from_parameter(format!("{size}x{size}")), &setup, |b, s| {
            b.iter(|| optimize_lights(s, &mut optimizer));
        });
    }
    group.finish();
}

fn by_lights(c: &mut Criterion) {
    let mut group = c.benchmark_group("optimize/180x180");
    group.sample_size(20);
    for lights in [1usize, 4, 32] {
        let setup = setup(180, lights);
        let mut optimizer = Optimizer::new(OptimizeOptions::default());
        group.throughput(Throughput::Elements(lights as u64));
        group.bench_with_input(BenchmarkId::new("lights", lights), &setup, |b, s| {
            b.iter(|| optimize_lights(s, &mut optimizer));
        });
    }
    group.finish();
}

/// Sample extraction alone for 1/4/32 lights at 180x180: one light at a
/// time (`from_readback` per light), all lights in one pass, and all lights
/// into reused samples (`from_readback_all_into`).
fn extraction(c: &mut Criterion) {
    let mut group = c.benchmark_group("optimize/extract_180x180");
    group.sample_size(20);
    for lights in [1usize, 4, 32] {
        let setup = setup(180, lights);
        group.throughput(Throughput::Elements(lights as u64));
        group.bench_with_input(BenchmarkId::new("per_light", lights), &setup, |b, s| {
            let readback = s.readback.as_readback(false);
            b.iter(|| {
                s.problems
                    .iter()
                    .enumerate()
                    .map(|(bit, p)| {
                        Samples::from_readback(p, &readback, bit as u32, &SampleOptions::default())
                            .expect("samples")
                            .boundary()
                            .len()
                    })
                    .sum::<usize>()
            });
        });
        group.bench_with_input(BenchmarkId::new("all_lights", lights), &setup, |b, s| {
            let readback = s.readback.as_readback(false);
            b.iter(|| {
                Samples::from_readback_all(&s.problems, &readback, &SampleOptions::default())
                    .expect("samples")
                    .iter()
                    .map(|samples| samples.boundary().len())
                    .sum::<usize>()
            });
        });
        // Into the previous iteration's samples and workspace (an engine's
        // frame loop): the same work without allocation once warm.
        group.bench_with_input(BenchmarkId::new("all_lights_into", lights), &setup, |b, s| {
            let readback = s.readback.as_readback(false);
            let (mut out, mut workspace) = (Vec::new(), optimize::SampleWorkspace::new());
            b.iter(|| {
                Samples::from_readback_all_into(
                    &s.problems,
                    &readback,
                    &SampleOptions::default(),
                    &mut out,
                    &mut workspace,
                )
                .expect("samples");
                out.iter().map(|samples| samples.boundary().len()).sum::<usize>()
            });
        });
    }
    group.finish();
}

/// 1/4/32 lights together at 180x180, as an engine runs them: all lights'
/// samples in one pass, then `optimize_lights` (parallel with `rayon`).
fn together(c: &mut Criterion) {
    let mut group = c.benchmark_group("optimize/180x180_together");
    group.sample_size(20);
    for lights in [1usize, 4, 32] {
        let setup = setup(180, lights);
        let mut optimizers = vec![Optimizer::new(OptimizeOptions::default()); lights];
        let prev = vec![None; lights];
        group.throughput(Throughput::Elements(lights as u64));
        group.bench_with_input(BenchmarkId::new("lights", lights), &setup, |b, s| {
            let readback = s.readback.as_readback(false);
            b.iter(|| {
                let samples =
                    Samples::from_readback_all(&s.problems, &readback, &SampleOptions::default()).expect("samples");
                let results = optimize::optimize_lights(&mut optimizers, &samples, &prev).expect("lengths");
                std::hint::black_box(results).len()
            });
        });
    }
    group.finish();
}

criterion_group!(benches, by_resolution, by_lights, extraction, together);
criterion_main!(benches);
