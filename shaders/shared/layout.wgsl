// Keep in sync with src/gpu/layout.rs (ContactDims) and src/kernels/contact.rs (field order).
struct ContactDims {
    // Pairs in this dispatch (the stride of every per-pair field array).
    num_pairs: u32,
    // Variants per site in the whole batch: site = (pair_offset + i) / num_variants.
    num_variants: u32,
    // Index of this dispatch's first pair in the whole batch.
    pair_offset: u32,
    // Built MASKED: V, the variants per site of the engine's pairs (site · V + variant)
    // from which the compacted list of searching variants picks.
    mask_variants: u32,
}

// Keep in sync with src/gpu/layout.rs (ChainDims).
struct ChainDims {
    // Variants in this dispatch (the stride of every field array).
    num_variants: u32,
    // Nodes of the chain.
    num_nodes: u32,
    _pad0: u32,
    _pad1: u32,
}

// Keep in sync with src/gpu/layout.rs (AssembleDims).
struct AssembleDims {
    num_variants: u32,
    num_nodes: u32,
    num_sites: u32,
    _pad: u32,
}

// Keep in sync with src/gpu/layout.rs (BeamDims).
struct BeamDims {
    num_variants: u32,
    num_elements: u32,
    _pad0: u32,
    _pad1: u32,
}

// Keep in sync with src/gpu/layout.rs (LuDims).
struct LuDims {
    num_variants: u32,
    num_nodes: u32,
    // Nodes [begin, end) of this dispatch.
    begin: u32,
    end: u32,
    // 0 forward elimination, 1 back substitution.
    phase: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}
