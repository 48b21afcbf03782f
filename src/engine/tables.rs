//! The tables of a batch of variants (mesh, sections, frames, sites, constraints, loads), built
//! once from the variants' models, all on the first one's mesh. Split from `engine/mod.rs`
//! (issue 24: no file over 800 lines), behaviour unchanged.

use super::*;

/// An error unless every model shares the first one's mesh, number of sites and friction
/// model.
pub(crate) fn check_same_mesh(models: &[Model]) -> Result<(), crate::error::SystemError> {
    let base = models
        .first()
        .ok_or(crate::error::SystemError::Unsupported("no variants".into()))?;
    for m in models {
        if m.nodes.len() != base.nodes.len()
            || m.elements.len() != base.elements.len()
            || m.sites.len() != base.sites.len()
        {
            return Err(crate::error::SystemError::Unsupported(
                "variants differ in mesh or number of sites; run them on the CPU".into(),
            ));
        }
        // One contact kernel serves the ensemble: one friction model.
        if m.friction != base.friction {
            return Err(crate::error::SystemError::Unsupported(
                "variants differ in friction model (split, coupled: e.g. reaming \
                        beside rotating); run them on the CPU"
                    .into(),
            ));
        }
    }
    Ok(())
}

/// A table of `rows` rows of `v` values each, variant-fastest (`[r v + j] = value(r, j)`),
/// filled in parallel in blocks of `block` rows (a node's, say): within a block each
/// variant's values are taken together, so a variant's data is read close together and
/// every write lands in the block's rows. Writing a variant's column at a time strides by
/// `v` on every write; at V = 4096 that serial transpose was most of a dynamic batch's
/// setup (issue 27, `docs/performance.md`).
pub(crate) fn variant_fastest<X: Copy + Default + Send + Sync>(
    rows: usize,
    v: usize,
    block: usize,
    value: impl Fn(usize, usize) -> X + Sync,
) -> Vec<X> {
    use rayon::prelude::*;
    let mut out = vec![X::default(); rows * v];
    if v == 0 {
        return out;
    }
    let block = block.max(1);
    out.par_chunks_mut(block * v)
        .enumerate()
        .for_each(|(b, chunk)| {
            let first = b * block;
            let count = chunk.len() / v;
            for j in 0..v {
                for r in 0..count {
                    chunk[r * v + j] = value(first + r, j);
                }
            }
        });
    out
}

/// The tables of a batch of variants (all on the first one's mesh).
pub fn ensemble_tables<T: Real>(
    models: &[Model],
) -> Result<BatchTables<T>, crate::error::SystemError> {
    ensemble_tables_from(models, None)
}

/// As [`ensemble_tables`], the batch starting from `start` (displacements from the
/// reference `3 n V`, rotations `9 n V`; none: each variant laid on the low side) — a
/// compacted or re-tried batch starts where its variants stand, and does not lay them out
/// again.
pub fn ensemble_tables_from<T: Real>(
    models: &[Model],
    start: Option<(Vec<T>, Vec<T>)>,
) -> Result<BatchTables<T>, crate::error::SystemError> {
    check_same_mesh(models)?;
    let t = |x: f64| T::from_f64_lossy(x);
    let base = &models[0];
    let (v, n, s_count) = (models.len(), base.nodes.len(), base.sites.len());
    let (basis, fixed) = constraint_tables(base);
    let (x, rot) = match start {
        Some(given) => given,
        None => {
            // Each variant laid on the low side (in parallel), then the tables a node at a
            // time ([`variant_fastest`]).
            use rayon::prelude::*;
            let laid: Vec<_> = models
                .par_iter()
                .map(crate::solve::statics::static_start)
                .collect();
            (
                variant_fastest(3 * n, v, 3, |r, j| t(laid[j].u[r / 3][r % 3])),
                variant_fastest(
                    9 * n,
                    v,
                    9,
                    |r, j| t(laid[j].rot[r / 9][(r % 9) / 3][r % 3]),
                ),
            )
        }
    };
    let start = ConfigBatch {
        num_variants: v,
        num_nodes: n,
        x,
        rot,
        basis: basis.iter().map(|&b| t(b)).collect(),
        landed: vec![0; n * v],
    };
    let p = s_count * v;
    let mut node_site = vec![NO_SITE; n * v];
    for (j, m) in models.iter().enumerate() {
        for (k, site) in m.sites.iter().enumerate() {
            node_site[site.node * v + j] = k as u32;
        }
    }
    // The pair tables, `[k V + j]` per field: site by site, in parallel
    // ([`variant_fastest`]), each model's law parameters taken once.
    use rayon::prelude::*;
    let arrays: Vec<Vec<[f64; PARAMS_LEN]>> = models
        .par_iter()
        .map(|m| m.sites.iter().map(|x| x.params.to_array()).collect())
        .collect();
    let normal = |k: usize, j: usize| {
        let m = &models[j];
        let axis = m.nodes[m.sites[k].node].hole_axis;
        let len = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
        (axis, len)
    };
    let pair_node = variant_fastest(s_count, v, 1, |k, j| models[j].sites[k].node as u32);
    // Pair-major: the three components of a pair's normal together.
    let mut pair_normals = vec![T::zero(); 3 * p];
    pair_normals
        .par_chunks_mut(3 * v)
        .enumerate()
        .for_each(|(k, chunk)| {
            for (j, out) in chunk.chunks_exact_mut(3).enumerate() {
                let (axis, len) = normal(k, j);
                for a in 0..3 {
                    out[a] = t(axis[a] / len);
                }
            }
        });
    // Fields 3–5 the axial speed along the hole's axis, 6 the rotation speed.
    let pair_state = variant_fastest(STATE_LEN * s_count, v, s_count, |r, j| {
        let (f, k) = (r / s_count.max(1), r % s_count.max(1));
        let m = &models[j];
        match f {
            3..=5 => t(m.nodes[m.sites[k].node].hole_axis[f - 3] * m.axial_speed),
            6 => t(m.rotation_speed),
            _ => T::zero(),
        }
    });
    let params = variant_fastest(PARAMS_LEN * s_count, v, s_count, |r, j| {
        t(arrays[j][r % s_count.max(1)][r / s_count.max(1)])
    });
    let mut batch = ContactBatch::<T>::new(1, p);
    batch.pair_params = params;
    let terms = batch.required_terms(base.friction, ContactMode::Static);
    let node_ref: Vec<f64> = base.nodes.iter().flat_map(|nd| nd.position).collect();
    let mut tables = BatchTables {
        num_variants: v,
        num_nodes: n,
        num_sites: s_count,
        basis: start.basis.clone(),
        fixed,
        node_site,
        pair_node,
        node_ref,
        pair_normals,
        pair_state,
        start,
        base: Vec::new(),
        pair_base: Vec::new(),
        chords: Vec::new(),
        rest: crate::kernels::beam::rest_table(models, &|_| 1.0)
            .into_iter()
            .map(|x| T::from_f64_lossy(x))
            .collect(),
        terms,
    };
    // The static solve starts from the reference as base.
    tables.set_base(base, vec![0.0; 3 * n * v]);
    Ok(tables)
}

#[cfg(test)]
mod tests {
    use super::variant_fastest;

    /// Every entry where the column-at-a-time loop it replaced put it, for blocks that do
    /// and do not divide the rows, one variant and many.
    #[test]
    fn variant_fastest_puts_every_value_where_a_column_loop_would() {
        for (rows, v, block) in [
            (7, 5, 3),
            (6, 1, 6),
            (12, 33, 4),
            (1, 9, 9),
            (0, 4, 2),
            (5, 3, 0),
        ] {
            let value = |r: usize, j: usize| (1000 * r + j) as u64;
            let got = variant_fastest(rows, v, block, value);
            let mut want = vec![0u64; rows * v];
            for j in 0..v {
                for r in 0..rows {
                    want[r * v + j] = value(r, j);
                }
            }
            assert_eq!(got, want, "rows {rows}, v {v}, block {block}");
        }
    }
}
