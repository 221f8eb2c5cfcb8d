//! Velocity divergence, paper 1 eq 11: `<div u>_i = -sum_j (u_j - u_i) . grad W_ij m_j / rho_j`.
//! The continuity equation (eq 1) is `drho_i/dt = -rho_i <div u>_i`; the wall part of the
//! divergence comes from the wall model (eq 52). With the density power `k` of paper 3,
//! eq 38 (volume part, before the `1/gamma_i`): `-sum_j (rho_j/rho_i)^k (u_j - u_i) . grad W_ij V_j`.

use crate::dim::Vector;

/// One pair's contribution to eq 11: `-(u_j - u_i) . grad W_ij V_j`.
#[inline(always)]
pub fn pair<V: Vector>(u_i: V, u_j: V, grad_w_ij: V, volume_j: f64) -> f64 {
    pair_sides(u_i, u_j, grad_w_ij, [0.0, volume_j]).0
}

/// One pair's contributions to eq 11 of both particles, `(to i, to j)`: `-(u_j - u_i) .
/// grad W_ij V_j` and, with `grad W_ji = -grad W_ij`, the same product with `V_i` (each the
/// bits its own particle's sum would add). `volume` is `[V_i, V_j]`.
#[inline(always)]
pub fn pair_sides<V: Vector>(u_i: V, u_j: V, grad_w_ij: V, volume: [f64; 2]) -> (f64, f64) {
    let q = -(u_j - u_i).dot(grad_w_ij);
    (q * volume[1], q * volume[0])
}

/// One pair's contribution to paper 3, eq 38, with `ratio = (rho_i / rho_j)^k`:
/// `-(u_j - u_i) . grad W_ij V_j / ratio`.
#[inline(always)]
pub fn pair_k<V: Vector>(u_i: V, u_j: V, grad_w_ij: V, volume_j: f64, ratio: f64) -> f64 {
    pair_k_sides(u_i, u_j, grad_w_ij, [0.0, volume_j], [ratio, 1.0]).0
}

/// [`pair_k`] for both particles, `(to i, to j)`, with `ratio = [(rho_i / rho_j)^k,
/// (rho_j / rho_i)^k]`.
#[inline(always)]
pub fn pair_k_sides<V: Vector>(
    u_i: V,
    u_j: V,
    grad_w_ij: V,
    volume: [f64; 2],
    ratio: [f64; 2],
) -> (f64, f64) {
    let q = -(u_j - u_i).dot(grad_w_ij);
    (q * volume[1] / ratio[0], q * volume[0] / ratio[1])
}
