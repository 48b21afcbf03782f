//! Twin of `shaders/sites.wgsl`: each contact pair's displacement, gathered from the
//! configuration (the contact kernel's `d`; states are displacements from the reference).
//!
//! One invocation per (site, variant) pair `i = site · V + variant`:
//! `d_k = u[(3 node + k) V + variant]`, written to fields 0–2 of the pair state (fields
//! 3–6, the wall-relative velocity and spin, are the host's: they do not depend on the
//! configuration in a static solve). `pair_node[i]` is the pair's node, so a variant may
//! carry its stabilizers at other nodes than its neighbours.

use crate::physics::Real;

/// Writes `d` of every pair into `pair_state` (field-major, `[field · P + i]`).
pub fn gather_sites<T: Real>(
    pair_node: &[u32],
    u: &[T],
    num_variants: usize,
    pair_state: &mut [T],
) {
    let p = pair_node.len();
    for i in 0..p {
        let v = i % num_variants;
        let node = pair_node[i] as usize;
        for k in 0..3 {
            pair_state[k * p + i] = u[(3 * node + k) * num_variants + v];
        }
    }
}
