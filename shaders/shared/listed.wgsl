// Kernels built MASKED (the engines' line-search trials and the dynamic engine's Newton
// iterations) run one invocation per (item, listed variant) of the compacted list each
// declares, `searching` = [A, v_0, …, v_{A−1}]: invocation g takes item g / A and variant
// v_{g mod A}; from `items` · A on, none (the item returned is `items`).
fn listed(g: u32, items: u32) -> vec2<u32> {
    let count = searching[0];
    if (g >= items * count) {
        return vec2<u32>(items, 0u);
    }
    return vec2<u32>(g / count, searching[1u + g % count]);
}
