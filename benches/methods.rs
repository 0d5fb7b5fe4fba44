//! One criterion bench per classical method, over a fixed set of seeded
//! configurations (the property tests' generator).

#[path = "../tests/common/mod.rs"]
mod common;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use lixel::{Parameterization, ShadowProblem};

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

criterion_group!(benches, methods);
criterion_main!(benches);
