//! Twin of `shaders/beam.wgsl`: internal force (12) and consistent tangent (12×12) of every
//! (element, variant), by [`crate::physics::beam::force_and_tangent_variation`] (the
//! closed-form force's values once, and their first variation along each direction, as the
//! kernel) — or the force alone ([`crate::physics::beam::element_force`], the kernel built
//! with `FORCE_ONLY`) — laid out for the assembly: `[(12 e + j) V + v]` and the tangent's 81
//! independent entries `[(81 e + 9 r + d) V + v]` ([`tangent_slot`]). Inputs: displacements
//! `w` from each variant's *base* configuration `X + b` `[(3 i + k) V + v]`, rotations
//! `[(9 i + 3 r + c) V + v]` (the twin takes them in f64), reference triads per node and
//! sections per element (shared by the variants), and per element and variant the base
//! chord `c = (X₂ + b₂) − (X₁ + b₁)` with its stretch `|c| − l0` ([`base_chords`]). An
//! element's nodes are placed at `w₁` and `c + w₂`: only the chord matters, and it keeps
//! its digits in f32. The static engine's base starts at the reference (`b = 0`) and in
//! f32 moves to the configuration reached at each load step; the dynamic engine's is each
//! variant's static equilibrium, so its states are the millimetres of motion, not the
//! metres a kilometre string hangs down (whose f32 quantum, 2.4e-7 m at 2 m, times a
//! collar's axial stiffness is a kilonewton).

use rayon::prelude::*;

use crate::model::Model;
use crate::physics::beam::{
    element_force, force_and_tangent_variation, Chord, ElementStiffness, Mat3,
};

/// Values of an element's tangent per (element, variant) in the beam kernel's output: of
/// the 144 entries of `K_jk = ∂f_j/∂Δ_k`, the 81 it computes — rows 3–11 (`θ₁`, `x₂`,
/// `θ₂`) along its nine directions `d` (0–2 node 2's translations, columns 6–8; 3–5 node
/// 1's spins, columns 3–5; 6–8 node 2's spins, columns 9–11), at `[(81 e + 9 r + d) V + v]`
/// with `r = j − 3`. The rest are their negations, exactly: `f_x₁ = −f_x₂` (rows 0–2 are
/// rows 6–8 negated) and the element sees the translations only through `x₂ − x₁` (columns
/// 0–2 are columns 6–8 negated). The element tangents are the largest array between the
/// beam kernel and the assembly: 81 values instead of 144 to write and read.
pub const TANGENT_LEN: usize = 81;

/// Where entry `(j, k)` of an element's 12×12 tangent lies in the beam kernel's output
/// ([`TANGENT_LEN`]): its index `9 r + d` there, and whether the entry is that value
/// negated. `shaders/assemble.wgsl`'s `tangent_at` is the same map.
pub const fn tangent_slot(j: usize, k: usize) -> (usize, bool) {
    let (r, row_negated) = if j < 3 { (j + 3, true) } else { (j - 3, false) };
    let (d, col_negated) = match k {
        0..=2 => (k, true),
        3..=5 => (k, false),
        6..=8 => (k - 6, false),
        _ => (k - 3, false),
    };
    (9 * r + d, row_negated != col_negated)
}

/// The beam kernel's output entry `(r, d)` ([`TANGENT_LEN`]) as an entry `(j, k)` of the
/// 12×12 tangent: `j = r + 3`, `k` the column of direction `d`.
pub const fn tangent_source(r: usize, d: usize) -> (usize, usize) {
    let k = match d {
        0..=2 => d + 6,
        3..=5 => d,
        _ => d + 3,
    };
    (r + 3, k)
}

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

/// Values per (element, variant) in [`base_chords`]: the chord's three components and its
/// stretch.
pub const CHORD_LEN: usize = 4;

/// The kernel's `chord` binding, `[(4 e + k) V + v]`: per element and variant the base
/// chord `c = (X₂ + b₂) − (X₁ + b₁)` (`k` = 0–2) and its stretch `|c| − l0` (`k` = 3),
/// both in f64 (the stretch is what f32 cannot form from the chord: a strain of 1e-4 is
/// 1e-4 m on an element, three digits of its length). `base` holds the displacements `b`
/// of the base from the reference, `[(3 i + k) V + v]` (zeros: the reference itself).
pub fn base_chords(model: &Model, base: &[f64], num_variants: usize) -> Vec<f64> {
    let nv = num_variants;
    let ne = model.elements.len();
    let mut out = vec![0.0; CHORD_LEN * ne * nv];
    for (e, el) in model.elements.iter().enumerate() {
        let (a, b) = (model.nodes[e].position, model.nodes[e + 1].position);
        for v in 0..nv {
            let shift = |i: usize, k: usize| base[(3 * i + k) * nv + v];
            let c: [f64; 3] =
                std::array::from_fn(|k| (b[k] + shift(e + 1, k)) - (a[k] + shift(e, k)));
            for k in 0..3 {
                out[(CHORD_LEN * e + k) * nv + v] = c[k];
            }
            let l = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
            out[(CHORD_LEN * e + 3) * nv + v] = l - el.length0;
        }
    }
    out
}

/// Values per (element, variant) in [`rest_table`]: `θ̄⁰₁` and `θ̄⁰₂`.
pub const REST_LEN: usize = 6;

/// The kernel's `rest` binding, `[(6 e + k) V + v]`: element `e`'s unstrained rotations in
/// variant `v` (`k` 0–2 at node 1, 3–5 at node 2; zero but at a kink), each model's kinks at
/// `scale(v)` of their angle ([`Model::kinks`]). Empty when no model has a kink: the kernel
/// is then built without the binding.
pub fn rest_table(models: &[Model], scale: &dyn Fn(usize) -> f64) -> Vec<f64> {
    if models.iter().all(|m| m.bends.is_empty()) {
        return Vec::new();
    }
    let nv = models.len();
    let ne = models[0].elements.len();
    let mut out = vec![0.0; REST_LEN * ne * nv];
    for (v, m) in models.iter().enumerate() {
        set_rest_column(&mut out, nv, v, m, scale(v));
    }
    out
}

/// Writes variant `v`'s column of a [`rest_table`] of `nv` variants: `model`'s kinks at
/// `scale` of their angle.
pub fn set_rest_column<T: crate::physics::Real>(
    table: &mut [T],
    nv: usize,
    v: usize,
    model: &Model,
    scale: f64,
) {
    for (e, rest) in model.kinks(scale) {
        for k in 0..REST_LEN {
            table[(REST_LEN * e + k) * nv + v] = T::from_f64_lossy(rest[k / 3][k % 3]);
        }
    }
}

/// Element forces and tangents of V variants (rayon over elements, each writing its own
/// slab of the outputs; the tangents' 81 independent entries, [`TANGENT_LEN`]) at
/// displacements `u` from the base whose chords are `chords` ([`base_chords`]) and rotations
/// `rot`, with the unstrained rotations `rest` ([`rest_table`]; empty: none); with `tangent`
/// false the forces alone (the tangents returned are empty, as the force-only kernel leaves
/// its tangent binding out).
pub fn beam(
    model: &Model,
    num_variants: usize,
    u: &[f64],
    rot: &[f64],
    chords: &[f64],
    rest: &[f64],
    tangent: bool,
) -> (Vec<f64>, Vec<f64>) {
    let nv = num_variants;
    let ne = model.elements.len();
    let mut force = vec![0.0; 12 * ne * nv];
    let mut tangent_out = if tangent {
        vec![0.0; TANGENT_LEN * ne * nv]
    } else {
        Vec::new()
    };
    // Element e's entries are `[(12 e + j) V + v]` and `[(81 e + 9 r + d) V + v]`: one
    // contiguous slab of each output per element.
    let tangent_slabs: Vec<&mut [f64]> = if tangent {
        tangent_out.chunks_mut((TANGENT_LEN * nv).max(1)).collect()
    } else {
        (0..ne).map(|_| <&mut [f64]>::default()).collect()
    };
    force
        .par_chunks_mut((12 * nv).max(1))
        .zip(tangent_slabs)
        .enumerate()
        .for_each(|(e, (f_slab, k_slab))| {
            let triad = |i: usize, v: usize| -> Mat3<f64> {
                let f = &model.nodes[i].frame0;
                std::array::from_fn(|r| {
                    std::array::from_fn(|c| {
                        (0..3)
                            .map(|m| rot[(9 * i + 3 * r + m) * nv + v] * f[m][c])
                            .sum()
                    })
                })
            };
            let el = &model.elements[e];
            let form = Chord::Positions {
                length0: el.length0,
            };
            for v in 0..nv {
                // Node 2 at c + w₂: the chord's positions form (the f64 kernel's).
                let x = [
                    std::array::from_fn(|k| u[(3 * e + k) * nv + v]),
                    std::array::from_fn(|k| {
                        chords[(CHORD_LEN * e + k) * nv + v] + u[(3 * (e + 1) + k) * nv + v]
                    }),
                ];
                let t = [triad(e, v), triad(e + 1, v)];
                let mut k = ElementStiffness::of(&el.section, el.length0);
                if !rest.is_empty() {
                    k.rest = std::array::from_fn(|node| {
                        std::array::from_fn(|c| rest[(REST_LEN * e + 3 * node + c) * nv + v])
                    });
                }
                if tangent {
                    let (f, kt) = force_and_tangent_variation(&x, &t, &form, &k);
                    for j in 0..12 {
                        f_slab[j * nv + v] = f[j];
                    }
                    for r in 0..9 {
                        for d in 0..9 {
                            let (j, c) = tangent_source(r, d);
                            k_slab[(9 * r + d) * nv + v] = kt[j][c];
                        }
                    }
                } else {
                    let f = element_force(&x, &t, &form, &k);
                    for j in 0..12 {
                        f_slab[j * nv + v] = f[j];
                    }
                }
            }
        });
    (force, tangent_out)
}
