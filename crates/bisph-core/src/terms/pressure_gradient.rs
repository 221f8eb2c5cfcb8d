//! Pressure gradient, paper 1 eq 10: `<grad p>_i = -sum_j (p_j + p_i) grad W_ij m_j / rho_j`,
//! with `grad W_ij = grad W(r_j - r_i)`. Its wall part comes from the wall model (eq 51).
//! With the density power `k` of paper 3, eq 37 (volume part, before the `1/gamma_i`):
//! `-sum_j [(rho_i/rho_j)^k p_j + (rho_j/rho_i)^k p_i] grad W_ij V_j`; `k = 0` is eq 10.

use crate::dim::Vector;

/// One pair's contribution to eq 10: `-(p_i + p_j) grad W_ij V_j`.
#[inline(always)]
pub fn pair<V: Vector>(p_i: f64, p_j: f64, grad_w_ij: V, volume_j: f64) -> V {
    pair_sides(p_i, p_j, grad_w_ij, [0.0, volume_j]).0
}

/// One pair's contributions to eq 10 of both particles, `(to i, to j)`: `-(p_i + p_j)
/// grad W_ij V_j` and, with `grad W_ji = -grad W_ij`, `(p_i + p_j) grad W_ij V_i` (each the
/// bits its own particle's sum would add; `m_i a_i = -m_j a_j`). `volume` is `[V_i, V_j]`.
#[inline(always)]
pub fn pair_sides<V: Vector>(p_i: f64, p_j: f64, grad_w_ij: V, volume: [f64; 2]) -> (V, V) {
    let sum = p_i + p_j;
    (
        grad_w_ij * (-sum * volume[1]),
        grad_w_ij * (sum * volume[0]),
    )
}

/// One pair's contribution to paper 3, eq 37, with `ratio = (rho_i / rho_j)^k`:
/// `-(p_j ratio + p_i / ratio) grad W_ij V_j`.
#[inline(always)]
pub fn pair_k<V: Vector>(p_i: f64, p_j: f64, grad_w_ij: V, volume_j: f64, ratio: f64) -> V {
    pair_k_sides(p_i, p_j, grad_w_ij, [0.0, volume_j], [ratio, 1.0]).0
}

/// [`pair_k`] for both particles, `(to i, to j)`, with `ratio = [(rho_i / rho_j)^k,
/// (rho_j / rho_i)^k]` and `grad W_ji = -grad W_ij`.
#[inline(always)]
pub fn pair_k_sides<V: Vector>(
    p_i: f64,
    p_j: f64,
    grad_w_ij: V,
    volume: [f64; 2],
    ratio: [f64; 2],
) -> (V, V) {
    (
        grad_w_ij * (-(p_i / ratio[0] + p_j * ratio[0]) * volume[1]),
        -(grad_w_ij * (-(p_j / ratio[1] + p_i * ratio[1]) * volume[0])),
    )
}
