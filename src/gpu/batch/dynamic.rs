//! The dynamic batch of the GPU ensemble ([`crate::engine::dynamic`]): the state at `t_n`,
//! the Newton unknown and a line-search candidate resident on the GPU, with the static batch's
//! buffers, pipelines and helpers ([`super`]). Split from `gpu/batch/mod.rs` (issue 24: no file
//! over 800 lines), behaviour unchanged.

use super::*;
use crate::gpu::pass_clock::PassClock;

/// A batch of variants resident on the GPU for a dynamic run
/// ([`crate::engine::dynamic`]): the state at `t_n`, the Newton unknown `v̇_{n+1}` and a
/// candidate for the line search, one trial state and its system. Per iteration the host
/// reads four norms, a status and the inertial scale per variant. An iteration forms the
/// system of the variants still iterating, a line-search trial the residual alone (the
/// kernels built `FORCE_ONLY`) of those still searching — the kernels built `MASKED` on the
/// list `[A, v_0, …]` where not every variant is: only they pay for it (issue 27).
pub struct GpuDynamic<T: GpuReal> {
    ctx: &'static GpuContext,
    p: DynamicPipelines,
    g: DynamicGroups,
    b: DynamicBuffers,
    num_variants: usize,
    num_nodes: usize,
    num_pairs: usize,
    a0: T,
    c: Common,
    /// Line-search trials formed in one submission ([`super::Rounds`]).
    rounds: super::Rounds,
    /// The device's time of the passes read back ([`crate::tally`]), where it has stamps.
    clock: Option<crate::gpu::pass_clock::PassClock>,
    _keep: Vec<wgpu::Buffer>,
    _real: PhantomData<T>,
}

struct DynamicPipelines {
    predict: Arc<wgpu::ComputePipeline>,
    accelerate: Arc<wgpu::ComputePipeline>,
    scale: Arc<wgpu::ComputePipeline>,
    beam: Arc<wgpu::ComputePipeline>,
    sites: Arc<wgpu::ComputePipeline>,
    contact: Arc<wgpu::ComputePipeline>,
    assemble: Arc<wgpu::ComputePipeline>,
    block_lu: Arc<wgpu::ComputePipeline>,
    norms: Arc<wgpu::ComputePipeline>,
    /// The line-search trials' kernels: the residual alone, for the listed variants.
    trial: TrialPipelines,
    /// The Newton iterations' kernels for the listed variants (those still iterating),
    /// where the predictor, sites and norms are the trials' own.
    beam_masked: Arc<wgpu::ComputePipeline>,
    contact_masked: Arc<wgpu::ComputePipeline>,
    assemble_masked: Arc<wgpu::ComputePipeline>,
    scale_masked: Arc<wgpu::ComputePipeline>,
}

/// The Newton iterations' bind groups for the listed variants (`c.active` last).
struct IterateGroups {
    predict: wgpu::BindGroup,
    beam: wgpu::BindGroup,
    contact: wgpu::BindGroup,
    assemble: wgpu::BindGroup,
    norms: wgpu::BindGroup,
    scale: wgpu::BindGroup,
}

/// What one evaluation records ([`GpuDynamic::record_evaluate`]).
#[derive(Clone, Copy)]
enum Evaluation {
    /// The system of every variant at the unknown.
    All,
    /// The system of the `A` variants listed (those still iterating).
    Listed(usize),
    /// The residual of the `A` variants listed at the candidate (a line-search trial).
    Trial(usize),
}

/// The dynamic line-search trials' kernels: the correction and the predictor at the
/// candidate, beam forces, sites, contact forces and the residual, each built `MASKED`
/// (one invocation per item and listed variant); `FORCE_ONLY` where it has a matrix part.
struct TrialPipelines {
    accelerate: Arc<wgpu::ComputePipeline>,
    predict: Arc<wgpu::ComputePipeline>,
    beam: Arc<wgpu::ComputePipeline>,
    sites: Arc<wgpu::ComputePipeline>,
    contact: Arc<wgpu::ComputePipeline>,
    assemble: Arc<wgpu::ComputePipeline>,
    norms: Arc<wgpu::ComputePipeline>,
}

/// The trials' bind groups (every one with the list `c.active` last).
struct TrialGroups {
    accelerate: wgpu::BindGroup,
    predict: wgpu::BindGroup,
    beam: wgpu::BindGroup,
    sites: wgpu::BindGroup,
    contact: wgpu::BindGroup,
    assemble: wgpu::BindGroup,
    norms: wgpu::BindGroup,
}

struct DynamicGroups {
    predict_unknown: wgpu::BindGroup,
    accelerate: wgpu::BindGroup,
    scale: wgpu::BindGroup,
    beam: wgpu::BindGroup,
    sites: wgpu::BindGroup,
    contact: wgpu::BindGroup,
    assemble: wgpu::BindGroup,
    lu: Vec<wgpu::BindGroup>,
    norms_iterate: wgpu::BindGroup,
    trial: TrialGroups,
    listed: IterateGroups,
}

struct DynamicBuffers {
    coef: wgpu::Buffer,
    flags: wgpu::Buffer,
    top: wgpu::Buffer,
    dyn_coef: wgpu::Buffer,
    scale: wgpu::Buffer,
    // State at t_n, the unknown and the candidate, the trial state.
    u_n: wgpu::Buffer,
    rot_n: wgpu::Buffer,
    vel_n: wgpu::Buffer,
    acc_n: wgpu::Buffer,
    vdot_n: wgpu::Buffer,
    vdot_k: wgpu::Buffer,
    vdot_c: wgpu::Buffer,
    u_1: wgpu::Buffer,
    rot_1: wgpu::Buffer,
    vel_1: wgpu::Buffer,
    acc_1: wgpu::Buffer,
    /// The iteration's norms, kept while the trial formed with it writes its own.
    iterate_norms: wgpu::Buffer,
}

impl DynamicBuffers {
    /// The state at `t_n` beside its counterpart at `t_{n+1}` (the trial state, and the
    /// unknown for `v̇`), pair by pair: a batch's start copies the first into the second, a
    /// step's end the second into the first.
    fn steps(&self) -> [(&wgpu::Buffer, &wgpu::Buffer); 5] {
        [
            (&self.u_n, &self.u_1),
            (&self.rot_n, &self.rot_1),
            (&self.vel_n, &self.vel_1),
            (&self.acc_n, &self.acc_1),
            (&self.vdot_n, &self.vdot_k),
        ]
    }
}

impl<T: GpuReal> GpuDynamic<T> {
    /// Compiles (or fetches) the kernels for the batch's terms and precision and uploads
    /// its tables and start state.
    pub fn new(
        ctx: &'static GpuContext,
        model: &Model,
        tables: &BatchTables<T>,
        dynamic: &crate::engine::dynamic::DynamicTables<T>,
    ) -> Result<Self, GpuError> {
        use crate::gpu::dynamics::DynamicsKernel;
        let f64 = T::IS_F64;
        let kink = !tables.rest.is_empty();
        let (v, n) = (tables.num_variants, tables.num_nodes);
        let p = tables.pair_node.len();
        let size = std::mem::size_of::<T>();
        let c = Common::new(
            ctx,
            model,
            tables,
            Some(&dynamic.pair_params),
            Some(&dynamic.f_ext),
        )?;
        let k = |kernel: Kernel| kernel.pipeline(ctx, f64);
        let pl = DynamicPipelines {
            predict: k(Kernel::Dynamics(DynamicsKernel::Predict))?,
            accelerate: k(Kernel::Dynamics(DynamicsKernel::Accelerate))?,
            scale: k(Kernel::Dynamics(DynamicsKernel::Scale))?,
            beam: k(Kernel::Beam { kink })?,
            sites: k(Kernel::Sites { dynamic: true })?,
            contact: k(Kernel::Contact(&tables.terms))?,
            assemble: k(Kernel::Assemble {
                dynamic: true,
                unbalance: !dynamic.unbalance.is_empty(),
            })?,
            block_lu: k(Kernel::BlockLu(c.lu_form))?,
            norms: k(Kernel::Norms { trial: false })?,
            trial: TrialPipelines {
                accelerate: k(Kernel::DynamicsMasked(DynamicsKernel::Accelerate))?,
                predict: k(Kernel::DynamicsMasked(DynamicsKernel::Predict))?,
                beam: k(Kernel::BeamTrial { kink })?,
                sites: k(Kernel::SitesTrial { dynamic: true })?,
                contact: k(Kernel::ContactTrial(&tables.terms))?,
                assemble: k(Kernel::AssembleTrial {
                    dynamic: true,
                    unbalance: !dynamic.unbalance.is_empty(),
                })?,
                norms: k(Kernel::Norms { trial: true })?,
            },
            beam_masked: k(Kernel::BeamMasked { kink })?,
            contact_masked: k(Kernel::ContactMasked(&tables.terms))?,
            assemble_masked: k(Kernel::AssembleMasked {
                unbalance: !dynamic.unbalance.is_empty(),
            })?,
            scale_masked: k(Kernel::DynamicsMasked(DynamicsKernel::Scale))?,
        };
        let mass = storage(ctx, "mass", &dynamic.mass);
        let inertia0 = storage(ctx, "inertia0", &dynamic.inertia0);
        let unbalance =
            (!dynamic.unbalance.is_empty()).then(|| storage(ctx, "unbalance", &dynamic.unbalance));
        let [diag, upper, lower, rhs] = system_buffers(ctx, v, n, size);
        let st = &dynamic.start;
        let b = DynamicBuffers {
            coef: empty(ctx, "coef", 5 * size),
            flags: empty(ctx, "step_flags", 4),
            top: empty(ctx, "top", crate::kernels::dynamics::TOP_LEN * v * size),
            dyn_coef: empty(ctx, "dyn_coef", 3 * size),
            scale: empty(ctx, "scale", v * size),
            u_n: storage(ctx, "u_n", &st.u),
            rot_n: storage(ctx, "rot_n", &st.rot),
            vel_n: storage(ctx, "vel_n", &st.vel),
            acc_n: storage(ctx, "acc_n", &st.acc),
            vdot_n: storage(ctx, "vdot_n", &st.vdot),
            vdot_k: empty(ctx, "vdot_k", st.vdot.len() * size),
            vdot_c: empty(ctx, "vdot_c", st.vdot.len() * size),
            u_1: empty(ctx, "u_1", st.u.len() * size),
            rot_1: empty(ctx, "rot_1", st.rot.len() * size),
            vel_1: empty(ctx, "vel_1", st.vel.len() * size),
            acc_1: empty(ctx, "acc_1", st.acc.len() * size),
            iterate_norms: empty(ctx, "iterate_norms", 4 * v * size),
        };
        // The unknown, the candidate and the trial state start as the state: uploaded once,
        // copied on the device (at V = 4096 the uploads were a large part of the setup).
        let mut e = encoder(ctx, "dynamic start");
        Self::copy_all(&mut e, &b.steps());
        Self::copy_all(&mut e, &[(&b.vdot_n, &b.vdot_c)]);
        ctx.queue.submit([e.finish()]);
        let predict_inputs = |vdot| {
            vec![
                &c.chain_dims,
                &b.coef,
                &b.flags,
                &b.top,
                &b.u_n,
                &b.rot_n,
                &b.vel_n,
                &b.acc_n,
                &b.vdot_n,
                vdot,
                &b.u_1,
                &b.rot_1,
                &b.vel_1,
                &b.acc_1,
            ]
        };
        let mut assemble = c.assembly_inputs(true);
        assemble.extend([
            &b.dyn_coef,
            &mass,
            &inertia0,
            &b.rot_1,
            &b.vel_1,
            &b.vdot_k,
            &c.normals,
        ]);
        assemble.extend(&unbalance);
        assemble.extend([&diag, &upper, &lower, &rhs]);
        // The trials' residual: the static inputs, the output and the list, then the
        // dynamic inputs (at the candidate).
        let mut assemble_trial = c.assembly_inputs(false);
        assemble_trial.extend([&rhs, &c.active]);
        assemble_trial.extend([&b.dyn_coef, &mass, &inertia0, &b.rot_1, &b.vel_1, &b.vdot_c]);
        assemble_trial.extend(&unbalance);
        let tp = &pl.trial;
        let trial = TrialGroups {
            accelerate: bind(
                ctx,
                &tp.accelerate,
                "accelerate_trial",
                &[
                    &c.chain_dims,
                    &c.basis,
                    &b.vdot_k,
                    &c.delta,
                    &c.alpha,
                    &b.vdot_c,
                    &c.active,
                ],
            ),
            predict: bind(
                ctx,
                &tp.predict,
                "predict_trial",
                &[&predict_inputs(&b.vdot_c)[..], &[&c.active]].concat(),
            ),
            beam: c.beam_group(ctx, &tp.beam, &b.u_1, &b.rot_1, true, true),
            sites: bind(
                ctx,
                &tp.sites,
                "sites_trial",
                &[
                    &c.sites_dims,
                    &c.pair_node,
                    &b.u_1,
                    &c.pair_base,
                    &c.pair_state,
                    &b.vel_1,
                    &c.normals,
                    &c.active,
                ],
            ),
            contact: c.contact_group(ctx, &tp.contact, true),
            assemble: bind(ctx, &tp.assemble, "assemble_trial", &assemble_trial),
            norms: c.norms_group(ctx, &tp.norms, &c.alpha, &rhs, true),
        };
        let listed = IterateGroups {
            predict: bind(
                ctx,
                &tp.predict,
                "predict_masked",
                &[&predict_inputs(&b.vdot_k)[..], &[&c.active]].concat(),
            ),
            beam: c.beam_group(ctx, &pl.beam_masked, &b.u_1, &b.rot_1, false, true),
            contact: c.contact_group(ctx, &pl.contact_masked, true),
            assemble: bind(
                ctx,
                &pl.assemble_masked,
                "assemble_masked",
                &[&assemble[..], &[&c.active]].concat(),
            ),
            norms: c.norms_group(ctx, &tp.norms, &c.ones, &rhs, true),
            scale: bind(
                ctx,
                &pl.scale_masked,
                "scale_masked",
                &[&c.chain_dims, &mass, &b.vdot_k, &b.scale, &c.active],
            ),
        };
        let g = DynamicGroups {
            predict_unknown: bind(ctx, &pl.predict, "predict", &predict_inputs(&b.vdot_k)),
            accelerate: bind(
                ctx,
                &pl.accelerate,
                "accelerate",
                &[
                    &c.chain_dims,
                    &c.basis,
                    &b.vdot_k,
                    &c.delta,
                    &c.alpha,
                    &b.vdot_c,
                ],
            ),
            scale: bind(
                ctx,
                &pl.scale,
                "scale",
                &[&c.chain_dims, &mass, &b.vdot_k, &b.scale],
            ),
            beam: c.beam_group(ctx, &pl.beam, &b.u_1, &b.rot_1, false, false),
            sites: bind(
                ctx,
                &pl.sites,
                "sites",
                &[
                    &c.sites_dims,
                    &c.pair_node,
                    &b.u_1,
                    &c.pair_base,
                    &c.pair_state,
                    &b.vel_1,
                    &c.normals,
                ],
            ),
            contact: c.contact_group(ctx, &pl.contact, false),
            assemble: bind(ctx, &pl.assemble, "assemble", &assemble),
            lu: c.lu_groups(ctx, &pl.block_lu, [&diag, &upper, &lower, &rhs]),
            norms_iterate: c.norms_group(ctx, &pl.norms, &c.ones, &rhs, false),
            trial,
            listed,
        };
        Ok(GpuDynamic {
            ctx,
            p: pl,
            g,
            b,
            num_variants: v,
            num_nodes: n,
            num_pairs: p,
            a0: T::from_f64_lossy(dynamic.a0),
            c,
            rounds: super::Rounds::new(ctx, v, size),
            clock: crate::gpu::pass_clock::PassClock::new(ctx, "dynamic pass"),
            _keep: [mass, inertia0, diag, upper, lower, rhs]
                .into_iter()
                .chain(unbalance)
                .collect(),
            _real: PhantomData,
        })
    }

    /// Records predict, beam, sites, contact, assembly: at the unknown the system of every
    /// variant, or of the variants listed in `c.active`; at the candidate (a line-search
    /// trial) the residual alone of the listed ones.
    fn record_evaluate(&self, pass: &mut wgpu::ComputePass, what: Evaluation) {
        let (g, p) = (&self.g, &self.p);
        let (tg, tp, lg) = (&g.trial, &p.trial, &g.listed);
        let v = match what {
            Evaluation::All => self.num_variants,
            Evaluation::Listed(a) | Evaluation::Trial(a) => a,
        };
        let pairs = self.num_pairs / self.num_variants.max(1) * v;
        record_chain(pass, true, self.num_nodes, v, pairs, |stage| {
            Some(match (what, stage) {
                (Evaluation::All, Stage::Predict) => (&*p.predict, &g.predict_unknown),
                (Evaluation::All, Stage::Beam) => (&*p.beam, &g.beam),
                (Evaluation::All, Stage::Sites) => (&*p.sites, &g.sites),
                (Evaluation::All, Stage::Contact) => (&*p.contact, &g.contact),
                (Evaluation::All, Stage::Assemble) => (&*p.assemble, &g.assemble),
                (Evaluation::Listed(_), Stage::Predict) => (&*tp.predict, &lg.predict),
                (Evaluation::Listed(_), Stage::Beam) => (&*p.beam_masked, &lg.beam),
                // The sites gather at the unknown and at the candidate reads the same
                // trial state (`u_1`, `vel_1`).
                (Evaluation::Listed(_), Stage::Sites) => (&*tp.sites, &tg.sites),
                (Evaluation::Listed(_), Stage::Contact) => (&*p.contact_masked, &lg.contact),
                (Evaluation::Listed(_), Stage::Assemble) => (&*p.assemble_masked, &lg.assemble),
                (Evaluation::Trial(_), Stage::Predict) => (&*tp.predict, &tg.predict),
                (Evaluation::Trial(_), Stage::Beam) => (&*tp.beam, &tg.beam),
                (Evaluation::Trial(_), Stage::Sites) => (&*tp.sites, &tg.sites),
                (Evaluation::Trial(_), Stage::Contact) => (&*tp.contact, &tg.contact),
                (Evaluation::Trial(_), Stage::Assemble) => (&*tp.assemble, &tg.assemble),
            })
        });
    }

    /// Records a line-search trial at the `α` in `c.alpha`: the candidate of every variant
    /// (`first`: the search's first trial) or of the `count` listed in `c.active`, and the
    /// residual and norms of the listed ones.
    fn record_trial(&self, pass: &mut wgpu::ComputePass, first: bool, count: usize) {
        let n = self.num_nodes;
        if first {
            dispatch(
                pass,
                &self.p.accelerate,
                &self.g.accelerate,
                n * self.num_variants,
            );
        } else {
            let (p, g) = (&self.p.trial.accelerate, &self.g.trial.accelerate);
            dispatch(pass, p, g, n * count);
        }
        self.record_evaluate(pass, Evaluation::Trial(count));
        dispatch(pass, &self.p.trial.norms, &self.g.trial.norms, count);
    }

    fn copy_all(encoder: &mut wgpu::CommandEncoder, pairs: &[(&wgpu::Buffer, &wgpu::Buffer)]) {
        for (from, to) in pairs {
            encoder.copy_buffer_to_buffer(from, 0, to, 0, from.size());
        }
    }
}

impl<T: GpuReal> crate::engine::dynamic::ResidentDynamic<T> for GpuDynamic<T> {
    fn begin_step(
        &mut self,
        c: &crate::kernels::dynamics::StepCoefficients<T>,
        top: &[T],
    ) -> Result<(), crate::error::SystemError> {
        let q = &self.ctx.queue;
        let (hg, hhb) = crate::engine::dynamic::options_coefficients(c);
        q.write_buffer(&self.b.coef, 0, bytemuck::cast_slice(&c.reals()[..]));
        q.write_buffer(&self.b.flags, 0, bytemuck::cast_slice(&[c.flags()]));
        q.write_buffer(&self.b.top, 0, bytemuck::cast_slice(top));
        q.write_buffer(
            &self.b.dyn_coef,
            0,
            bytemuck::cast_slice(&[hg, hhb, self.a0]),
        );
        let mut e = encoder(self.ctx, "begin_step");
        Self::copy_all(&mut e, &[(&self.b.vdot_n, &self.b.vdot_k)]);
        q.submit([e.finish()]);
        Ok(())
    }

    fn iterate(
        &mut self,
        running: &[bool],
    ) -> Result<crate::engine::dynamic::Iteration<T>, crate::error::SystemError> {
        let v = self.num_variants;
        let q = &self.ctx.queue;
        let mut e = encoder(self.ctx, "iterate");
        // Every variant iterating: the kernels over all of them. Else only the listed ones
        // (built `MASKED`): the block solve skips a variant whose status starts at
        // SINGULAR, so the others start there and the listed ones at RUNNING.
        let all = running.iter().all(|&r| r);
        // The list serves the trial formed with the iteration too.
        let list = super::search_list(running);
        let count = list.len() - 1;
        q.write_buffer(&self.c.active, 0, bytemuck::cast_slice(&list));
        if all {
            self.c.reset_status(&mut e, v);
        } else {
            let start: Vec<u32> = running
                .iter()
                .map(|&r| if r { RUNNING } else { SINGULAR })
                .collect();
            q.write_buffer(&self.c.status, 0, bytemuck::cast_slice(&start));
        }
        // The line search's first trial, formed in the same submission: α = 1 for the
        // variants iterating, 0 for the others (as `trial` with `first` sets them).
        let full: Vec<f64> = running.iter().map(|&r| f64::from(u8::from(r))).collect();
        q.write_buffer(
            &self.c.alpha,
            0,
            bytemuck::cast_slice(&crate::engine::negated::<T>(&full)),
        );
        let clock = self.clock.as_ref();
        {
            let mut pass = PassClock::span_pass(clock, &mut e, 0, true, true);
            let (g, p) = (&self.g, &self.p);
            match all {
                true => self.record_evaluate(&mut pass, Evaluation::All),
                false => self.record_evaluate(&mut pass, Evaluation::Listed(count)),
            }
            self.c.record_lu(&mut pass, &p.block_lu, &g.lu);
            match all {
                true => {
                    dispatch(&mut pass, &p.norms, &g.norms_iterate, v);
                    dispatch(&mut pass, &p.scale, &g.scale, v);
                }
                false => {
                    dispatch(&mut pass, &p.trial.norms, &g.listed.norms, count);
                    dispatch(&mut pass, &p.scale_masked, &g.listed.scale, count);
                }
            }
        }
        let size = std::mem::size_of::<T>() as u64;
        let norms_bytes = 4 * v as u64 * size;
        e.copy_buffer_to_buffer(&self.c.norms, 0, &self.b.iterate_norms, 0, norms_bytes);
        {
            let mut pass = PassClock::span_pass(clock, &mut e, 1, true, true);
            self.record_trial(&mut pass, true, count);
        }
        let mut reads = vec![
            (&self.b.iterate_norms, norms_bytes),
            (&self.c.status, 4 * v as u64),
            (&self.b.scale, v as u64 * size),
            (&self.c.norms, norms_bytes),
        ];
        reads.extend(clock.map(|c| c.resolve_spans(&mut e, 2)));
        let out = self
            .c
            .staging
            .read(self.ctx, e, &reads)
            .map_err(crate::error::SystemError::from)?;
        if let (Some(c), Some(stamps)) = (clock, out.get(4)) {
            c.record_span(stamps, 0, 0);
            c.record_span(stamps, 1, 1);
        }
        let status: Vec<u32> = values(&out[1]);
        if status.contains(&RUNNING) {
            return Err(crate::error::SystemError::BlockSolve(
                "a dispatch did not complete (status left at running)".into(),
            ));
        }
        Ok(crate::engine::dynamic::Iteration {
            norms: norms_from_bytes(&out[0]),
            status,
            inertial: values(&out[2]),
            full_step: Some(norms_from_bytes(&out[3])),
        })
    }

    fn correct(&mut self, alpha: &[T]) -> Result<(), crate::error::SystemError> {
        self.ctx
            .queue
            .write_buffer(&self.c.alpha, 0, bytemuck::cast_slice(alpha));
        let mut e = encoder(self.ctx, "correct");
        {
            let mut pass = e.begin_compute_pass(&Default::default());
            dispatch(
                &mut pass,
                &self.p.accelerate,
                &self.g.accelerate,
                self.num_nodes * self.num_variants,
            );
        }
        Self::copy_all(&mut e, &[(&self.b.vdot_c, &self.b.vdot_k)]);
        self.ctx.queue.submit([e.finish()]);
        Ok(())
    }

    fn accept_trial(&mut self) -> Result<(), crate::error::SystemError> {
        // The candidate (with the top's prescribed accelerations the predictor wrote into
        // it) becomes the unknown; the trial formed its residual only, so the next
        // iteration evaluates its system.
        let mut e = encoder(self.ctx, "accept_trial");
        Self::copy_all(&mut e, &[(&self.b.vdot_c, &self.b.vdot_k)]);
        self.ctx.queue.submit([e.finish()]);
        Ok(())
    }

    fn end_step(&mut self) -> Result<(), crate::error::SystemError> {
        let mut e = encoder(self.ctx, "end_step");
        {
            let mut pass = e.begin_compute_pass(&Default::default());
            dispatch(
                &mut pass,
                &self.p.predict,
                &self.g.predict_unknown,
                self.num_nodes * self.num_variants,
            );
        }
        Self::copy_all(&mut e, &self.b.steps().map(|(at_n, next)| (next, at_n)));
        self.ctx.queue.submit([e.finish()]);
        Ok(())
    }

    fn set_state(
        &mut self,
        s: &crate::kernels::dynamics::DynamicBatch<T>,
    ) -> Result<(), crate::error::SystemError> {
        let b = &self.b;
        let q = &self.ctx.queue;
        for (buffer, data) in [
            (&b.u_n, &s.u),
            (&b.rot_n, &s.rot),
            (&b.vel_n, &s.vel),
            (&b.acc_n, &s.acc),
            (&b.vdot_n, &s.vdot),
        ] {
            q.write_buffer(buffer, 0, bytemuck::cast_slice(data));
        }
        Ok(())
    }

    fn state(
        &mut self,
    ) -> Result<crate::kernels::dynamics::DynamicBatch<T>, crate::error::SystemError> {
        let (v, n) = (self.num_variants, self.num_nodes);
        let size = std::mem::size_of::<T>() as u64;
        let nv = (n * v) as u64 * size;
        let b = &self.b;
        let out = self
            .c
            .staging
            .read(
                self.ctx,
                encoder(self.ctx, "state"),
                &[
                    (&b.u_n, 3 * nv),
                    (&b.rot_n, 9 * nv),
                    (&b.vel_n, 6 * nv),
                    (&b.acc_n, 6 * nv),
                    (&b.vdot_n, 6 * nv),
                ],
            )
            .map_err(crate::error::SystemError::from)?;
        let cast = |bytes: &Vec<u8>| -> Vec<T> { bytemuck::cast_slice(bytes).to_vec() };
        Ok(crate::kernels::dynamics::DynamicBatch {
            num_variants: v,
            num_nodes: n,
            u: cast(&out[0]),
            rot: cast(&out[1]),
            vel: cast(&out[2]),
            acc: cast(&out[3]),
            vdot: cast(&out[4]),
        })
    }
}

impl<T: GpuReal> crate::engine::ResidentTrials<T> for GpuDynamic<T> {
    fn trial(
        &mut self,
        alpha: &[T],
        search: &[bool],
        first: bool,
    ) -> Result<Norms<T>, crate::error::SystemError> {
        super::single(self.trials(&[alpha.to_vec()], search, first))
    }

    fn trials_per_round(&self) -> usize {
        self.rounds.round
    }

    fn trials(
        &mut self,
        alphas: &[Vec<T>],
        search: &[bool],
        first: bool,
    ) -> Result<Vec<Norms<T>>, crate::error::SystemError> {
        let record = |pass: &mut wgpu::ComputePass, first: bool, listed: usize| {
            self.record_trial(pass, first, listed)
        };
        let clock = self.clock.as_ref();
        self.rounds
            .form(self.ctx, &self.c, clock, (alphas, search, first), &record)
    }
}
