// Keep in sync with src/gpu/layout.rs (ContactDims) and src/kernels/contact.rs (field order).
struct ContactDims {
    // Pairs in this dispatch (the stride of every per-pair field array).
    num_pairs: u32,
    // Variants per site in the whole batch: site = (pair_offset + i) / num_variants.
    num_variants: u32,
    // Index of this dispatch's first pair in the whole batch.
    pair_offset: u32,
    _pad: u32,
}
