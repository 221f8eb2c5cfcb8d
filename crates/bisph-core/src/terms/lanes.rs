//! The scatter sweeps in 3-D in the lanes of AVX2 registers, on processors that have AVX2
//! (checked at run time), each pair once for both particles:
//! - the listed sweep of a midpoint step's pressure gradient and velocity divergence (paper 1,
//!   eqs 10-11), the four components of a pair's share (`grad p` and `div u`) in the four
//!   lanes of one register, the single-precision kernel gradients of the list widened exactly
//!   as the scalar sweep widens them;
//! - the explicit step's sweep of the Verlet list filtered at the positions, with the
//!   density diffusion in its Laplacian form (delta-SPH): four pairs at a time, one pair per
//!   lane, their shares transposed to one register per pair for the sums.
//!
//! Every lane performs the operations of [`super::pair_shares`] on its value, in its order
//! (the dot products' terms are added left to right), or ones with the same result in every
//! case (a sign moved from one factor of a product to the other), no multiply-add is fused,
//! and each particle receives its shares in the scalar sweep's order: the sums have the bits
//! of the scalar sweep.

use super::{FluidSums, GradientSums, RateModel, Side};
use crate::dim::Vector;
use crate::eos::Eos;
use crate::neighbours::{ListedPairs, Listing, PairBlocks};
use crate::terms::DiffusionForm;
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
        || !crate::avx2::available()
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

/// Sweeps the Verlet list `pairs`, filtered at `positions`, into `sums` with the lanes: the
/// pressure gradient, the velocity divergence and the density diffusion of `model` (paper 1
/// eqs 10-11, [`super::density_diffusion`]) when the space is 3-D, the list has no periodic
/// axes, the processor has AVX2 and the diffusion takes its Laplacian form with no
/// hydrostatic correction or that of a linear equation of state; returns `false`, having done
/// nothing, otherwise. `sides` are the particles' packed values.
pub(super) fn sweep_filtered_diffused<V: Vector>(
    model: &RateModel<V>,
    positions: &[V],
    sides: &[Side<V>],
    pairs: &PairBlocks<V>,
    sums: &mut [FluidSums<V>],
) -> bool {
    if TypeId::of::<V>() != TypeId::of::<DVec3>() || !crate::avx2::available() {
        return false;
    }
    // SAFETY: `V` is `DVec3` (checked above), so each cast names the type it already has.
    let (model, positions, sides, pairs, sums) = unsafe {
        (
            &*(model as *const RateModel<V> as *const RateModel<DVec3>),
            &*(positions as *const [V] as *const [DVec3]),
            &*(sides as *const [Side<V>] as *const [Side<DVec3>]),
            &*(pairs as *const PairBlocks<V> as *const PairBlocks<DVec3>),
            &mut *(sums as *mut [FluidSums<V>] as *mut [FluidSums<DVec3>]),
        )
    };
    let diffusion = &model.diffusion;
    let hydrostatic = diffusion.hydrostatic_gradient;
    let linear = matches!(diffusion.eos, Eos::Linear { .. });
    if diffusion.form != DiffusionForm::Laplacian || (hydrostatic != DVec3::ZERO && !linear) {
        return false;
    }
    let (inv_h, grad_alpha) = model.kernel.gradient_constants();
    let constants = Diffused {
        inv_h,
        grad_alpha,
        minus_two_scale: -2.0 * diffusion.scale,
        hydrostatic: hydrostatic.to_array(),
        rho0: diffusion.eos.rho0(),
    };
    x86_diffused::sweep(
        &constants,
        model.kernel.support,
        positions,
        sides,
        pairs,
        sums,
    )
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

/// The constants of [`sweep_filtered_diffused`]: the kernel's `1/h` and gradient constant,
/// `-2 delta h c0` of the diffusion, its hydrostatic gradient `rho0 g / c0^2` and the linear
/// equation of state's `rho0`.
struct Diffused {
    inv_h: f64,
    grad_alpha: f64,
    minus_two_scale: f64,
    hydrostatic: [f64; 3],
    rho0: f64,
}

#[cfg(target_arch = "x86_64")]
mod x86_diffused {
    use super::{Diffused, FluidSums, PairBlocks, Side};
    use crate::avx2::transpose;
    use glam::DVec3;
    use std::arch::x86_64::*;

    /// The sweep of [`super::sweep_filtered_diffused`] with `constants`, the pairs filtered
    /// within `support`; `false` where the list declines the lanes.
    pub(in super::super) fn sweep(
        constants: &Diffused,
        support: f64,
        positions: &[DVec3],
        sides: &[Side<DVec3>],
        pairs: &PairBlocks<DVec3>,
        sums: &mut [FluidSums<DVec3>],
    ) -> bool {
        pairs.sweep_rows_in_lanes(positions, support, sums, |i, run, n, index, slot| {
            // SAFETY: AVX2 is present (checked by the sweep); the run's particle and partners
            // are its task's alone (`RunValues::all`); `i` and `index` index `sides` (the
            // list's points, checked against `sums`, which has the length of `sides`);
            // `index` and `slot` hold `n` rounded up to a multiple of four entries.
            unsafe { scatter_diffused_row(constants, sides, i, run.all(), n, index, slot) }
        })
    }

    /// Values per particle's [`FluidSums`]: `(grad p, div u)`, the diffusion, then the
    /// viscous and Shepard sums that this sweep leaves as they are.
    const STRIDE: usize = 9;
    const _: () = assert!(std::mem::size_of::<FluidSums<DVec3>>() == 8 * STRIDE);

    /// The shares of the pairs of `i` with `index[k]` (offsets and squared lengths in
    /// `slot[k]`, `k < n`) added to `sums[i]` (summed in registers over the row) and to
    /// `sums[index[k]]`: four pairs at a time, `(x, y, z, r^2)` transposed into one register
    /// each, and so the partners' values; the shares to each particle transposed back to one
    /// register per pair.
    ///
    /// # Safety
    /// The processor has AVX2; `sums` points to the sums of every particle of `sides`, no
    /// other task writes those of `i` and of the row's partners; `i` and every `index[k]`
    /// (none equal to `i`) index `sides`; `index` and `slot` hold `n` rounded up to a
    /// multiple of four entries.
    #[target_feature(enable = "avx2")]
    unsafe fn scatter_diffused_row(
        c: &Diffused,
        sides: &[Side<DVec3>],
        i: usize,
        sums: *mut FluidSums<DVec3>,
        n: usize,
        index: &[u32],
        slot: &[[f64; 4]],
    ) {
        debug_assert!(index.len() >= n.next_multiple_of(4) && slot.len() >= index.len());
        let sides = sides.as_ptr() as *const f64;
        let sums = sums as *mut f64;
        let slot = slot.as_ptr() as *const f64;
        // A side is 6 values: (x, y, z, density) of the velocity row, then (pressure, volume).
        let a = sides.add(6 * i);
        let [ux_a, uy_a, uz_a, rho_a, p_a, v_a] =
            [0, 1, 2, 3, 4, 5].map(|k| _mm256_broadcast_sd(&*a.add(k)));
        let inv_h = _mm256_set1_pd(c.inv_h);
        let grad_alpha = _mm256_set1_pd(c.grad_alpha);
        let minus_two_scale = _mm256_set1_pd(c.minus_two_scale);
        let [hx, hy, hz] = c.hydrostatic.map(|v| _mm256_set1_pd(v));
        let rho0 = _mm256_set1_pd(c.rho0);
        let (half, one, zero) = (
            _mm256_set1_pd(0.5),
            _mm256_set1_pd(1.0),
            _mm256_setzero_pd(),
        );
        let sign = _mm256_set1_pd(-0.0);
        let own = sums.add(STRIDE * i);
        let mut sum_own = _mm256_loadu_pd(own);
        let mut diffusion_own = *own.add(4);
        let mut diffusion = [[0.0; 4]; 2];
        for group in (0..n).step_by(4) {
            let [x, y, z, r2] =
                transpose([0, 1, 2, 3].map(|k| _mm256_loadu_pd(slot.add(4 * (group + k)))));
            // The kernel gradient factor of `Wendland::gradient_factor_within`, `grad W = f r_ij`.
            let q = _mm256_mul_pd(_mm256_sqrt_pd(r2), inv_h);
            let w = _mm256_sub_pd(one, _mm256_mul_pd(half, q));
            let f = _mm256_mul_pd(_mm256_mul_pd(_mm256_mul_pd(grad_alpha, w), w), w);
            let (gx, gy, gz) = (
                _mm256_mul_pd(x, f),
                _mm256_mul_pd(y, f),
                _mm256_mul_pd(z, f),
            );
            let b = [0, 1, 2, 3].map(|k| sides.add(6 * index[group + k] as usize));
            let [ux, uy, uz, rho_b] = transpose(b.map(|b| _mm256_loadu_pd(b)));
            // (p, V) of partners 0 and 2, and of 1 and 3, interleaved into p and V.
            let pv02 = _mm256_set_m128d(_mm_loadu_pd(b[2].add(4)), _mm_loadu_pd(b[0].add(4)));
            let pv13 = _mm256_set_m128d(_mm_loadu_pd(b[3].add(4)), _mm_loadu_pd(b[1].add(4)));
            let p_b = _mm256_unpacklo_pd(pv02, pv13);
            let v_b = _mm256_unpackhi_pd(pv02, pv13);
            // Paper 1 eq 11: q = -(u_b - u_a) . grad W, its terms added x, y, then z.
            let dot = _mm256_add_pd(
                _mm256_add_pd(
                    _mm256_mul_pd(_mm256_sub_pd(ux, ux_a), gx),
                    _mm256_mul_pd(_mm256_sub_pd(uy, uy_a), gy),
                ),
                _mm256_mul_pd(_mm256_sub_pd(uz, uz_a), gz),
            );
            let q = _mm256_xor_pd(dot, sign);
            // Paper 1 eq 10: -(p_a + p_b) V_b grad W to `i`, (p_a + p_b) V_a grad W to `j`.
            let sum = _mm256_add_pd(p_a, p_b);
            let to_own = _mm256_mul_pd(_mm256_xor_pd(sum, sign), v_b);
            let to_partner = _mm256_mul_pd(sum, v_a);
            let own_shares = transpose([
                _mm256_mul_pd(gx, to_own),
                _mm256_mul_pd(gy, to_own),
                _mm256_mul_pd(gz, to_own),
                _mm256_mul_pd(q, v_b),
            ]);
            let partner_shares = transpose([
                _mm256_mul_pd(gx, to_partner),
                _mm256_mul_pd(gy, to_partner),
                _mm256_mul_pd(gz, to_partner),
                _mm256_mul_pd(q, v_a),
            ]);
            // The diffusion: e = -2 scale ((rho_b - rho_a) - hydrostatic) f, the hydrostatic
            // difference `g' . r_ij` times `(rho_a + rho_b) / (2 rho0)` where it is not zero.
            let mut hydrostatic = _mm256_add_pd(
                _mm256_add_pd(_mm256_mul_pd(hx, x), _mm256_mul_pd(hy, y)),
                _mm256_mul_pd(hz, z),
            );
            let factor = _mm256_div_pd(_mm256_mul_pd(half, _mm256_add_pd(rho_a, rho_b)), rho0);
            let nonzero = _mm256_cmp_pd(hydrostatic, zero, _CMP_NEQ_UQ);
            hydrostatic =
                _mm256_blendv_pd(hydrostatic, _mm256_mul_pd(hydrostatic, factor), nonzero);
            let excess = _mm256_sub_pd(_mm256_sub_pd(rho_b, rho_a), hydrostatic);
            let e = _mm256_mul_pd(_mm256_mul_pd(minus_two_scale, excess), f);
            _mm256_storeu_pd(diffusion[0].as_mut_ptr(), _mm256_mul_pd(e, v_b));
            _mm256_storeu_pd(
                diffusion[1].as_mut_ptr(),
                _mm256_xor_pd(_mm256_mul_pd(e, v_a), sign),
            );
            for k in 0..(n - group).min(4) {
                sum_own = _mm256_add_pd(sum_own, own_shares[k]);
                diffusion_own += diffusion[0][k];
                let partner = sums.add(STRIDE * index[group + k] as usize);
                _mm256_storeu_pd(
                    partner,
                    _mm256_add_pd(_mm256_loadu_pd(partner), partner_shares[k]),
                );
                *partner.add(4) += diffusion[1][k];
            }
        }
        _mm256_storeu_pd(own, sum_own);
        *own.add(4) = diffusion_own;
    }
}

#[cfg(not(target_arch = "x86_64"))]
mod x86_diffused {
    use super::{Diffused, FluidSums, PairBlocks, Side};
    use glam::DVec3;

    /// No processor but x86-64 is taken for AVX2.
    pub(in super::super) fn sweep(
        _: &Diffused,
        _: f64,
        _: &[DVec3],
        _: &[Side<DVec3>],
        _: &PairBlocks<DVec3>,
        _: &mut [FluidSums<DVec3>],
    ) -> bool {
        false
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
                !crate::avx2::available(),
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

    /// The explicit sweep with the density diffusion, with and without the hydrostatic
    /// correction, gives the scalar sweep's sums to the bit, the Verlet list filtered at
    /// positions moved within half its skin.
    #[test]
    fn the_diffused_lanes_give_the_bits_of_the_scalar_sweep() {
        use crate::terms::{scatter_run, DensityDiffusion, Viscosity};
        let mut s = 0x9e37_79b9_7f4a_7c15;
        let (n, h) = (3000, 0.1);
        let kernel = crate::kernel::Wendland::new(h, 3);
        let (support, skin) = (kernel.support, 0.1 * kernel.support);
        let built: Vec<DVec3> = (0..n)
            .map(|_| DVec3::new(random(&mut s), random(&mut s), random(&mut s)))
            .collect();
        let moved: Vec<DVec3> = (built.iter())
            .map(|&x| x + 0.25 * skin * DVec3::new(random(&mut s), random(&mut s), random(&mut s)))
            .collect();
        let sides: Vec<Side<DVec3>> = (0..n)
            .map(|_| Side {
                u: DVec3::new(random(&mut s), random(&mut s), random(&mut s)),
                rho: 1000.0 + 10.0 * random(&mut s),
                p: 1e4 * random(&mut s),
                volume: 1e-3 * (1.5 + random(&mut s)),
            })
            .collect();
        let mut grid = CellGrid::new(support + skin);
        grid.rebuild(&built);
        let mut blocks = PairBlocks::default();
        blocks.rebuild(&grid, &built, n, support + skin);
        let eos = Eos::Linear {
            rho0: 1000.0,
            c0: 40.0,
            p0: 0.0,
        };
        for hydrostatic in [DVec3::ZERO, DVec3::new(0.0, 0.0, -9.81 * 1000.0 / 1600.0)] {
            let model = RateModel {
                kernel,
                gravity: DVec3::new(0.0, 0.0, -9.81),
                diffusion: DensityDiffusion {
                    scale: 0.1 * h * 40.0,
                    hydrostatic_gradient: hydrostatic,
                    eos,
                    form: DiffusionForm::Laplacian,
                },
                viscosity: Viscosity::default(),
                body_force: DVec3::ZERO,
                density_power: 0,
                summation_density: false,
                wall_continuity_in_drift: false,
            };
            let mut scalar = vec![FluidSums::ZERO; n];
            blocks.sweep(&moved, support, &mut scalar, |i, run, index, r_ij, r2| {
                scatter_run::<DVec3, false, true, false, false>(
                    &model,
                    &sides,
                    (i, run),
                    index,
                    r_ij,
                    |k| {
                        let r = r2[k].sqrt();
                        (r, kernel.gradient_factor_within(r))
                    },
                )
            });
            let mut lanes = vec![FluidSums::ZERO; n];
            if !sweep_filtered_diffused(&model, &moved, &sides, &blocks, &mut lanes) {
                assert!(!crate::avx2::available(), "the lanes declined the sweep");
                return;
            }
            let bits = |v: &[FluidSums<DVec3>]| -> Vec<[u64; 9]> {
                v.iter()
                    .map(|s| {
                        let (g, v) = (s.grad_p, s.viscous);
                        [
                            g.x,
                            g.y,
                            g.z,
                            s.div_u,
                            s.diffusion,
                            v.x,
                            v.y,
                            v.z,
                            s.shepard,
                        ]
                        .map(f64::to_bits)
                    })
                    .collect()
            };
            assert_eq!(bits(&lanes), bits(&scalar));
            let diffused = scalar.iter().filter(|s| s.diffusion != 0.0).count();
            assert!(
                diffused > n * 9 / 10,
                "{diffused} of {n} particles diffused"
            );
        }
    }
}
