// NaN-propagating maximum: a bit test, as comparisons with NaN may be folded away.
// Included by update.wgsl (norms) and dynamics.wgsl (force scale).
fn is_nan_or_inf(p: real) -> bool {
    return (bitcast<u32>(f32(p)) & 0x7f800000u) == 0x7f800000u;
}
