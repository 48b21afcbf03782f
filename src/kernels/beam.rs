//! Twin of `shaders/beam.wgsl`: internal force (12) and consistent tangent (12×12) of every
//! (element, variant), by [`crate::physics::beam::force_and_tangent`] (hyper-dual
//! evaluations of the co-rotated element energy), laid out for the assembly:
//! `[(12 e + j) V + v]` and `[(144 e + 12 j + k) V + v]`. Inputs: displacements from the
//! reference positions `[(3 i + k) V + v]`, rotations `[(9 i + 3 r + c) V + v]` (the twin
//! takes them in f64), reference triads per node, sections and reference chords per
//! element, shared by the variants. An element's nodes are placed at `u₁` and `c + u₂`
//! (`c = X₂ − X₁`): only the chord matters, and it keeps its digits in f32.

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

/// Reference chord `X₂ − X₁` per element (the kernel's `chord0` binding).
pub fn chord_table(model: &Model) -> Vec<f64> {
    (0..model.elements.len())
        .flat_map(|e| {
            let (a, b) = (model.nodes[e].position, model.nodes[e + 1].position);
            [b[0] - a[0], b[1] - a[1], b[2] - a[2]]
        })
        .collect()
}

/// Element forces and tangents of V variants (rayon over elements × variants) at
/// displacements `u` and rotations `rot`.
pub fn beam(model: &Model, num_variants: usize, u: &[f64], rot: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let chord = chord_table(model);
    let nv = num_variants;
    let ne = model.elements.len();
    let per: Vec<([f64; 12], [[f64; 12]; 12])> = (0..ne * nv)
        .into_par_iter()
        .map(|idx| {
            let (e, v) = (idx / nv, idx % nv);
            let disp = |i: usize| -> [f64; 3] { std::array::from_fn(|k| u[(3 * i + k) * nv + v]) };
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
                x: [
                    disp(e),
                    std::array::from_fn(|k| chord[3 * e + k] + u[(3 * (e + 1) + k) * nv + v]),
                ],
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
