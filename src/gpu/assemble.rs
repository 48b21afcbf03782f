//! Runs `shaders/assemble.wgsl` (twin: `src/kernels/assemble.rs`).

use crate::error::GpuError;
use crate::gpu::compose::compose_if;
use crate::gpu::contact::GpuReal;
use crate::gpu::dispatch::{run_once, Out};
use crate::gpu::layout::AssembleDims;
use crate::gpu::GpuContext;
use crate::kernels::assemble::AssemblyInputs;
use crate::kernels::block_lu::ChainBatch;

/// The WGSL text of the static assembly at a precision.
pub fn assemble_wgsl(f64: bool) -> Result<String, GpuError> {
    assemble_wgsl_for(false, f64)
}

/// The WGSL text of the static or dynamic assembly at a precision.
pub fn assemble_wgsl_for(dynamic: bool, f64: bool) -> Result<String, GpuError> {
    assemble_wgsl_with(dynamic, false, f64)
}

/// The WGSL text of the assembly: static or dynamic, with (`unbalance`, dynamic only) the
/// mass-imbalance binding and terms, at a precision.
pub fn assemble_wgsl_with(dynamic: bool, unbalance: bool, f64: bool) -> Result<String, GpuError> {
    compose_if(
        "assemble.wgsl",
        &[("UNBALANCE", dynamic && unbalance), ("DYNAMIC", dynamic)],
        f64,
    )
}

/// The WGSL text of the dynamic assembly (system and residual) built `MASKED`: the listed
/// variants `[A, v_0, …]` alone (bound after the outputs), one invocation per (node, listed
/// variant); with `unbalance` the mass-imbalance terms.
pub fn assemble_dynamic_masked_wgsl(unbalance: bool, f64: bool) -> Result<String, GpuError> {
    compose_if(
        "assemble.wgsl",
        &[
            ("UNBALANCE", unbalance),
            ("DYNAMIC", true),
            ("MASKED", true),
        ],
        f64,
    )
}

/// The WGSL text of the static assembly built `FORCE_ONLY` (the residual alone, for the
/// line-search trials; twin: [`crate::kernels::assemble::assemble_residual`]).
/// `masked`: one invocation per (node, listed variant) of the compacted list of searching
/// variants `[A, v_0, …]` (binding 9); the others are skipped.
pub fn assemble_force_wgsl(f64: bool, masked: bool) -> Result<String, GpuError> {
    assemble_force_wgsl_with(false, false, f64, masked)
}

/// The WGSL text of the assembly built `FORCE_ONLY`, static or (`dynamic`, with
/// `unbalance` the mass-imbalance terms) dynamic: the residual alone (twin:
/// [`crate::kernels::assemble::assemble_residual`]), the same sums in the same order as the
/// full kernel's. The dynamic inputs (`dyn_coef`, mass, inertia, rotations, velocities,
/// accelerations, imbalance) are bound after the output (and the list, `masked`).
pub fn assemble_force_wgsl_with(
    dynamic: bool,
    unbalance: bool,
    f64: bool,
    masked: bool,
) -> Result<String, GpuError> {
    compose_if(
        "assemble.wgsl",
        &[
            ("FORCE_ONLY", true),
            ("MASKED", masked),
            ("DYNAMIC", dynamic),
            ("UNBALANCE", dynamic && unbalance),
        ],
        f64,
    )
}

/// The WGSL text of the static assembly built `SHIFT` (a relaxation's proximal shift,
/// [`crate::kernels::assemble::ShiftInputs`]; its bindings `shift`, `anchor`, `x`,
/// `rot_shift`, `anchor_rot`, `rot` last):
/// `force_only` the residual alone, `masked` as [`assemble_force_wgsl`].
pub fn assemble_shift_wgsl(f64: bool, force_only: bool, masked: bool) -> Result<String, GpuError> {
    compose_if(
        "assemble.wgsl",
        &[
            ("FORCE_ONLY", force_only),
            ("MASKED", force_only && masked),
            ("SHIFT", true),
        ],
        f64,
    )
}

/// The shift's inputs of `a` (`shift`, `anchor`, `x`, `rot_shift`, `anchor_rot`, `rot`),
/// empty without one: bound after the kernel's outputs, so passed as outputs that start
/// with them (the kernel only reads them). Where no rotation is shifted (`rot_shift`
/// empty), `rot_shift` is a fresh buffer (wgpu zeroes it) and the rotations, then unread,
/// one node's worth.
pub fn shift_bindings<T: GpuReal>(a: &AssemblyInputs<T>) -> Vec<Out<'_>> {
    a.shift
        .iter()
        .flat_map(|sh| {
            fn bytes<T: GpuReal>(x: &[T], or: usize) -> Out<'_> {
                if x.is_empty() {
                    Out::Empty(or * std::mem::size_of::<T>())
                } else {
                    Out::From(bytemuck::cast_slice(x))
                }
            }
            [
                Out::From(bytemuck::cast_slice(&sh.shift)),
                Out::From(bytemuck::cast_slice(&sh.anchor)),
                Out::From(bytemuck::cast_slice(&sh.x)),
                bytes(&sh.rot_shift, a.num_variants),
                bytes(&sh.anchor_rot, 9),
                bytes(&sh.rot, 9),
            ]
        })
        .collect()
}

/// The dimensions and the static inputs (bindings 1–8, or 1–7 without the tangents) of
/// the assembly of `a`.
pub fn static_bindings<T: GpuReal>(
    a: &AssemblyInputs<T>,
    tangent: bool,
) -> (AssembleDims, Vec<&[u8]>) {
    let dims = AssembleDims {
        num_variants: a.num_variants as u32,
        num_nodes: a.num_nodes as u32,
        num_sites: a.num_sites as u32,
        _pad: 0,
    };
    let mut inputs: Vec<&[u8]> = vec![bytemuck::cast_slice(&a.elem_force)];
    if tangent {
        inputs.push(bytemuck::cast_slice(&a.elem_tangent));
    }
    inputs.extend([
        bytemuck::cast_slice(&a.contact),
        bytemuck::cast_slice(&a.contact_flag),
        bytemuck::cast_slice(&a.node_site),
        bytemuck::cast_slice(&a.f_ext),
        bytemuck::cast_slice(&a.basis),
        bytemuck::cast_slice(&a.fixed),
    ]);
    (dims, inputs)
}

/// Assembles every variant on the GPU; the result is laid out as the twin's.
pub fn assemble_gpu<T: GpuReal>(
    ctx: &'static GpuContext,
    a: &AssemblyInputs<T>,
) -> Result<ChainBatch<T>, GpuError> {
    crate::gpu::contact::require_precision::<T>(ctx)?;
    let (n, nv) = (a.num_nodes, a.num_variants);
    let m = n.saturating_sub(1);
    let size = std::mem::size_of::<T>();
    let largest = [a.elem_tangent.len() * size, a.contact.len() * size]
        .into_iter()
        .max()
        .unwrap_or(0);
    if largest as u64 > ctx.max_binding_bytes() {
        return Err(GpuError::Unsupported(format!(
            "{largest} bytes in one binding exceed the adapter's {}; split the variants",
            ctx.max_binding_bytes()
        )));
    }
    let unbalance = a.dynamic.as_ref().is_some_and(|d| !d.unbalance.is_empty());
    let wgsl = match (&a.dynamic, &a.shift) {
        (Some(_), Some(_)) => {
            return Err(GpuError::Unsupported(
                "the proximal shift is static only".into(),
            ))
        }
        (None, Some(_)) => assemble_shift_wgsl(T::IS_F64, false, false)?,
        _ => assemble_wgsl_with(a.dynamic.is_some(), unbalance, T::IS_F64)?,
    };
    let pipeline = ctx.pipeline("assemble", &wgsl)?;
    let (dims, mut inputs) = static_bindings(a, true);
    if let Some(dy) = &a.dynamic {
        inputs.extend([
            bytemuck::cast_slice(&dy.coefficients[..]),
            bytemuck::cast_slice(&dy.mass),
            bytemuck::cast_slice(&dy.inertia0),
            bytemuck::cast_slice(&dy.rot),
            bytemuck::cast_slice(&dy.vel),
            bytemuck::cast_slice(&dy.vdot),
            bytemuck::cast_slice(&dy.pair_normals),
        ]);
        if unbalance {
            inputs.push(bytemuck::cast_slice(&dy.unbalance));
        }
    }
    let mut outputs = vec![
        Out::Empty(36 * n * nv * size),
        Out::Empty(36 * m * nv * size),
        Out::Empty(36 * m * nv * size),
        Out::Empty(6 * n * nv * size),
    ];
    outputs.extend(shift_bindings(a));
    let out = run_once(
        ctx,
        &pipeline,
        "assemble",
        bytemuck::bytes_of(&dims),
        &inputs,
        &outputs,
        n * nv,
    )?;
    let cast = |b: &Vec<u8>| -> Vec<T> { bytemuck::cast_slice(b).to_vec() };
    Ok(ChainBatch {
        num_variants: nv,
        num_nodes: n,
        diag: cast(&out[0]),
        upper: cast(&out[1]),
        lower: cast(&out[2]),
        rhs: cast(&out[3]),
    })
}
