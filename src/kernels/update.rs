//! Twin of `shaders/update.wgsl`: the Newton update of every variant's configuration and
//! its convergence measures.
//!
//! `update`: one invocation per (node, variant): `x_i += α B_i Δu_i` (`B_i` the node's
//! translation basis, identity but at a bit held in the hole frame; at a contact site near
//! its wall the step follows the wall, `physics::contact::wall_following_step`, and one off
//! it whose step would end inside it lands on it, once a landing epoch,
//! `physics::contact::landing_step`), and one on a soft-law wall goes no deeper than its
//! bound, `physics::contact::deepening_step`) and
//! `R_i ← exp([α Δθ_i]×) R_i`. The exponential is written with series, the same in both
//! (no f64 trigonometry on Vulkan): with `φ = |θ|` reduced to `[0, π]` (a rotation by
//! `φ > π` is one by `φ − 2π·round(φ/2π)` about the same axis) and `h = φ/2`,
//! `sin φ / φ = sinc h · cos h` and `(1 − cos φ)/φ² = ½ sinc² h`, no cancellation anywhere.
//!
//! `norms`: one invocation per variant: the largest residual entry and the largest entry of
//! the applied step `α Δ`, which the host compares with its tolerances, and the line
//! search's `Δ · r` and `r · r` (so the host reads four numbers per variant, not vectors).
//!
//! Layout: node vector entry `k` of node `i`, variant `v` at `[(3 i + k) V + v]` (positions),
//! `[(9 i + 3 r + c) V + v]` (rotations, row-major), `[(6 i + k) V + v]` (steps and
//! residuals); bases `[9 i + 3 r + c]`, shared by the variants.

// Index loops mirror the WGSL kernel line for line.
#![allow(clippy::needless_range_loop)]
use rayon::prelude::*;

use crate::physics::Real;

/// Terms of the Taylor series of `sinc` and `cos` on `[0, π/2]` (the last term below 2e-17).
pub const SERIES_TERMS: usize = 12;

/// `1/(2k+1)!` (sinc) and `1/(2k)!` (cos), `k = 0 … SERIES_TERMS − 1`, formed once at
/// compile time (the factorials as the same left-to-right products in f64 the series always
/// used, so every coefficient is the same bit for bit).
const SERIES_COEFFICIENTS: [[f64; 2]; SERIES_TERMS] = {
    let mut table = [[0.0; 2]; SERIES_TERMS];
    let mut k = 0;
    while k < SERIES_TERMS {
        table[k] = [1.0 / factorial(2 * k + 1), 1.0 / factorial(2 * k)];
        k += 1;
    }
    table
};

/// `(sinc h, cos h)` for `0 ≤ h ≤ π/2`, Horner in `h²`.
pub fn sinc_cos<T: Real>(h: T) -> (T, T) {
    let h2 = h * h;
    let mut s = T::zero();
    let mut c = T::zero();
    for k in (0..SERIES_TERMS).rev() {
        // sinc: Σ (−1)^k h^{2k}/(2k+1)!, cos: Σ (−1)^k h^{2k}/(2k)!.
        let [sk, ck] = SERIES_COEFFICIENTS[k];
        let (sk, ck) = (T::from_f64_lossy(sk), T::from_f64_lossy(ck));
        let sign = if k % 2 == 0 {
            T::one()
        } else {
            T::zero() - T::one()
        };
        s = s * h2 + sign * sk;
        c = c * h2 + sign * ck;
    }
    (s, c)
}

/// `n!` as the product `1 · 1 · 2 · … · n` in f64, left to right.
const fn factorial(n: usize) -> f64 {
    let mut p = 1.0;
    let mut k = 1;
    while k <= n {
        p *= k as f64;
        k += 1;
    }
    p
}

/// `exp([θ]×)` by [`sinc_cos`] (row-major 3×3).
pub fn rotation_exp_series<T: Real>(theta: [T; 3]) -> [[T; 3]; 3] {
    let pi = std::f64::consts::PI;
    let phi = (theta[0] * theta[0] + theta[1] * theta[1] + theta[2] * theta[2]).sqrt();
    let phi_f = phi.to_f64_lossy();
    let t = if phi_f > pi {
        // φ − 2π·round(φ/2π) ∈ [−π, π], along the same axis.
        let turns = T::from_f64_lossy((phi_f / (2.0 * pi)).round());
        let f = (phi - turns * T::from_f64_lossy(2.0 * pi)) / phi;
        [theta[0] * f, theta[1] * f, theta[2] * f]
    } else {
        theta
    };
    let phi = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
    let half = T::from_f64_lossy(0.5);
    let (s, c) = sinc_cos(phi * half);
    let a = s * c;
    let b = half * s * s;
    let k = [
        [T::zero(), T::zero() - t[2], t[1]],
        [t[2], T::zero(), T::zero() - t[0]],
        [T::zero() - t[1], t[0], T::zero()],
    ];
    let mut r = [[T::zero(); 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let mut kk = T::zero();
            for m in 0..3 {
                kk = kk + k[i][m] * k[m][j];
            }
            let eye = if i == j { T::one() } else { T::zero() };
            r[i][j] = eye + a * k[i][j] + b * kk;
        }
    }
    r
}

/// Configurations of V variants on a chain of n nodes.
#[derive(Clone, Debug, PartialEq)]
pub struct ConfigBatch<T> {
    /// Variants V.
    pub num_variants: usize,
    /// Nodes n.
    pub num_nodes: usize,
    /// Positions, `3 n V`.
    pub x: Vec<T>,
    /// Rotations, `9 n V`.
    pub rot: Vec<T>,
    /// Translation basis per node, `9 n` (identity where the node has none).
    pub basis: Vec<T>,
    /// Per (node, variant), `n V`: the landing epoch in which the node last landed on its
    /// wall ([`UpdateWalls::epoch`]); empty: no node lands.
    pub landed: Vec<u32>,
}

/// The contact sites the update makes follow the wall
/// ([`crate::physics::contact::wall_following_step`], as `solve_static`'s update).
#[derive(Clone, Debug, Default)]
pub struct UpdateWalls<T> {
    /// Site at each (node, variant), `n V` ([`crate::kernels::assemble::NO_SITE`] where
    /// none); empty: no site anywhere.
    pub node_site: Vec<u32>,
    /// The base across the hole axis per pair `i = site · V + variant`, `3 P`.
    pub pair_base: Vec<T>,
    /// Hole axis per pair, `3 P`.
    pub pair_normals: Vec<T>,
    /// Law parameters per pair, `PARAMS_LEN · P`, field-major (clearance first).
    pub pair_params: Vec<T>,
    /// Landing epoch per variant, `V` (empty, or 0 for a variant: no node lands): a contact
    /// node off its wall whose step would end in it lands on it
    /// ([`crate::physics::contact::landing_step`]) if it has not landed in this epoch
    /// ([`ConfigBatch::landed`]); the static engine starts a new epoch for a variant at each
    /// load target and each restart, and sets 0 while it relaxes, so a node lands once per
    /// load step and not in a relaxation, as in `solve_static`.
    pub epoch: Vec<u32>,
}

impl ConfigBatch<f64> {
    /// The batch with every real mapped by `f` (to f32, as
    /// [`crate::kernels::assemble::AssemblyInputs::map_static`]).
    pub fn map<U>(&self, f: impl Fn(f64) -> U) -> ConfigBatch<U> {
        let c = |x: &[f64]| x.iter().map(|&y| f(y)).collect::<Vec<U>>();
        ConfigBatch {
            num_variants: self.num_variants,
            num_nodes: self.num_nodes,
            x: c(&self.x),
            rot: c(&self.rot),
            basis: c(&self.basis),
            landed: self.landed.clone(),
        }
    }
}

impl UpdateWalls<f64> {
    /// The walls with every real mapped by `f` (as [`ConfigBatch::map`]).
    pub fn map<U>(&self, f: impl Fn(f64) -> U) -> UpdateWalls<U> {
        let c = |x: &[f64]| x.iter().map(|&y| f(y)).collect::<Vec<U>>();
        UpdateWalls {
            node_site: self.node_site.clone(),
            pair_base: c(&self.pair_base),
            pair_normals: c(&self.pair_normals),
            pair_params: c(&self.pair_params),
            epoch: self.epoch.clone(),
        }
    }
}

/// The update of node `i`, variant `v`: new position and rotation.
fn update_node<T: Real>(
    b: &ConfigBatch<T>,
    walls: &UpdateWalls<T>,
    delta: &[T],
    alpha: &[T],
    i: usize,
    v: usize,
) -> ([T; 3], [T; 9], Option<u32>) {
    let nv = b.num_variants;
    let al = alpha[v];
    let du: [T; 3] = std::array::from_fn(|k| al * delta[(6 * i + k) * nv + v]);
    let mut step = [T::zero(); 3];
    for r in 0..3 {
        let mut s = T::zero();
        for k in 0..3 {
            s = s + b.basis[9 * i + 3 * r + k] * du[k];
        }
        step[r] = s;
    }
    let old: [T; 3] = std::array::from_fn(|k| b.x[(3 * i + k) * nv + v]);
    let mut landed = b.landed.get(i * nv + v).copied();
    let site = walls
        .node_site
        .get(i * nv + v)
        .copied()
        .unwrap_or(crate::kernels::assemble::NO_SITE);
    if site != crate::kernels::assemble::NO_SITE {
        // The node's offset from its hole axis point: the base across the axis plus the
        // displacement (the step uses only the part across the axis).
        let pair = site as usize * nv + v;
        let p = walls.pair_normals.len() / 3;
        let d: [T; 3] = std::array::from_fn(|k| walls.pair_base[3 * pair + k] + old[k]);
        let t: [T; 3] = std::array::from_fn(|k| walls.pair_normals[3 * pair + k]);
        let min_radius = T::from_f64_lossy(crate::physics::contact::wall_following_radius(
            walls.pair_params[pair].to_f64_lossy(),
        ));
        debug_assert!(pair < p);
        step = crate::physics::contact::wall_following_step(&d, &t, &step, min_radius);
        if let (Some(m), Some(&e)) = (landed.as_mut(), walls.epoch.get(v)) {
            if e != 0 && *m != e {
                let l =
                    crate::physics::contact::landing_step(&d, &t, &step, walls.pair_params[pair]);
                if l != step {
                    step = l;
                    *m = e;
                }
            }
        }
        let exponent = walls.pair_params[3 * p + pair].to_f64_lossy();
        if crate::physics::contact::deepens(exponent) {
            step = crate::physics::contact::deepening_step(&d, &t, &step, walls.pair_params[pair]);
        }
    }
    let x: [T; 3] = std::array::from_fn(|k| old[k] + step[k]);
    let dth: [T; 3] = std::array::from_fn(|k| al * delta[(6 * i + 3 + k) * nv + v]);
    let e = rotation_exp_series(dth);
    let mut rot = [T::zero(); 9];
    for r in 0..3 {
        for c in 0..3 {
            let mut s = T::zero();
            for m in 0..3 {
                s = s + e[r][m] * b.rot[(9 * i + 3 * m + c) * nv + v];
            }
            rot[3 * r + c] = s;
        }
    }
    (x, rot, landed)
}

/// Applies `α_v Δ_v` to every variant (rayon over nodes × variants), contact nodes near
/// their wall moving along it and, once an epoch, landing on it ([`UpdateWalls::epoch`]).
pub fn update<T: Real + Send + Sync>(
    b: &mut ConfigBatch<T>,
    walls: &UpdateWalls<T>,
    delta: &[T],
    alpha: &[T],
) {
    let (n, nv) = (b.num_nodes, b.num_variants);
    let new: Vec<_> = (0..n * nv)
        .into_par_iter()
        .map(|idx| update_node(b, walls, delta, alpha, idx / nv, idx % nv))
        .collect();
    for (idx, (x, rot, landed)) in new.into_iter().enumerate() {
        let (i, v) = (idx / nv, idx % nv);
        if let Some(m) = landed {
            b.landed[idx] = m;
        }
        for k in 0..3 {
            b.x[(3 * i + k) * nv + v] = x[k];
        }
        for k in 0..9 {
            b.rot[(9 * i + k) * nv + v] = rot[k];
        }
    }
}

/// Per-variant measures of a residual `r` and a step `Δ` (the norms kernel's output).
#[derive(Clone, Debug, PartialEq)]
pub struct Norms<T> {
    /// Largest `|r|` (NaN or ∞ where any entry is).
    pub residual_max: Vec<T>,
    /// Largest `|α Δ|`.
    pub step_max: Vec<T>,
    /// `Δ · r` (the line search's slope; no α).
    pub step_dot_residual: Vec<T>,
    /// `r · r`.
    pub residual_square: Vec<T>,
}

/// The four measures of variant `v`, summed in index order (as the kernel).
pub fn norms_of_variant<T: Real>(
    residual: &[T],
    delta: &[T],
    alpha: &[T],
    num_nodes: usize,
    num_variants: usize,
    v: usize,
) -> [T; 4] {
    let mut r = T::zero();
    let mut d = T::zero();
    let mut dot = T::zero();
    let mut square = T::zero();
    for k in 0..6 * num_nodes {
        let rk = residual[k * num_variants + v];
        let dk = delta[k * num_variants + v];
        let ra = rk.abs();
        let da = (alpha[v] * dk).abs();
        if ra.to_f64_lossy() > r.to_f64_lossy() || !ra.to_f64_lossy().is_finite() {
            r = ra;
        }
        if da.to_f64_lossy() > d.to_f64_lossy() || !da.to_f64_lossy().is_finite() {
            d = da;
        }
        dot = dot + dk * rk;
        square = square + rk * rk;
    }
    [r, d, dot, square]
}

/// Per variant: the largest `|r|` and `|α Δ|` over its `6 n` entries, `Δ · r` and `r · r`.
pub fn norms<T: Real + Send + Sync>(
    residual: &[T],
    delta: &[T],
    alpha: &[T],
    num_nodes: usize,
    num_variants: usize,
) -> Norms<T> {
    let per: Vec<[T; 4]> = (0..num_variants)
        .into_par_iter()
        .map(|v| norms_of_variant(residual, delta, alpha, num_nodes, num_variants, v))
        .collect();
    Norms::from_rows(&per)
}

impl<T: Copy> Norms<T> {
    /// From one `[max r, max αΔ, Δ·r, r·r]` row per variant.
    pub fn from_rows(rows: &[[T; 4]]) -> Self {
        Norms {
            residual_max: rows.iter().map(|r| r[0]).collect(),
            step_max: rows.iter().map(|r| r[1]).collect(),
            step_dot_residual: rows.iter().map(|r| r[2]).collect(),
            residual_square: rows.iter().map(|r| r[3]).collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shader_writes_out_the_twins_series_coefficients_bit_for_bit() {
        // shaders/shared/rotation_exp.wgsl writes each (−1)^k/(2k+1)! and (−1)^k/(2k)! as
        // a literal on a line ending "// sinc k" or "// cos k": each must parse to the
        // twin's coefficient exactly (an f64 literal reads back to the value it was printed
        // from), and every k must be there once.
        let text = include_str!("../../shaders/shared/rotation_exp.wgsl");
        let mut seen = [[false; 2]; SERIES_TERMS];
        for line in text.lines() {
            let Some((code, tag)) = line.split_once("// ") else {
                continue;
            };
            let (which, k) = match tag.split_once(' ') {
                Some(("sinc", k)) => (0, k),
                Some(("cos", k)) => (1, k),
                _ => continue,
            };
            let k: usize = k.trim().parse().expect("k after the tag");
            let literal = code
                .split_once("real(")
                .and_then(|(_, r)| r.split_once(')'))
                .map(|(l, _)| l)
                .expect("a real(…) literal on a tagged line");
            let value: f64 = literal.parse().expect("an f64 literal");
            let sign = if k.is_multiple_of(2) { 1.0 } else { -1.0 };
            assert_eq!(
                value.to_bits(),
                (sign * SERIES_COEFFICIENTS[k][which]).to_bits(),
                "{line}"
            );
            assert!(!seen[k][which], "{line}: twice");
            seen[k][which] = true;
        }
        assert!(seen.iter().flatten().all(|&s| s), "{seen:?}");
    }

    #[test]
    fn series_exponential_matches_rodrigues_with_std_trig() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let mut worst: f64 = 0.0;
        for k in 0..2000 {
            let scale = 10f64.powi(k % 12 - 9) * 10.0; // 1e-8 … 1e2 rad
            let th: [f64; 3] = std::array::from_fn(|_| rng.random_range(-1.0..1.0) * scale);
            let a = rotation_exp_series(th);
            let b = crate::physics::beam::rotation_exp(&th);
            let phi = (th[0] * th[0] + th[1] * th[1] + th[2] * th[2]).sqrt();
            for r in 0..3 {
                for c in 0..3 {
                    // Both sides reduce the angle by whole turns: rounding ≈ ε·φ each.
                    worst = worst.max((a[r][c] - b[r][c]).abs() / (1.0 + phi));
                }
            }
            // Orthogonal to rounding.
            for r in 0..3 {
                for c in 0..3 {
                    let dot: f64 = (0..3).map(|m| a[r][m] * a[c][m]).sum();
                    assert!((dot - f64::from(r == c)).abs() < 1e-14);
                }
            }
        }
        assert!(worst < 2e-15, "{worst:e} per (1 + φ)");
    }
}
