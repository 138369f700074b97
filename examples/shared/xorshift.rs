//! The pseudo-random numbers of the table-error examples: xorshift64, a fixed seed, so
//! every run checks the same points.

/// Uniform numbers in [0, 1), the same sequence on every run.
pub fn uniform() -> impl FnMut() -> f64 {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}
