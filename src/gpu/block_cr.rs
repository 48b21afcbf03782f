//! The cyclic form of the block solve (`shaders/block_cr.wgsl`, twin
//! `src/kernels/block_cr.rs`): its written-out code and its passes. It is run by
//! [`crate::gpu::block_lu`] as [`crate::gpu::block_lu::LuForm::Cyclic`], on the same
//! bindings as the chain walk.

use std::fmt::Write;

use crate::kernels::block_cr::levels;

/// Phase of the first pass (level 1's odd nodes factored; node 0 solved if alone).
const LOAD: u32 = 2;
/// Phase of a level's even update (and the factoring of the next level's odd nodes).
const REDUCE: u32 = 3;
/// Phase of a level's back substitution.
const BACK: u32 = 4;

/// The passes of an `n`-node chain, `(stride, nodes of the pass, phase)`: the load, a
/// reduction per level, then the back substitution from the coarsest level.
pub fn passes(n: usize) -> Vec<(usize, usize, u32)> {
    let levels = levels(n);
    let mut out = vec![(1, if n == 1 { 1 } else { n / 2 }, LOAD)];
    out.extend(levels.iter().map(|&s| (s, (n - 1) / (2 * s) + 1, REDUCE)));
    out.extend(
        levels
            .iter()
            .rev()
            .map(|&s| (s, (n - 1 - s) / (2 * s) + 1, BACK)),
    );
    out
}

/// Entries per variant of the workspace, `(work_x, work_z)`: `D`, `WL`, `WU` per node and
/// `y` per node.
pub fn workspace(n: usize) -> (usize, usize) {
    (108 * n, 6 * n)
}

/// `shaders/block_cr.wgsl` with its markers written out.
pub fn expand(text: &str) -> String {
    static PARTS: std::sync::OnceLock<[(&str, String); 6]> = std::sync::OnceLock::new();
    let parts = PARTS.get_or_init(|| {
        [
            ("    //@LOAD\n", load()),
            ("        //@UPDATE\n", update()),
            ("        //@STORE\n", store()),
            ("    //@FACTOR\n", factor()),
            ("        //@SOLVE\n", solve()),
            ("        //@BACK\n", back()),
        ]
    });
    let mut out = text.to_string();
    for (marker, code) in parts {
        out = out.replace(marker, code);
    }
    out
}

fn load() -> String {
    let mut s = String::new();
    let w = &mut s;
    for r in 0..6 {
        for c in 0..6 {
            let _ = writeln!(w, "    var d{r}_{c}: real;");
        }
        let _ = writeln!(w, "    var y{r}: real;");
    }
    let _ = writeln!(w, "    if (from_inputs) {{");
    for r in 0..6 {
        for c in 0..6 {
            let _ = writeln!(w, "        d{r}_{c} = diag[blk(i, {}u, v)];", 6 * r + c);
        }
        let _ = writeln!(w, "        y{r} = rhs[vec_at(i, {r}u, v)];");
    }
    let _ = writeln!(w, "    }} else {{");
    for r in 0..6 {
        for c in 0..6 {
            let _ = writeln!(
                w,
                "        d{r}_{c} = work_x[wk(0u, i, {}u, v)];",
                6 * r + c
            );
        }
        let _ = writeln!(w, "        y{r} = work_z[vec_at(i, {r}u, v)];");
    }
    let _ = writeln!(w, "    }}");
    s
}

/// `D −= A B` with `B` the field `b_field` of node `j` (twin: `sub_product`).
fn sub_product(w: &mut String, b_field: u32) {
    for c in 0..6 {
        let _ = writeln!(w, "            {{");
        for k in 0..6 {
            let _ = writeln!(
                w,
                "                let q{k} = work_x[wk({b_field}u, j, {}u, v)];",
                6 * k + c
            );
        }
        for r in 0..6 {
            for k in 0..6 {
                let _ = writeln!(w, "                d{r}_{c} = d{r}_{c} - a{r}_{k} * q{k};");
            }
        }
        let _ = writeln!(w, "            }}");
    }
}

/// `y −= A r_j` (twin: `sub_vec`).
fn sub_vec(w: &mut String) {
    let _ = writeln!(w, "            {{");
    for k in 0..6 {
        let _ = writeln!(w, "                let q{k} = work_z[vec_at(j, {k}u, v)];");
    }
    for r in 0..6 {
        for k in 0..6 {
            let _ = writeln!(w, "                y{r} = y{r} - a{r}_{k} * q{k};");
        }
    }
    let _ = writeln!(w, "            }}");
}

/// Field `out_field` of node `i` ← `−A B`, `B` the field `b_field` of node `j` (twin:
/// `neg_product`).
fn neg_product(w: &mut String, indent: &str, b_field: u32, out_field: u32) {
    for c in 0..6 {
        let _ = writeln!(w, "{indent}{{");
        for k in 0..6 {
            let _ = writeln!(
                w,
                "{indent}    let q{k} = work_x[wk({b_field}u, j, {}u, v)];",
                6 * k + c
            );
        }
        for r in 0..6 {
            let _ = writeln!(w, "{indent}    {{");
            let _ = writeln!(w, "{indent}        var t = real(0.0);");
            for k in 0..6 {
                let _ = writeln!(w, "{indent}        t = t - a{r}_{k} * q{k};");
            }
            let _ = writeln!(
                w,
                "{indent}        work_x[wk({out_field}u, i, {}u, v)] = t;",
                6 * r + c
            );
            let _ = writeln!(w, "{indent}    }}");
        }
        let _ = writeln!(w, "{indent}}}");
    }
}

/// `A` = the coupling `field` of node `i` (1: `WL`, at level 1 the input `lower` block of
/// row `i`; 2: `WU`, at level 1 `upper`).
fn load_coupling(w: &mut String, field: u32) {
    let input = match field {
        1 => "lower[blk(i - 1u",
        _ => "upper[blk(i",
    };
    for r in 0..6 {
        for k in 0..6 {
            let _ = writeln!(w, "            var a{r}_{k}: real;");
        }
    }
    let _ = writeln!(w, "            if (s == 1u) {{");
    for r in 0..6 {
        for k in 0..6 {
            let _ = writeln!(
                w,
                "                a{r}_{k} = {input}, {}u, v)];",
                6 * r + k
            );
        }
    }
    let _ = writeln!(w, "            }} else {{");
    for r in 0..6 {
        for k in 0..6 {
            let _ = writeln!(
                w,
                "                a{r}_{k} = work_x[wk({field}u, i, {}u, v)];",
                6 * r + k
            );
        }
    }
    let _ = writeln!(w, "            }}");
}

fn update() -> String {
    let mut s = String::new();
    let w = &mut s;
    // The left odd neighbour: WL_i, with P_j in field 1 and Q_j in field 2.
    let _ = writeln!(w, "        if (i >= 2u * s) {{");
    let _ = writeln!(w, "            let j = i - s;");
    load_coupling(w, 1);
    sub_product(w, 2);
    sub_vec(w);
    neg_product(w, "            ", 1, 1);
    let _ = writeln!(w, "        }}");
    // The right odd neighbour: WU_i.
    let _ = writeln!(w, "        if (i + s < n) {{");
    let _ = writeln!(w, "            let j = i + s;");
    load_coupling(w, 2);
    sub_product(w, 1);
    sub_vec(w);
    let _ = writeln!(w, "            if (j + s < n) {{");
    neg_product(w, "                ", 2, 2);
    let _ = writeln!(w, "            }}");
    let _ = writeln!(w, "        }}");
    s
}

fn store() -> String {
    let mut s = String::new();
    let w = &mut s;
    for r in 0..6 {
        for c in 0..6 {
            let _ = writeln!(
                w,
                "        work_x[wk(0u, i, {}u, v)] = d{r}_{c};",
                6 * r + c
            );
        }
        let _ = writeln!(w, "        work_z[vec_at(i, {r}u, v)] = y{r};");
    }
    s
}

/// LU with partial pivoting of `d` in place (twin: `factor`): `sw{col}` the row swapped
/// in at step `col`, `iv{col}` the pivot's reciprocal, `bad` a zero or non-finite pivot.
fn factor() -> String {
    let mut s = String::new();
    let w = &mut s;
    let _ = writeln!(w, "    var bad = false;");
    for q in 0..6 {
        let _ = writeln!(w, "    var sw{q} = {q}u;");
        let _ = writeln!(w, "    var iv{q} = real(0.0);");
    }
    for col in 0..6 {
        let _ = writeln!(w, "    {{");
        let _ = writeln!(w, "        var p = {col}u;");
        let _ = writeln!(w, "        var best = abs(d{col}_{col});");
        for r in col + 1..6 {
            let _ = writeln!(
                w,
                "        if (abs(d{r}_{col}) > best) {{ p = {r}u; best = abs(d{r}_{col}); }}"
            );
        }
        for r in col + 1..6 {
            let _ = writeln!(w, "        if (p == {r}u) {{");
            for c in 0..6 {
                let _ = writeln!(
                    w,
                    "            {{ let t = d{col}_{c}; d{col}_{c} = d{r}_{c}; d{r}_{c} = t; }}"
                );
            }
            let _ = writeln!(w, "        }}");
        }
        let _ = writeln!(w, "        sw{col} = p;");
        let _ = writeln!(w, "        let pivot = d{col}_{col};");
        let _ = writeln!(w, "        if (bad_pivot(pivot)) {{ bad = true; }}");
        let _ = writeln!(w, "        iv{col} = real(1.0) / pivot;");
        for r in col + 1..6 {
            let _ = writeln!(w, "        {{");
            let _ = writeln!(w, "            let f = d{r}_{col} * iv{col};");
            let _ = writeln!(w, "            d{r}_{col} = f;");
            for c in col + 1..6 {
                let _ = writeln!(w, "            d{r}_{c} = d{r}_{c} - f * d{col}_{c};");
            }
            let _ = writeln!(w, "        }}");
        }
        let _ = writeln!(w, "    }}");
    }
    s
}

/// Column `col` of `[WL | WU | y]` solved with the factor (twin: `Factored::solve`).
fn solve() -> String {
    let mut s = String::new();
    let w = &mut s;
    for r in 0..6 {
        let _ = writeln!(w, "        var b{r}: real;");
    }
    let _ = writeln!(w, "        if (col < 6u) {{");
    let _ = writeln!(w, "            if (phase == 2u) {{");
    for r in 0..6 {
        let _ = writeln!(
            w,
            "                b{r} = lower[blk(i - 1u, {}u + col, v)];",
            6 * r
        );
    }
    let _ = writeln!(w, "            }} else {{");
    for r in 0..6 {
        let _ = writeln!(
            w,
            "                b{r} = work_x[wk(1u, i, {}u + col, v)];",
            6 * r
        );
    }
    let _ = writeln!(w, "            }}");
    let _ = writeln!(w, "        }} else if (col < 12u) {{");
    let _ = writeln!(w, "            if (phase == 2u) {{");
    for r in 0..6 {
        let _ = writeln!(
            w,
            "                b{r} = upper[blk(i, {}u + col - 6u, v)];",
            6 * r
        );
    }
    let _ = writeln!(w, "            }} else {{");
    for r in 0..6 {
        let _ = writeln!(
            w,
            "                b{r} = work_x[wk(2u, i, {}u + col - 6u, v)];",
            6 * r
        );
    }
    let _ = writeln!(w, "            }}");
    let _ = writeln!(w, "        }} else {{");
    for r in 0..6 {
        let _ = writeln!(w, "            b{r} = y{r};");
    }
    let _ = writeln!(w, "        }}");
    for q in 0..6 {
        for r in q + 1..6 {
            let _ = writeln!(
                w,
                "        if (sw{q} == {r}u) {{ let t = b{q}; b{q} = b{r}; b{r} = t; }}"
            );
        }
    }
    for r in 1..6 {
        for k in 0..r {
            let _ = writeln!(w, "        b{r} = b{r} - d{r}_{k} * b{k};");
        }
    }
    for r in (0..6).rev() {
        for k in r + 1..6 {
            let _ = writeln!(w, "        b{r} = b{r} - d{r}_{k} * b{k};");
        }
        let _ = writeln!(w, "        b{r} = b{r} * iv{r};");
    }
    let _ = writeln!(w, "        if (col < 6u) {{");
    for r in 0..6 {
        let _ = writeln!(
            w,
            "            work_x[wk(1u, i, {}u + col, v)] = b{r};",
            6 * r
        );
    }
    let _ = writeln!(w, "        }} else if (col < 12u) {{");
    for r in 0..6 {
        let _ = writeln!(
            w,
            "            work_x[wk(2u, i, {}u + col - 6u, v)] = b{r};",
            6 * r
        );
    }
    let _ = writeln!(w, "        }} else if (alone) {{");
    for r in 0..6 {
        let _ = writeln!(w, "            x[vec_at(0u, {r}u, v)] = b{r};");
    }
    let _ = writeln!(w, "        }} else {{");
    for r in 0..6 {
        let _ = writeln!(w, "            work_z[vec_at(i, {r}u, v)] = b{r};");
    }
    let _ = writeln!(w, "        }}");
    s
}

/// `x_j = r_j − P_j x_{j−s} − Q_j x_{j+s}` (twin: the back substitution of `solve_one`).
fn back() -> String {
    let mut s = String::new();
    let w = &mut s;
    for c in 0..6 {
        let _ = writeln!(w, "        let xl{c} = x[vec_at(j - s, {c}u, v)];");
        let _ = writeln!(w, "        var xr{c} = real(0.0);");
    }
    let _ = writeln!(w, "        if (right) {{");
    for c in 0..6 {
        let _ = writeln!(w, "            xr{c} = x[vec_at(j + s, {c}u, v)];");
    }
    let _ = writeln!(w, "        }}");
    for r in 0..6 {
        let _ = writeln!(w, "        {{");
        let _ = writeln!(w, "            var t = work_z[vec_at(j, {r}u, v)];");
        for c in 0..6 {
            let _ = writeln!(
                w,
                "            t = t - work_x[wk(1u, j, {}u, v)] * xl{c};",
                6 * r + c
            );
        }
        let _ = writeln!(w, "            if (right) {{");
        for c in 0..6 {
            let _ = writeln!(
                w,
                "                t = t - work_x[wk(2u, j, {}u, v)] * xr{c};",
                6 * r + c
            );
        }
        let _ = writeln!(w, "            }}");
        let _ = writeln!(w, "            x[vec_at(j, {r}u, v)] = t;");
        let _ = writeln!(w, "        }}");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The passes, read as `shaders/block_cr.wgsl` reads them (node from the invocation's
    /// `k`, factored or solved where the shader decides), eliminate every node exactly once
    /// (node 0 last, alone) and give every other node exactly one back substitution, at
    /// every chain length up to 600.
    #[test]
    fn the_passes_eliminate_and_substitute_every_node_once() {
        for n in 1..=600usize {
            let mut factored = vec![0u32; n];
            let mut substituted = vec![0u32; n];
            let mut solved_alone = 0;
            for (s, nodes, phase) in passes(n) {
                for k in 0..nodes {
                    match phase {
                        LOAD => {
                            let i = if n == 1 { 0 } else { 2 * k + 1 };
                            assert!(i < n, "n {n}: load node {i}");
                            if n == 1 {
                                solved_alone += 1;
                            } else {
                                factored[i] += 1;
                            }
                        }
                        REDUCE => {
                            let i = 2 * s * k;
                            assert!(i < n, "n {n}: reduce node {i} at {s}");
                            // Its odd neighbours were factored before this pass.
                            for j in [i.checked_sub(s), Some(i + s).filter(|&j| j < n)]
                                .into_iter()
                                .flatten()
                            {
                                assert_eq!(factored[j], 1, "n {n}: node {i} at {s} reads {j}");
                            }
                            assert_eq!(factored[i], 0, "n {n}: node {i} updated after its factor");
                            if i % (4 * s) == 2 * s {
                                factored[i] += 1;
                            } else if i == 0 && 2 * s >= n {
                                solved_alone += 1;
                            }
                        }
                        BACK => {
                            let j = s + 2 * s * k;
                            assert!(j < n && j % (2 * s) == s, "n {n}: back node {j} at {s}");
                            substituted[j] += 1;
                        }
                        _ => unreachable!(),
                    }
                }
            }
            assert_eq!(solved_alone, 1, "n {n}: node 0 solved once");
            assert_eq!(factored[0], 0, "n {n}");
            assert!(factored[1..].iter().all(|&c| c == 1), "n {n}: {factored:?}");
            assert!(
                substituted[1..].iter().all(|&c| c == 1),
                "n {n}: {substituted:?}"
            );
            assert_eq!(substituted[0], 0);
            // The widest pass fits the batch's dispatch bound (n invocations a variant).
            assert!(passes(n).iter().all(|p| p.1 <= n));
        }
    }
}
