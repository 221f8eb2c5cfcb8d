//! The listed sweep of the pressure gradient and the velocity divergence in 3-D (paper 1,
//! eqs 10-11, each pair once for both particles) with the four components of a pair's share
//! (`grad p` and `div u`) in the four lanes of one AVX2 register, on processors that have
//! AVX2 (checked at run time). The single-precision kernel gradients of the list are widened
//! exactly, as the scalar sweep widens them; every lane performs the operations of
//! [`super::pair_shares`] on its component, in its order (the dot product's terms are added
//! left to right), or ones with the same result in every case (a sign moved from one factor
//! of a product to the other), and no multiply-add is fused: the sums have the bits of the
//! scalar sweep.

use super::{GradientSums, Side};
use crate::dim::Vector;
use crate::neighbours::{ListedPairs, Listing};
use glam::DVec3;
use std::any::TypeId;

/// Sweeps `listed` into `sums` with the lanes when the pairs carry their kernel gradients
/// ([`Listing::Product`]), the space is 3-D and the processor has AVX2; returns `false`, having
/// done nothing, otherwise. `sides` are the particles' packed values.
pub(super) fn sweep_listed_gradients<V: Vector>(
    sides: &[Side<V>],
    listed: &ListedPairs<V>,
    sums: &mut [GradientSums<V>],
) -> bool {
    if TypeId::of::<V>() != TypeId::of::<DVec3>()
        || listed.listing() != Listing::Product
        || !has_avx2()
    {
        return false;
    }
    // SAFETY: `V` is `DVec3` (checked above), so each cast names the type it already has.
    let (sides, listed, sums) = unsafe {
        (
            &*(sides as *const [Side<V>] as *const [Side<DVec3>]),
            &*(listed as *const ListedPairs<V> as *const ListedPairs<DVec3>),
            &mut *(sums as *mut [GradientSums<V>] as *mut [GradientSums<DVec3>]),
        )
    };
    listed.sweep_single(sums, |i, run, index, gradient| {
        // SAFETY: AVX2 is present (checked above); the run's particle and partners are its
        // task's alone (`RunValues::all`), `i` and `index` index `sides` (the list's points,
        // checked against `sums`, which has the length of `sides`), and `gradient` holds three
        // components per partner and the padding after them (`ListedPairs::sweep_single`).
        unsafe { x86::scatter_run(sides, i, run.all(), index, gradient) }
    });
    true
}

#[cfg(target_arch = "x86_64")]
fn has_avx2() -> bool {
    std::arch::is_x86_feature_detected!("avx2")
}

#[cfg(not(target_arch = "x86_64"))]
fn has_avx2() -> bool {
    false
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::{GradientSums, Side};
    use glam::DVec3;
    use std::arch::x86_64::*;

    /// The shares of the pairs of `i` with `index[k]` (kernel gradients at `gradient[3 k..]`,
    /// single precision) added to `sums[i]` (summed in a register over the run) and to
    /// `sums[index[k]]`.
    ///
    /// Both particles' shares are one register of gradient lanes `(g, d)`, `d = (u_b - u_a) . g`
    /// in the fourth, times a register of coefficients: `(-(p_a + p_b) V_b, .., -V_b)` for `i`
    /// and `((p_a + p_b) V_a, .., -V_a)` for the partner. `d (-V) = (-d) V` exactly, so the
    /// fourth lanes carry the divergence shares `q V` of [`super::super::velocity_divergence`]
    /// with their bits.
    ///
    /// # Safety
    /// The processor has AVX2; `sums` points to the sums of every particle of `sides`, no
    /// other task writes those of `i` and of the run's partners; `i` and every `index[k]`
    /// (none equal to `i`) index `sides`; `gradient` is readable for `3 len + 1` values.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn scatter_run(
        sides: &[Side<DVec3>],
        i: usize,
        sums: *mut GradientSums<DVec3>,
        index: &[u32],
        gradient: *const f32,
    ) {
        let sides = sides.as_ptr() as *const f64;
        let sums = sums as *mut f64;
        // A side is 6 values: (x, y, z, density) of the velocity row, then (pressure, volume);
        // a particle's sums 4: (grad p, div u).
        let a = sides.add(6 * i);
        let u_a = _mm256_loadu_pd(a);
        let p_a = _mm256_broadcast_sd(&*a.add(4));
        let volume_a = _mm256_broadcast_sd(&*a.add(5));
        // The fourth lane of the coefficients, and the sign of their first three for `i`.
        let minus_one = _mm256_set1_pd(-1.0);
        let negate_xyz = _mm256_set_pd(0.0, -0.0, -0.0, -0.0);
        let own = sums.add(4 * i);
        let mut sum_own = _mm256_loadu_pd(own);
        let mut g = gradient;
        for &j in index {
            let b = sides.add(6 * j as usize);
            // (x, y, z) widened; the fourth value (the next pair's, or padding) is replaced
            // below and its product with the density difference is not read.
            let g4 = _mm256_cvtps_pd(_mm_loadu_ps(g));
            g = g.add(3);
            // d = (u_b - u_a) . g, its terms added x, y, then z.
            let product = _mm256_mul_pd(_mm256_sub_pd(_mm256_loadu_pd(b), u_a), g4);
            let low = _mm256_castpd256_pd128(product);
            let xy = _mm_add_sd(low, _mm_unpackhi_pd(low, low));
            let d = _mm_add_sd(xy, _mm256_extractf128_pd(product, 1));
            let gd = _mm256_blend_pd(g4, _mm256_broadcastsd_pd(d), 0b1000);
            // (p_a + p_b, .., -1), times V_a for the partner, negated in x, y, z and times V_b
            // for `i`.
            let sum = _mm256_add_pd(p_a, _mm256_broadcast_sd(&*b.add(4)));
            let coefficients = _mm256_blend_pd(sum, minus_one, 0b1000);
            let to_partner = _mm256_mul_pd(coefficients, volume_a);
            let to_own = _mm256_mul_pd(
                _mm256_xor_pd(coefficients, negate_xyz),
                _mm256_broadcast_sd(&*b.add(5)),
            );
            sum_own = _mm256_add_pd(sum_own, _mm256_mul_pd(gd, to_own));
            let partner = sums.add(4 * j as usize);
            let shared = _mm256_add_pd(_mm256_loadu_pd(partner), _mm256_mul_pd(gd, to_partner));
            _mm256_storeu_pd(partner, shared);
        }
        _mm256_storeu_pd(own, sum_own);
    }
}

#[cfg(not(target_arch = "x86_64"))]
mod x86 {
    use super::{GradientSums, Side};
    use glam::DVec3;

    /// Never called: no processor but x86-64 is taken for AVX2.
    pub(super) unsafe fn scatter_run(
        _: &[Side<DVec3>],
        _: usize,
        _: *mut GradientSums<DVec3>,
        _: &[u32],
        _: *const f32,
    ) {
        unreachable!("the lanes need AVX2")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::neighbours::{CellGrid, PairBlocks};
    use crate::terms::{pressure_gradient, velocity_divergence};

    /// `x` in `[-1, 1)` from the state `s` (xorshift).
    fn random(s: &mut u64) -> f64 {
        *s ^= *s << 13;
        *s ^= *s >> 7;
        *s ^= *s << 17;
        (*s >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }

    #[test]
    fn the_lanes_give_the_bits_of_the_pair_terms() {
        let mut s = 0x2545_f491_4f6c_dd1d;
        let (n, radius) = (2000, 0.4);
        let points: Vec<DVec3> = (0..n)
            .map(|_| DVec3::new(random(&mut s), random(&mut s), random(&mut s)))
            .collect();
        let sides: Vec<Side<DVec3>> = (0..n)
            .map(|_| Side {
                u: DVec3::new(random(&mut s), random(&mut s), random(&mut s)),
                rho: 1000.0 + random(&mut s),
                p: 1e4 * random(&mut s),
                volume: 1e-3 * (1.5 + random(&mut s)),
            })
            .collect();
        let mut grid = CellGrid::new(radius);
        grid.rebuild(&points);
        let mut blocks = PairBlocks::default();
        blocks.rebuild(&grid, &points, n, radius);
        let mut listed = ListedPairs::default();
        let factor = |r: f64| -(radius - r).powi(3) / radius;
        blocks.list(&points, radius, factor, Listing::Product, &mut listed);
        assert!(listed.pairs() > 10 * n);

        // The scalar sweep: the pair terms of each pair added to both particles in turn.
        let mut scalar = vec![GradientSums::ZERO; n];
        listed.sweep(&mut scalar, |i, run, index, gradient, _| {
            let a = sides[i];
            for (k, (&j, &g)) in index.iter().zip(gradient).enumerate() {
                let b = sides[j as usize];
                let volume = [a.volume, b.volume];
                let p = pressure_gradient::pair_sides(a.p, b.p, g, volume);
                let d = velocity_divergence::pair_sides(a.u, b.u, g, volume);
                let own = run.first();
                own.grad_p += p.0;
                own.div_u += d.0;
                let partner = run.partner(k);
                partner.grad_p += p.1;
                partner.div_u += d.1;
            }
        });
        let mut lanes = vec![GradientSums::ZERO; n];
        if !sweep_listed_gradients(&sides, &listed, &mut lanes) {
            assert!(
                !has_avx2(),
                "the lanes declined a 3-D list of kernel gradients"
            );
            return;
        }
        let bits = |v: &[GradientSums<DVec3>]| -> Vec<[u64; 4]> {
            v.iter()
                .map(|s| {
                    let g = s.grad_p;
                    [g.x, g.y, g.z, s.div_u].map(f64::to_bits)
                })
                .collect()
        };
        assert_eq!(bits(&lanes), bits(&scalar));
        assert!(scalar.iter().all(|s| s.div_u != 0.0));
    }
}
