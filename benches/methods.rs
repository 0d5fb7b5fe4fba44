//! One criterion bench per classical method, over a fixed set of seeded
//! configurations (the property tests' generator: random cameras), and on a
//! fixed camera with the same lights. Both go through `ShadowProblem::solve`
//! (its per-thread workspace: no allocation once warm). A third group solves
//! the fixed camera's problems each through its own `SolveWorkspace`, as an
//! engine keeping a workspace per light does from frame to frame while
//! camera and lights stand still (every cache hits).

#[path = "../tests/common/mod.rs"]
mod common;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use lixel::{Parameterization, ShadowProblem, SolveWorkspace};

fn problems() -> Vec<ShadowProblem> {
    (0..64).filter_map(|i| common::config(42, i).problem()).collect()
}

fn methods(c: &mut Criterion) {
    let problems = problems();
    let mut group = c.benchmark_group("methods");
    for parameterization in Parameterization::ALL_DEFAULT {
        group.bench_with_input(
            BenchmarkId::new(parameterization.method().name(), problems.len()),
            &parameterization,
            |b, p| {
                b.iter(|| problems.iter().map(|problem| problem.solve(p).is_ok() as usize).sum::<usize>());
            },
        );
    }
    group.finish();
}

/// The frame-to-frame case: one camera and scene bounds (the first seeded
/// configuration's) with the 64 seeded configurations' lights. `solve` keeps
/// a per-thread workspace whose camera cache (view planes, `V ∩ R`, `V`)
/// then hits for every point and directional light (its per-light entries
/// miss: the light changes on every call); on the random configurations
/// above every call misses it.
fn fixed_camera(c: &mut Criterion) {
    let all = problems();
    let first = &all[0];
    let problems: Vec<ShadowProblem> = all
        .iter()
        .filter_map(|p| ShadowProblem::new(*first.camera(), *p.light(), *first.bounds(), first.map_size()).ok())
        .collect();
    let mut group = c.benchmark_group("methods_fixed_camera");
    for parameterization in Parameterization::ALL_DEFAULT {
        group.bench_with_input(
            BenchmarkId::new(parameterization.method().name(), problems.len()),
            &parameterization,
            |b, p| {
                b.iter(|| problems.iter().map(|problem| problem.solve(p).is_ok() as usize).sum::<usize>());
            },
        );
    }
    group.finish();
}

/// [`fixed_camera`]'s problems, each solved through its own workspace
/// (`solve_with`): the camera cache and the caster-body cache both hit, as
/// for an engine's static lights under a still camera. The methods still
/// run in full from those bodies on (cone, axis, fit, depth range).
fn fixed_camera_per_light(c: &mut Criterion) {
    let all = problems();
    let first = &all[0];
    let problems: Vec<ShadowProblem> = all
        .iter()
        .filter_map(|p| ShadowProblem::new(*first.camera(), *p.light(), *first.bounds(), first.map_size()).ok())
        .collect();
    let mut group = c.benchmark_group("methods_fixed_camera_per_light");
    for parameterization in Parameterization::ALL_DEFAULT {
        let mut workspaces: Vec<SolveWorkspace> = problems.iter().map(|_| SolveWorkspace::new()).collect();
        group.bench_with_input(
            BenchmarkId::new(parameterization.method().name(), problems.len()),
            &parameterization,
            |b, p| {
                b.iter(|| {
                    problems
                        .iter()
                        .zip(&mut workspaces)
                        .map(|(problem, workspace)| problem.solve_with(p, workspace).is_ok() as usize)
                        .sum::<usize>()
                });
            },
        );
    }
    group.finish();
}

criterion_group!(benches, methods, fixed_camera, fixed_camera_per_light);
criterion_main!(benches);
