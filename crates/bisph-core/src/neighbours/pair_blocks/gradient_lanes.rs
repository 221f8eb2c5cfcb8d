//! The listing of a midpoint step's kernel gradients in 3-D ([`Listing::Product`]) with four
//! candidates in the lanes of AVX2 registers, on processors that have AVX2 (checked at run
//! time) and without periodic axes. Each lane performs the operations of the scalar listing
//! on its candidate, in its order, with no multiply-add fused: the offset `x_j - x_i`, its
//! squared length `(x x + y y) + z z`, the filter `r^2 < (2h)^2`, the root, the kernel
//! gradient factor of [`Wendland::gradient_factor`] and the product, rounded to single
//! precision. Kept candidates are written without a branch: every candidate is stored at the
//! next free slot, which only a kept one advances. The list has the bits of the scalar one.
//!
//! [`Listing::Product`]: super::Listing::Product

use super::{BlockChunk, ListedChunk, GRADIENT_PADDING};
use crate::kernel::Wendland;
use glam::DVec3;
use std::arch::x86_64::*;

impl ListedChunk<DVec3> {
    /// Lists the pairs of `from` within the support of `kernel` at `points` with their kernel
    /// gradients, as [`ListedChunk::fill`] does under [`super::Listing::Product`].
    ///
    /// # Safety
    /// The processor has AVX2; every index of `from` indexes `points`.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn fill_gradients(
        &mut self,
        from: &BlockChunk,
        points: &[DVec3],
        kernel: &Wendland,
    ) {
        self.empty();
        let (inv_h, grad_alpha) = kernel.gradient_constants();
        let constants = Constants {
            r2max: _mm256_set1_pd(kernel.support * kernel.support),
            inv_h: _mm256_set1_pd(inv_h),
            grad_alpha: _mm256_set1_pd(grad_alpha),
            half: _mm256_set1_pd(0.5),
            one: _mm256_set1_pd(1.0),
            two: _mm256_set1_pd(2.0),
        };
        let points = points.as_ptr() as *const f64;
        for (r, &i) in from.first.iter().enumerate() {
            let partners = &from.second[from.start[r] as usize..from.start[r + 1] as usize];
            let listed = self.second.len();
            // Room for a store at every candidate and at the repeated ones of a short last
            // group (at most one slot past the candidates), and for the fourth value that a
            // 16-byte store writes.
            self.second.reserve(partners.len() + 1);
            self.gradient.reserve(3 * (partners.len() + 1) + 1);
            let index = self.second.as_mut_ptr().add(listed);
            let gradient = self.gradient.as_mut_ptr().add(3 * listed);
            let x = load_point(points, i as usize);
            let mut kept = 0usize;
            for group in partners.chunks(4) {
                let (j, valid, offset) = candidate_group(points, x, group);
                let (inside, factor) = factors(&offset, &constants);
                let inside = inside & valid;
                for k in 0..4 {
                    let f = match k {
                        0 => _mm256_permute4x64_pd(factor, 0x00),
                        1 => _mm256_permute4x64_pd(factor, 0x55),
                        2 => _mm256_permute4x64_pd(factor, 0xaa),
                        _ => _mm256_permute4x64_pd(factor, 0xff),
                    };
                    let g = _mm256_cvtpd_ps(_mm256_mul_pd(offset[k], f));
                    _mm_storeu_ps(gradient.add(3 * kept), g);
                    *index.add(kept) = j[k];
                    kept += ((inside >> k) & 1) as usize;
                }
            }
            self.second.set_len(listed + kept);
            self.gradient.set_len(3 * (listed + kept));
            if kept > 0 {
                self.first.push(i);
                self.start.push((listed + kept) as u32);
            }
        }
        self.gradient.extend([0.0; GRADIENT_PADDING]);
    }
}

/// The broadcast constants of [`ListedChunk::fill_gradients`].
struct Constants {
    r2max: __m256d,
    inv_h: __m256d,
    grad_alpha: __m256d,
    half: __m256d,
    one: __m256d,
    two: __m256d,
}

/// The point `i` of `points` (three values per point) as `(x, y, z, 0)`.
#[inline]
#[target_feature(enable = "avx2")]
pub(super) unsafe fn load_point(points: *const f64, i: usize) -> __m256d {
    _mm256_maskload_pd(points.add(3 * i), _mm256_set_epi64x(0, -1, -1, -1))
}

/// A group of one to four candidates: the candidates, a short group's last repeated to
/// four (a repeat is never kept); the bits of the group's own; and their offsets from `x`
/// at `points`, `(x_j - x, 0)`.
#[inline]
#[target_feature(enable = "avx2")]
pub(super) unsafe fn candidate_group(
    points: *const f64,
    x: __m256d,
    group: &[u32],
) -> ([u32; 4], u32, [__m256d; 4]) {
    let last = group[group.len() - 1];
    let j = [0, 1, 2, 3].map(|k| group.get(k).copied().unwrap_or(last));
    let offset = j.map(|j| _mm256_sub_pd(load_point(points, j as usize), x));
    (j, (1u32 << group.len()) - 1, offset)
}

/// The squared lengths `(x x + y y) + z z` of four offsets `(x, y, z, _)`, one per lane.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn squared_lengths(offset: &[__m256d; 4]) -> __m256d {
    let [x, y, z, _] = crate::avx2::transpose(*offset);
    _mm256_add_pd(
        _mm256_add_pd(_mm256_mul_pd(x, x), _mm256_mul_pd(y, y)),
        _mm256_mul_pd(z, z),
    )
}

/// For four offsets `(x, y, z, 0)`: the bits of those within the support (`r^2 < r2max`) and
/// their kernel gradient factors, one per lane.
#[target_feature(enable = "avx2")]
unsafe fn factors(offset: &[__m256d; 4], c: &Constants) -> (u32, __m256d) {
    let r2 = squared_lengths(offset);
    let inside = _mm256_movemask_pd(_mm256_cmp_pd(r2, c.r2max, _CMP_LT_OQ)) as u32;
    let q = _mm256_mul_pd(_mm256_sqrt_pd(r2), c.inv_h);
    let a = _mm256_sub_pd(c.one, _mm256_mul_pd(c.half, q));
    let factor = _mm256_mul_pd(_mm256_mul_pd(_mm256_mul_pd(c.grad_alpha, a), a), a);
    // Zero (+0) from q = 2 on, as the scalar factor returns.
    let beyond = _mm256_cmp_pd(q, c.two, _CMP_GE_OQ);
    (inside, _mm256_andnot_pd(beyond, factor))
}

impl super::PairBlocks<DVec3> {
    /// [`super::PairBlocks::list_kernel_gradients`] in the lanes.
    ///
    /// # Safety
    /// The processor has AVX2; the blocks have no periodic axes.
    pub(super) unsafe fn list_gradients_in_lanes(
        &self,
        points: &[DVec3],
        kernel: &Wendland,
        listed: &mut super::ListedPairs<DVec3>,
    ) {
        use rayon::prelude::*;
        assert!(
            points.len() >= self.len(),
            "fewer points than the blocks list"
        );
        listed.len = self.len();
        listed.listing = super::Listing::Product;
        listed.classes.resize_with(self.classes.len(), Vec::new);
        for (to, from) in listed.classes.iter_mut().zip(&self.classes) {
            to.resize_with(from.len(), Default::default);
            to.par_iter_mut()
                .zip(from.par_iter())
                .for_each(|(to, from)| {
                    // SAFETY: AVX2 is present (the caller's promise); the blocks index `points`
                    // (checked above).
                    unsafe { to.fill_gradients(from, points, kernel) }
                });
        }
    }
}
