//! A batch of variants resident on the GPU for the ensemble Newton iteration
//! ([`crate::engine`]): every buffer and bind group is made once, when the batch is opened;
//! an iteration records the kernels (beam → sites → contact → assembly → block LU → norms,
//! then update → … for a trial) into command buffers, and the host reads back only the
//! four norms and the solve status per variant ([`Norms`]), and writes one α per variant.
//!
//! Two configuration slots (current and trial) each with their assembled system: a trial
//! the line search accepts becomes the current one by swapping slots, without evaluating
//! again.

use std::marker::PhantomData;
use std::sync::Arc;

use wgpu::util::DeviceExt;

use crate::engine::Stage;
use crate::engine::{BatchTables, ResidentStatic, Shift};
use crate::error::GpuError;
use crate::gpu::block_lu::LuForm;
use crate::gpu::contact::{require_precision, GpuReal};
use crate::gpu::dispatch::WORKGROUP;
use crate::gpu::kernel::Kernel;
use crate::gpu::layout::{AssembleDims, BeamDims, ChainDims, ContactDims};
use crate::gpu::readback::values;
use crate::gpu::GpuContext;
use crate::kernels::beam::TANGENT_LEN;
use crate::kernels::contact::{OUTPUT_LEN, STATE_LEN};
use crate::kernels::update::{ConfigBatch, Norms};
use crate::model::Model;
use crate::physics::contact::PARAMS_LEN;

mod common;
mod dynamic;
mod iteration;
use common::Common;
pub use dynamic::GpuDynamic;
pub use iteration::{sites_trial_wgsl, sites_wgsl, sites_wgsl_for};

/// Status the block solve starts with; still there afterwards means it did not finish.
const RUNNING: u32 = 2;
use crate::kernels::block_lu::SINGULAR;

/// Bytes per variant of every buffer of a batch, for a chain of `n` nodes with `s` sites
/// at `size`-byte floats: two configurations and two assembled systems, the base and its
/// chords, element forces and tangents, contact inputs and outputs (all
/// [`OUTPUT_LEN`] fields: the dynamic engine's; a static batch holds
/// [`crate::kernels::contact::output_fields`]), loads, the factorisation workspace, the
/// step, and the per-variant scalars. (The shared tables — translation bases, sections,
/// frames — are per batch.)
pub fn bytes_per_variant(n: usize, s: usize, size: usize) -> usize {
    let m = n.saturating_sub(1);
    let reals = 2 * 12 * n            // x, rot: two slots
        + 4 * m                       // base chords and stretches
        + 12 * m + TANGENT_LEN * m    // element force, tangent
        + (OUTPUT_LEN + STATE_LEN + PARAMS_LEN + 6) * s // contact out, state, params, normals, base
        + 6 * n                       // loads
        + 2 * (36 * n + 72 * m + 6 * n) // two systems
        + 36 * m + 6 * n + 6 * n      // LU workspace, y, Δ
        + 4 + 1; // norms, α
    size * reals + 4 * (n + 2 * s + 1) // node_site, pair_node, contact flags, status
}

/// The largest per-variant array of one binding, in bytes: the element tangents.
/// (The block solve's workspace in its largest form: the form depends on the batch's size.)
fn largest_binding_per_variant(n: usize, s: usize, size: usize) -> usize {
    let m = n.saturating_sub(1);
    size * (TANGENT_LEN * m)
        .max(36 * n)
        .max(OUTPUT_LEN * s)
        .max(LuForm::Cyclic.workspace(n).0)
}

/// The most variants of `model` one batch may hold on `ctx`: every binding within the
/// adapter's limit, every dispatch within its workgroup count.
pub fn max_variants(ctx: &GpuContext, model: &Model, size: usize) -> usize {
    let n = model.nodes.len();
    let s = model.sites.len();
    let by_binding = ctx.max_binding_bytes() as usize / largest_binding_per_variant(n, s, size);
    // Every form's widest dispatch is at most n invocations a variant.
    let widest = n.max(s).max(LuForm::Lanes.widest(n));
    let by_groups = ctx.limits.max_compute_workgroups_per_dimension as usize * WORKGROUP / widest;
    by_binding.min(by_groups).max(1)
}

struct Slot {
    x: wgpu::Buffer,
    rot: wgpu::Buffer,
    beam: wgpu::BindGroup,
    /// The trials' beam kernel (force only, masked).
    beam_force: wgpu::BindGroup,
    sites: wgpu::BindGroup,
    /// The trials' sites gather (masked).
    sites_trial: wgpu::BindGroup,
    assemble: wgpu::BindGroup,
    /// The residual-only assembly's group (trials).
    assemble_force: wgpu::BindGroup,
    lu: Vec<wgpu::BindGroup>,
    norms_solve: wgpu::BindGroup,
    norms_trial: wgpu::BindGroup,
    update: wgpu::BindGroup,
    /// A trial into this slot from the other: every variant moved (the search's first).
    update_trial_all: wgpu::BindGroup,
    /// A trial into this slot from the other: the searching variants alone.
    update_trial: wgpu::BindGroup,
    /// The assembled system: diag, upper, lower, rhs.
    system: [wgpu::Buffer; 4],
}

/// A relaxation's proximal shift on the GPU, made when a batch first relaxes: the
/// assembly built `SHIFT` (full and trial forms), the shifts per variant and the anchors
/// (translations', rotations'), and each slot's bind groups of those kernels.
struct ShiftParts {
    assemble: Arc<wgpu::ComputePipeline>,
    assemble_force: Arc<wgpu::ComputePipeline>,
    shift: wgpu::Buffer,
    anchor: wgpu::Buffer,
    rot_shift: wgpu::Buffer,
    anchor_rot: wgpu::Buffer,
    /// `rot_shift` holds a rotations' shift (else zeros: a fresh buffer, or cleared).
    rotations: bool,
    /// Per slot: the full assembly's group and the trials'.
    groups: [(wgpu::BindGroup, wgpu::BindGroup); 2],
}

struct Pipelines {
    beam: Arc<wgpu::ComputePipeline>,
    /// The beam kernel built `FORCE_ONLY` and `MASKED` (line-search trials).
    beam_force: Arc<wgpu::ComputePipeline>,
    sites: Arc<wgpu::ComputePipeline>,
    /// The sites gather built `MASKED` (trials).
    sites_trial: Arc<wgpu::ComputePipeline>,
    contact: Arc<wgpu::ComputePipeline>,
    /// The contact kernel built `FORCE_ONLY` and `MASKED` (line-search trials: `g` alone).
    contact_force: Arc<wgpu::ComputePipeline>,
    assemble: Arc<wgpu::ComputePipeline>,
    /// The assembly built `FORCE_ONLY` and `MASKED` (line-search trials: the residual alone).
    assemble_force: Arc<wgpu::ComputePipeline>,
    block_lu: Arc<wgpu::ComputePipeline>,
    norms: Arc<wgpu::ComputePipeline>,
    /// The norms built `MASKED` (trials).
    norms_trial: Arc<wgpu::ComputePipeline>,
    update: Arc<wgpu::ComputePipeline>,
    /// The update built `OUT_OF_PLACE` and `MASKED` (trials: from one slot into the other).
    update_trial: Arc<wgpu::ComputePipeline>,
}

/// A batch of variants on the GPU (see the module docs).
pub struct GpuStatic<T: GpuReal> {
    ctx: &'static GpuContext,
    p: Pipelines,
    slots: [Slot; 2],
    /// Whether each slot's assembled system has its tangent (a trial's has its residual only).
    formed: [bool; 2],
    current: usize,
    contact: wgpu::BindGroup,
    contact_force: wgpu::BindGroup,
    c: Common,
    num_variants: usize,
    num_nodes: usize,
    num_pairs: usize,
    /// A relaxation's shift (made at the first); `shifted`: the assembly runs with it.
    shift: Option<ShiftParts>,
    shifted: bool,
    /// The solve's norms, kept while the trial formed with it writes its own.
    solve_norms: wgpu::Buffer,
    /// Line-search trials formed in one submission ([`Rounds`]).
    rounds: Rounds,
    /// Each variant's landing epoch ([`crate::kernels::update::UpdateWalls::epoch`]).
    epoch: wgpu::Buffer,
    _real: PhantomData<T>,
}

fn storage<T: bytemuck::Pod>(ctx: &GpuContext, label: &str, data: &[T]) -> wgpu::Buffer {
    let bytes: &[u8] = bytemuck::cast_slice(data);
    // Bindings may not be empty: pad to one 16-byte word.
    let padded: Vec<u8>;
    let contents = if bytes.len() < 16 {
        padded = bytes
            .iter()
            .copied()
            .chain(std::iter::repeat(0))
            .take(16)
            .collect();
        &padded[..]
    } else {
        bytes
    };
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
        })
}

fn empty(ctx: &GpuContext, label: &str, bytes: usize) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes.max(16) as u64,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    })
}

/// The block-tridiagonal system of `v` variants of `n` nodes, as the static and the dynamic
/// batch hold it: diagonal, upper and lower 6×6 blocks and the right-hand side.
fn system_buffers(ctx: &GpuContext, v: usize, n: usize, size: usize) -> [wgpu::Buffer; 4] {
    let m = n.saturating_sub(1).max(1);
    [
        empty(ctx, "diag", 36 * n * v * size),
        empty(ctx, "upper", 36 * m * v * size),
        empty(ctx, "lower", 36 * m * v * size),
        empty(ctx, "rhs", 6 * n * v * size),
    ]
}

/// A kernel's parameter block (binding 0): read-only storage, not a uniform, which lavapipe
/// would inline and recompile the kernel for at every dispatch (see `tests/shaders.rs`).
fn param_block<U: bytemuck::Pod>(ctx: &GpuContext, label: &str, u: &U) -> wgpu::Buffer {
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::bytes_of(u),
            usage: wgpu::BufferUsages::STORAGE,
        })
}

/// A bind group with `buffers` at bindings 0, 1, … in order (the batches', and the
/// one-shot runners' of the tests).
pub fn bind(
    ctx: &GpuContext,
    pipeline: &wgpu::ComputePipeline,
    label: &str,
    buffers: &[&wgpu::Buffer],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = buffers
        .iter()
        .enumerate()
        .map(|(k, b)| wgpu::BindGroupEntry {
            binding: k as u32,
            resource: b.as_entire_binding(),
        })
        .collect();
    ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    })
}

/// Records `pipeline` on `group` for `invocations` invocations (none: nothing).
pub fn dispatch(
    pass: &mut wgpu::ComputePass,
    pipeline: &wgpu::ComputePipeline,
    group: &wgpu::BindGroup,
    invocations: usize,
) {
    if invocations == 0 {
        return;
    }
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, group, &[]);
    pass.dispatch_workgroups(invocations.div_ceil(WORKGROUP) as u32, 1, 1);
}

impl<T: GpuReal> GpuStatic<T> {
    /// Compiles (or fetches) the kernels for the batch's terms and precision and uploads
    /// its tables and start configuration.
    pub fn new(
        ctx: &'static GpuContext,
        model: &Model,
        tables: &BatchTables<T>,
    ) -> Result<Self, GpuError> {
        let f64 = T::IS_F64;
        let kink = !tables.rest.is_empty();
        let (v, n) = (tables.num_variants, tables.num_nodes);
        let p = tables.pair_node.len();
        let size = std::mem::size_of::<T>();
        let c = Common::new(ctx, model, tables, None, None)?;
        let k = |kernel: Kernel| kernel.pipeline(ctx, f64);
        let pipelines = Pipelines {
            beam: k(Kernel::Beam { kink })?,
            beam_force: k(Kernel::BeamTrial { kink })?,
            sites: k(Kernel::Sites { dynamic: false })?,
            sites_trial: k(Kernel::SitesTrial { dynamic: false })?,
            contact: k(Kernel::Contact(&tables.terms))?,
            contact_force: k(Kernel::ContactTrial(&tables.terms))?,
            assemble: k(Kernel::Assemble {
                dynamic: false,
                unbalance: false,
            })?,
            assemble_force: k(Kernel::AssembleTrial {
                dynamic: false,
                unbalance: false,
            })?,
            block_lu: k(Kernel::BlockLu(c.lu_form))?,
            norms: k(Kernel::Norms { trial: false })?,
            norms_trial: k(Kernel::Norms { trial: true })?,
            update: k(Kernel::Update { trial: false })?,
            update_trial: k(Kernel::Update { trial: true })?,
        };
        let contact = c.contact_group(ctx, &pipelines.contact, false);
        let contact_force = c.contact_group(ctx, &pipelines.contact_force, true);
        let configs = ["config_a", "config_b"].map(|label| {
            (
                storage(ctx, label, &tables.start.x),
                storage(ctx, label, &tables.start.rot),
                storage(ctx, label, &vec![0u32; n * v]),
            )
        });
        // No landing until the engine sets the epochs (`set_landing_epochs`).
        let epoch = storage(ctx, "epoch", &vec![0u32; v]);
        let make_slot = |k: usize| -> Slot {
            let (x, rot, landed) = configs[k].clone();
            let (x_from, rot_from, landed_from) = &configs[1 - k];
            let [diag, upper, lower, rhs] = system_buffers(ctx, v, n, size);
            let beam = c.beam_group(ctx, &pipelines.beam, &x, &rot, false, false);
            let beam_force = c.beam_group(ctx, &pipelines.beam_force, &x, &rot, true, true);
            let sites = bind(
                ctx,
                &pipelines.sites,
                "sites",
                &[&c.sites_dims, &c.pair_node, &x, &c.pair_base, &c.pair_state],
            );
            let sites_trial = bind(
                ctx,
                &pipelines.sites_trial,
                "sites_trial",
                &[
                    &c.sites_dims,
                    &c.pair_node,
                    &x,
                    &c.pair_base,
                    &c.pair_state,
                    &c.active,
                ],
            );
            let inputs = c.assembly_inputs(true);
            let assemble = bind(
                ctx,
                &pipelines.assemble,
                "assemble",
                &[&inputs[..], &[&diag, &upper, &lower, &rhs]].concat(),
            );
            let assemble_force = bind(
                ctx,
                &pipelines.assemble_force,
                "assemble_force",
                &[&c.assembly_inputs(false)[..], &[&rhs, &c.active]].concat(),
            );
            let lu = c.lu_groups(ctx, &pipelines.block_lu, [&diag, &upper, &lower, &rhs]);
            let norms_solve = c.norms_group(ctx, &pipelines.norms, &c.ones, &rhs, false);
            let norms_trial = c.norms_group(ctx, &pipelines.norms_trial, &c.alpha, &rhs, true);
            let walls = [
                &c.chain_dims,
                &c.delta,
                &c.alpha,
                &c.basis,
                &c.node_site,
                &c.pair_base,
                &c.normals,
                &c.params,
            ];
            let update = bind(
                ctx,
                &pipelines.update,
                "update",
                &[&walls[..], &[&x, &rot, &landed, &epoch]].concat(),
            );
            let trial_update = |mask: &wgpu::Buffer| {
                bind(
                    ctx,
                    &pipelines.update_trial,
                    "update_trial",
                    &[
                        &walls[..],
                        &[
                            x_from,
                            rot_from,
                            &x,
                            &rot,
                            landed_from,
                            &landed,
                            &epoch,
                            mask,
                        ],
                    ]
                    .concat(),
                )
            };
            let update_trial_all = trial_update(&c.all_active);
            let update_trial = trial_update(&c.active);
            Slot {
                x,
                rot,
                beam,
                beam_force,
                sites,
                sites_trial,
                assemble,
                assemble_force,
                lu,
                norms_solve,
                norms_trial,
                update,
                update_trial_all,
                update_trial,
                system: [diag, upper, lower, rhs],
            }
        };
        let slots = [make_slot(0), make_slot(1)];
        Ok(GpuStatic {
            epoch,
            solve_norms: empty(ctx, "solve_norms", 4 * v * size),
            rounds: Rounds::new(ctx, v, size),
            ctx,
            p: pipelines,
            slots,
            formed: [false; 2],
            current: 0,
            contact,
            contact_force,
            c,
            num_variants: v,
            num_nodes: n,
            num_pairs: p,
            shift: None,
            shifted: false,
            _real: PhantomData,
        })
    }

    /// The shift's kernels, buffers and bind groups (made once, at a batch's first
    /// relaxation).
    fn shift_parts(&self) -> Result<ShiftParts, GpuError> {
        let ctx = self.ctx;
        let f64 = T::IS_F64;
        let size = std::mem::size_of::<T>();
        let (v, n) = (self.num_variants, self.num_nodes);
        let assemble = Kernel::AssembleShift { trial: false }.pipeline(ctx, f64)?;
        let assemble_force = Kernel::AssembleShift { trial: true }.pipeline(ctx, f64)?;
        let shift = empty(ctx, "shift", v * size);
        let anchor = empty(ctx, "anchor", 3 * n * v * size);
        let rot_shift = empty(ctx, "rot_shift", v * size);
        let anchor_rot = empty(ctx, "anchor_rot", 9 * n * v * size);
        let c = &self.c;
        let groups = [0, 1].map(|k| {
            let slot = &self.slots[k];
            let [diag, upper, lower, rhs] = &slot.system;
            let tail = [&shift, &anchor, &slot.x, &rot_shift, &anchor_rot, &slot.rot];
            let full = bind(
                ctx,
                &assemble,
                "assemble_shift",
                &[
                    &c.assembly_inputs(true)[..],
                    &[diag, upper, lower, rhs],
                    &tail,
                ]
                .concat(),
            );
            let force = bind(
                ctx,
                &assemble_force,
                "assemble_trial_shift",
                &[&c.assembly_inputs(false)[..], &[rhs, &c.active], &tail].concat(),
            );
            (full, force)
        });
        Ok(ShiftParts {
            assemble,
            assemble_force,
            shift,
            anchor,
            rot_shift,
            anchor_rot,
            rotations: false,
            groups,
        })
    }

    /// Records the evaluation of `slot`: beam, sites, contact, assembly, with the tangent
    /// for every variant (`trial` None), or, for a trial of the `Some(A)` variants listed
    /// in `c.active`, the residual alone of those (the kernels built `FORCE_ONLY` and
    /// `MASKED`, one invocation per item and listed variant).
    fn record_evaluate(&self, pass: &mut wgpu::ComputePass, slot: usize, trial: Option<usize>) {
        let s = &self.slots[slot];
        let p = &self.p;
        let tangent = trial.is_none();
        let v = trial.unwrap_or(self.num_variants);
        let pairs = self.num_pairs / self.num_variants.max(1) * v;
        record_chain(pass, false, self.num_nodes, v, pairs, |stage| match stage {
            Stage::Predict => None,
            Stage::Beam if tangent => Some((&*p.beam, &s.beam)),
            Stage::Beam => Some((&*p.beam_force, &s.beam_force)),
            Stage::Sites if tangent => Some((&*p.sites, &s.sites)),
            Stage::Sites => Some((&*p.sites_trial, &s.sites_trial)),
            Stage::Contact if tangent => Some((&*p.contact, &self.contact)),
            Stage::Contact => Some((&*p.contact_force, &self.contact_force)),
            Stage::Assemble => match (&self.shift, self.shifted, tangent) {
                (Some(sh), true, true) => Some((&*sh.assemble, &sh.groups[slot].0)),
                (Some(sh), true, false) => Some((&*sh.assemble_force, &sh.groups[slot].1)),
                (_, _, true) => Some((&*p.assemble, &s.assemble)),
                (_, _, false) => Some((&*p.assemble_force, &s.assemble_force)),
            },
        });
    }

    /// Records a line-search trial at the `α` in `c.alpha` into the other slot: the update
    /// of every variant (`first`: the search's first trial) or of the `count` listed in
    /// `c.active`, and the residual and norms of the listed ones (the kernels built
    /// `MASKED`, one invocation per item and listed variant: issue 27, only the variants
    /// still searching pay for a trial).
    fn record_trial(&self, pass: &mut wgpu::ComputePass, first: bool, count: usize) {
        let other = 1 - self.current;
        let b = &self.slots[other];
        let (update, moved) = if first {
            (&b.update_trial_all, self.num_variants)
        } else {
            (&b.update_trial, count)
        };
        dispatch(pass, &self.p.update_trial, update, self.num_nodes * moved);
        self.record_evaluate(pass, other, Some(count));
        dispatch(pass, &self.p.norms_trial, &b.norms_trial, count);
    }

    fn encoder(&self, label: &str) -> wgpu::CommandEncoder {
        encoder(self.ctx, label)
    }

    /// An encoder with the current system's block solve and its norms recorded (the
    /// statuses reset first); an error where the current slot holds a trial's residual
    /// alone.
    fn record_solve(&self) -> Result<wgpu::CommandEncoder, crate::error::SystemError> {
        if !self.formed[self.current] {
            return Err(crate::error::SystemError::Order(
                "tangent not formed (a trial's residual only)",
            ));
        }
        let v = self.num_variants;
        let s = &self.slots[self.current];
        let mut encoder = self.encoder("solve");
        self.c.reset_status(&mut encoder, v);
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            self.c.record_lu(&mut pass, &self.p.block_lu, &s.lu);
            dispatch(&mut pass, &self.p.norms, &s.norms_solve, v);
        }
        Ok(encoder)
    }

    /// Submits `encoder` after copying the norms and statuses out; reads them back.
    fn finish_with_norms(
        &self,
        encoder: wgpu::CommandEncoder,
    ) -> Result<(Norms<T>, Vec<u32>), GpuError> {
        let v = self.num_variants;
        let norm_bytes = (4 * v * std::mem::size_of::<T>()) as u64;
        let out = self.c.staging.read(
            self.ctx,
            encoder,
            &[(&self.c.norms, norm_bytes), (&self.c.status, 4 * v as u64)],
        )?;
        Ok((norms_from_bytes(&out[0]), values(&out[1])))
    }
}

/// Records the evaluation chain ([`crate::engine::evaluation`]) into `pass`, each stage
/// with the pipeline and bind group `bind` gives it (`None`: not on this path).
fn record_chain<'b>(
    pass: &mut wgpu::ComputePass,
    dynamic: bool,
    n: usize,
    v: usize,
    p: usize,
    bind: impl Fn(Stage) -> Option<(&'b wgpu::ComputePipeline, &'b wgpu::BindGroup)>,
) {
    for &stage in crate::engine::evaluation(dynamic) {
        if let Some((pipeline, group)) = bind(stage) {
            dispatch(
                pass,
                pipeline,
                group,
                crate::engine::invocations(stage, n, v, p),
            );
        }
    }
}

/// Line-search trials a resident batch forms at most in one submission on a GPU (after the
/// first, which it forms with the iteration): the next halvings of the variants still
/// searching, speculatively, in rounds of 2, 4 and 8 ([`crate::solve::newton`]; issue 27,
/// item 3). Measured on lavapipe (V = 256, dynamic): 25.6–28.4 read-backs a step against
/// 48.4–53.6 one trial at a time, for a third more trial passes.
pub const MAX_TRIALS_PER_ROUND: usize = 8;

static FORCED_ROUND: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// Trials per submission for `ctx`'s adapter: 1 on every adapter, unless forced
/// ([`force_trials_per_round`]; `bench ensemble --trial-round`, tests). Rounds cut the
/// read-backs but not the time on either device measured, because a speculative trial's
/// passes cost the device about what the round trip they save costs the host:
/// - lavapipe (V = 256, dynamic): up to 1.3× slower with rounds of 8;
/// - NVIDIA H100 (stop 52, `bench ensemble --nodes 100 --variants 16,256 --steps 5
///   --repeats 5 --trial-round 1|8`, alternated, four runs each): the median run 2–8 %
///   slower with rounds (V = 16 f64: 0.093 → 0.099 s; V = 256 f64: 0.150 → 0.156 s);
///   read-backs per step 29.2 → 23.2 at V = 16, while the trials' device time rose
///   16 → 24 ms and the waiting outside the passes stayed at 32 ms. The static engines likewise (stress, f64:
///   0.121–0.126 s with 1, 0.122–0.123 s with 8).
pub fn trials_per_round() -> usize {
    match FORCED_ROUND.load(std::sync::atomic::Ordering::Relaxed) {
        0 => 1,
        k => k.min(MAX_TRIALS_PER_ROUND),
    }
}

/// Forces the trials per submission of batches opened from now on (`None`: the adapter's
/// choice), as [`crate::gpu::block_lu::force_lu_form`] forces the block solve's form.
pub fn force_trials_per_round(round: Option<usize>) {
    let k = round.map_or(0, |k| k.clamp(1, MAX_TRIALS_PER_ROUND));
    FORCED_ROUND.store(k, std::sync::atomic::Ordering::Relaxed);
}

/// A resident batch's line-search trials formed several to a submission: how many at most
/// ([`trials_per_round`]) and their buffers, a round's `α` (`round · V`) and norms
/// (`round · 4 V`).
struct Rounds {
    round: usize,
    alphas: wgpu::Buffer,
    norms: wgpu::Buffer,
}

impl Rounds {
    fn new(ctx: &GpuContext, v: usize, size: usize) -> Self {
        let round = trials_per_round();
        Rounds {
            round,
            alphas: empty(ctx, "round_alphas", round * v * size),
            norms: empty(ctx, "round_norms", round * 4 * v * size),
        }
    }

    /// Forms the trials at `alphas` in one submission for the variants `search` (the
    /// search's `first` for the first of them): each trial's `α` copied into `c.alpha` (a
    /// round of one writes it there), its
    /// passes recorded by `record(pass, first, listed)` (stamped by `clock` as one span,
    /// from the first trial's start to the last one's end), its norms copied out; the norms
    /// of each, read back.
    fn form<T: GpuReal>(
        &self,
        ctx: &GpuContext,
        c: &Common,
        clock: Option<&crate::gpu::pass_clock::PassClock>,
        (alphas, search, first): (&[Vec<T>], &[bool], bool),
        record: &dyn Fn(&mut wgpu::ComputePass, bool, usize),
    ) -> Result<Vec<Norms<T>>, crate::error::SystemError> {
        let (v, k) = (search.len(), alphas.len());
        if k == 0 || k > self.round {
            return Err(crate::error::SystemError::Order(
                "a round of trials beyond the batch's buffers",
            ));
        }
        let size = std::mem::size_of::<T>() as u64;
        let (row, norm_bytes) = (v as u64 * size, 4 * v as u64 * size);
        // A round of one (the default) writes its α straight into the kernels' buffer and
        // reads its norms where the kernels leave them: no copies through the round's.
        let single = k == 1;
        for (i, a) in alphas.iter().enumerate() {
            let (to, at) = if single {
                (&c.alpha, 0)
            } else {
                (&self.alphas, i as u64 * row)
            };
            ctx.queue.write_buffer(to, at, bytemuck::cast_slice(a));
        }
        // The variants still searching, compacted: [A, v_0, …, v_{A−1}].
        let list = search_list(search);
        let count = list.len() - 1;
        ctx.queue
            .write_buffer(&c.active, 0, bytemuck::cast_slice(&list));
        let mut e = encoder(ctx, "trials");
        for i in 0..k {
            if !single {
                e.copy_buffer_to_buffer(&self.alphas, i as u64 * row, &c.alpha, 0, row);
            }
            {
                let mut pass = crate::gpu::pass_clock::PassClock::span_pass(
                    clock,
                    &mut e,
                    0,
                    i == 0,
                    i + 1 == k,
                );
                record(&mut pass, first && i == 0, count);
            }
            if !single {
                let at = i as u64 * norm_bytes;
                e.copy_buffer_to_buffer(&c.norms, 0, &self.norms, at, norm_bytes);
            }
        }
        let mut reads = vec![if single {
            (&c.norms, norm_bytes)
        } else {
            (&self.norms, k as u64 * norm_bytes)
        }];
        reads.extend(clock.map(|c| c.resolve(&mut e)));
        let out = c
            .staging
            .read(ctx, e, &reads)
            .map_err(crate::error::SystemError::from)?;
        if let (Some(clock), Some(stamps)) = (clock, out.get(1)) {
            clock.record_span(stamps, 0, k as u64);
        }
        Ok(out[0]
            .chunks_exact(norm_bytes as usize)
            .map(norms_from_bytes)
            .collect())
    }
}

/// The one trial of a round of one ([`crate::engine::ResidentTrials::trial`] on a batch
/// that forms its trials in rounds).
fn single<T>(
    round: Result<Vec<Norms<T>>, crate::error::SystemError>,
) -> Result<Norms<T>, crate::error::SystemError> {
    round?
        .pop()
        .ok_or(crate::error::SystemError::Order("no trial formed"))
}

/// The variants still searching (`search[j]`), compacted as the kernels built `MASKED`
/// read them: `[A, v_0, …, v_{A−1}]`.
fn search_list(search: &[bool]) -> Vec<u32> {
    let mut list: Vec<u32> = vec![0];
    list.extend((0..search.len() as u32).filter(|&j| search[j as usize]));
    list[0] = (list.len() - 1) as u32;
    list
}

/// A command encoder on `ctx`'s device.
pub fn encoder(ctx: &GpuContext, label: &str) -> wgpu::CommandEncoder {
    ctx.device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) })
}

/// `[max r, max αΔ, Δ·r, r·r]` rows per variant, from the norms kernel's output bytes.
fn norms_from_bytes<T: GpuReal>(bytes: &[u8]) -> Norms<T> {
    let values: &[T] = bytemuck::cast_slice(bytes);
    let rows: Vec<[T; 4]> = values
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect();
    Norms::from_rows(&rows)
}
