//! A small deterministic generator for unit tests (xorshift64): reproducible
//! random inputs without a dependency, one definition for every test module.

/// One xorshift64 step (13, 7, 17).
pub(crate) fn step(mut state: u64) -> u64 {
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    state
}

/// Uniform `f64` in `[0, 1)` from the top 53 bits of successive states.
pub(crate) fn unit(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = step(state);
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}
