//! Twin of `shaders/beam.wgsl`: internal force (12) and consistent tangent (12×12) of every
//! (element, variant), by [`crate::physics::beam::force_and_tangent`] (hyper-dual
//! evaluations of the co-rotated element energy), laid out for the assembly:
//! `[(12 e + j) V + v]` and `[(144 e + 12 j + k) V + v]`. Inputs: positions
//! `[(3 i + k) V + v]`, rotations `[(9 i + 3 r + c) V + v]` (the twin takes them in f64),
//! reference triads per node and sections per element, shared by the variants.

use rayon::prelude::*;

use crate::model::Model;
use crate::physics::beam::{force_and_tangent, ElementState, Mat3};

/// Per element: `EA/l0, GJ/l0, EI/l0, l0` (the kernel's `section` binding).
pub fn section_table(model: &Model) -> Vec<f64> {
    model
        .elements
        .iter()
        .flat_map(|e| {
            let s = &e.section;
            [
                s.youngs_modulus * s.area / e.length0,
                s.shear_modulus * s.polar_moment / e.length0,
                s.bending_stiffness() / e.length0,
                e.length0,
            ]
        })
        .collect()
}

/// Reference triads per node, row-major (the kernel's `frame0` binding).
pub fn frame_table(model: &Model) -> Vec<f64> {
    model
        .nodes
        .iter()
        .flat_map(|n| n.frame0.iter().flatten().copied().collect::<Vec<f64>>())
        .collect()
}

/// Element forces and tangents of V variants (rayon over elements × variants).
pub fn beam(model: &Model, num_variants: usize, x: &[f64], rot: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let nv = num_variants;
    let ne = model.elements.len();
    let per: Vec<([f64; 12], [[f64; 12]; 12])> = (0..ne * nv)
        .into_par_iter()
        .map(|idx| {
            let (e, v) = (idx / nv, idx % nv);
            let pos = |i: usize| -> [f64; 3] { std::array::from_fn(|k| x[(3 * i + k) * nv + v]) };
            let triad = |i: usize| -> Mat3<f64> {
                let f = &model.nodes[i].frame0;
                std::array::from_fn(|r| {
                    std::array::from_fn(|c| {
                        (0..3)
                            .map(|m| rot[(9 * i + 3 * r + m) * nv + v] * f[m][c])
                            .sum()
                    })
                })
            };
            let es = ElementState {
                x: [pos(e), pos(e + 1)],
                triad: [triad(e), triad(e + 1)],
            };
            let el = &model.elements[e];
            force_and_tangent(&es, &el.section, el.length0)
        })
        .collect();
    let mut force = vec![0.0; 12 * ne * nv];
    let mut tangent = vec![0.0; 144 * ne * nv];
    for (idx, (f, k)) in per.into_iter().enumerate() {
        let (e, v) = (idx / nv, idx % nv);
        for j in 0..12 {
            force[(12 * e + j) * nv + v] = f[j];
            for c in 0..12 {
                tangent[(144 * e + 12 * j + c) * nv + v] = k[j][c];
            }
        }
    }
    (force, tangent)
}
