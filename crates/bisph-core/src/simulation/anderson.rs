//! Anderson acceleration of the midpoint iterations (Walker & Ni 2011, SIAM J. Numer. Anal.
//! 49(4), 1715-1735: "type II" with a window of `depth` differences).
//!
//! The iterations of a midpoint step seek the fixed point `x = G(x)` of the map from the
//! rates `x = (a_i, rhodot_i, A_k)` (fluid accelerations, density rates, the bodies'
//! generalised accelerations) to the rates evaluated at the midpoint state they give. The
//! plain iteration takes `x_{m+1} = g_m = G(x_m)`; Anderson's takes
//! `x_{m+1} = g_m - sum_j gamma_j (g_{m-j+1} - g_{m-j})`, with `gamma` minimising the
//! weighted norm of `f_m - sum_j gamma_j (f_{m-j+1} - f_{m-j})` over the last `depth`
//! differences of the residuals `f = g - x`. The fixed point, and so the converged step, is
//! the same; only the number of evaluations to reach it changes. The norm weighs each
//! particle by its mass and puts the density rates in the units of an acceleration,
//! `|y|^2 = sum_i m_i (|y_a,i|^2 + (c0 / rho0)^2 y_rhodot,i^2) + sum_k I_k y_A,k^2`, with
//! `I_k` the bodies' generalised inertias (the residue of paper 1, eq 53, weighs particles by
//! their mass too).

use crate::dim::Vector;
use std::collections::VecDeque;

/// One vector of rates of the midpoint iterations.
#[derive(Clone, Debug, Default)]
struct Rates<V> {
    acceleration: Vec<V>,
    density_rate: Vec<f64>,
    body: Vec<f64>,
}

impl<V: Vector> Rates<V> {
    /// `self <- g - x`.
    fn set_difference(&mut self, g: RatesView<'_, V>, x: RatesView<'_, V>) {
        fill(
            &mut self.acceleration,
            g.acceleration,
            x.acceleration,
            |g, x| g - x,
        );
        fill(
            &mut self.density_rate,
            g.density_rate,
            x.density_rate,
            |g, x| g - x,
        );
        fill(&mut self.body, g.body, x.body, |g, x| g - x);
    }

    fn view(&self) -> RatesView<'_, V> {
        RatesView {
            acceleration: &self.acceleration,
            density_rate: &self.density_rate,
            body: &self.body,
        }
    }

    /// `self <- new - self`: the difference from the value held to `new`.
    fn set_change_to(&mut self, new: RatesView<'_, V>) {
        for (d, &n) in self.acceleration.iter_mut().zip(new.acceleration) {
            *d = n - *d;
        }
        for (d, &n) in self.density_rate.iter_mut().zip(new.density_rate) {
            *d = n - *d;
        }
        for (d, &n) in self.body.iter_mut().zip(new.body) {
            *d = n - *d;
        }
    }

    fn copy_from(&mut self, from: RatesView<'_, V>) {
        self.acceleration.clear();
        self.acceleration.extend_from_slice(from.acceleration);
        self.density_rate.clear();
        self.density_rate.extend_from_slice(from.density_rate);
        self.body.clear();
        self.body.extend_from_slice(from.body);
    }
}

/// `out[i] = op(a[i], b[i])`.
fn fill<T: Copy>(out: &mut Vec<T>, a: &[T], b: &[T], op: impl Fn(T, T) -> T) {
    out.clear();
    out.extend(a.iter().zip(b).map(|(&a, &b)| op(a, b)));
}

/// Borrowed rates (the fluid's and the bodies' own arrays).
#[derive(Clone, Copy, Debug)]
pub(super) struct RatesView<'a, V> {
    pub acceleration: &'a [V],
    pub density_rate: &'a [f64],
    pub body: &'a [f64],
}

/// The weighted inner product `<y, z>` of the norm above, summed the same way whatever the
/// number of threads or parts.
pub(super) trait InnerProduct<V> {
    fn inner(&self, y: RatesView<'_, V>, z: RatesView<'_, V>) -> f64;
}

/// The history of one step's iterations.
#[derive(Debug, Default)]
pub(super) struct Anderson<V> {
    depth: usize,
    /// `f_m` and `g_m` of the last iteration, once there is one.
    residual: Rates<V>,
    evaluation: Rates<V>,
    held: bool,
    /// The last `depth` differences `f_{j+1} - f_j` and `g_{j+1} - g_j`, oldest first.
    residual_changes: VecDeque<Rates<V>>,
    evaluation_changes: VecDeque<Rates<V>>,
    /// `<df_j, df_l>` of the held residual differences, and `<df_j, f_m>`: each iteration
    /// adds one row, and `f_m = f_{m-1} + df_new` updates the projections by that row.
    gram: VecDeque<VecDeque<f64>>,
    projection: VecDeque<f64>,
    /// Storage of dropped differences, reused.
    spare: Vec<Rates<V>>,
}

impl<V: Vector> Anderson<V> {
    /// A history that keeps `depth` differences (0: the plain iteration).
    pub fn new(depth: usize) -> Self {
        Anderson {
            depth,
            ..Default::default()
        }
    }

    /// The number of differences kept.
    pub fn depth(&self) -> usize {
        self.depth
    }

    /// Forgets the iterations of the last step.
    pub fn restart(&mut self) {
        self.held = false;
        while !self.residual_changes.is_empty() {
            self.drop_oldest();
        }
    }

    fn drop_oldest(&mut self) {
        self.spare.extend(self.residual_changes.pop_front());
        self.spare.extend(self.evaluation_changes.pop_front());
        self.gram.pop_front();
        for row in &mut self.gram {
            row.pop_front();
        }
        self.projection.pop_front();
    }

    /// Takes the guess `x` of an iteration and its evaluation `g = G(x)` and overwrites `g`
    /// with the next guess (leaves it, the plain iteration's guess, with no window).
    pub fn next_guess(
        &mut self,
        x: RatesView<'_, V>,
        g: (&mut [V], &mut [f64], &mut [f64]),
        product: &impl InnerProduct<V>,
    ) {
        if self.depth == 0 {
            return;
        }
        let g_view = RatesView {
            acceleration: &*g.0,
            density_rate: &*g.1,
            body: &*g.2,
        };
        if self.held {
            // The new differences: the held f and g, then their change to the new ones.
            let mut df = self.spare.pop().unwrap_or_default();
            df.copy_from(self.residual.view());
            let mut dg = self.spare.pop().unwrap_or_default();
            dg.copy_from(self.evaluation.view());
            self.residual.set_difference(g_view, x);
            df.set_change_to(self.residual.view());
            dg.set_change_to(g_view);
            if self.residual_changes.len() == self.depth {
                self.drop_oldest();
            }
            let row: VecDeque<f64> = self
                .residual_changes
                .iter()
                .map(|d| product.inner(d.view(), df.view()))
                .chain([product.inner(df.view(), df.view())])
                .collect();
            for ((p, gram), &r) in self.projection.iter_mut().zip(&mut self.gram).zip(&row) {
                *p += r;
                gram.push_back(r);
            }
            self.projection
                .push_back(product.inner(df.view(), self.residual.view()));
            self.gram.push_back(row);
            self.residual_changes.push_back(df);
            self.evaluation_changes.push_back(dg);
        } else {
            self.residual.set_difference(g_view, x);
        }
        self.evaluation.copy_from(g_view);
        self.held = true;
        let gamma = self.coefficients();
        for (dg, &c) in self.evaluation_changes.iter().zip(&gamma) {
            for (a, &d) in g.0.iter_mut().zip(&dg.acceleration) {
                *a -= d * c;
            }
            for (r, &d) in g.1.iter_mut().zip(&dg.density_rate) {
                *r -= c * d;
            }
            for (b, &d) in g.2.iter_mut().zip(&dg.body) {
                *b -= c * d;
            }
        }
    }

    /// `gamma` of the least-squares problem over the held differences, by its normal
    /// equations; the oldest differences are dropped while they are nearly dependent.
    fn coefficients(&mut self) -> Vec<f64> {
        loop {
            let n = self.residual_changes.len();
            if n == 0 {
                return Vec::new();
            }
            let a = (0..n)
                .map(|j| {
                    let mut row: Vec<f64> = self.gram[j].iter().copied().collect();
                    row.push(self.projection[j]);
                    row
                })
                .collect();
            if let Some(gamma) = solve(a) {
                return gamma;
            }
            self.drop_oldest();
        }
    }
}

/// Solves the symmetric positive semi-definite system held as the augmented rows `a`
/// (`[A | b]`, by Cholesky's factorisation `A = L L^T`); `None` when a pivot falls below
/// `1e-10` of its diagonal entry (the differences nearly dependent).
fn solve(a: Vec<Vec<f64>>) -> Option<Vec<f64>> {
    let n = a.len();
    let dot = |x: &[f64], y: &[f64]| -> f64 { x.iter().zip(y).map(|(x, y)| x * y).sum() };
    let mut l: Vec<Vec<f64>> = Vec::with_capacity(n);
    for (k, row) in a.iter().enumerate() {
        let mut lk = Vec::with_capacity(k + 1);
        for (j, lj) in l.iter().enumerate() {
            lk.push((row[j] - dot(&lk, &lj[..j])) / lj[j]);
        }
        let pivot = row[k] - dot(&lk, &lk);
        if pivot.is_nan() || pivot <= 1e-10 * row[k] {
            return None;
        }
        lk.push(pivot.sqrt());
        l.push(lk);
    }
    // L y = b, then L^T x = y.
    let mut y: Vec<f64> = Vec::with_capacity(n);
    for (row, lk) in a.iter().zip(&l) {
        let k = y.len();
        y.push((row[n] - dot(&lk[..k], &y)) / lk[k]);
    }
    let mut x = vec![0.0; n];
    for k in (0..n).rev() {
        let above: f64 = (k + 1..n).map(|j| l[j][k] * x[j]).sum();
        x[k] = (y[k] - above) / l[k][k];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;

    struct Plain;
    impl InnerProduct<DVec2> for Plain {
        fn inner(&self, y: RatesView<'_, DVec2>, z: RatesView<'_, DVec2>) -> f64 {
            let a: f64 = y
                .acceleration
                .iter()
                .zip(z.acceleration)
                .map(|(a, b)| a.dot(*b))
                .sum();
            let r: f64 = y
                .density_rate
                .iter()
                .zip(z.density_rate)
                .map(|(a, b)| a * b)
                .sum();
            let b: f64 = y.body.iter().zip(z.body).map(|(a, b)| a * b).sum();
            a + r + b
        }
    }

    /// The map `G(x) = b + J x` with `J` of eigenvalues spread over `[-0.15, 0]` (the
    /// midpoint iterations' acoustic coupling): the plain iteration gains a factor 0.15 per
    /// pass; a Krylov method on `I - J` (spectrum in `[1, 1.15]`), which Anderson's mixing
    /// approaches, gains `(sqrt(1.15) - 1) / (sqrt(1.15) + 1) = 0.035`, 1.77 times the digits
    /// per pass. With a window of 3 it must take at most two thirds of the plain passes.
    #[test]
    fn anderson_beats_the_plain_iteration_on_a_linear_contraction() {
        let n = 6;
        let lambda: Vec<f64> = (0..2 * n)
            .map(|k| -0.15 * k as f64 / (2 * n - 1) as f64)
            .collect();
        let b: Vec<f64> = (0..2 * n).map(|k| 1.0 + 0.3 * k as f64).collect();
        let fixed: Vec<f64> = b.iter().zip(&lambda).map(|(b, l)| b / (1.0 - l)).collect();
        let evaluate = |x: &[f64]| -> Vec<f64> {
            x.iter()
                .zip(&lambda)
                .zip(&b)
                .map(|((x, l), b)| b + l * x)
                .collect()
        };
        let error = |x: &[f64]| -> f64 {
            x.iter()
                .zip(&fixed)
                .map(|(x, f)| (x - f).abs())
                .fold(0.0, f64::max)
        };
        let passes = |depth: usize| -> usize {
            let mut anderson = Anderson::<DVec2>::new(depth);
            let mut x = vec![0.0; 2 * n];
            for pass in 1..100 {
                let g = evaluate(&x);
                let x_acc: Vec<DVec2> =
                    (0..n).map(|i| DVec2::new(x[2 * i], x[2 * i + 1])).collect();
                let mut g_acc: Vec<DVec2> =
                    (0..n).map(|i| DVec2::new(g[2 * i], g[2 * i + 1])).collect();
                let x_view = RatesView {
                    acceleration: &x_acc,
                    density_rate: &[],
                    body: &[],
                };
                anderson.next_guess(x_view, (&mut g_acc, &mut [], &mut []), &Plain);
                x = g_acc.iter().flat_map(|v| [v.x, v.y]).collect();
                if error(&x) < 1e-12 {
                    return pass;
                }
            }
            100
        };
        let (plain, accelerated) = (passes(0), passes(3));
        assert!(plain >= 14, "plain: {plain}");
        assert!(
            3 * accelerated <= 2 * plain,
            "plain {plain}, Anderson {accelerated}"
        );
    }

    #[test]
    fn dependent_differences_are_dropped() {
        let a = vec![vec![1.0, 1.0, 2.0], vec![1.0, 1.0, 2.0]];
        assert!(solve(a).is_none());
        let a = vec![vec![4.0, 2.0, 2.0], vec![2.0, 3.0, 1.0]];
        let x = solve(a).unwrap();
        assert!((4.0 * x[0] + 2.0 * x[1] - 2.0).abs() < 1e-14);
        assert!((2.0 * x[0] + 3.0 * x[1] - 1.0).abs() < 1e-14);
    }
}
