//! `#[repr(C)]` structs shared with WGSL. Keep in sync with `shaders/shared/layout.wgsl`.

use bytemuck::{Pod, Zeroable};

/// Dispatch dimensions of the contact kernel (parameter binding 0 of `shaders/contact.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct ContactDims {
    /// Pairs in this dispatch: the stride of every per-pair field array.
    pub num_pairs: u32,
    /// Variants per site in the whole batch: `site = (pair_offset + i) / num_variants`.
    pub num_variants: u32,
    /// Index of this dispatch's first pair in the whole batch.
    pub pair_offset: u32,
    /// The kernel built `MASKED`: V, the variants per site of the engine's pairs
    /// (`site · V + variant`) from which the compacted list of searching variants picks.
    /// Unused otherwise.
    pub mask_variants: u32,
}

/// Dispatch dimensions of the block-tridiagonal solve (parameter binding 0 of
/// `shaders/block_lu.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct ChainDims {
    /// Variants in this dispatch: the stride of every field array.
    pub num_variants: u32,
    /// Nodes of the chain.
    pub num_nodes: u32,
    /// Padding to 16 bytes.
    pub _pad0: u32,
    /// Padding.
    pub _pad1: u32,
}

/// Dispatch dimensions of the assembly (parameter binding 0 of `shaders/assemble.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct AssembleDims {
    /// Variants V.
    pub num_variants: u32,
    /// Nodes n.
    pub num_nodes: u32,
    /// Contact sites S per variant.
    pub num_sites: u32,
    /// Padding to 16 bytes.
    pub _pad: u32,
}

/// Dispatch dimensions of the beam kernel (parameter binding 0 of `shaders/beam.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct BeamDims {
    /// Variants V.
    pub num_variants: u32,
    /// Elements of the chain.
    pub num_elements: u32,
    /// Padding to 16 bytes.
    pub _pad0: u32,
    /// Padding.
    pub _pad1: u32,
}

/// Dispatch dimensions of one pass of the block solve (parameter binding 0 of
/// `shaders/block_lu.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct LuDims {
    /// Variants in this dispatch.
    pub num_variants: u32,
    /// Nodes of the chain.
    pub num_nodes: u32,
    /// First node of this pass.
    pub begin: u32,
    /// One past the last node of this pass.
    pub end: u32,
    /// 0 forward elimination, 1 back substitution.
    pub phase: u32,
    /// Padding to 32 bytes.
    pub _pad0: u32,
    /// Padding.
    pub _pad1: u32,
    /// Padding.
    pub _pad2: u32,
}
