//! The geometric Shepard factor (paper 2): `gamma(x) = int_Omega W(y - x) dy` computed from
//! the wall elements alone, so free surfaces do not change it.
//!
//! With `W = div(r What(|r|))`, `What(rho) = rho^-d int_0^rho s^(d-1) W(s) ds` (paper 2, eq 9),
//! and splitting off the point-source part `1 / (A_d rho^d)` (whose flux through a closed
//! boundary is exactly 1), `gamma(x) = 1 + sum_j r_n,j int_{S_j} F(|y - x|) dS` with normals
//! out of the fluid, `r_n,j = (c_j - x) . n_j` and, inside the support (zero beyond),
//! `F(q) = [q^5/32 - 35q^4/128 + 7q^3/8 - 35q^2/32 + 7/8] / (pi h^2) - 1 / (2 pi q^2 h^2)` in 2-D
//! (the sign of the polynomial part corrected from the paper's printed eq 11).
//!
//! 2-D segments are integrated in closed form: each segment is clipped to the support circle,
//! the polynomial part uses `int (a^2 + u^2)^(k/2) du` exactly, and the divergent part is
//! `-theta / (2 pi)` with `theta` the signed angle the clipped segment subtends (paper 2,
//! eqs 13-15). A point on a wall is evaluated a distance `1e-12 h` inside the fluid, the limit
//! from the fluid side (`gamma = 1/2` on a flat wall, `1/4` at a right-angled corner).
//! 3-D planar elements (triangles, quadrilateral patches) are integrated exactly as well, in
//! polar coordinates about the foot of the perpendicular (see [`patch_contribution`]), with
//! `F = [21q^5/1024 - 45q^4/256 + 35q^3/64 - 21q^2/32 + 7/16] / (pi h^3) - 1 / (4 pi q^3 h^3)`.

use super::BoundaryElements;
use crate::dim::Vector;
use crate::kernel::Wendland;
use crate::neighbours::{CellGrid, Periodicity};
use glam::{DVec2, DVec3};
use std::f64::consts::PI;

/// `int_0^u (a^2 + t^2)^(k/2) dt` for `k = 0, 2, 3, 4, 5`, as `[I0, I2, I3, I4, I5]`.
pub(crate) fn radial_moments(a: f64, u: f64) -> [f64; 5] {
    let (a2, u2) = (a * a, u * u);
    let rho = (a2 + u2).sqrt();
    let log_term = if a == 0.0 { 0.0 } else { (u / a.abs()).asinh() };
    let i0 = u;
    let i2 = a2 * u + u * u2 / 3.0;
    let i3 = u * (2.0 * u2 + 5.0 * a2) * rho / 8.0 + 3.0 * a2 * a2 / 8.0 * log_term;
    let i4 = a2 * a2 * u + 2.0 * a2 * u * u2 / 3.0 + u * u2 * u2 / 5.0;
    let i5 = u * (8.0 * u2 * u2 + 26.0 * a2 * u2 + 33.0 * a2 * a2) * rho / 48.0
        + 5.0 * a2 * a2 * a2 / 16.0 * log_term;
    [i0, i2, i3, i4, i5]
}

/// `int F_P(q) dl` (in units of `h`) along the line at distance `a` from the point, from
/// foot offset `u0` to `u1` (all lengths in units of `h`); `F_P` the polynomial part.
fn polynomial_integral(a: f64, u0: f64, u1: f64) -> f64 {
    let m1 = radial_moments(a, u1);
    let m0 = radial_moments(a, u0);
    let d: [f64; 5] = std::array::from_fn(|k| m1[k] - m0[k]);
    // [q^5/32 - 35q^4/128 + 7q^3/8 - 35q^2/32 + 7/8] / pi
    (d[4] / 32.0 - 35.0 * d[3] / 128.0 + 7.0 * d[2] / 8.0 - 35.0 * d[1] / 32.0 + 7.0 * d[0] / 8.0)
        / PI
}

/// Contribution of the segment `p0 -> p1` with outward normal `n` to `gamma(x) - 1`.
pub fn segment_contribution(kernel: &Wendland, x: DVec2, p0: DVec2, p1: DVec2, n: DVec2) -> f64 {
    let h = kernel.h;
    let d = p1 - p0;
    let length = d.length();
    if length == 0.0 {
        return 0.0;
    }
    let t = d / length;
    // Work in units of h, with the foot of the perpendicular from x as origin along t.
    let a = (p0 - x).dot(n) / h; // signed normal distance, > 0 on the fluid side
                                 // Both ends from their own offsets (not `s0 + length`): exact near a corner at `x`.
    let s0 = (p0 - x).dot(t) / h;
    let s1 = (p1 - x).dot(t) / h;
    let half_chord2 = 4.0 - a * a;
    if half_chord2 <= 0.0 {
        return 0.0;
    }
    let half_chord = half_chord2.sqrt();
    let (u0, u1) = (s0.max(-half_chord), s1.min(half_chord));
    if u0 >= u1 {
        return 0.0;
    }
    let polynomial = a * polynomial_integral(a.abs(), u0, u1);
    // Signed angle subtended by the clipped segment: atan(u1/a) - atan(u0/a).
    let theta = if a == 0.0 {
        0.0
    } else {
        (u1 / a).atan() - (u0 / a).atan()
    };
    polynomial - theta / (2.0 * PI)
}

/// `Phi(q) = int q F_P(q) dq` (3-D, kernel units), the radial antiderivative of the polynomial
/// part: `int_0^rho F_P(q) rho' drho' = Phi(q(rho)) - Phi(|a|)` with `q^2 = a^2 + rho^2`.
fn phi3(q: f64) -> f64 {
    let q2 = q * q;
    let q4 = q2 * q2;
    (7.0 * q2 / 32.0 - 21.0 * q4 / 128.0 + 7.0 * q4 * q / 64.0 - 15.0 * q4 * q2 / 512.0
        + 3.0 * q4 * q2 * q / 1024.0)
        / PI
}

/// Antiderivatives `int_0^t (A + s^2)^(k/2) ds` for `k = -1, 0, 1, 2, 3, 4, 5` (`A > 0`).
fn moments3(big_a: f64, t: f64) -> [f64; 7] {
    let t2 = t * t;
    let r = (big_a + t2).sqrt();
    let ash = (t / big_a.sqrt()).asinh();
    [
        ash,
        t,
        0.5 * (t * r + big_a * ash),
        big_a * t + t * t2 / 3.0,
        t * (2.0 * t2 + 5.0 * big_a) * r / 8.0 + 3.0 * big_a * big_a / 8.0 * ash,
        big_a * big_a * t + 2.0 * big_a * t * t2 / 3.0 + t * t2 * t2 / 5.0,
        t * (8.0 * t2 * t2 + 26.0 * big_a * t2 + 33.0 * big_a * big_a) * r / 48.0
            + 5.0 * big_a * big_a * big_a / 16.0 * ash,
    ]
}

/// Fan triangle of one polygon edge (paper 2, eqs 16-17, integrated exactly): the part of the
/// triangle (foot of the perpendicular, `p(t0)`, `p(t1)`) inside the support, with the edge
/// line `p(t) = d nu + t tau` at signed in-plane distance `d` (> 0 counter-clockwise) and the
/// point at signed height `a` (> 0 on the fluid side), all in units of `h`. Returns
/// `a int F(q) dS` over it, `F = F_P - 1/(4 pi q^3)`.
///
/// In polar coordinates about the foot, `a int_0^rho_max F rho drho` is
/// `a [Phi(Q) - Phi(|a|)] - sign(a) (1 - |a|/Q) / (4 pi)` with `Q = q(rho_max)`; on the edge
/// `dtheta = d dt / (d^2 + t^2)`, and `int (A + t^2)^(k/2) / (d^2 + t^2) dt`, `A = a^2 + d^2`,
/// follows from `f_k = (A + t^2)^(k/2 - 1) + a^2 f_(k-2)` down to `atan` terms. Where the edge
/// leaves the support the remaining angle sees `Q = 2`.
fn edge_integral(a: f64, d: f64, t0: f64, t1: f64) -> f64 {
    let sa = if a >= 0.0 { 1.0 } else { -1.0 };
    let (aa, ad) = (a.abs(), d.abs());
    let rb2 = 4.0 - a * a;
    let phi_a = phi3(aa);
    let arc_value = a * (phi3(2.0) - phi_a) - sa * (1.0 - 0.5 * aa) / (4.0 * PI);
    let angle = |t: f64| (t / d).atan();
    if ad * ad >= rb2 {
        return arc_value * (angle(t1) - angle(t0));
    }
    let tb = (rb2 - d * d).sqrt();
    let mut total = 0.0;
    if t0 < -tb {
        total += arc_value * (angle(t1.min(-tb)) - angle(t0));
    }
    if t1 > tb {
        total += arc_value * (angle(t1) - angle(t0.max(tb)));
    }
    let (u0, u1) = (t0.max(-tb), t1.min(tb));
    if u0 < u1 {
        let a2 = a * a;
        let big_a = a2 + d * d;
        let (m1, m0) = (moments3(big_a, u1), moments3(big_a, u0));
        let i: [f64; 7] = std::array::from_fn(|k| m1[k] - m0[k]);
        let e0 = angle(u1) - angle(u0);
        let tilt = |t: f64| (aa * t).atan2(ad * (big_a + t * t).sqrt());
        // |a| d int dt / ((d^2 + t^2) sqrt(A + t^2)).
        let g = d.signum() * (tilt(u1) - tilt(u0));
        let e2 = d * i[1] + a2 * e0;
        let e4 = d * i[3] + a2 * e2;
        let e6 = d * i[5] + a2 * e4;
        let e1 = d * i[0] + aa * g;
        let e3 = d * i[2] + a2 * e1;
        let e5 = d * i[4] + a2 * e3;
        let e7 = d * i[6] + a2 * e5;
        let poly = (7.0 * e2 / 32.0 - 21.0 * e4 / 128.0 + 7.0 * e5 / 64.0 - 15.0 * e6 / 512.0
            + 3.0 * e7 / 1024.0)
            / PI;
        total += a * (poly - phi_a * e0) - sa * (e0 - g) / (4.0 * PI);
    }
    total
}

/// Contribution of the planar polygon `corners` (3-D: a triangle or a quadrilateral patch) with
/// outward normal `n` to `gamma(x) - 1`, `r_n int_{S cap B} F(|y - x|) dS` (paper 2, eqs 8 and
/// 16-17), exact: the element is clipped to the support sphere and integrated in polar
/// coordinates about the foot of the perpendicular from `x`, one fan triangle per edge
/// ([`edge_integral`]); the divergent part is `-Omega/(4 pi)` with `Omega` the solid angle of
/// the clipped element, signed positive on the fluid side. Holds for triangles and for square
/// patches alike, and for a foot inside or outside the element.
pub fn patch_contribution(
    kernel: &Wendland,
    x: DVec3,
    corners: &[DVec3],
    n: DVec3,
    _area: f64,
) -> f64 {
    let h = kernel.h;
    if corners.len() < 3 {
        return 0.0;
    }
    let a = (corners[0] - x).dot(n) / h;
    if a.abs() >= 2.0 {
        return 0.0;
    }
    let e1 = n.any_orthonormal_vector();
    let e2 = n.cross(e1);
    let foot = x + n * (a * h);
    let mut pts = [DVec2::ZERO; 8];
    let m = corners.len().min(8);
    for (p, &c) in pts.iter_mut().zip(corners) {
        let r = (c - foot) / h;
        *p = DVec2::new(r.dot(e1), r.dot(e2));
    }
    let pts = &pts[..m];
    let centroid = pts.iter().copied().sum::<DVec2>() / m as f64;
    let radius = pts
        .iter()
        .map(|&p| (p - centroid).length())
        .fold(0.0, f64::max);
    let rb = (4.0 - a * a).sqrt();
    if centroid.length() - radius >= rb {
        return 0.0;
    }
    let mut twice_area = 0.0;
    let mut sum = 0.0;
    for k in 0..m {
        let (p0, p1) = (pts[k], pts[(k + 1) % m]);
        twice_area += p0.perp_dot(p1);
        sum += edge_term(a, p0, p1);
    }
    if twice_area < 0.0 {
        -sum
    } else {
        sum
    }
}

/// The fan triangle of the edge `p0 -> p1` ([`edge_integral`]), its ends given in the plane
/// relative to the foot of the perpendicular, in units of `h`.
fn edge_term(a: f64, p0: DVec2, p1: DVec2) -> f64 {
    let edge = p1 - p0;
    let length = edge.length();
    if length == 0.0 {
        return 0.0;
    }
    let tau = edge / length;
    // `p0 x p1 / L`: exactly antisymmetric, so an edge shared by two elements cancels.
    let d = p0.perp_dot(p1) / length;
    if d == 0.0 {
        return 0.0; // the foot is on this edge's line: an empty fan triangle
    }
    // Both ends from their own offsets: exact when a corner is next to the foot.
    edge_integral(a, d, p0.dot(tau), p1.dot(tau))
}

/// Contribution to `gamma(x) - 1` of a planar region with outward normal `n` given by its
/// boundary edges, `edges[2k] -> edges[2k + 1]`, oriented counter-clockwise about `n`
/// (paper 2, eqs 8 and 16-17): the sum of their fan triangles, as in
/// [`patch_contribution`], for any union of coplanar elements (edges shared by two of them
/// cancel, so only the region's outline is needed).
pub fn face_contribution(kernel: &Wendland, x: DVec3, edges: &[DVec3], n: DVec3) -> f64 {
    let h = kernel.h;
    let Some(&p) = edges.first() else {
        return 0.0;
    };
    let a = (p - x).dot(n) / h;
    if a.abs() >= 2.0 {
        return 0.0;
    }
    let e1 = n.any_orthonormal_vector();
    let e2 = n.cross(e1);
    let foot = x + n * (a * h);
    let local = |c: DVec3| {
        let r = (c - foot) / h;
        DVec2::new(r.dot(e1), r.dot(e2))
    };
    edges
        .chunks_exact(2)
        .map(|e| edge_term(a, local(e[0]), local(e[1])))
        .sum()
}

/// 2-D pieces of a [`GammaCache`]: every maximal run of consecutive elements that continue
/// one straight wall (each starts exactly where the previous one ends, with the same normal,
/// perpendicular to both) becomes one segment; other elements stay as they are.
pub(crate) fn merge_segments(e: &BoundaryElements<DVec2>, cache: &mut GammaCache<DVec2>) {
    let straight = |c: &[DVec2], n: DVec2| {
        let d = c[1] - c[0];
        c.len() == 2 && n.dot(d).abs() <= 1e-12 * d.length()
    };
    let mut j = 0;
    while j < e.len() {
        let c = e.current_corners(j);
        let n = e.normal[j];
        let mut area = e.area[j];
        if c.len() == 2 && straight(c, n) {
            let (p0, mut p1) = (c[0], c[1]);
            let d0 = p1 - p0;
            while j + 1 < e.len() {
                let next = e.current_corners(j + 1);
                if next.len() != 2
                    || next[0] != p1
                    || e.normal[j + 1] != n
                    || (next[1] - next[0]).dot(d0) <= 0.0
                    || !straight(next, n)
                {
                    break;
                }
                p1 = next[1];
                area += e.area[j + 1];
                j += 1;
            }
            cache.push_piece(
                &[p0, p1],
                n,
                area,
                (p0 + p1) * 0.5,
                (p1 - p0).length() * 0.5,
            );
        } else {
            cache.push_piece(&c[..2], n, area, e.centre[j], e.reach[j]);
        }
        j += 1;
    }
}

/// 3-D pieces of a [`GammaCache`]: the elements of one plane (same normal, bit for bit, and
/// the same offset along it) become one region, the outline left when every edge shared by
/// two of them (the same two corners, opposite directions) is dropped, with runs of
/// collinear outline edges joined; each element is first oriented counter-clockwise about
/// its normal. A box face is then one rectangle of four edges, whatever its mesh.
pub(crate) fn merge_faces(e: &BoundaryElements<DVec3>, cache: &mut GammaCache<DVec3>) {
    use std::collections::HashMap;
    let bits = |p: DVec3| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
    // Corners of element j, counter-clockwise about its normal.
    let oriented = |j: usize| {
        let c = e.current_corners(j);
        let mut newell = DVec3::ZERO;
        for k in 0..c.len() {
            newell += c[k].cross(c[(k + 1) % c.len()]);
        }
        let mut v = c.to_vec();
        if newell.dot(e.normal[j]) < 0.0 {
            v.reverse();
        }
        v
    };
    let scale = e.max_reach.max(f64::MIN_POSITIVE);
    let mut planar = Vec::new();
    for j in 0..e.len() {
        let (c, n) = (e.current_corners(j), e.normal[j]);
        if c.len() >= 3 && c.iter().all(|&p| n.dot(p - c[0]).abs() <= 1e-12 * scale) {
            planar.push((bits(n), n.dot(c[0]), j));
        } else if c.len() >= 3 {
            // Not flat: a piece of its own, as the element-by-element sum sees it.
            let v = oriented(j);
            let mut edges = Vec::with_capacity(2 * v.len());
            for k in 0..v.len() {
                edges.extend([v[k], v[(k + 1) % v.len()]]);
            }
            cache.push_piece(&edges, n, e.area[j], e.centre[j], e.reach[j]);
        }
    }
    planar.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut g = 0;
    while g < planar.len() {
        let mut end = g + 1;
        while end < planar.len()
            && planar[end].0 == planar[g].0
            && (planar[end].1 - planar[g].1).abs() <= 1e-10 * scale
        {
            end += 1;
        }
        let mut members: Vec<usize> = planar[g..end].iter().map(|m| m.2).collect();
        members.sort_unstable();
        g = end;
        // Outline: every element's edges, shared ones dropped in pairs.
        let mut edges: Vec<(DVec3, DVec3)> = Vec::new();
        let mut area = 0.0;
        for &j in &members {
            let v = oriented(j);
            area += e.area[j];
            for k in 0..v.len() {
                edges.push((v[k], v[(k + 1) % v.len()]));
            }
        }
        let mut alive = vec![true; edges.len()];
        let mut open: HashMap<([u64; 3], [u64; 3]), Vec<usize>> = HashMap::new();
        for (i, &(p, q)) in edges.iter().enumerate() {
            if let Some(k) = open.get_mut(&(bits(q), bits(p))).and_then(|v| v.pop()) {
                alive[k] = false;
                alive[i] = false;
            } else {
                open.entry((bits(p), bits(q))).or_default().push(i);
            }
        }
        let outline: Vec<(DVec3, DVec3)> = edges
            .iter()
            .zip(&alive)
            .filter(|(_, &a)| a)
            .map(|(&e, _)| e)
            .collect();
        if outline.is_empty() {
            continue;
        }
        // Join collinear runs: an edge continues the one ending where it starts when that
        // corner has exactly one edge in and one out and the two are parallel.
        let mut starting: HashMap<[u64; 3], Vec<usize>> = HashMap::new();
        let mut ending: HashMap<[u64; 3], usize> = HashMap::new();
        for (i, &(p, q)) in outline.iter().enumerate() {
            starting.entry(bits(p)).or_default().push(i);
            *ending.entry(bits(q)).or_default() += 1;
        }
        let parallel = |i: usize, k: usize| {
            let (u, v) = (outline[i].1 - outline[i].0, outline[k].1 - outline[k].0);
            u.dot(v) > 0.0 && u.cross(v).length() <= 1e-12 * u.length() * v.length()
        };
        let next = |i: usize| {
            let q = bits(outline[i].1);
            match (starting.get(&q).map(Vec::as_slice), ending.get(&q)) {
                (Some(&[k]), Some(&1)) if k != i && parallel(i, k) => Some(k),
                _ => None,
            }
        };
        let mut continues = vec![false; outline.len()];
        for i in 0..outline.len() {
            if let Some(k) = next(i) {
                continues[k] = true;
            }
        }
        let mut used = vec![false; outline.len()];
        let mut corners = Vec::new();
        let chain = |i: usize, used: &mut Vec<bool>, corners: &mut Vec<DVec3>| {
            let start = outline[i].0;
            let mut last = i;
            used[i] = true;
            while let Some(k) = next(last) {
                if used[k] {
                    break;
                }
                used[k] = true;
                last = k;
            }
            corners.extend([start, outline[last].1]);
        };
        for i in 0..outline.len() {
            if !continues[i] && !used[i] {
                chain(i, &mut used, &mut corners);
            }
        }
        for i in 0..outline.len() {
            if !used[i] {
                chain(i, &mut used, &mut corners);
            }
        }
        let (mut lo, mut hi) = (corners[0], corners[0]);
        for &c in &corners {
            lo = lo.min(c);
            hi = hi.max(c);
        }
        let centre = (lo + hi) * 0.5;
        let reach = corners
            .iter()
            .map(|&c| (c - centre).length())
            .fold(0.0, f64::max);
        let n = e.normal[members[0]];
        cache.push_piece(&corners, n, area, centre, reach);
    }
}

/// Solid angle subtended by the triangle with corners at `a`, `b`, `c` (relative to the
/// viewpoint), Van Oosterom & Strackee (1983); signed by the corner order.
pub fn triangle_solid_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let numerator = a.dot(b.cross(c));
    let denominator = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    2.0 * numerator.atan2(denominator)
}

/// Geometric Shepard factor at `x` from the wall elements near it (paper 2, eq 8).
///
/// A point on a wall element is first moved `1e-12 h` into the fluid, along the sum of the
/// inward normals of the elements it lies on (the one-sided limit, exact to about `1e-12`).
/// Every element that overlaps the support is visited, whatever the grid's cell size. When
/// `elements` carry a [`GammaCache`] built for this kernel (simulations build one), its
/// merged pieces and candidate lists are used instead of the walk over `grid`.
pub fn gamma<V: Vector>(
    kernel: &Wendland,
    x: V,
    elements: &BoundaryElements<V>,
    grid: &CellGrid<V>,
) -> f64 {
    if elements.gamma_cache.is_built_for(kernel.support) {
        return elements.gamma_cache.gamma(kernel, x);
    }
    let eps = 1e-12 * kernel.h;
    let radius = kernel.support + elements.max_reach;
    // One walk sums the contributions and finds the elements the point lies on; only such a
    // point (rare) is moved and summed again.
    let sum_at = |x: V, shift: &mut V| {
        let mut gamma = 1.0;
        // Periodic axes: the grid hands each element's image shift; the element's corners are
        // stored at its own image, so the point is moved instead (minimum image).
        grid.for_each_candidate_within_shifted(x, radius, |j, image| {
            let r = elements.centre[j] + image - x;
            let reach = elements.reach[j];
            if r.length_squared() > (kernel.support + reach) * (kernel.support + reach) {
                return;
            }
            let rn = r.dot(elements.normal[j]);
            if rn.abs() < eps && (r - elements.normal[j] * rn).length() <= reach * (1.0 + 1e-12) {
                *shift -= elements.normal[j] * eps;
            }
            gamma += V::wall_gamma_contribution(
                kernel,
                x - image,
                elements.current_corners(j),
                elements.normal[j],
                elements.area[j],
            );
        });
        gamma
    };
    let mut shift = V::ZERO;
    let gamma = sum_at(x, &mut shift);
    if shift == V::ZERO {
        return gamma;
    }
    let mut unused = V::ZERO;
    sum_at(x + shift, &mut unused)
}

/// Wall pieces prepared for the geometric Shepard factor, with per-cell candidate lists.
///
/// `gamma` depends on the wall geometry only, not on how it is cut into elements: the
/// integral over a segment is the sum of the integrals over its parts. So in 2-D every run of
/// consecutive elements that continue one straight wall (each starts exactly where the
/// previous one ends, the same normal, perpendicular to both) becomes one piece, and a
/// particle near a flat wall evaluates one exact segment integral instead of one per element
/// within its support. Other elements (3-D polygons, isolated segments) are pieces of their
/// own. A uniform grid over the pieces (cells of `support / 2` in 2-D, `support` in 3-D)
/// lists, per cell, every piece (with its periodic image) that comes within the support of
/// some point of the cell; a point in a cell with an empty list, or outside the grid, has
/// `gamma = 1` without a walk. Built from the current element corners, so moving and
/// stretching walls rebuild it when they are placed ([`super::Walls::move_to`]); the sum is
/// over the cell's list in piece order, independent of threads.
#[derive(Clone, Debug, Default)]
pub struct GammaCache<V: Vector> {
    /// Kernel support the lists hold for; 0 when not built.
    support: f64,
    period: Periodicity<V>,
    /// Corners of every piece, flattened: piece `p` owns `corners[start[p]..start[p + 1]]`.
    corners: Vec<V>,
    start: Vec<u32>,
    normal: Vec<V>,
    area: Vec<f64>,
    centre: Vec<V>,
    reach: Vec<f64>,
    origin: V,
    inv_cell: f64,
    dims: [usize; 3],
    /// Candidates of cell `c`: `candidates[cell_start[c]..cell_start[c + 1]]`, each a piece
    /// and the index of its image shift in `shifts`.
    cell_start: Vec<u32>,
    candidates: Vec<(u32, u32)>,
    shifts: Vec<V>,
}

impl<V: Vector> GammaCache<V> {
    /// `true` when the lists were built for a kernel of this support.
    pub fn is_built_for(&self, support: f64) -> bool {
        self.support > 0.0 && self.support == support
    }

    /// The support the lists were built for (0 when not built).
    pub fn support(&self) -> f64 {
        self.support
    }

    /// Number of pieces (merged wall segments and other elements).
    pub fn pieces(&self) -> usize {
        self.normal.len()
    }

    /// Corners of piece `p`.
    fn piece_corners(&self, p: usize) -> &[V] {
        &self.corners[self.start[p] as usize..self.start[p + 1] as usize]
    }

    /// Rebuilds the pieces and lists from the current `elements` for kernel support
    /// `support`, with `period` the periodic axes (elements in the primary period).
    pub fn rebuild(
        &mut self,
        elements: &BoundaryElements<V>,
        support: f64,
        period: Periodicity<V>,
    ) {
        self.support = support;
        self.period = period;
        self.merge_pieces(elements);
        self.build_lists();
    }

    /// Pieces from the current elements (see [`merge_segments`], [`merge_faces`]).
    fn merge_pieces(&mut self, e: &BoundaryElements<V>) {
        self.corners.clear();
        self.start.clear();
        self.start.push(0);
        self.normal.clear();
        self.area.clear();
        self.centre.clear();
        self.reach.clear();
        V::merge_gamma_pieces(e, self);
    }

    /// Appends a piece: its corners (2-D: the segment's two ends; 3-D: its outline edges as
    /// pairs of ends), outward normal, area, and a centre and reach bounding it.
    pub(crate) fn push_piece(
        &mut self,
        corners: &[V],
        normal: V,
        area: f64,
        centre: V,
        reach: f64,
    ) {
        self.corners.extend_from_slice(corners);
        self.start.push(self.corners.len() as u32);
        self.normal.push(normal);
        self.area.push(area);
        self.centre.push(centre);
        self.reach.push(reach);
    }

    /// The uniform grid over the pieces and each cell's candidates.
    fn build_lists(&mut self) {
        let support = self.support;
        self.shifts.clear();
        self.candidates.clear();
        self.cell_start.clear();
        if self.normal.is_empty() {
            self.dims = [0; 3];
            return;
        }
        let (mut lo, mut hi) = (self.corners[0], self.corners[0]);
        for &c in &self.corners {
            lo = lo.min_by_component(c);
            hi = hi.max_by_component(c);
        }
        for k in 0..V::DIM {
            if self.period.is_periodic(k) {
                let m = self.period.min.get(k);
                lo.set(k, m);
                hi.set(k, m + self.period.length.get(k));
            } else {
                lo.set(k, lo.get(k) - support);
                hi.set(k, hi.get(k) + support);
            }
        }
        let mut cell = if V::DIM == 2 { 0.5 * support } else { support };
        let dims = loop {
            let mut dims = [1usize; 3];
            for (k, d) in dims.iter_mut().enumerate().take(V::DIM) {
                *d = (((hi.get(k) - lo.get(k)) / cell).ceil() as usize).max(1);
            }
            // Bounded memory for walls spread over a large region.
            if dims[0] * dims[1] * dims[2] <= 1 << 22 {
                break dims;
            }
            cell *= 2.0;
        };
        self.origin = lo;
        self.inv_cell = 1.0 / cell;
        self.dims = dims;
        // Image shifts: every combination of -2..=2 periods along the periodic axes.
        let mut ranges = [(0i64, 0i64); 3];
        for (k, r) in ranges.iter_mut().enumerate().take(V::DIM) {
            if self.period.is_periodic(k) {
                *r = (-2, 2);
            }
        }
        for a in ranges[0].0..=ranges[0].1 {
            for b in ranges[1].0..=ranges[1].1 {
                for c in ranges[2].0..=ranges[2].1 {
                    let mut s = V::ZERO;
                    for (k, m) in [a, b, c].into_iter().enumerate().take(V::DIM) {
                        s.set(k, m as f64 * self.period.length.get(k));
                    }
                    self.shifts.push(s);
                }
            }
        }
        let half_diagonal = 0.5 * cell * (V::DIM as f64).sqrt();
        let mut pairs: Vec<(u32, u32, u32)> = Vec::new();
        for p in 0..self.normal.len() {
            let corners = self.piece_corners(p);
            let (mut plo, mut phi) = (corners[0], corners[0]);
            for &c in corners {
                plo = plo.min_by_component(c);
                phi = phi.max_by_component(c);
            }
            for (si, &s) in self.shifts.iter().enumerate() {
                // Cells that the piece's box, widened by the support, overlaps.
                let mut range = [(0usize, 0usize); 3];
                let mut empty = false;
                for (k, r) in range.iter_mut().enumerate() {
                    if k >= V::DIM {
                        continue;
                    }
                    let a = ((plo.get(k) + s.get(k) - support - lo.get(k)) * self.inv_cell).floor();
                    let b = ((phi.get(k) + s.get(k) + support - lo.get(k)) * self.inv_cell).floor();
                    let (a, b) = (a.max(0.0), b.min(dims[k] as f64 - 1.0));
                    if a > b {
                        empty = true;
                        break;
                    }
                    *r = (a as usize, b as usize);
                }
                if empty {
                    continue;
                }
                for cz in range[2].0..=range[2].1 {
                    for cy in range[1].0..=range[1].1 {
                        for cx in range[0].0..=range[0].1 {
                            let mut mid = lo;
                            for (k, ck) in [cx, cy, cz].into_iter().enumerate().take(V::DIM) {
                                mid.set(k, lo.get(k) + (ck as f64 + 0.5) * cell);
                            }
                            // A lower bound of the distance from the cell's centre.
                            let distance = if V::DIM == 2 {
                                segment_distance(mid - s, corners[0], corners[1])
                            } else {
                                let sphere = (self.centre[p] + s - mid).length() - self.reach[p];
                                let plane = self.normal[p].dot(mid - s - corners[0]).abs();
                                sphere.max(plane)
                            };
                            if distance < support + half_diagonal {
                                let c = cx + dims[0] * (cy + dims[1] * cz);
                                pairs.push((c as u32, p as u32, si as u32));
                            }
                        }
                    }
                }
            }
        }
        // Counting sort by cell, stable: each cell's pieces in piece order.
        let cells = dims[0] * dims[1] * dims[2];
        self.cell_start.resize(cells + 1, 0);
        for &(c, _, _) in &pairs {
            self.cell_start[c as usize + 1] += 1;
        }
        for c in 0..cells {
            self.cell_start[c + 1] += self.cell_start[c];
        }
        self.candidates.resize(pairs.len(), (0, 0));
        let mut fill = self.cell_start.clone();
        for &(c, p, s) in &pairs {
            let slot = &mut fill[c as usize];
            self.candidates[*slot as usize] = (p, s);
            *slot += 1;
        }
    }

    /// The candidates of the cell holding `x` (empty outside the grid).
    #[inline(always)]
    fn cell_candidates(&self, x: V) -> &[(u32, u32)] {
        let mut c = 0usize;
        let mut stride = 1usize;
        for k in 0..V::DIM {
            let v = (x.get(k) - self.origin.get(k)) * self.inv_cell;
            // Also rejects NaN.
            if !(v >= 0.0 && v < self.dims[k] as f64) {
                return &[];
            }
            c += v as usize * stride;
            stride *= self.dims[k];
        }
        &self.candidates[self.cell_start[c] as usize..self.cell_start[c + 1] as usize]
    }

    /// Geometric Shepard factor at `x` (paper 2, eq 8), as [`gamma`] but over the cell's
    /// candidate pieces. The kernel must have the support the lists were built for.
    pub fn gamma(&self, kernel: &Wendland, x: V) -> f64 {
        debug_assert!(self.is_built_for(kernel.support));
        let eps = 1e-12 * kernel.h;
        let mut shift = V::ZERO;
        let gamma = self.sum_at(kernel, x, eps, &mut shift);
        if shift == V::ZERO {
            return gamma;
        }
        let mut unused = V::ZERO;
        self.sum_at(kernel, x + shift, eps, &mut unused)
    }

    /// `1 + sum` of the candidates' contributions at `x`; subtracts `eps n` from `shift` for
    /// each piece `x` lies on.
    #[inline(always)]
    fn sum_at(&self, kernel: &Wendland, x: V, eps: f64, shift: &mut V) -> f64 {
        let x = self.period.wrap(x);
        let mut gamma = 1.0;
        for &(p, s) in self.cell_candidates(x) {
            let p = p as usize;
            let xs = x - self.shifts[s as usize];
            let r = self.centre[p] - xs;
            let (n, reach) = (self.normal[p], self.reach[p]);
            if r.length_squared() > (self.support + reach) * (self.support + reach) {
                continue;
            }
            let rn = r.dot(n);
            if rn.abs() < eps && (r - n * rn).length() <= reach * (1.0 + 1e-12) {
                *shift -= n * eps;
            }
            gamma += V::piece_gamma_contribution(kernel, xs, self.piece_corners(p), n);
        }
        gamma
    }
}

/// Distance from `x` to the segment `p0 -> p1`.
fn segment_distance<V: Vector>(x: V, p0: V, p1: V) -> f64 {
    let d = p1 - p0;
    let l2 = d.length_squared();
    let t = if l2 > 0.0 {
        ((x - p0).dot(d) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p0 + d * t - x).length()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::box_elements_2d;

    #[test]
    fn radial_moments_match_quadrature() {
        for &a in &[0.0, 0.3, 1.7] {
            let u = 1.3;
            let n = 200_000;
            let mut num = [0.0; 5];
            for k in 0..n {
                let t = (k as f64 + 0.5) * u / n as f64;
                let rho = (a * a + t * t).sqrt();
                for (m, p) in num.iter_mut().zip([0, 2, 3, 4, 5]) {
                    *m += rho.powi(p) * u / n as f64;
                }
            }
            let exact = radial_moments(a, u);
            for k in 0..5 {
                assert!(
                    (num[k] - exact[k]).abs() < 1e-8 * (1.0 + exact[k].abs()),
                    "a={a} k={k}"
                );
            }
        }
    }

    use crate::quadrature::gauss_legendre as gauss;

    /// Area integral of W over the box's interior within the support of `x`, by iterated
    /// Gauss quadrature over exact limits (the integrand is smooth inside them).
    fn reference_gamma(kernel: &Wendland, x: DVec2, lo: DVec2, hi: DVec2) -> f64 {
        let s = kernel.support;
        let (y0, y1) = ((x.y - s).max(lo.y), (x.y + s).min(hi.y));
        gauss(y0, y1, 64, |y| {
            let half = (s * s - (y - x.y) * (y - x.y)).max(0.0).sqrt();
            let (x0, x1) = ((x.x - half).max(lo.x), (x.x + half).min(hi.x));
            if x1 <= x0 {
                return 0.0;
            }
            gauss(x0, x1, 64, |xx| {
                kernel.value(DVec2::new(xx - x.x, y - x.y).length())
            })
        })
    }

    #[test]
    fn matches_area_integral_near_walls_and_corners() {
        let (lo, hi) = (DVec2::ZERO, DVec2::new(1.0, 1.0));
        let dx = 0.01;
        let kernel = Wendland::new(0.02, 2);
        let mut e = BoundaryElements::default();
        for s in box_elements_2d(lo, hi, &[], dx) {
            e.push(s.centre, s.normal, s.area, 0, &s.corners);
        }
        let mut grid = CellGrid::new(kernel.support);
        grid.rebuild(&e.centre);
        for &(x, y) in &[
            (0.5, 0.013),
            (0.5, 0.031),
            (0.007, 0.021),
            (0.011, 0.013),
            (0.5, 0.5),
            (0.5, 0.0399),
        ] {
            let p = DVec2::new(x, y);
            let g = gamma(&kernel, p, &e, &grid);
            let r = reference_gamma(&kernel, p, lo, hi);
            assert!((g - r).abs() < 1e-9, "({x},{y}): {g} vs {r}");
        }
        // On the wall and at a corner: exact limits.
        assert!((gamma(&kernel, DVec2::new(0.5, 0.0), &e, &grid) - 0.5).abs() < 1e-10);
        assert!((gamma(&kernel, DVec2::new(0.503, 0.0), &e, &grid) - 0.5).abs() < 1e-10);
        assert!((gamma(&kernel, DVec2::new(0.0, 0.0), &e, &grid) - 0.25).abs() < 1e-10);
        assert!((gamma(&kernel, DVec2::new(1.0, 1.0), &e, &grid) - 0.25).abs() < 1e-10);
    }

    /// Volume integral of W over the box's interior within the support of `x`: iterated Gauss
    /// quadrature over exact limits, each range split at the point's own coordinate.
    fn reference_gamma_3d(kernel: &Wendland, x: DVec3, lo: DVec3, hi: DVec3) -> f64 {
        let s = kernel.support;
        let split = |a: f64, b: f64, c: f64, panels: usize, f: &mut dyn FnMut(f64) -> f64| {
            if b <= a {
                return 0.0;
            }
            if c > a && c < b {
                gauss(a, c, panels, &mut *f) + gauss(c, b, panels, &mut *f)
            } else {
                gauss(a, b, panels, &mut *f)
            }
        };
        let panels = 10;
        split(
            (x.z - s).max(lo.z),
            (x.z + s).min(hi.z),
            x.z,
            panels,
            &mut |z| {
                let dz = z - x.z;
                let ry = (s * s - dz * dz).max(0.0).sqrt();
                split(
                    (x.y - ry).max(lo.y),
                    (x.y + ry).min(hi.y),
                    x.y,
                    panels,
                    &mut |y| {
                        let dy = y - x.y;
                        let rx = (s * s - dz * dz - dy * dy).max(0.0).sqrt();
                        split(
                            (x.x - rx).max(lo.x),
                            (x.x + rx).min(hi.x),
                            x.x,
                            panels,
                            &mut |xx| kernel.value(DVec3::new(xx - x.x, dy, dz).length()),
                        )
                    },
                )
            },
        )
    }

    fn walls_3d(shapes: Vec<crate::geometry::ElementShape<DVec3>>) -> BoundaryElements<DVec3> {
        let mut e = BoundaryElements::default();
        for s in shapes {
            e.push(s.centre, s.normal, s.area, 0, &s.corners);
        }
        e
    }

    /// The unit cube's walls three ways: square patches, triangles, and faces with patches of
    /// unequal sizes.
    fn cube_walls(dx: f64) -> Vec<(&'static str, BoundaryElements<DVec3>)> {
        use crate::geometry::{box_elements_3d, rectangle_elements, triangulate};
        let (lo, hi) = (DVec3::ZERO, DVec3::ONE);
        let patches = box_elements_3d(lo, hi, &[], dx);
        let triangles = triangulate(patches.clone());
        let mut mixed = Vec::new();
        for k in 0..6 {
            let axis = k / 2;
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let mut origin = lo;
            let mut normal = DVec3::ZERO;
            normal[axis] = if k % 2 == 1 { 1.0 } else { -1.0 };
            if k % 2 == 1 {
                origin[axis] = hi[axis];
            }
            let (mut e1, mut e2) = (DVec3::ZERO, DVec3::ZERO);
            e1[u] = 1.0;
            e2[v] = 1.0;
            let size = dx * [1.0, 0.73, 1.31][axis];
            let face = rectangle_elements(origin, e1, e2, normal, size);
            mixed.extend(if k % 2 == 0 { triangulate(face) } else { face });
        }
        vec![
            ("square patches", walls_3d(patches)),
            ("triangles", walls_3d(triangles)),
            ("unequal mixed elements", walls_3d(mixed)),
        ]
    }

    #[test]
    fn exact_3d_limits_on_walls_edges_and_corners() {
        let kernel = Wendland::new(0.1, 3);
        for (name, e) in cube_walls(0.05) {
            let mut grid = CellGrid::new(kernel.support);
            grid.rebuild(&e.centre);
            let g = |x: f64, y: f64, z: f64| gamma(&kernel, DVec3::new(x, y, z), &e, &grid);
            for (p, expected) in [
                ((0.5, 0.5, 0.0), 0.5),
                ((0.5, 0.5, 1.0), 0.5),
                ((0.525, 0.5, 0.0), 0.5), // a patch edge or a triangle diagonal
                ((0.55, 0.45, 1.0), 0.5), // a patch vertex
                ((0.313, 0.0, 0.77), 0.5), // anywhere
                ((0.5, 0.0, 0.0), 0.25),
                ((1.0, 0.37, 1.0), 0.25),
                ((0.0, 0.0, 0.0), 0.125),
                ((1.0, 1.0, 1.0), 0.125),
                ((1.0, 0.0, 1.0), 0.125),
                ((0.5, 0.5, 0.5), 1.0),
            ] {
                let v = g(p.0, p.1, p.2);
                assert!(
                    (v - expected).abs() < 1e-10,
                    "{name} at {p:?}: {v} vs {expected}"
                );
            }
        }
    }

    #[test]
    fn exact_3d_matches_volume_integral_near_walls_edges_and_corners() {
        let kernel = Wendland::new(0.1, 3);
        let points = [
            DVec3::new(0.5, 0.5, 0.03),
            DVec3::new(0.51, 0.47, 0.17),
            DVec3::new(0.5, 0.02, 0.05),
            DVec3::new(0.03, 0.02, 0.05),
            DVec3::new(0.013, 0.171, 0.007),
            DVec3::new(0.96, 0.99, 0.93),
        ];
        let refs: Vec<f64> = points
            .iter()
            .map(|&p| reference_gamma_3d(&kernel, p, DVec3::ZERO, DVec3::ONE))
            .collect();
        for (name, e) in cube_walls(0.05) {
            let mut grid = CellGrid::new(kernel.support);
            grid.rebuild(&e.centre);
            for (&p, &r) in points.iter().zip(&refs) {
                let v = gamma(&kernel, p, &e, &grid);
                eprintln!(
                    "{name} at {p}: gamma {v:.15} reference {r:.15} diff {:.2e}",
                    v - r
                );
                assert!((v - r).abs() < 1e-10, "{name} at {p}: {v} vs {r}");
            }
        }
    }

    #[test]
    fn divergent_part_is_the_solid_angle_of_a_small_element() {
        // An element entirely inside the support: the divergent part of the exact integral is
        // -Omega / 4 pi, Omega from Van Oosterom-Strackee; the polynomial part is smooth.
        let kernel = Wendland::new(1.0, 3);
        let corners = [
            DVec3::new(0.1, -0.2, 0.3),
            DVec3::new(0.4, 0.1, 0.3),
            DVec3::new(-0.1, 0.3, 0.3),
        ];
        let n = DVec3::Z;
        for x in [DVec3::new(0.05, 0.0, 0.0), DVec3::new(0.9, 0.6, -0.2)] {
            let exact = patch_contribution(&kernel, x, &corners, n, 0.0);
            let omega = triangle_solid_angle(corners[0] - x, corners[1] - x, corners[2] - x).abs();
            // Polynomial part by a fine midpoint rule on barycentric sub-triangles.
            let m = 400;
            let mut poly = 0.0;
            let (a, b, c) = (corners[0], corners[1], corners[2]);
            let area = 0.5 * (b - a).cross(c - a).length();
            for i in 0..m {
                for j in 0..m - i {
                    for (u, v, w) in [
                        ((i as f64 + 1.0 / 3.0), (j as f64 + 1.0 / 3.0), 1.0),
                        ((i as f64 + 2.0 / 3.0), (j as f64 + 2.0 / 3.0), -1.0),
                    ] {
                        if w < 0.0 && i + j + 1 >= m {
                            continue;
                        }
                        let y = a + (b - a) * (u / m as f64) + (c - a) * (v / m as f64);
                        let q = (y - x).length();
                        let fp = (21.0 * q.powi(5) / 1024.0 - 45.0 * q.powi(4) / 256.0
                            + 35.0 * q.powi(3) / 64.0
                            - 21.0 * q * q / 32.0
                            + 7.0 / 16.0)
                            / PI;
                        poly += fp * area / (m * m) as f64;
                    }
                }
            }
            let rn = (a - x).dot(n);
            let expected = rn * poly - omega / (4.0 * PI);
            assert!((exact - expected).abs() < 1e-6, "{exact} vs {expected}");
        }
    }

    /// Gamma from the cache against the element-by-element walk at `points`.
    fn cache_matches_walk<V: Vector>(
        kernel: &Wendland,
        e: &BoundaryElements<V>,
        period: Periodicity<V>,
        points: &[V],
        tolerance: f64,
    ) {
        let mut grid = CellGrid::with_period(kernel.support, period).unwrap();
        grid.rebuild(&e.centre);
        let mut cached = e.clone();
        cached.gamma_cache.rebuild(e, kernel.support, period);
        assert!(cached.gamma_cache.pieces() <= e.len());
        for &x in points {
            let walk = gamma(kernel, x, e, &grid);
            let fast = gamma(kernel, x, &cached, &grid);
            assert!(
                (walk - fast).abs() < tolerance,
                "at {x:?}: walk {walk} cache {fast}"
            );
        }
    }

    /// Seeded uniform numbers in `[0, 1)` (a 64-bit linear congruential generator).
    fn uniform(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed;
        move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// A scatter of points over `[lo, hi]` plus the given extra ones.
    fn scatter_2d(lo: DVec2, hi: DVec2, n: usize, extra: &[DVec2]) -> Vec<DVec2> {
        let mut next = uniform(12345);
        let mut v: Vec<DVec2> = (0..n)
            .map(|_| lo + (hi - lo) * DVec2::new(next(), next()))
            .collect();
        v.extend_from_slice(extra);
        v
    }

    #[test]
    fn cache_merges_straight_walls_and_matches_the_walk() {
        let kernel = Wendland::new(0.02, 2);
        let dx = 0.01;
        let mut e = BoundaryElements::default();
        for s in box_elements_2d(DVec2::ZERO, DVec2::new(1.0, 0.6), &["+y".into()], dx) {
            e.push(s.centre, s.normal, s.area, 0, &s.corners);
        }
        // A polygon of unequal segments (a circle of 40 sides, radius 0.1) inside the box.
        let c = DVec2::new(0.5, 0.3);
        for k in 0..40 {
            // Unequal sides.
            let angle = |k: usize| {
                let t = 2.0 * PI * (k % 40) as f64 / 40.0;
                t + 0.05 * (3.0 * t).sin()
            };
            let (a0, a1) = (angle(k), angle(k + 1));
            let (p0, p1) = (
                c + 0.1 * DVec2::new(a0.cos(), a0.sin()),
                c + 0.1 * DVec2::new(a1.cos(), a1.sin()),
            );
            let t = (p1 - p0).normalize();
            // Fluid outside the circle: normals point into it.
            e.push(
                (p0 + p1) * 0.5,
                DVec2::new(-t.y, t.x),
                (p1 - p0).length(),
                1,
                &[p0, p1],
            );
        }
        let mut cached = e.clone();
        cached
            .gamma_cache
            .rebuild(&e, kernel.support, Periodicity::none());
        // Bottom, right and left walls, one piece each; the circle's 40 sides.
        assert_eq!(cached.gamma_cache.pieces(), 3 + 40);
        let extra = [
            DVec2::new(0.5, 0.0),
            DVec2::new(0.503, 0.0),
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 0.3),
            DVec2::new(0.5, 0.2),
            DVec2::new(0.5, 0.62),
            DVec2::new(-0.5, 0.3),
            DVec2::new(0.4, 0.3), // inside the circle (behind its wall)
        ];
        let points = scatter_2d(
            DVec2::new(-0.05, -0.05),
            DVec2::new(1.05, 0.7),
            4000,
            &extra,
        );
        cache_matches_walk(&kernel, &e, Periodicity::none(), &points, 1e-12);
        let mut grid = CellGrid::new(kernel.support);
        grid.rebuild(&e.centre);
        let g = |x: f64, y: f64| gamma(&kernel, DVec2::new(x, y), &cached, &grid);
        assert!((g(0.5, 0.0) - 0.5).abs() < 1e-10);
        assert!((g(0.503, 0.0) - 0.5).abs() < 1e-10);
        assert!((g(0.0, 0.0) - 0.25).abs() < 1e-10);
        assert!((g(1.0, 0.0) - 0.25).abs() < 1e-10);
        assert_eq!(g(0.25, 0.3), 1.0);
    }

    #[test]
    fn cache_sees_periodic_images() {
        // A channel periodic along x: floor and ceiling cut into elements, the floor's
        // elements wrapped so that one straddles the period's ends.
        let kernel = Wendland::new(0.02, 2);
        let period = Periodicity {
            min: DVec2::ZERO,
            length: DVec2::new(0.5, 0.0),
        };
        let mut e = BoundaryElements::default();
        let shapes =
            crate::geometry::segment_elements(DVec2::new(0.013, 0.0), DVec2::new(0.513, 0.0), 0.01);
        for s in shapes.into_iter().chain(crate::geometry::segment_elements(
            DVec2::new(0.5, 0.2),
            DVec2::new(0.0, 0.2),
            0.01,
        )) {
            let w = period.wrap(s.centre) - s.centre;
            let corners: Vec<DVec2> = s.corners.iter().map(|&c| c + w).collect();
            e.push(s.centre + w, s.normal, s.area, 0, &corners);
        }
        let points = scatter_2d(
            DVec2::new(0.0, -0.01),
            DVec2::new(0.5, 0.21),
            3000,
            &[
                DVec2::new(0.0, 0.0),
                DVec2::new(0.013, 0.0),
                DVec2::new(0.4999, 0.2),
                DVec2::new(0.7, 0.01), // outside the primary period
            ],
        );
        cache_matches_walk(&kernel, &e, period, &points, 1e-12);
    }

    #[test]
    fn cache_matches_the_walk_in_3d() {
        let kernel = Wendland::new(0.1, 3);
        let mut next = uniform(777);
        let mut points: Vec<DVec3> = (0..300)
            .map(|_| DVec3::new(next(), next(), next()) * 1.2 - DVec3::splat(0.1))
            .collect();
        points.extend([
            DVec3::new(0.5, 0.5, 0.0),
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.37, 1.0),
        ]);
        for (name, e) in cube_walls(0.05) {
            // On a wall the walk moves a point 1e-12 h off the wall once per element it lies
            // on (up to eight triangles), the cache once per face: 1e-10 apart there.
            cache_matches_walk(&kernel, &e, Periodicity::none(), &points, 1e-10);
            // Each face one rectangle of four edges.
            let mut cache = GammaCache::default();
            cache.rebuild(&e, kernel.support, Periodicity::none());
            assert_eq!(cache.pieces(), 6, "{name}");
            for p in 0..6 {
                assert_eq!(cache.piece_corners(p).len(), 8, "{name}");
            }
        }
    }
}
