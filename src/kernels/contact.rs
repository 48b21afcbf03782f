//! Twin: `shaders/contact.wgsl`. Contact element for V variants × S sites, on the CPU.
//!
//! Pair `i = site · num_variants + variant` (variant index fastest, as on the GPU); per-pair
//! fields are stored field-major (`field · num_pairs + i`). The loop body is
//! [`crate::physics::contact::evaluate`]; this file only lays the data out the GPU's way.

use rayon::prelude::*;

use crate::physics::contact::{
    evaluate, ContactMode, ContactParams, ContactResponse, ContactTerms, FrictionModel, SpringLaw,
    PARAMS_LEN,
};
use crate::physics::Real;

/// Scalars of per-pair state: `d` (3) = x − x0, `v` (3), `omega`.
pub const STATE_LEN: usize = 7;
/// Scalars of per-pair output: `g` (6), `K` (18, row-major 6×3), `C` (18), `c_omega` (6).
pub const OUTPUT_LEN: usize = 48;
/// Offset of `g` in the output fields.
pub const OUT_G: usize = 0;
/// Offset of `K`.
pub const OUT_K: usize = 6;
/// Offset of `C`.
pub const OUT_C: usize = 24;
/// Offset of `c_omega`.
pub const OUT_C_OMEGA: usize = 42;

/// The output fields a scene's kernel writes and its buffers hold: all [`OUTPUT_LEN`] in
/// dynamics, only `g` and `K` (the first [`OUT_C`]) in statics — the damping matrices `C`
/// and `c_omega` of a static scene are zero and never read, so no memory is allocated for
/// them (`shaders/contact.wgsl` `OUT_FIELDS`). The layout `[field · P + i]` is the same
/// either way.
pub fn output_fields(terms: &ContactTerms) -> usize {
    match terms.mode {
        ContactMode::Dynamic => OUTPUT_LEN,
        ContactMode::Static => OUT_C,
    }
}

/// Inputs of one contact evaluation over V variants × S sites.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactBatch<T> {
    /// V: variants per site.
    pub num_variants: usize,
    /// S: sites.
    pub num_sites: usize,
    /// Unit hole axis per site: `[3·site + k]`.
    pub site_normals: Vec<T>,
    /// [`ContactParams`] fields, field-major: `[field · P + i]`.
    pub pair_params: Vec<T>,
    /// State fields (`d`, `v`, `omega`), field-major: `[field · P + i]`.
    pub pair_state: Vec<T>,
}

impl<T: Real> ContactBatch<T> {
    /// A batch of zeros (no contact anywhere) for V variants × S sites.
    pub fn new(num_variants: usize, num_sites: usize) -> Self {
        let p = num_variants * num_sites;
        ContactBatch {
            num_variants,
            num_sites,
            site_normals: vec![T::zero(); 3 * num_sites],
            pair_params: vec![T::zero(); PARAMS_LEN * p],
            pair_state: vec![T::zero(); STATE_LEN * p],
        }
    }

    /// P = V·S, the number of (variant, site) pairs.
    pub fn num_pairs(&self) -> usize {
        self.num_variants * self.num_sites
    }

    /// Pair index of (variant, site).
    pub fn pair_index(&self, variant: usize, site: usize) -> usize {
        site * self.num_variants + variant
    }

    /// Sets the hole axis of a site (normalised here).
    pub fn set_site_normal(&mut self, site: usize, n: [T; 3]) {
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        for (slot, x) in self.site_normals[3 * site..3 * site + 3].iter_mut().zip(n) {
            *slot = x / len;
        }
    }

    /// Hole axis of a site.
    pub fn site_normal(&self, site: usize) -> [T; 3] {
        let s = &self.site_normals[3 * site..3 * site + 3];
        [s[0], s[1], s[2]]
    }

    /// Sets the law parameters of pair `i`.
    pub fn set_params(&mut self, i: usize, params: &ContactParams<T>) {
        let p = self.num_pairs();
        for (k, x) in params.to_array().into_iter().enumerate() {
            self.pair_params[k * p + i] = x;
        }
    }

    /// Law parameters of pair `i`.
    pub fn params(&self, i: usize) -> ContactParams<T> {
        let p = self.num_pairs();
        ContactParams::from_array(std::array::from_fn(|k| self.pair_params[k * p + i]))
    }

    /// Sets the state of pair `i`: displacement from the site's reference point, velocity,
    /// spin rate.
    pub fn set_state(&mut self, i: usize, d: [T; 3], v: [T; 3], omega: T) {
        let p = self.num_pairs();
        let s = [d[0], d[1], d[2], v[0], v[1], v[2], omega];
        for (k, x) in s.into_iter().enumerate() {
            self.pair_state[k * p + i] = x;
        }
    }

    /// State of pair `i` as `(d, v, omega)`.
    pub fn state(&self, i: usize) -> ([T; 3], [T; 3], T) {
        let p = self.num_pairs();
        let s = |k: usize| self.pair_state[k * p + i];
        ([s(0), s(1), s(2)], [s(3), s(4), s(5)], s(6))
    }

    /// The least general kernel that evaluates this batch exactly: the spring law from the
    /// exponents present, damping only if some `c > 0` in dynamic mode, friction only if
    /// some `mu > 0`.
    pub fn required_terms(&self, friction: FrictionModel, mode: ContactMode) -> ContactTerms {
        let p = self.num_pairs();
        let field = |k: usize| &self.pair_params[k * p..(k + 1) * p];
        let spring = field(3)
            .iter()
            .map(|m| SpringLaw::for_exponent(m.to_f64_lossy()))
            .fold(SpringLaw::Linear, SpringLaw::join);
        let damping = mode == ContactMode::Dynamic && field(4).iter().any(|c| *c > T::zero());
        let has_friction = field(5).iter().chain(field(6)).any(|mu| *mu > T::zero());
        ContactTerms {
            spring,
            damping,
            friction: has_friction.then_some(friction),
            mode,
        }
    }

    /// Converts to another float type.
    pub fn cast<U: Real>(&self) -> ContactBatch<U> {
        let c = |v: &Vec<T>| {
            v.iter()
                .map(|x| U::from_f64_lossy(x.to_f64_lossy()))
                .collect()
        };
        ContactBatch {
            num_variants: self.num_variants,
            num_sites: self.num_sites,
            site_normals: c(&self.site_normals),
            pair_params: c(&self.pair_params),
            pair_state: c(&self.pair_state),
        }
    }
}

/// Outputs of one contact evaluation, in the GPU's layout.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactOutputs<T> {
    /// P.
    pub num_pairs: usize,
    /// 1 where the disk touches the wall.
    pub contact: Vec<u32>,
    /// `OUTPUT_LEN` fields, field-major: `[field · P + i]`.
    pub values: Vec<T>,
}

impl<T: Real> ContactOutputs<T> {
    /// Zeroed outputs for P pairs.
    pub fn new(num_pairs: usize) -> Self {
        ContactOutputs {
            num_pairs,
            contact: vec![0; num_pairs],
            values: vec![T::zero(); OUTPUT_LEN * num_pairs],
        }
    }

    /// The response of pair `i`.
    pub fn response(&self, i: usize) -> ContactResponse<T> {
        let p = self.num_pairs;
        let f = |k: usize| self.values[k * p + i];
        ContactResponse {
            contact: self.contact[i] != 0,
            g: std::array::from_fn(|r| f(OUT_G + r)),
            k: std::array::from_fn(|r| std::array::from_fn(|c| f(OUT_K + 3 * r + c))),
            c: std::array::from_fn(|r| std::array::from_fn(|c| f(OUT_C + 3 * r + c))),
            c_omega: std::array::from_fn(|r| f(OUT_C_OMEGA + r)),
        }
    }

    /// All output fields of pair `i` in layout order.
    pub fn fields(&self, i: usize) -> [T; OUTPUT_LEN] {
        std::array::from_fn(|k| self.values[k * self.num_pairs + i])
    }
}

/// Flattens a response into the output field order.
pub fn response_fields<T: Real>(r: &ContactResponse<T>) -> [T; OUTPUT_LEN] {
    let mut out = [T::zero(); OUTPUT_LEN];
    out[OUT_G..OUT_G + 6].copy_from_slice(&r.g);
    for row in 0..6 {
        for col in 0..3 {
            out[OUT_K + 3 * row + col] = r.k[row][col];
            out[OUT_C + 3 * row + col] = r.c[row][col];
        }
    }
    out[OUT_C_OMEGA..OUT_C_OMEGA + 6].copy_from_slice(&r.c_omega);
    out
}

/// One parallel task: first pair, its contact flags, and one slice per output field.
type Block<'a, T> = (usize, &'a mut [u32], Vec<&'a mut [T]>);

/// Pairs per parallel task.
const BLOCK: usize = 2048;

/// The CPU twin of `shaders/contact.wgsl`: evaluates every pair of `batch` with the
/// terms `terms`, in parallel over blocks of pairs (rayon), into `out`.
pub fn contact<T: Real>(
    terms: &ContactTerms,
    batch: &ContactBatch<T>,
    out: &mut ContactOutputs<T>,
) {
    let p = batch.num_pairs();
    assert_eq!(out.num_pairs, p, "output sized for another batch");
    // Per block, one mutable slice of each output field.
    let mut field_blocks: Vec<std::slice::ChunksMut<'_, T>> = out
        .values
        .chunks_mut(p.max(1))
        .map(|f| f.chunks_mut(BLOCK))
        .collect();
    let mut blocks: Vec<Block<'_, T>> = Vec::new();
    for (b, flags) in out.contact.chunks_mut(BLOCK).enumerate() {
        let fields: Vec<&mut [T]> = field_blocks
            .iter_mut()
            .map(|it| it.next().expect("field blocks match flag blocks"))
            .collect();
        blocks.push((b * BLOCK, flags, fields));
    }
    blocks
        .into_par_iter()
        .for_each(|(start, flags, mut fields)| {
            for (local, flag) in flags.iter_mut().enumerate() {
                let i = start + local;
                let site = i / batch.num_variants;
                let n = batch.site_normal(site);
                let (d, v, omega) = batch.state(i);
                let response = evaluate(&n, &d, &v, omega, &batch.params(i), terms);
                *flag = u32::from(response.contact);
                for (k, x) in response_fields(&response).into_iter().enumerate() {
                    fields[k][local] = x;
                }
            }
        });
}
