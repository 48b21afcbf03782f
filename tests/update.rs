//! The update kernel (`shaders/update.wgsl`, twin `src/kernels/update.rs`): the twin moves
//! a configuration as the static solver does; the GPU equals the twin; NaN shows in the
//! norms of its own variant only.
#![allow(clippy::needless_range_loop)]

mod common;

use common::runners::{norms_gpu, update_gpu};
use holewall::kernels::update::{norms, update, ConfigBatch, UpdateWalls};
use holewall::physics::beam::rotation_exp;
use rand::{Rng, SeedableRng};

/// Contact sites at every other node of `n`, for `v` variants, their tables zero (to be
/// filled), with the landing `epoch`.
fn sites_at_every_other_node(
    v: usize,
    n: usize,
    epoch: Vec<u32>,
) -> (Vec<usize>, UpdateWalls<f64>) {
    let sites: Vec<usize> = (0..n).step_by(2).collect();
    let p = sites.len() * v;
    let mut pair_params = vec![0.0; holewall::physics::contact::PARAMS_LEN * p];
    // A linear law (spring exponent, field 3, 1): no depth bound.
    pair_params[3 * p..4 * p].fill(1.0);
    let walls = UpdateWalls {
        node_site: vec![holewall::kernels::assemble::NO_SITE; n * v],
        pair_base: vec![0.0; 3 * p],
        pair_normals: vec![0.0; 3 * p],
        pair_params,
        epoch,
    };
    (sites, walls)
}

/// A batch of V = 8 variants on n = 12 nodes at zero offset, every other node a site on a
/// vertical hole axis of clearance `c`, `base` from the axis in a random direction per
/// variant (rng `seed`), stepped `step` radially outward and 1 mm along the axis.
fn radial_steps(
    seed: u64,
    c: f64,
    base: f64,
    step: f64,
    epoch: Vec<u32>,
) -> (Vec<usize>, UpdateWalls<f64>, ConfigBatch<f64>, Vec<f64>) {
    let (v, n) = (8, 12);
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let (mut b0, _, _) = batch(v, n, &mut rng);
    b0.x.iter_mut().for_each(|x| *x = 0.0);
    let mut delta = vec![0.0; 6 * n * v];
    let (sites, mut walls) = sites_at_every_other_node(v, n, epoch);
    for (k, &node) in sites.iter().enumerate() {
        for j in 0..v {
            let i = k * v + j;
            walls.node_site[node * v + j] = k as u32;
            let phi: f64 = rng.random_range(0.0..std::f64::consts::TAU);
            let (cs, sn) = (phi.cos(), phi.sin());
            walls.pair_normals[3 * i + 2] = 1.0;
            walls.pair_base[3 * i] = base * cs;
            walls.pair_base[3 * i + 1] = base * sn;
            walls.pair_params[i] = c;
            delta[(6 * node) * v + j] = step * cs;
            delta[(6 * node + 1) * v + j] = step * sn;
            delta[(6 * node + 2) * v + j] = 1e-3;
        }
    }
    (sites, walls, b0, delta)
}

/// The lateral offset from its hole axis of `node` (a site of [`radial_steps`]), variant `j`,
/// at positions `x`.
fn radius_of(walls: &UpdateWalls<f64>, x: &[f64], v: usize, node: usize, j: usize) -> f64 {
    let i = (node / 2) * v + j;
    let e: Vec<f64> = (0..2)
        .map(|a| walls.pair_base[3 * i + a] + x[(3 * node + a) * v + j])
        .collect();
    (e[0] * e[0] + e[1] * e[1]).sqrt()
}

/// The largest |a − b| over two position vectors (in f64).
fn max_diff<T: Copy + Into<f64>>(a: &[T], b: &[T]) -> f64 {
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (&x, &y)| m.max((x.into() - y.into()).abs()))
}

fn cast(x: &[f64]) -> Vec<f32> {
    x.iter().map(|&x| x as f32).collect()
}

fn batch(
    v: usize,
    n: usize,
    rng: &mut rand::rngs::StdRng,
) -> (ConfigBatch<f64>, Vec<f64>, Vec<f64>) {
    let mut b = ConfigBatch {
        num_variants: v,
        num_nodes: n,
        x: (0..3 * n * v)
            .map(|_| rng.random_range(-100.0..100.0))
            .collect(),
        rot: vec![0.0; 9 * n * v],
        basis: vec![0.0; 9 * n],
        landed: Vec::new(),
    };
    for i in 0..n {
        // A rotated basis at the last node (the bit held in the hole frame), identity elsewhere.
        let basis = if i + 1 == n {
            rotation_exp(&[0.3, -0.2, 0.5])
        } else {
            rotation_exp(&[0.0; 3])
        };
        for r in 0..3 {
            for c in 0..3 {
                b.basis[9 * i + 3 * r + c] = basis[r][c];
            }
        }
        for j in 0..v {
            let th: [f64; 3] = std::array::from_fn(|_| rng.random_range(-2.0..2.0));
            let rot = rotation_exp(&th);
            for r in 0..3 {
                for c in 0..3 {
                    b.rot[(9 * i + 3 * r + c) * v + j] = rot[r][c];
                }
            }
        }
    }
    let delta: Vec<f64> = (0..6 * n * v)
        .map(|_| rng.random_range(-0.05..0.05))
        .collect();
    let alpha: Vec<f64> = (0..v).map(|_| rng.random_range(0.1..1.0)).collect();
    (b, delta, alpha)
}

#[test]
fn update_matches_rodrigues_and_gpu_matches_twin() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(9);
    let (v, n) = (16, 20);
    let (b0, delta, alpha) = batch(v, n, &mut rng);
    let mut twin = b0.clone();
    update(&mut twin, &UpdateWalls::default(), &delta, &alpha);
    // Against the formulas with std trigonometry (the static solver's update).
    let mut worst: f64 = 0.0;
    for j in 0..v {
        for i in 0..n {
            let du: [f64; 3] = std::array::from_fn(|k| alpha[j] * delta[(6 * i + k) * v + j]);
            let th: [f64; 3] = std::array::from_fn(|k| alpha[j] * delta[(6 * i + 3 + k) * v + j]);
            let e = rotation_exp(&th);
            for r in 0..3 {
                let bx: f64 = (0..3).map(|k| b0.basis[9 * i + 3 * r + k] * du[k]).sum();
                let x = b0.x[(3 * i + r) * v + j] + bx;
                worst = worst.max((twin.x[(3 * i + r) * v + j] - x).abs() / x.abs().max(1.0));
                for c in 0..3 {
                    let rc: f64 = (0..3)
                        .map(|m| e[r][m] * b0.rot[(9 * i + 3 * m + c) * v + j])
                        .sum();
                    worst = worst.max((twin.rot[(9 * i + 3 * r + c) * v + j] - rc).abs());
                }
            }
        }
    }
    eprintln!("twin vs std-trig update: {worst:.2e}");
    assert!(worst <= 1e-15);
    let residual: Vec<f64> = (0..6 * n * v)
        .map(|_| rng.random_range(-1e3..1e3))
        .collect();
    let twin_norms = norms(&residual, &delta, &alpha, n, v);
    // Against plain sums.
    for j in 0..v {
        let dot: f64 = (0..6 * n)
            .map(|k| delta[k * v + j] * residual[k * v + j])
            .sum();
        let sq: f64 = (0..6 * n).map(|k| residual[k * v + j].powi(2)).sum();
        let rmax = (0..6 * n).fold(0.0f64, |m, k| m.max(residual[k * v + j].abs()));
        let dmax = (0..6 * n).fold(0.0f64, |m, k| m.max((alpha[j] * delta[k * v + j]).abs()));
        assert_eq!(twin_norms.step_dot_residual[j], dot);
        assert_eq!(twin_norms.residual_square[j], sq);
        assert_eq!(twin_norms.residual_max[j], rmax);
        assert_eq!(twin_norms.step_max[j], dmax);
    }
    let Some(ctx) = common::gpu() else { return };
    if ctx.has_f64 {
        let mut gpu = b0.clone();
        update_gpu(ctx, &mut gpu, &UpdateWalls::default(), &delta, &alpha).unwrap();
        let diff = gpu
            .x
            .iter()
            .zip(&twin.x)
            .chain(gpu.rot.iter().zip(&twin.rot))
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs() / b.abs().max(1.0)));
        eprintln!("GPU f64 vs twin: {diff:.2e}");
        assert!(diff <= 1e-15);
        let gpu_norms = norms_gpu(ctx, &residual, &delta, &alpha, n, v).unwrap();
        assert_eq!(gpu_norms.residual_max, twin_norms.residual_max);
        assert_eq!(gpu_norms.step_max, twin_norms.step_max);
        // Sums in the same order; the compiler may fuse multiply-adds.
        for (a, b) in [
            (&gpu_norms.step_dot_residual, &twin_norms.step_dot_residual),
            (&gpu_norms.residual_square, &twin_norms.residual_square),
        ] {
            for j in 0..v {
                assert!(
                    (a[j] - b[j]).abs() <= 1e-13 * b[j].abs().max(1.0),
                    "{} vs {}",
                    a[j],
                    b[j]
                );
            }
        }
    }
    // f32: against the f64 twin.
    let mut b32 = b0.map(|x| x as f32);
    update_gpu(
        ctx,
        &mut b32,
        &UpdateWalls::default(),
        &cast(&delta),
        &cast(&alpha),
    )
    .unwrap();
    let rot_err = b32
        .rot
        .iter()
        .zip(&twin.rot)
        .fold(0.0f64, |m, (a, b)| m.max((*a as f64 - b).abs()));
    eprintln!("GPU f32 rotations vs f64 twin: {rot_err:.2e} (u32 = 6.0e-8)");
    assert!(rot_err <= 16.0 * f32::EPSILON as f64);
    // NaN in one variant's residual shows in its norm only.
    let mut bad = residual.clone();
    bad[7 * v + 3] = f64::NAN;
    let bad_norms = norms(&bad, &delta, &alpha, n, v);
    assert!(bad_norms.residual_max[3].is_nan());
    assert!(bad_norms.residual_square[3].is_nan());
    for j in (0..v).filter(|&j| j != 3) {
        assert_eq!(bad_norms.residual_max[j], twin_norms.residual_max[j]);
        assert_eq!(bad_norms.residual_square[j], twin_norms.residual_square[j]);
    }
    let r_bad32 = norms_gpu(ctx, &cast(&bad), &cast(&delta), &cast(&alpha), n, v)
        .unwrap()
        .residual_max;
    assert!(
        !r_bad32[3].is_finite(),
        "GPU f32 norm of the NaN variant: {}",
        r_bad32[3]
    );
    assert!(r_bad32
        .iter()
        .enumerate()
        .all(|(j, x)| j == 3 || x.is_finite()));
}

/// Contact nodes near their wall step along it: a circumferential step keeps the radius
/// (where a straight one would push the node `s²/2r` into the wall), a step is unchanged to
/// first order, and the GPU kernel equals the twin.
#[test]
fn contact_nodes_step_along_their_wall_on_both_paths() {
    use holewall::physics::contact::wall_following_step;
    let t = [0.0, 0.6, 0.8];
    let (r, e_t) = (0.04, [0.0, 0.8, -0.6]);
    let d = [r, 0.0, 0.0];
    for s in [1e-6, 1e-4, 1e-2] {
        let du = [0.0, 0.8 * s, -0.6 * s];
        let moved = wall_following_step(&d, &t, &du, 0.02);
        let x: Vec<f64> = (0..3).map(|k| d[k] + moved[k]).collect();
        let radius = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
        assert!((radius - r).abs() <= 1e-16 * 4.0, "{radius} vs {r}");
        // First order: the difference from the straight step is O(s²/r).
        let diff = (0..3)
            .map(|k| (moved[k] - du[k]).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(diff <= s * s / r, "{diff:e} for s = {s:e}");
        let _ = e_t;
    }
    // Inside min_radius: unchanged.
    assert_eq!(
        wall_following_step(&[0.01, 0.0, 0.0], &t, &[1e-3, 2e-3, 0.0], 0.02),
        [1e-3, 2e-3, 0.0]
    );
    // A batch with sites at every other node, offsets at the wall, both paths.
    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    let (v, n) = (8, 12);
    let (mut b0, delta, alpha) = batch(v, n, &mut rng);
    let (sites, mut walls) = sites_at_every_other_node(v, n, Vec::new());
    for (k, &node) in sites.iter().enumerate() {
        for j in 0..v {
            let i = k * v + j;
            walls.node_site[node * v + j] = k as u32;
            let axis: [f64; 3] = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
            let len = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
            for a in 0..3 {
                walls.pair_normals[3 * i + a] = axis[a] / len;
                walls.pair_base[3 * i + a] = rng.random_range(-0.01..0.01);
                // Displacements of a few centimetres: near the wall of a 4 cm clearance.
                b0.x[(3 * node + a) * v + j] = rng.random_range(-0.05..0.05);
            }
            walls.pair_params[i] = 0.04;
        }
    }
    let mut twin = b0.clone();
    update(&mut twin, &walls, &delta, &alpha);
    let mut plain = b0.clone();
    update(&mut plain, &UpdateWalls::default(), &delta, &alpha);
    let moved = twin.x.iter().zip(&plain.x).filter(|(a, b)| a != b).count();
    assert!(moved > 0, "no node followed its wall");
    let Some(ctx) = common::gpu() else { return };
    if ctx.has_f64 {
        let mut gpu = b0.clone();
        update_gpu(ctx, &mut gpu, &walls, &delta, &alpha).unwrap();
        let diff = max_diff(&gpu.x, &twin.x);
        eprintln!("wall-following update, GPU f64 vs twin: {diff:.2e} m ({moved} coordinates moved off the straight step)");
        assert!(diff <= 1e-15);
    }
}

/// A node off its wall whose step would end inside it lands on it, LANDING_DEPTH of its
/// clearance inside, with its axial step kept; a node on its wall, or one whose step stays
/// off it, keeps its step. In a batch a node lands once an epoch: the twin marks it, does not
/// land it again in the same epoch, and does in the next; the GPU moves and marks as the twin.
#[test]
fn a_node_stepping_through_its_wall_lands_on_it_once_an_epoch() {
    use holewall::physics::contact::{landing_step, LANDING_DEPTH};
    let t = [0.0, 0.0, 1.0];
    let c = 0.05;
    let land = c * (1.0 + LANDING_DEPTH);
    // 0.3 mm off the wall, a step 3.2 mm out and 1 mm along the axis (corpus well 221's).
    let d = [c - 3e-4, 0.0, 7.0];
    let du = [3.2e-3, 1e-4, 1e-3];
    let l = landing_step(&d, &t, &du, c);
    let e: Vec<f64> = (0..3).map(|k| d[k] + l[k]).collect();
    let r = (e[0] * e[0] + e[1] * e[1]).sqrt();
    assert!((r - land).abs() <= 1e-15, "landed at {r} for {land}");
    // The axial step kept, to the rounding of the node's 7 m axial offset.
    assert!((l[2] - du[2]).abs() <= 2.0 * f64::EPSILON * 7.0, "{}", l[2]);
    // The landing point lies on the straight step's lateral direction.
    let ex = d[0] + du[0];
    assert!((e[1] / e[0] - du[1] / ex).abs() <= 1e-12);
    // On the wall already, or staying off it: the step itself.
    assert_eq!(landing_step(&[c + 1e-5, 0.0, 0.0], &t, &du, c), du);
    assert_eq!(
        landing_step(&[c - 3e-3, 0.0, 0.0], &t, &[1e-3, 0.0, 0.0], c),
        [1e-3, 0.0, 0.0]
    );

    // A batch: every other node a site 0.5 mm off a 5 cm clearance, stepped 2 mm out.
    let (sites, walls, mut b0, delta) = radial_steps(29, c, c - 5e-4, 2e-3, vec![1; 8]);
    let (v, n) = (b0.num_variants, b0.num_nodes);
    b0.landed = vec![0; n * v];
    let alpha = vec![1.0; v];
    let radius = |b: &ConfigBatch<f64>, node: usize, j: usize| radius_of(&walls, &b.x, v, node, j);
    let mut twin = b0.clone();
    update(&mut twin, &walls, &delta, &alpha);
    for &node in &sites {
        for j in 0..v {
            assert!((radius(&twin, node, j) - land).abs() <= 1e-15);
            assert_eq!(twin.landed[node * v + j], 1, "marked with the epoch");
        }
    }
    // The same epoch: the same step from the start does not land a marked node.
    let mut again = b0.clone();
    again.landed = twin.landed.clone();
    update(&mut again, &walls, &delta, &alpha);
    assert!(
        (radius(&again, 0, 0) - (c + 1.5e-3)).abs() <= 1e-12,
        "landed twice in one epoch"
    );
    // The next epoch of variant 0 only: its nodes land again, the others' do not.
    let mut next = walls.clone();
    next.epoch[0] = 2;
    let mut third = b0.clone();
    third.landed = twin.landed.clone();
    update(&mut third, &next, &delta, &alpha);
    assert!((radius(&third, 0, 0) - land).abs() <= 1e-15);
    assert!((radius(&third, 0, 1) - (c + 1.5e-3)).abs() <= 1e-12);
    let Some(ctx) = common::gpu() else { return };
    if ctx.has_f64 {
        for (w, landed) in [(&walls, &b0.landed), (&next, &twin.landed)] {
            let mut gpu = b0.clone();
            gpu.landed = landed.clone();
            let mut cpu = gpu.clone();
            update(&mut cpu, w, &delta, &alpha);
            update_gpu(ctx, &mut gpu, w, &delta, &alpha).unwrap();
            let diff = max_diff(&gpu.x, &cpu.x);
            eprintln!("landing update, GPU f64 vs twin: {diff:.2e} m");
            assert!(diff <= 1e-16);
            assert_eq!(gpu.landed, cpu.landed);
        }
    }
    // f32: the same marks, the landing radius to f32 rounding.
    let (w32, b32) = (walls.map(|x| x as f32), b0.map(|x| x as f32));
    let mut cpu = b32.clone();
    update(&mut cpu, &w32, &cast(&delta), &cast(&alpha));
    let mut gpu = b32.clone();
    update_gpu(ctx, &mut gpu, &w32, &cast(&delta), &cast(&alpha)).unwrap();
    assert_eq!(gpu.landed, cpu.landed);
    assert_eq!(cpu.landed, twin.landed);
    let diff = max_diff(&gpu.x, &cpu.x);
    eprintln!("landing update, GPU f32 vs twin: {diff:.2e} m");
    assert!(diff <= f64::from(4.0 * f32::EPSILON * 0.05));
}

/// A soft-law node (spring exponent below 1) whose step would take it more than
/// DEEPENING_FACTOR times deeper — or, from off its wall or at its onset, deeper than
/// LANDING_DEPTH of its clearance — stops at that depth on the step's lateral direction,
/// with its axial step kept; a shallower step, or any step on a linear law, is unchanged.
/// In a batch the twin bounds the soft-law nodes in f64 and in f32, and the GPU moves them
/// as the twin, to the bit in f64 (to f32 rounding in f32).
#[test]
fn a_soft_law_node_goes_no_deeper_than_its_bound() {
    use holewall::physics::contact::{deepening_step, deepens, DEEPENING_FACTOR, LANDING_DEPTH};
    assert!(deepens(2.0 / 3.0) && deepens(0.1));
    assert!(!deepens(1.0) && !deepens(1.5));
    let t = [0.0, 0.0, 1.0];
    let c = 0.05;
    let depth = |d: &[f64; 3], du: &[f64; 3]| -> f64 {
        let e: Vec<f64> = (0..3).map(|k| d[k] + du[k]).collect();
        (e[0] * e[0] + e[1] * e[1]).sqrt() - c
    };
    // 10 µm in, a step 3 mm in and 1 mm along the axis: it ends 40 µm in.
    let d = [c + 1e-5, 0.0, 7.0];
    let du = [3e-3, 2e-4, 1e-3];
    let l = deepening_step(&d, &t, &du, c);
    assert!(
        (depth(&d, &l) - DEEPENING_FACTOR * 1e-5).abs() <= 1e-15,
        "{}",
        depth(&d, &l)
    );
    assert!((l[2] - du[2]).abs() <= 2.0 * f64::EPSILON * 7.0);
    let e: Vec<f64> = (0..3).map(|k| d[k] + l[k]).collect();
    assert!((e[1] / e[0] - du[1] / (d[0] + du[0])).abs() <= 1e-12);
    // From off the wall: to the landing depth.
    let off = [c - 3e-4, 0.0, 0.0];
    let l = deepening_step(&off, &t, &du, c);
    assert!((depth(&off, &l) - LANDING_DEPTH * c).abs() <= 1e-15);
    // Within the bound, or outward: the step itself.
    assert_eq!(
        deepening_step(&d, &t, &[2e-5, 0.0, 0.0], c),
        [2e-5, 0.0, 0.0]
    );
    assert_eq!(
        deepening_step(&d, &t, &[-1e-3, 0.0, 0.0], c),
        [-1e-3, 0.0, 0.0]
    );

    // A batch: every other node a site 10 µm in a 5 cm clearance, stepped 3 mm in; the
    // even variants on a soft law (m = 2/3), the odd on a linear one.
    let (sites, mut walls, b0, delta) = radial_steps(31, c, c + 1e-5, 3e-3, Vec::new());
    let v = b0.num_variants;
    let p = sites.len() * v;
    for i in 0..p {
        walls.pair_params[3 * p + i] = if i % v % 2 == 0 { 2.0 / 3.0 } else { 1.0 };
    }
    let alpha = vec![1.0; v];
    let radius = |x: &[f64], node: usize, j: usize| radius_of(&walls, x, v, node, j);
    let mut twin = b0.clone();
    update(&mut twin, &walls, &delta, &alpha);
    for &node in &sites {
        for j in 0..v {
            let want = if j % 2 == 0 {
                c + DEEPENING_FACTOR * 1e-5
            } else {
                c + 1e-5 + 3e-3
            };
            assert!(
                (radius(&twin.x, node, j) - want).abs() <= 1e-15,
                "node {node} variant {j}: {} for {want}",
                radius(&twin.x, node, j)
            );
        }
    }
    let (w32, b32) = (walls.map(|x| x as f32), b0.map(|x| x as f32));
    let mut cpu32 = b32.clone();
    update(&mut cpu32, &w32, &cast(&delta), &cast(&alpha));
    // f32: the same bound, to f32 rounding of a 5 cm offset.
    let x64: Vec<f64> = cpu32.x.iter().map(|&x| x as f64).collect();
    for &node in &sites {
        for j in 0..v {
            let want = radius(&twin.x, node, j);
            assert!(
                (radius(&x64, node, j) - want).abs() <= 1e-7,
                "f32 node {node} variant {j}: {} for {want}",
                radius(&x64, node, j)
            );
        }
    }
    let Some(ctx) = common::gpu() else { return };
    if ctx.has_f64 {
        let mut gpu = b0.clone();
        update_gpu(ctx, &mut gpu, &walls, &delta, &alpha).unwrap();
        assert_eq!(gpu.x, twin.x, "GPU f64 against the twin");
    }
    let mut gpu32 = b32.clone();
    update_gpu(ctx, &mut gpu32, &w32, &cast(&delta), &cast(&alpha)).unwrap();
    let diff = max_diff(&gpu32.x, &cpu32.x);
    eprintln!("soft-law update, GPU f32 vs twin: {diff:.2e} m");
    assert!(diff <= f64::from(4.0 * f32::EPSILON * 0.05));
}
