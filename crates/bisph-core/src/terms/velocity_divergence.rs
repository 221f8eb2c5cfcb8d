//! Velocity divergence, paper 1 eq 11: `<div u>_i = -sum_j (u_j - u_i) . grad W_ij m_j / rho_j`.
//! The continuity equation (eq 1) is `drho_i/dt = -rho_i <div u>_i`; the wall part of the
//! divergence comes from the wall model (eq 52). With the density power `k` of paper 3,
//! eq 38 (volume part, before the `1/gamma_i`): `-sum_j (rho_j/rho_i)^k (u_j - u_i) . grad W_ij V_j`.

use crate::dim::Vector;

/// One pair's contribution to eq 11: `-(u_j - u_i) . grad W_ij V_j`.
#[inline(always)]
pub fn pair<V: Vector>(u_i: V, u_j: V, grad_w_ij: V, volume_j: f64) -> f64 {
    -(u_j - u_i).dot(grad_w_ij) * volume_j
}

/// One pair's contribution to paper 3, eq 38, with `ratio = (rho_i / rho_j)^k`:
/// `-(u_j - u_i) . grad W_ij V_j / ratio`.
#[inline(always)]
pub fn pair_k<V: Vector>(u_i: V, u_j: V, grad_w_ij: V, volume_j: f64, ratio: f64) -> f64 {
    -(u_j - u_i).dot(grad_w_ij) * volume_j / ratio
}
