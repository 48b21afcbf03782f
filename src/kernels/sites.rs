//! Twin of `shaders/sites.wgsl`: each contact pair's displacement, gathered from the
//! configuration (the contact kernel's `d = b + w`; states `w` are displacements from a
//! base configuration, `b` the base's from the reference, across the pair's hole axis).
//!
//! One invocation per (site, variant) pair `i = site · V + variant`:
//! `d_k = b[3 i + k] + w[(3 node + k) V + variant]`, written to fields 0–2 of the pair
//! state (fields 3–6, the wall-relative velocity and spin, are the host's: they do not
//! depend on the configuration in a static solve). `pair_node[i]` is the pair's node, so a
//! variant may carry its stabilizers at other nodes than its neighbours.
//!
//! [`gather_sites_dynamic`] (the kernel's DYNAMIC form, whose base is each variant's
//! static equilibrium) also writes the node's velocity and its spin about the hole axis,
//! `n · ω` (as `solve::dynamics`).

use crate::kernels::dynamics::DynamicBatch;
use crate::physics::Real;

/// The base's displacement at every pair with its component along the pair's hole axis
/// removed, `b − n (n·b)`, `[3 i + k]` (formed in f64 from the axes the kernel sees): the
/// contact uses only the part of `d` across the axis, and the base's metres along a
/// deviated hole would otherwise round that part to f32's quantum of metres.
pub fn pair_base<T: Real>(
    pair_node: &[u32],
    pair_normals: &[T],
    base: &[f64],
    num_variants: usize,
) -> Vec<f64> {
    let mut out = vec![0.0; 3 * pair_node.len()];
    for (i, &node) in pair_node.iter().enumerate() {
        let v = i % num_variants;
        let b: [f64; 3] = std::array::from_fn(|k| base[(3 * node as usize + k) * num_variants + v]);
        let n: [f64; 3] = std::array::from_fn(|k| pair_normals[3 * i + k].to_f64_lossy());
        let along = (0..3).map(|k| n[k] * b[k]).sum::<f64>();
        for k in 0..3 {
            out[3 * i + k] = b[k] - n[k] * along;
        }
    }
    out
}

/// Writes `d = b + w` of every pair into `pair_state` (field-major, `[field · P + i]`):
/// `u` the displacements `w` from the base, `pair_base` the base's `b` at each pair
/// ([`pair_base`], `[3 i + k]`).
pub fn gather_sites<T: Real>(
    pair_node: &[u32],
    u: &[T],
    pair_base: &[T],
    num_variants: usize,
    pair_state: &mut [T],
) {
    let p = pair_node.len();
    for i in 0..p {
        let v = i % num_variants;
        let node = pair_node[i] as usize;
        for k in 0..3 {
            pair_state[k * p + i] = pair_base[3 * i + k] + u[(3 * node + k) * num_variants + v];
        }
    }
}

/// As [`gather_sites`] from `state`, whose displacements `u` are from the base (at the
/// pairs `pair_base`, `d = b + u`), and fields 3–6 from its velocities `vel` (`6 n V`: ẋ, ω) and
/// the pairs' hole axes `pair_normals` (`3 P`): `v = ẋ`, `omega = n · ω`.
pub fn gather_sites_dynamic<T: Real>(
    pair_node: &[u32],
    pair_normals: &[T],
    state: &DynamicBatch<T>,
    pair_base: &[T],
    pair_state: &mut [T],
) {
    let (vel, num_variants) = (&state.vel, state.num_variants);
    gather_sites(pair_node, &state.u, pair_base, num_variants, pair_state);
    let p = pair_node.len();
    for i in 0..p {
        let v = i % num_variants;
        let node = pair_node[i] as usize;
        let mut spin = T::zero();
        for k in 0..3 {
            pair_state[(3 + k) * p + i] = vel[(6 * node + k) * num_variants + v];
            spin = spin + pair_normals[3 * i + k] * vel[(6 * node + 3 + k) * num_variants + v];
        }
        pair_state[6 * p + i] = spin;
    }
}
