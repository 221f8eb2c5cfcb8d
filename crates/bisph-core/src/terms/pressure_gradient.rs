//! Pressure gradient, paper 1 eq 10: `<grad p>_i = -sum_j (p_j + p_i) grad W_ij m_j / rho_j`,
//! with `grad W_ij = grad W(r_j - r_i)`. Its wall part comes from the wall model (eq 51).
//! With the density power `k` of paper 3, eq 37 (volume part, before the `1/gamma_i`):
//! `-sum_j [(rho_i/rho_j)^k p_j + (rho_j/rho_i)^k p_i] grad W_ij V_j`; `k = 0` is eq 10.

use crate::dim::Vector;

/// One pair's contribution to eq 10: `-(p_i + p_j) grad W_ij V_j`.
#[inline(always)]
pub fn pair<V: Vector>(p_i: f64, p_j: f64, grad_w_ij: V, volume_j: f64) -> V {
    grad_w_ij * (-(p_i + p_j) * volume_j)
}

/// One pair's contribution to paper 3, eq 37, with `ratio = (rho_i / rho_j)^k`:
/// `-(p_j ratio + p_i / ratio) grad W_ij V_j`.
#[inline(always)]
pub fn pair_k<V: Vector>(p_i: f64, p_j: f64, grad_w_ij: V, volume_j: f64, ratio: f64) -> V {
    grad_w_ij * (-(p_i / ratio + p_j * ratio) * volume_j)
}
