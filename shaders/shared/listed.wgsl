// The item (node, element or site) and variant of invocation g of a kernel that runs one
// invocation per (item, variant): variant-fastest over all `nv` variants, or, built MASKED
// (the engines' line-search trials and the dynamic engine's Newton iterations), over the
// compacted list the kernel declares, `searching` = [A, v_0, …, v_{A−1}] (item g / A,
// variant v_{g mod A}). From items · nv (items · A) on, none: the item returned is `items`.
fn item_of(g: u32, items: u32, nv: u32) -> vec2<u32> {
#if MASKED
    let count = searching[0];
    if (g >= items * count) {
        return vec2<u32>(items, 0u);
    }
    return vec2<u32>(g / count, searching[1u + g % count]);
#else
    if (g >= items * nv) {
        return vec2<u32>(items, 0u);
    }
    return vec2<u32>(g / nv, g % nv);
#endif
}
