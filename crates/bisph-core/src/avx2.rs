//! What the sweeps in AVX2 lanes share: the run-time check for the instructions and the
//! transpose of four rows of four values.

/// `true` when the processor has AVX2 (checked at run time; never off x86-64).
#[cfg(target_arch = "x86_64")]
pub(crate) fn available() -> bool {
    std::arch::is_x86_feature_detected!("avx2")
}

/// `true` when the processor has AVX2 (checked at run time; never off x86-64).
#[cfg(not(target_arch = "x86_64"))]
pub(crate) fn available() -> bool {
    false
}

/// The 4 x 4 transpose of four rows: the rows' first components in one register, then their
/// second, third and fourth.
///
/// # Safety
/// The processor has AVX2.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn transpose(
    rows: [std::arch::x86_64::__m256d; 4],
) -> [std::arch::x86_64::__m256d; 4] {
    use std::arch::x86_64::*;
    let low01 = _mm256_unpacklo_pd(rows[0], rows[1]);
    let high01 = _mm256_unpackhi_pd(rows[0], rows[1]);
    let low23 = _mm256_unpacklo_pd(rows[2], rows[3]);
    let high23 = _mm256_unpackhi_pd(rows[2], rows[3]);
    [
        _mm256_permute2f128_pd(low01, low23, 0x20),
        _mm256_permute2f128_pd(high01, high23, 0x20),
        _mm256_permute2f128_pd(low01, low23, 0x31),
        _mm256_permute2f128_pd(high01, high23, 0x31),
    ]
}
