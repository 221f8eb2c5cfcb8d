//! The filters of the pair blocks in 3-D with four candidates in the lanes of AVX2
//! registers, on processors that have AVX2 (checked at run time) and without periodic axes,
//! candidates kept without a branch per candidate, their offsets `x_j - x_i` and squared
//! lengths `(x x + y y) + z z` those of the scalar filters, so the same candidates are kept:
//! - the build of the list: the candidates of a block's cells within the listing radius
//!   ([`BlockChunk::fill`]);
//! - the explicit step's filter of the list at the positions: each row's partners within the
//!   radius with their offsets and squared lengths ([`super::PairBlocks::sweep`]), handed
//!   over as one row for a sweep in lanes.

use super::gradient_lanes::{candidate_group, load_point, squared_lengths};
use super::{sweep_classes, BlockChunk, PairBlocks, RunValues};
use crate::neighbours::CellGrid;
use glam::DVec3;
use std::arch::x86_64::*;

impl BlockChunk {
    /// [`BlockChunk::fill`] with the candidates in lanes: the same rows, partner for partner.
    ///
    /// # Safety
    /// The processor has AVX2; `grid` indexes `points`.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn fill_in_lanes(
        &mut self,
        grid: &CellGrid<DVec3>,
        points: &[DVec3],
        owned: usize,
        r2max: f64,
    ) {
        self.first.clear();
        self.start.clear();
        self.second.clear();
        self.start.push(0);
        let points = points.as_ptr() as *const f64;
        let r2max = _mm256_set1_pd(r2max);
        for a in &self.anchors {
            let cells = grid.block_cells(*a);
            for d in 0..8 {
                let (s0, s1) = cells[d];
                for s in s0..s1 {
                    let p = grid.items[s] as usize;
                    let x = load_point(points, p);
                    // A halo particle keeps only partners below `owned`.
                    let last = if p >= owned { owned as u32 } else { u32::MAX };
                    for (d2, &(t0, t1)) in cells.iter().enumerate().skip(d) {
                        if d2 & d != 0 {
                            continue;
                        }
                        let from = if d2 == d { s + 1 } else { t0 };
                        let candidates = &grid.items[from..t1];
                        let listed = self.second.len();
                        // Every candidate is stored at the next free slot, at most one past
                        // the kept ones.
                        self.second.reserve(candidates.len() + 1);
                        let out = self.second.as_mut_ptr().add(listed);
                        let mut kept = 0usize;
                        for group in candidates.chunks(4) {
                            let (q, mut keep, offset) = candidate_group(points, x, group);
                            for (k, &q) in q.iter().enumerate() {
                                keep &= !(u32::from(q >= last) << k);
                            }
                            let r2 = squared_lengths(&offset);
                            keep &= _mm256_movemask_pd(_mm256_cmp_pd(r2, r2max, _CMP_LT_OQ)) as u32;
                            for (k, &q) in q.iter().enumerate() {
                                *out.add(kept) = q;
                                kept += ((keep >> k) & 1) as usize;
                            }
                        }
                        self.second.set_len(listed + kept);
                    }
                    if self.second.len() > *self.start.last().unwrap() as usize {
                        self.first.push(p as u32);
                        self.start.push(self.second.len() as u32);
                    }
                }
            }
        }
    }
}

/// One task's filtered row: the kept partners' indices and their slots `(r_ij, |r_ij|^2)`,
/// the last repeated up to a multiple of four.
#[derive(Default)]
struct KeptRow {
    index: Vec<u32>,
    slot: Vec<[f64; 4]>,
}

impl PairBlocks<DVec3> {
    /// [`PairBlocks::sweep`] with the filter in lanes and whole rows: for each first particle
    /// `i` with partners within `radius` at `points`, `visit(i, values, n, index, slot)` with
    /// `index[k]` the `n` kept partners in the list's order, `slot[k] = (r_ij, |r_ij|^2)`
    /// theirs (the scalar filter's bits), both repeating the last up to a multiple of four.
    /// Returns `false`, having done nothing, where the lanes do not apply (a periodic axis,
    /// or a processor without AVX2).
    ///
    /// # Panics
    /// When `points` or `values` hold fewer entries than the list.
    pub(crate) fn sweep_rows_in_lanes<T: Send>(
        &self,
        points: &[DVec3],
        radius: f64,
        values: &mut [T],
        visit: impl Fn(usize, &mut RunValues<'_, T>, usize, &[u32], &[[f64; 4]]) + Sync,
    ) -> bool {
        if self.period.any() || !crate::avx2::available() {
            return false;
        }
        assert!(points.len() >= self.len(), "fewer points than listed");
        let r2max = radius * radius;
        sweep_classes(
            &self.classes,
            self.len(),
            values,
            KeptRow::default,
            |chunk: &BlockChunk, shared, row| {
                for (r, &i) in chunk.first.iter().enumerate() {
                    let partners =
                        &chunk.second[chunk.start[r] as usize..chunk.start[r + 1] as usize];
                    // SAFETY: AVX2 is present (checked above); the list's points index
                    // `points` (checked above).
                    let n = unsafe { row.filter(points, i, partners, r2max) };
                    if n > 0 {
                        let i = i as usize;
                        let index = &row.index[..];
                        let mut run = RunValues { shared, i, index };
                        visit(i, &mut run, n, index, &row.slot);
                    }
                }
            },
        );
        true
    }
}

impl KeptRow {
    /// Keeps the `partners` of `i` within `sqrt(r2max)` at `points`; returns how many.
    ///
    /// # Safety
    /// The processor has AVX2; `i` and every partner index `points`.
    #[target_feature(enable = "avx2")]
    unsafe fn filter(&mut self, points: &[DVec3], i: u32, partners: &[u32], r2max: f64) -> usize {
        self.index.clear();
        self.slot.clear();
        // Every candidate is stored at the next free slot, at most one past the kept ones
        // for each; the repeats of the last take at most three more.
        self.index.reserve(partners.len() + 4);
        self.slot.reserve(partners.len() + 4);
        let index = self.index.as_mut_ptr();
        let slot = self.slot.as_mut_ptr() as *mut f64;
        let points = points.as_ptr() as *const f64;
        let x = load_point(points, i as usize);
        let r2max = _mm256_set1_pd(r2max);
        let mut kept = 0usize;
        for group in partners.chunks(4) {
            let (j, valid, offset) = candidate_group(points, x, group);
            let r2 = squared_lengths(&offset);
            let inside = _mm256_movemask_pd(_mm256_cmp_pd(r2, r2max, _CMP_LT_OQ)) as u32 & valid;
            let r2 = [
                _mm256_permute4x64_pd(r2, 0x00),
                _mm256_permute4x64_pd(r2, 0x55),
                _mm256_permute4x64_pd(r2, 0xaa),
                _mm256_permute4x64_pd(r2, 0xff),
            ];
            for k in 0..4 {
                _mm256_storeu_pd(
                    slot.add(4 * kept),
                    _mm256_blend_pd(offset[k], r2[k], 0b1000),
                );
                *index.add(kept) = j[k];
                kept += ((inside >> k) & 1) as usize;
            }
        }
        let padded = kept.next_multiple_of(4);
        if kept > 0 {
            for k in kept..padded {
                *index.add(k) = *index.add(kept - 1);
                _mm256_storeu_pd(slot.add(4 * k), _mm256_loadu_pd(slot.add(4 * (kept - 1))));
            }
        }
        self.index.set_len(padded);
        self.slot.set_len(padded);
        kept
    }
}
