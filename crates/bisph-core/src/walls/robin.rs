//! Robin wall conditions of any order for a scalar field (paper 3, section 6.1, eqs 64-74),
//! with the hydrostatic correction of eq 83.
//!
//! The condition `mu1 f + mu2 df/dn = mu3` holds on the wall (eq 64), **`n` pointing into the
//! fluid** (paper 3's convention; the rest of the code has normals out of the fluid, so pass
//! `-n_j`). Along the normal through a wall point `v`, `f` is fitted by the polynomial of
//! order `m` that meets the condition at the wall (eq 66):
//! `lambda(x) = sum_{i=2}^m beta_i x^i + (mu3 - mu1 beta_1) / mu2 x + beta_1`,
//! `x = r_av . n_v`, by weighted least squares over the fluid neighbours (eqs 68-73) with
//! weights `V_a W_va` (eq 72). The wall value is `f_v = lambda(0) = beta_1` (eq 74).
//! `m = 1`, `mu1 = mu3 = 0` is the Shepard extrapolation of eq 16 (Neumann, first order);
//! `mu2 -> 0` gives the Dirichlet limit `f_v -> mu3 / mu1`.

use crate::dim::Vector;

/// Highest supported order `m`.
pub const MAX_ORDER: usize = 6;

/// The coefficients of `mu1 f + mu2 df/dn = mu3` (eq 64), `n` into the fluid, `mu2 != 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RobinCondition {
    /// `mu1` (0: Neumann).
    pub mu1: f64,
    /// `mu2` (non-zero).
    pub mu2: f64,
    /// `mu3`.
    pub mu3: f64,
}

impl RobinCondition {
    /// The Neumann condition `df/dn = g`.
    pub fn neumann(g: f64) -> Self {
        RobinCondition {
            mu1: 0.0,
            mu2: 1.0,
            mu3: g,
        }
    }

    /// The wall-normal derivative `df/dn = (mu3 - mu1 f) / mu2` (eq 65) for a wall value `f`.
    pub fn normal_derivative(&self, f: f64) -> f64 {
        (self.mu3 - self.mu1 * f) / self.mu2
    }
}

/// One fluid neighbour of a wall point: offset `r_a - r_v`, value `y_a` (eq 69 uses `f_a`;
/// see [`hydrostatic_sample`] for eq 83) and weight `V_a W_va` (eq 72).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RobinSample<V> {
    /// `r_a - r_v`.
    pub offset: V,
    /// The field value the fit must follow.
    pub value: f64,
    /// `V_a W_va`.
    pub weight: f64,
}

/// Eq 83: the value a fluid particle contributes to the fit of the wall pressure when a body
/// force `g` acts, `p_a - rho_a [r_av - (r_av . n_v) n_v] . g`, so that tangential hydrostatic
/// variations do not leak into the wall value. `offset` is `r_a - r_v`.
pub fn hydrostatic_sample<V: Vector>(
    pressure: f64,
    density: f64,
    offset: V,
    normal: V,
    gravity: V,
) -> f64 {
    let tangential = offset - normal * offset.dot(normal);
    pressure - density * tangential.dot(gravity)
}

/// The wall value `beta_1` of eq 74 for the condition `c` with a fit of order `order`
/// (`1 <= order <= MAX_ORDER`) along the unit normal `normal` (into the fluid), from the
/// samples. `None` when the normal equations are singular (fewer than `order` samples at
/// distinct normal distances) or the order is out of range.
pub fn wall_value<V: Vector>(
    c: &RobinCondition,
    order: usize,
    normal: V,
    samples: impl IntoIterator<Item = RobinSample<V>>,
) -> Option<f64> {
    if order == 0 || order > MAX_ORDER || c.mu2 == 0.0 {
        return None;
    }
    // Normal equations X^T L X beta = X^T L y (eq 73), accumulated sample by sample.
    let mut a = [[0.0f64; MAX_ORDER]; MAX_ORDER];
    let mut b = [0.0f64; MAX_ORDER];
    let mut row = [0.0f64; MAX_ORDER];
    let mut any = false;
    for s in samples {
        if s.weight <= 0.0 {
            continue;
        }
        any = true;
        let x = s.offset.dot(normal);
        // Eq 68: X_a1 = 1 - mu1/mu2 x, X_aj = x^j; eq 69: y_a = f_a - mu3/mu2 x.
        row[0] = 1.0 - c.mu1 / c.mu2 * x;
        let mut power = x;
        for r in row.iter_mut().take(order).skip(1) {
            power *= x;
            *r = power;
        }
        let y = s.value - c.mu3 / c.mu2 * x;
        for i in 0..order {
            b[i] += s.weight * row[i] * y;
            for j in 0..order {
                a[i][j] += s.weight * row[i] * row[j];
            }
        }
    }
    if !any {
        return None;
    }
    solve_first(&mut a, &mut b, order)
}

/// First unknown of the `n x n` system `a z = b`, by Gaussian elimination with partial
/// pivoting on an equilibrated copy; `None` when the matrix is (numerically) singular.
#[allow(clippy::needless_range_loop)]
fn solve_first(
    a: &mut [[f64; MAX_ORDER]; MAX_ORDER],
    b: &mut [f64; MAX_ORDER],
    n: usize,
) -> Option<f64> {
    // Scale columns so that every diagonal entry is one (powers of x span many decades).
    let mut scale = [1.0f64; MAX_ORDER];
    for (i, s) in scale.iter_mut().enumerate().take(n) {
        if a[i][i] <= 0.0 {
            return None;
        }
        *s = 1.0 / a[i][i].sqrt();
    }
    for i in 0..n {
        for j in 0..n {
            a[i][j] *= scale[i] * scale[j];
        }
        b[i] *= scale[i];
    }
    for k in 0..n {
        let p = (k..n).max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))?;
        if a[p][k].abs() < 1e-13 {
            return None;
        }
        a.swap(k, p);
        b.swap(k, p);
        for i in k + 1..n {
            let f = a[i][k] / a[k][k];
            for j in k..n {
                a[i][j] -= f * a[k][j];
            }
            b[i] -= f * b[k];
        }
    }
    let mut z = [0.0f64; MAX_ORDER];
    for k in (0..n).rev() {
        let mut s = b[k];
        for j in k + 1..n {
            s -= a[k][j] * z[j];
        }
        z[k] = s / a[k][k];
    }
    Some(z[0] * scale[0])
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;

    fn samples(f: impl Fn(f64) -> f64, n: DVec2) -> Vec<RobinSample<DVec2>> {
        // Points off the normal too: only the normal distance matters.
        (0..12)
            .map(|k| {
                let x = 0.05 + 0.1 * k as f64;
                let offset = n * x + DVec2::new(n.y, -n.x) * (0.3 * (k as f64).sin());
                RobinSample {
                    offset,
                    value: f(x),
                    weight: (1.0 - x / 1.3).powi(4),
                }
            })
            .collect()
    }

    #[test]
    fn fits_of_order_m_are_exact_for_polynomials_meeting_the_condition() {
        let c = RobinCondition {
            mu1: -1.0,
            mu2: 1.0,
            mu3: 0.5,
        };
        let n = DVec2::new(0.6, 0.8);
        let beta1 = 0.7;
        let slope = c.normal_derivative(beta1);
        for order in 1..=4 {
            let f = |x: f64| {
                let mut v = beta1 + slope * x;
                for i in 2..=order {
                    v += 0.3 / i as f64 * x.powi(i as i32);
                }
                v
            };
            let got = wall_value(&c, order, n, samples(f, n)).unwrap();
            assert!((got - beta1).abs() < 1e-10, "order {order}: {got}");
        }
        // A quadratic is not followed by a first-order fit.
        let f = |x: f64| beta1 + slope * x + x * x;
        let got = wall_value(&c, 1, n, samples(f, n)).unwrap();
        assert!((got - beta1).abs() > 1e-2);
    }

    #[test]
    fn first_order_neumann_is_the_shepard_extrapolation_of_eq_16() {
        let n = DVec2::Y;
        let s = samples(|x| (3.0 * x).cos() + x, n);
        let shepard = s.iter().map(|s| s.weight * s.value).sum::<f64>()
            / s.iter().map(|s| s.weight).sum::<f64>();
        let got = wall_value(&RobinCondition::neumann(0.0), 1, n, s).unwrap();
        assert!((got - shepard).abs() < 1e-14);
    }

    #[test]
    fn dirichlet_limit_and_singular_fits() {
        let c = RobinCondition {
            mu1: 1.0,
            mu2: 1e-9,
            mu3: 2.5,
        };
        let n = DVec2::X;
        let got = wall_value(&c, 2, n, samples(|x| 2.5 + x * x, n)).unwrap();
        assert!((got - 2.5).abs() < 1e-6, "{got}");
        // Two samples at the same normal distance cannot fix a second-order fit.
        let same = [0.2, 0.2].map(|x| RobinSample {
            offset: DVec2::new(x, 0.0),
            value: 1.0,
            weight: 1.0,
        });
        assert_eq!(wall_value(&RobinCondition::neumann(0.0), 2, n, same), None);
        assert_eq!(wall_value(&RobinCondition::neumann(0.0), 0, n, same), None);
    }

    #[test]
    fn hydrostatic_sample_removes_tangential_hydrostatics_only() {
        // Vertical wall (normal +x into the fluid), gravity -y: a particle above the wall
        // point carries rho g dy less pressure; eq 83 adds it back.
        let g = DVec2::new(0.0, -9.81);
        let offset = DVec2::new(0.1, 0.5);
        let y = hydrostatic_sample(1000.0, 1000.0, offset, DVec2::X, g);
        assert!((y - (1000.0 + 1000.0 * 9.81 * 0.5)).abs() < 1e-9);
        // Along the normal nothing changes.
        let y = hydrostatic_sample(1000.0, 1000.0, DVec2::new(0.3, 0.0), DVec2::X, g);
        assert_eq!(y, 1000.0);
    }
}
