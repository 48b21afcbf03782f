//! The buffers every GPU batch has, static or dynamic ([`Common`]), and their bind groups.

use super::*;

/// The buffers every batch has, static or dynamic: shared tables, contact and element
/// work, the block solve's workspace and step, the per-variant scalars, and the parameter blocks.
pub(super) struct Common {
    /// Where every per-iteration read-back goes (one buffer, kept).
    pub(super) staging: crate::gpu::readback::Staging,
    pub(super) sections: wgpu::Buffer,
    pub(super) frames: wgpu::Buffer,
    pub(super) chords: wgpu::Buffer,
    /// Unstrained rotations per element and variant (a scene with a kink only).
    pub(super) rest: Option<wgpu::Buffer>,
    /// The base at every pair across its hole axis, `3 P` (the sites kernel's `b`).
    pub(super) pair_base: wgpu::Buffer,
    pub(super) basis: wgpu::Buffer,
    pub(super) fixed: wgpu::Buffer,
    pub(super) node_site: wgpu::Buffer,
    pub(super) pair_node: wgpu::Buffer,
    pub(super) normals: wgpu::Buffer,
    pub(super) pair_state: wgpu::Buffer,
    pub(super) params: wgpu::Buffer,
    pub(super) f_ext: wgpu::Buffer,
    pub(super) elem_force: wgpu::Buffer,
    pub(super) elem_tangent: wgpu::Buffer,
    pub(super) values: wgpu::Buffer,
    pub(super) flags: wgpu::Buffer,
    pub(super) work_x: wgpu::Buffer,
    pub(super) work_z: wgpu::Buffer,
    pub(super) delta: wgpu::Buffer,
    pub(super) status: wgpu::Buffer,
    /// [`RUNNING`] per variant: copied into `status` before every block solve.
    pub(super) running: wgpu::Buffer,
    pub(super) ones: wgpu::Buffer,
    /// The variants a trial evaluates (those still searching), compacted:
    /// `[A, v_0, …, v_{A−1}]`, room for V.
    pub(super) active: wgpu::Buffer,
    /// Every variant, `[V, 0, 1, …, V−1]` (a search's first trial moves them all).
    pub(super) all_active: wgpu::Buffer,
    pub(super) alpha: wgpu::Buffer,
    pub(super) norms: wgpu::Buffer,
    pub(super) chain_dims: wgpu::Buffer,
    pub(super) beam_dims: wgpu::Buffer,
    pub(super) sites_dims: wgpu::Buffer,
    pub(super) contact_dims: wgpu::Buffer,
    /// As `contact_dims`, with the activity mask's V (the masked trials' kernel).
    pub(super) contact_trial_dims: wgpu::Buffer,
    pub(super) assemble_dims: wgpu::Buffer,
    pub(super) lu_dims: Vec<wgpu::Buffer>,
    /// The block solve's form for this batch ([`crate::gpu::block_lu::LuForm::for_batch`]).
    pub(super) lu_form: crate::gpu::block_lu::LuForm,
    /// Invocations of each pass of the block solve (`lu_dims`), in its form.
    pub(super) lu_invocations: Vec<usize>,
}

impl Common {
    /// The beam kernel's bind group on configuration (`x`, `rot`); `force_only`: for the
    /// kernel built `FORCE_ONLY`, which has no tangent binding; `masked`: built `MASKED`
    /// (the list of variants last).
    pub(super) fn beam_group(
        &self,
        ctx: &GpuContext,
        pipeline: &wgpu::ComputePipeline,
        x: &wgpu::Buffer,
        rot: &wgpu::Buffer,
        force_only: bool,
        masked: bool,
    ) -> wgpu::BindGroup {
        let mut all = vec![
            &self.beam_dims,
            x,
            rot,
            &self.frames,
            &self.sections,
            &self.chords,
        ];
        all.extend(&self.rest);
        all.push(&self.elem_force);
        if !force_only {
            all.push(&self.elem_tangent);
        }
        if masked {
            all.push(&self.active);
        }
        bind(ctx, pipeline, "beam", &all)
    }

    /// The contact kernel's bind group; `masked`: for the kernel built `MASKED` (the
    /// activity mask last).
    pub(super) fn contact_group(
        &self,
        ctx: &GpuContext,
        pipeline: &wgpu::ComputePipeline,
        masked: bool,
    ) -> wgpu::BindGroup {
        let dims = if masked {
            &self.contact_trial_dims
        } else {
            &self.contact_dims
        };
        let mut all = vec![
            dims,
            &self.normals,
            &self.params,
            &self.pair_state,
            &self.values,
            &self.flags,
        ];
        if masked {
            all.push(&self.active);
        }
        bind(ctx, pipeline, "contact", &all)
    }

    /// The assembly's inputs before the constraints (bindings 0–8; `tangent` false: the
    /// residual-only kernel's 0–7, without the element tangents).
    pub(super) fn assembly_inputs(&self, tangent: bool) -> Vec<&wgpu::Buffer> {
        let mut all = vec![&self.assemble_dims, &self.elem_force];
        if tangent {
            all.push(&self.elem_tangent);
        }
        all.extend([
            &self.values,
            &self.flags,
            &self.node_site,
            &self.f_ext,
            &self.basis,
            &self.fixed,
        ]);
        all
    }

    /// Records the block solve's passes (`groups`, from [`Common::lu_groups`]) into `pass`.
    pub(super) fn record_lu(
        &self,
        pass: &mut wgpu::ComputePass,
        pipeline: &wgpu::ComputePipeline,
        groups: &[wgpu::BindGroup],
    ) {
        for (group, &k) in groups.iter().zip(&self.lu_invocations) {
            super::dispatch(pass, pipeline, group, k);
        }
    }

    /// One bind group per pass of the block solve of `system` (diag, upper, lower, rhs).
    pub(super) fn lu_groups(
        &self,
        ctx: &GpuContext,
        pipeline: &wgpu::ComputePipeline,
        system: [&wgpu::Buffer; 4],
    ) -> Vec<wgpu::BindGroup> {
        self.lu_dims
            .iter()
            .map(|d| {
                let [diag, upper, lower, rhs] = system;
                bind(
                    ctx,
                    pipeline,
                    "block_lu",
                    &[
                        d,
                        diag,
                        upper,
                        lower,
                        rhs,
                        &self.work_x,
                        &self.work_z,
                        &self.delta,
                        &self.status,
                    ],
                )
            })
            .collect()
    }

    /// Sets every variant's block-solve status to [`RUNNING`] (recorded on `encoder`).
    pub(super) fn reset_status(&self, encoder: &mut wgpu::CommandEncoder, v: usize) {
        encoder.copy_buffer_to_buffer(&self.running, 0, &self.status, 0, 4 * v as u64);
    }

    /// The norms of `rhs` and the step with `alpha` (or ones); `masked`: for the kernel
    /// built `MASKED` (the activity mask last).
    pub(super) fn norms_group(
        &self,
        ctx: &GpuContext,
        pipeline: &wgpu::ComputePipeline,
        alpha: &wgpu::Buffer,
        rhs: &wgpu::Buffer,
        masked: bool,
    ) -> wgpu::BindGroup {
        let mut all = vec![&self.chain_dims, &self.delta, alpha, rhs, &self.norms];
        if masked {
            all.push(&self.active);
        }
        bind(ctx, pipeline, "norms", &all)
    }

    /// Checks the batch against the adapter's limits and makes its common buffers; the
    /// pair parameters and loads start as given (or empty, written per load step).
    pub(super) fn new<T: GpuReal>(
        ctx: &'static GpuContext,
        model: &Model,
        tables: &BatchTables<T>,
        params: Option<&[T]>,
        f_ext: Option<&[T]>,
    ) -> Result<Self, GpuError> {
        require_precision::<T>(ctx)?;
        let (v, n, s) = (tables.num_variants, tables.num_nodes, tables.num_sites);
        let (m, p) = (n.saturating_sub(1), tables.pair_node.len());
        let size = std::mem::size_of::<T>();
        let lu_form = crate::gpu::block_lu::LuForm::for_batch(ctx, n, v);
        if largest_binding_per_variant(n, s, size) * v > ctx.max_binding_bytes() as usize {
            return Err(GpuError::Unsupported(format!(
                "{v} variants of {n} nodes exceed one binding of {} bytes; split the variants",
                ctx.max_binding_bytes()
            )));
        }
        // The norms loop over 6n entries per invocation: llvmpipe's loop budget.
        if 6 * n > 60_000 {
            return Err(GpuError::Unsupported(format!(
                "norms of {n} nodes exceed one invocation's loop budget"
            )));
        }
        let cast = |x: Vec<f64>| -> Vec<T> { x.into_iter().map(T::from_f64_lossy).collect() };
        let table = |label: &str, x: Vec<f64>| storage(ctx, label, &cast(x));
        let (lu_x, lu_z) = lu_form.workspace(n);
        let lu_plan = crate::gpu::block_lu::plan(lu_form, n, v);
        let given = |label: &str, x: Option<&[T]>, len: usize| match x {
            Some(x) => storage(ctx, label, x),
            None => empty(ctx, label, len * size),
        };
        Ok(Common {
            staging: Default::default(),
            sections: table("sections", crate::kernels::beam::section_table(model)),
            frames: table("frames", crate::kernels::beam::frame_table(model)),
            chords: storage(ctx, "chords", &tables.chords),
            rest: (!tables.rest.is_empty()).then(|| storage(ctx, "rest", &tables.rest)),
            pair_base: storage(ctx, "pair_base", &tables.pair_base),
            basis: storage(ctx, "basis", &tables.basis),
            fixed: storage(ctx, "fixed", &tables.fixed),
            node_site: storage(ctx, "node_site", &tables.node_site),
            pair_node: storage(ctx, "pair_node", &tables.pair_node),
            normals: storage(ctx, "pair_normals", &tables.pair_normals),
            pair_state: storage(ctx, "pair_state", &tables.pair_state),
            params: given("pair_params", params, PARAMS_LEN * p),
            f_ext: given("f_ext", f_ext, 6 * n * v),
            elem_force: empty(ctx, "elem_force", 12 * m * v * size),
            elem_tangent: empty(
                ctx,
                "elem_tangent",
                crate::kernels::beam::TANGENT_LEN * m * v * size,
            ),
            values: empty(
                ctx,
                "contact_values",
                crate::kernels::contact::output_fields(&tables.terms) * p * size,
            ),
            flags: empty(ctx, "contact_flags", 4 * p),
            work_x: empty(ctx, "lu_work", lu_x * v * size),
            work_z: empty(ctx, "lu_work_z", lu_z * v * size),
            delta: empty(ctx, "delta", 6 * n * v * size),
            status: empty(ctx, "status", 4 * v),
            running: storage(ctx, "status_running", &vec![RUNNING; v]),
            ones: storage(ctx, "ones", &vec![T::one(); v]),
            active: storage(ctx, "active", &vec![0u32; v + 1]),
            all_active: storage(
                ctx,
                "all_active",
                &std::iter::once(v as u32)
                    .chain(0..v as u32)
                    .collect::<Vec<u32>>(),
            ),
            alpha: empty(ctx, "alpha", v * size),
            norms: empty(ctx, "norms", 4 * v * size),
            chain_dims: param_block(
                ctx,
                "chain_dims",
                &ChainDims {
                    num_variants: v as u32,
                    num_nodes: n as u32,
                    _pad0: 0,
                    _pad1: 0,
                },
            ),
            beam_dims: param_block(
                ctx,
                "beam_dims",
                &BeamDims {
                    num_variants: v as u32,
                    num_elements: m as u32,
                    _pad0: 0,
                    _pad1: 0,
                },
            ),
            sites_dims: param_block(
                ctx,
                "sites_dims",
                &ContactDims {
                    num_pairs: p as u32,
                    num_variants: v as u32,
                    pair_offset: 0,
                    mask_variants: 0,
                },
            ),
            // The contact kernel sees one "variant" per site: every pair has its own axis.
            contact_dims: param_block(
                ctx,
                "contact_dims",
                &ContactDims {
                    num_pairs: p as u32,
                    num_variants: 1,
                    pair_offset: 0,
                    mask_variants: 0,
                },
            ),
            contact_trial_dims: param_block(
                ctx,
                "contact_trial_dims",
                &ContactDims {
                    num_pairs: p as u32,
                    num_variants: 1,
                    pair_offset: 0,
                    mask_variants: v as u32,
                },
            ),
            assemble_dims: param_block(
                ctx,
                "assemble_dims",
                &AssembleDims {
                    num_variants: v as u32,
                    num_nodes: n as u32,
                    num_sites: s as u32,
                    _pad: 0,
                },
            ),
            lu_dims: lu_plan
                .iter()
                .map(|(d, _)| param_block(ctx, "lu_dims", d))
                .collect(),
            lu_invocations: lu_plan.iter().map(|&(_, k)| k).collect(),
            lu_form,
        })
    }
}
