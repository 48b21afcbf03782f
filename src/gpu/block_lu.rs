//! Runs the block solve of every variant's block-tridiagonal system, variants split into
//! chunks that fit the adapter's binding limits, in one of three forms ([`LuForm`]): the
//! chain walk of `shaders/block_lu.wgsl` (twin `src/kernels/block_lu.rs`), one invocation
//! or [`LANES`] per variant, or cyclic reduction (`shaders/block_cr.wgsl`, twin
//! `src/kernels/block_cr.rs`, code in [`crate::gpu::block_cr`]). [`LuForm::for_batch`] is
//! the one choice between them.

use std::collections::BTreeSet;

use crate::error::GpuError;
use crate::gpu::compose::compose;
use crate::gpu::contact::GpuReal;
use crate::gpu::dispatch::{run_passes, Out, WORKGROUP};
use crate::gpu::layout::LuDims;
use crate::gpu::GpuContext;
use crate::kernels::block_lu::ChainBatch;

/// Nodes per dispatch of the block solve: keeps every loop of an invocation far below
/// llvmpipe's 65,535-iteration cut-off (≈ 700 inner iterations per node).
pub const NODES_PER_PASS: usize = 32;

/// Invocations per variant of the lane form (`shaders/block_lu.wgsl`: six rows and two
/// idle lanes, eight variants per workgroup of 64).
pub const LANES: usize = 8;

/// The forms of the block solve: the serial walk (one invocation per variant) on CPU-type
/// adapters (lavapipe: its workgroup is one core's SIMD lanes, and barriers cost more than
/// the rows they split — 2× the time measured there); on GPUs the lane walk (a chain's node
/// costs six lanes a sixth of the time; 8 V invocations keep an H100's SMs busier than V) or
/// cyclic reduction (log₂ n levels instead of n steps), as [`LuForm::for_batch`] chooses.
/// [`force_lu_form`] overrides it for a process (tests run every form on lavapipe).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LuForm {
    /// One invocation per variant.
    Serial,
    /// [`LANES`] invocations per variant.
    Lanes,
    /// Block cyclic reduction (`shaders/block_cr.wgsl`, [`crate::gpu::block_cr`]): an
    /// invocation per (node, variant) of each level, `2⌈log₂ n⌉ + 1` dispatches.
    Cyclic,
}

impl LuForm {
    /// The form for `ctx`'s adapter (or the override), for a batch of any size: the chain
    /// walk (serial on a CPU-type adapter, lanes on a GPU). [`LuForm::for_batch`] is the
    /// engine's choice.
    pub fn for_adapter(ctx: &GpuContext) -> LuForm {
        match FORCED.load(std::sync::atomic::Ordering::Relaxed) {
            1 => LuForm::Serial,
            2 => LuForm::Lanes,
            3 => LuForm::Cyclic,
            _ if ctx.info.device_type == wgpu::DeviceType::Cpu => LuForm::Serial,
            _ => LuForm::Lanes,
        }
    }

    /// The form for a batch of `v` variants of an `n`-node chain on `ctx`'s adapter (or the
    /// override): on a GPU, cyclic reduction where the walk's `n` dependent steps leave the
    /// device idle ([`cyclic_pays`]), the lane walk where the reduction's larger traffic
    /// costs more than the latency it saves; the serial walk on a CPU-type adapter
    /// (lavapipe: variants are its parallelism, and the reduction's extra work and
    /// dispatches cost it 2×).
    pub fn for_batch(ctx: &GpuContext, n: usize, v: usize) -> LuForm {
        match Self::for_adapter(ctx) {
            LuForm::Lanes
                if FORCED.load(std::sync::atomic::Ordering::Relaxed) == 0 && cyclic_pays(n, v) =>
            {
                LuForm::Cyclic
            }
            form => form,
        }
    }

    /// The choice [`LuForm::for_batch`] makes on `ctx`, in words (the benchmarks' headers).
    pub fn describe(ctx: &GpuContext) -> String {
        match (
            FORCED.load(std::sync::atomic::Ordering::Relaxed),
            Self::for_adapter(ctx),
        ) {
            (0, LuForm::Lanes) => {
                "Cyclic from 32 nodes up to 2048 variants (4096 from 400 nodes), Lanes otherwise"
                    .into()
            }
            (0, form) => format!("{form:?}"),
            (_, form) => format!("{form:?} (forced)"),
        }
    }

    /// Invocations per variant of its widest dispatch on an `n`-node chain.
    pub fn widest(self, n: usize) -> usize {
        match self {
            LuForm::Serial => 1,
            LuForm::Lanes => LANES,
            LuForm::Cyclic => n,
        }
    }

    /// Entries per variant of the workspace buffers `(work_x, work_z)` on an `n`-node chain.
    pub fn workspace(self, n: usize) -> (usize, usize) {
        match self {
            LuForm::Serial | LuForm::Lanes => (36 * n.saturating_sub(1).max(1), 6 * n),
            LuForm::Cyclic => crate::gpu::block_cr::workspace(n),
        }
    }
}

/// Whether a GPU batch of `v` variants of an `n`-node chain solves by cyclic reduction
/// ([`LuForm::for_batch`]) rather than by the lane walk. The walk takes `n` dependent node
/// steps of 16–27 µs on an H100 whatever `v` is; the reduction takes `2⌈log₂ n⌉ + 1`
/// dispatches of 35–55 µs plus work that grows with `n · v` (2.3× the walk's FLOPs, and its
/// workspace read and written at every level). Measured there (stop 52; `bench ensemble
/// --lu-form lanes|cyclic`, the median run, and `bench kernels`, the block solve alone):
/// - n = 102: the reduction ahead at V = 16 (runs 0.068–0.083 s against 0.085–0.088 s,
///   f64), 256, 1024 and 2048 (f32 0.203–0.209 s against 0.219–0.230 s); behind at
///   V = 4096 (f64 0.763 s against 0.677–0.685 s; the solve alone 2.38 ms against 2.05 ms,
///   f32);
/// - n = 402: ahead at V = 256 (f32 0.255 s against 0.331 s) and 1024 (0.436 s against
///   0.548 s); the solve alone at V = 4096 4.97 ms against 8.04 ms (f32);
/// - n = 21 (`bench device --quick`'s kernels part): behind at V = 16 and 256 (the solve
///   alone 0.44–0.45 ms against 0.34 ms, f32): 11 dispatches cost more than 21 node steps.
///   By the two costs above the walk is ahead below about 32 nodes.
///
/// Beyond what was measured (V > 4096, or V > 2048 on short chains) the walk is kept.
pub fn cyclic_pays(n: usize, v: usize) -> bool {
    n >= 32 && (v <= 2048 || (n >= 400 && v <= 4096))
}

/// The forced form: 0 none, 1 serial, 2 lanes, 3 cyclic.
static FORCED: std::sync::atomic::AtomicU8 = std::sync::atomic::AtomicU8::new(0);

/// Makes every block solve of this process (kernels built from now on) use `form`, or the
/// adapter's choice again (`None`). For tests: the lane form on lavapipe.
pub fn force_lu_form(form: Option<LuForm>) {
    let code = match form {
        None => 0,
        Some(LuForm::Serial) => 1,
        Some(LuForm::Lanes) => 2,
        Some(LuForm::Cyclic) => 3,
    };
    FORCED.store(code, std::sync::atomic::Ordering::Relaxed);
}

/// Status a variant's solve starts with; still there afterwards means it did not finish.
const RUNNING: u32 = 2;

/// The WGSL text of the block solve at a precision, in a form.
pub fn block_lu_wgsl(f64: bool, form: LuForm) -> Result<String, GpuError> {
    let mut flags = BTreeSet::new();
    if f64 {
        flags.insert("F64");
    }
    if form == LuForm::Serial {
        flags.insert("SERIAL");
    }
    if form == LuForm::Cyclic {
        let text = compose("block_cr.wgsl", &flags, f64)?;
        return Ok(crate::gpu::block_cr::expand(&text));
    }
    let text = compose("block_lu.wgsl", &flags, f64)?;
    // The written-out walk is the same text every time: made once per process.
    static FORWARD: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    static LANES_FORWARD: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    Ok(text
        .replace("    //@FORWARD\n", FORWARD.get_or_init(serial_forward))
        .replace(
            "    //@LANES_FORWARD\n",
            LANES_FORWARD.get_or_init(lanes_forward),
        ))
}

/// The lane form's forward walk (see `shaders/block_lu.wgsl`), written out: this lane's row
/// of the augmented block as 13 scalars `w{c}` and the permutation of partial pivoting as six
/// scalars `pm{q}` (the same in every lane of a variant), every loop over the six columns and
/// thirteen entries unrolled. A lane's row indexed at run time (`row[col]`) is a private
/// array in memory on a GPU — local memory on NVIDIA; the first H100 run measured this form
/// at 2.6 ms for a 21-node chain (issue 27). The pivot column and row still pass through
/// workgroup memory, where indexing at run time costs nothing extra. The operations and
/// their order are the loop form's, so the results are the twin's bit for bit.
fn lanes_forward() -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let w = &mut s;
    let _ = writeln!(
        w,
        "    for (var i = dims.begin; i < dims.end; i = i + 1u) {{"
    );
    for c in 0..13 {
        let _ = writeln!(w, "        var w{c} = real(0.0);");
    }
    let _ = writeln!(w, "        if (live) {{");
    for c in 0..6 {
        let _ = writeln!(w, "            w{c} = diag[blk(i, 6u * r + {c}u, v)];");
    }
    let _ = writeln!(w, "            if (i + 1u < n) {{");
    for c in 0..6 {
        let _ = writeln!(
            w,
            "                w{} = upper[blk(i, 6u * r + {c}u, v)];",
            6 + c
        );
    }
    let _ = writeln!(w, "            }}");
    let _ = writeln!(w, "            w12 = rhs[vec_at(i, r, v)];");
    let _ = writeln!(w, "            if (i > 0u) {{");
    for k in 0..6 {
        let _ = writeln!(w, "                {{");
        let _ = writeln!(
            w,
            "                    let l = lower[blk(i - 1u, 6u * r + {k}u, v)];"
        );
        for c in 0..6 {
            let _ = writeln!(
                w,
                "                    w{c} = w{c} - l * px[36u * slot + {}u];",
                6 * k + c
            );
        }
        let _ = writeln!(
            w,
            "                    w12 = w12 - l * pz[6u * slot + {k}u];"
        );
        let _ = writeln!(w, "                }}");
    }
    let _ = writeln!(w, "            }}");
    let _ = writeln!(w, "        }}");
    for q in 0..6 {
        let _ = writeln!(w, "        var pm{q} = {q}u;");
    }
    let _ = writeln!(w, "        var bad = false;");
    for col in 0..6 {
        let _ = writeln!(w, "        workgroupBarrier();");
        let _ = writeln!(w, "        if (live) {{ pcol[6u * slot + r] = w{col}; }}");
        let _ = writeln!(w, "        workgroupBarrier();");
        let _ = writeln!(w, "        {{");
        let _ = writeln!(w, "            var piv = pm{col};");
        let _ = writeln!(w, "            if (live) {{");
        let _ = writeln!(w, "                var p = {col}u;");
        let _ = writeln!(
            w,
            "                var best = abs(pcol[6u * slot + pm{col}]);"
        );
        for q in col + 1..6 {
            let _ = writeln!(
                w,
                "                if (abs(pcol[6u * slot + pm{q}]) > best) {{ p = {q}u; best = abs(pcol[6u * slot + pm{q}]); }}"
            );
        }
        for q in col + 1..6 {
            let _ = writeln!(
                w,
                "                if (p == {q}u) {{ let t = pm{col}; pm{col} = pm{q}; pm{q} = t; }}"
            );
        }
        let _ = writeln!(w, "                piv = pm{col};");
        let _ = writeln!(w, "                let pivot = pcol[6u * slot + piv];");
        let _ = writeln!(w, "                if (bad_pivot(pivot)) {{ bad = true; }}");
        let _ = writeln!(w, "                if (r == piv) {{");
        let _ = writeln!(w, "                    let inv = real(1.0) / pivot;");
        for c in col..13 {
            let _ = writeln!(
                w,
                "                    w{c} = w{c} * inv; prow[13u * slot + {c}u] = w{c};"
            );
        }
        let _ = writeln!(w, "                }}");
        let _ = writeln!(w, "            }}");
        let _ = writeln!(w, "            workgroupBarrier();");
        let _ = writeln!(w, "            if (live && r != piv) {{");
        let _ = writeln!(w, "                let f = w{col};");
        for c in col..13 {
            let _ = writeln!(
                w,
                "                w{c} = w{c} - f * prow[13u * slot + {c}u];"
            );
        }
        let _ = writeln!(w, "            }}");
        let _ = writeln!(w, "        }}");
    }
    let _ = writeln!(w, "        if (live && bad) {{");
    let _ = writeln!(
        w,
        "            // Singular: the twin's zero solution, and the variant stops here."
    );
    let _ = writeln!(w, "            if (r == 0u) {{ status[v] = 1u; }}");
    let _ = writeln!(
        w,
        "            for (var k = r; k < 6u * n; k = k + 6u) {{ x[k * dims.num_variants + v] = real(0.0); }}"
    );
    let _ = writeln!(w, "            live = false;");
    let _ = writeln!(w, "        }}");
    let _ = writeln!(w, "        workgroupBarrier();");
    let _ = writeln!(w, "        if (live) {{");
    let _ = writeln!(w, "            // This lane's row is row q of X_i and z_i.");
    let _ = writeln!(w, "            var q = 0u;");
    for k in 0..6 {
        let _ = writeln!(w, "            if (pm{k} == r) {{ q = {k}u; }}");
    }
    for c in 0..6 {
        let _ = writeln!(
            w,
            "            px[36u * slot + 6u * q + {c}u] = w{};",
            6 + c
        );
    }
    let _ = writeln!(w, "            if (i + 1u < n) {{");
    for c in 0..6 {
        let _ = writeln!(
            w,
            "                work_x[blk(i, 6u * q + {c}u, v)] = w{};",
            6 + c
        );
    }
    let _ = writeln!(w, "            }}");
    let _ = writeln!(w, "            pz[6u * slot + q] = w12;");
    let _ = writeln!(w, "            work_z[vec_at(i, q, v)] = w12;");
    let _ = writeln!(w, "        }}");
    let _ = writeln!(w, "        workgroupBarrier();");
    let _ = writeln!(w, "    }}");
    s
}

/// The serial form's forward walk (see `shaders/block_lu.wgsl`), written out: the augmented
/// block `[G_i | U_i | y_i]` as 78 scalars `a{r}_{c}`, `X_{i−1}` and `z_{i−1}` as `px{k}`,
/// `pz{k}`, every loop over rows and columns unrolled, the row swap of partial pivoting a
/// branch per candidate row — no private array indexed at run time, so a compiler keeps them
/// in registers (issue 27; an indexed `array<real, 78>` lives in memory). The operations and
/// their order are the twin's ([`crate::kernels::block_lu::eliminate`]), so the results are.
fn serial_forward() -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let w = &mut s;
    for r in 0..6 {
        for c in 0..13 {
            let _ = writeln!(w, "    var a{r}_{c}: real;");
        }
    }
    for k in 0..36 {
        let _ = writeln!(w, "    var px{k}: real;");
    }
    for k in 0..6 {
        let _ = writeln!(w, "    var pz{k}: real;");
    }
    let _ = writeln!(w, "    if (dims.begin > 0u) {{");
    for k in 0..36 {
        let _ = writeln!(w, "        px{k} = work_x[blk(dims.begin - 1u, {k}u, v)];");
    }
    for k in 0..6 {
        let _ = writeln!(
            w,
            "        pz{k} = work_z[vec_at(dims.begin - 1u, {k}u, v)];"
        );
    }
    let _ = writeln!(w, "    }}");
    let _ = writeln!(
        w,
        "    for (var i = dims.begin; i < dims.end; i = i + 1u) {{"
    );
    let _ = writeln!(w, "        let has_up = i + 1u < n;");
    for r in 0..6 {
        for c in 0..6 {
            let _ = writeln!(w, "        a{r}_{c} = diag[blk(i, {}u, v)];", 6 * r + c);
        }
        let _ = writeln!(w, "        if (has_up) {{");
        for c in 0..6 {
            let _ = writeln!(
                w,
                "            a{r}_{} = upper[blk(i, {}u, v)];",
                6 + c,
                6 * r + c
            );
        }
        let _ = writeln!(w, "        }} else {{");
        for c in 0..6 {
            let _ = writeln!(w, "            a{r}_{} = real(0.0);", 6 + c);
        }
        let _ = writeln!(w, "        }}");
        let _ = writeln!(w, "        a{r}_12 = rhs[vec_at(i, {r}u, v)];");
        let _ = writeln!(w, "        if (i > 0u) {{");
        for k in 0..6 {
            let _ = writeln!(w, "            {{");
            let _ = writeln!(
                w,
                "                let l = lower[blk(i - 1u, {}u, v)];",
                6 * r + k
            );
            for c in 0..6 {
                let _ = writeln!(
                    w,
                    "                a{r}_{c} = a{r}_{c} - l * px{};",
                    6 * k + c
                );
            }
            let _ = writeln!(w, "                a{r}_12 = a{r}_12 - l * pz{k};");
            let _ = writeln!(w, "            }}");
        }
        let _ = writeln!(w, "        }}");
    }
    // Gauss–Jordan with partial pivoting on the 6 × 13 block.
    for col in 0..6 {
        let _ = writeln!(w, "        {{");
        let _ = writeln!(w, "            var p = {col}u;");
        let _ = writeln!(w, "            var best = abs(a{col}_{col});");
        for r in col + 1..6 {
            let _ = writeln!(
                w,
                "            if (abs(a{r}_{col}) > best) {{ p = {r}u; best = abs(a{r}_{col}); }}"
            );
        }
        for r in col + 1..6 {
            let _ = writeln!(w, "            if (p == {r}u) {{");
            for c in 0..13 {
                let _ = writeln!(
                    w,
                    "                {{ let t = a{col}_{c}; a{col}_{c} = a{r}_{c}; a{r}_{c} = t; }}"
                );
            }
            let _ = writeln!(w, "            }}");
        }
        let _ = writeln!(w, "            let pivot = a{col}_{col};");
        let _ = writeln!(w, "            if (bad_pivot(pivot)) {{");
        let _ = writeln!(w, "                status[v] = 1u;");
        let _ = writeln!(
            w,
            "                for (var k = 0u; k < 6u * n; k = k + 1u) {{ x[k * dims.num_variants + v] = real(0.0); }}"
        );
        let _ = writeln!(w, "                return;");
        let _ = writeln!(w, "            }}");
        let _ = writeln!(w, "            let inv = real(1.0) / pivot;");
        for c in col..13 {
            let _ = writeln!(w, "            a{col}_{c} = a{col}_{c} * inv;");
        }
        for r in (0..6).filter(|&r| r != col) {
            let _ = writeln!(w, "            {{");
            let _ = writeln!(w, "                let f = a{r}_{col};");
            for c in col..13 {
                let _ = writeln!(w, "                a{r}_{c} = a{r}_{c} - f * a{col}_{c};");
            }
            let _ = writeln!(w, "            }}");
        }
        let _ = writeln!(w, "        }}");
    }
    for r in 0..6 {
        for c in 0..6 {
            let _ = writeln!(w, "        px{} = a{r}_{};", 6 * r + c, 6 + c);
        }
        let _ = writeln!(w, "        if (has_up) {{");
        for c in 0..6 {
            let _ = writeln!(
                w,
                "            work_x[blk(i, {}u, v)] = a{r}_{};",
                6 * r + c,
                6 + c
            );
        }
        let _ = writeln!(w, "        }}");
        let _ = writeln!(w, "        pz{r} = a{r}_12;");
        let _ = writeln!(w, "        work_z[vec_at(i, {r}u, v)] = a{r}_12;");
    }
    let _ = writeln!(w, "    }}");
    s
}

/// Bytes per variant on the GPU for a chain of `n` nodes at `size`-byte floats: the
/// matrix (3 block rows), right-hand side, factor workspace, solution and status.
pub fn bytes_per_variant(n: usize, size: usize) -> usize {
    let m = n.saturating_sub(1);
    size * (36 * n + 2 * 36 * m + 6 * n + 36 * m + 6 * n + 6 * n) + 4
}

/// The passes of the block solve of an `n`-node chain, `(begin, end, phase)`: forward
/// elimination from the top in passes of at most [`NODES_PER_PASS`] nodes, then back
/// substitution from the bit (see the shader: llvmpipe's loop limit).
pub fn passes(n: usize) -> Vec<(usize, usize, u32)> {
    let mut passes = Vec::new();
    let mut begin = 0;
    while begin < n {
        let end = (begin + NODES_PER_PASS).min(n);
        passes.push((begin, end, 0u32));
        begin = end;
    }
    let mut end = n;
    while end > 0 {
        let begin = end.saturating_sub(NODES_PER_PASS);
        passes.push((begin, end, 1u32));
        end = begin;
    }
    passes
}

/// Every dispatch of the block solve of an `n`-node chain in `form` for `v` variants: its
/// parameter block and its invocations ([`passes`]; the cyclic form's
/// [`crate::gpu::block_cr::passes`], whose `begin` is the level's stride and `end` the
/// nodes of the dispatch).
pub fn plan(form: LuForm, n: usize, v: usize) -> Vec<(LuDims, usize)> {
    let dims = |begin: usize, end: usize, phase: u32| LuDims {
        num_variants: v as u32,
        num_nodes: n as u32,
        begin: begin as u32,
        end: end as u32,
        phase,
        _pad0: 0,
        _pad1: 0,
        _pad2: 0,
    };
    match form {
        LuForm::Cyclic => crate::gpu::block_cr::passes(n)
            .into_iter()
            .map(|(stride, nodes, phase)| (dims(stride, nodes, phase), nodes * v))
            .collect(),
        _ => passes(n)
            .into_iter()
            .map(|(begin, end, phase)| (dims(begin, end, phase), form.widest(n) * v))
            .collect(),
    }
}

/// Solves every variant of `batch` on the GPU. Returns the field-major solution and a
/// status per variant, as [`crate::kernels::block_lu::block_lu`].
pub fn block_lu_gpu<T: GpuReal>(
    ctx: &'static GpuContext,
    batch: &ChainBatch<T>,
) -> Result<(Vec<T>, Vec<u32>), GpuError> {
    block_lu_gpu_chunked(ctx, batch, usize::MAX)
}

/// As [`block_lu_gpu`] with at most `max_chunk` variants per dispatch (tests).
pub fn block_lu_gpu_chunked<T: GpuReal>(
    ctx: &'static GpuContext,
    batch: &ChainBatch<T>,
    max_chunk: usize,
) -> Result<(Vec<T>, Vec<u32>), GpuError> {
    let form = LuForm::for_batch(ctx, batch.num_nodes, batch.num_variants.min(max_chunk));
    block_lu_gpu_form(ctx, batch, max_chunk, form)
}

/// As [`block_lu_gpu_chunked`] in a given form (tests: every form on any adapter).
pub fn block_lu_gpu_form<T: GpuReal>(
    ctx: &'static GpuContext,
    batch: &ChainBatch<T>,
    max_chunk: usize,
    form: LuForm,
) -> Result<(Vec<T>, Vec<u32>), GpuError> {
    crate::gpu::contact::require_precision::<T>(ctx)?;
    let wgsl = block_lu_wgsl(T::IS_F64, form)?;
    let pipeline = ctx.pipeline("block_lu", &wgsl)?;
    let size = std::mem::size_of::<T>();
    let (n, v) = (batch.num_nodes, batch.num_variants);
    let m = n.saturating_sub(1);
    let max_binding = ctx.max_binding_bytes() as usize;
    // The largest array per variant: a 36-float block field over n nodes, or the workspace.
    let (work_x, work_z) = form.workspace(n);
    let cap = (max_binding / ((36 * n).max(work_x).max(1) * size))
        .min(
            ctx.limits.max_compute_workgroups_per_dimension as usize * WORKGROUP
                / form.widest(n).max(1),
        )
        .min(max_chunk)
        .max(1);
    let mut x = vec![T::zero(); 6 * n * v];
    let mut status = vec![0u32; v];
    let mut offset = 0;
    while offset < v {
        let len = cap.min(v - offset);
        let gather = |data: &[T], rows: usize| -> Vec<T> {
            let mut out = Vec::with_capacity(rows * len.max(1));
            for k in 0..rows {
                out.extend_from_slice(&data[k * v + offset..k * v + offset + len]);
            }
            if out.is_empty() {
                out.push(T::zero());
            }
            out
        };
        let params = plan(form, n, len);
        let param_bytes: Vec<&[u8]> = params.iter().map(|(d, _)| bytemuck::bytes_of(d)).collect();
        let invocations: Vec<usize> = params.iter().map(|&(_, k)| k).collect();
        let (diag, upper, lower, rhs) = (
            gather(&batch.diag, 36 * n),
            gather(&batch.upper, 36 * m),
            gather(&batch.lower, 36 * m),
            gather(&batch.rhs, 6 * n),
        );
        let x_bytes = 6 * n * len * size;
        let running = vec![RUNNING; len];
        let out = run_passes(
            ctx,
            &pipeline,
            "block_lu",
            &param_bytes,
            &[
                bytemuck::cast_slice(&diag),
                bytemuck::cast_slice(&upper),
                bytemuck::cast_slice(&lower),
                bytemuck::cast_slice(&rhs),
            ],
            &[
                Out::Empty(work_x * len * size),
                Out::Empty(work_z * len * size),
                Out::Empty(x_bytes),
                Out::From(bytemuck::cast_slice(&running)),
            ],
            &invocations,
        )?;
        let xs: Vec<T> = crate::gpu::readback::values(&out[2]);
        let st: Vec<u32> = crate::gpu::readback::values(&out[3]);
        for k in 0..6 * n {
            x[k * v + offset..k * v + offset + len].copy_from_slice(&xs[k * len..(k + 1) * len]);
        }
        if st[..len].contains(&RUNNING) {
            return Err(GpuError::Device(
                "block solve: a dispatch did not complete (status left at running)".into(),
            ));
        }
        status[offset..offset + len].copy_from_slice(&st[..len]);
        offset += len;
    }
    Ok((x, status))
}
