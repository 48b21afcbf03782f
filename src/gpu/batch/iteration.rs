//! The static batch's Newton iteration on the GPU ([`crate::engine::ResidentStatic`] for
//! [`super::GpuStatic`]: evaluate, solve, trial, accept, commit, read and set the
//! configuration, rebase) and the sites gather kernel. Split from `gpu/batch/mod.rs`
//! (issue 24: no file over 800 lines), behaviour unchanged.

use super::*;

/// The WGSL text of the static sites gather at a precision.
pub fn sites_wgsl(f64: bool) -> Result<String, GpuError> {
    sites_wgsl_for(false, f64)
}

/// The WGSL text of the static sites gather built `MASKED` (the engine's line-search
/// trials: one invocation per (site, listed variant) of the compacted list `[A, v_0, …]`).
pub fn sites_trial_wgsl(f64: bool) -> Result<String, GpuError> {
    Kernel::SitesTrial { dynamic: false }.wgsl(f64)
}

/// The WGSL text of the static or dynamic sites gather at a precision.
pub fn sites_wgsl_for(dynamic: bool, f64: bool) -> Result<String, GpuError> {
    Kernel::Sites { dynamic }.wgsl(f64)
}

impl<T: GpuReal> ResidentStatic<T> for GpuStatic<T> {
    fn set_loads(
        &mut self,
        f_ext: &[T],
        pair_params: &[T],
        rest: &[T],
    ) -> Result<(), crate::error::SystemError> {
        let q = &self.ctx.queue;
        q.write_buffer(&self.c.f_ext, 0, bytemuck::cast_slice(f_ext));
        if let Some(b) = &self.c.rest {
            q.write_buffer(b, 0, bytemuck::cast_slice(rest));
        }
        if !pair_params.is_empty() {
            q.write_buffer(&self.c.params, 0, bytemuck::cast_slice(pair_params));
        }
        Ok(())
    }

    fn evaluate(&mut self) -> Result<(), crate::error::SystemError> {
        let mut encoder = self.encoder("evaluate");
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            self.record_evaluate(&mut pass, self.current, None);
        }
        self.ctx.queue.submit([encoder.finish()]);
        self.formed[self.current] = true;
        Ok(())
    }

    fn solve(&mut self) -> Result<(Norms<T>, Vec<u32>), crate::error::SystemError> {
        let encoder = self.record_solve()?;
        let (norms, status) = self
            .finish_with_norms(encoder)
            .map_err(crate::error::SystemError::from)?;
        if status.contains(&RUNNING) {
            return Err(crate::error::SystemError::BlockSolve(
                "a dispatch did not complete (status left at running)".into(),
            ));
        }
        Ok((norms, status))
    }

    fn solve_with_trial(
        &mut self,
    ) -> Result<crate::engine::SolvedWithTrial<T>, crate::error::SystemError> {
        let v = self.num_variants;
        let q = &self.ctx.queue;
        // The line search's first trial, formed in the same submission: α = 1 and every
        // variant searching.
        q.write_buffer(
            &self.c.alpha,
            0,
            bytemuck::cast_slice(&crate::engine::negated::<T>(&vec![1.0; v])),
        );
        let mut encoder = self.record_solve()?;
        let list_bytes = 4 * (v as u64 + 1);
        encoder.copy_buffer_to_buffer(&self.c.all_active, 0, &self.c.active, 0, list_bytes);
        let norm_bytes = (4 * v * std::mem::size_of::<T>()) as u64;
        encoder.copy_buffer_to_buffer(&self.c.norms, 0, &self.solve_norms, 0, norm_bytes);
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            self.record_trial(&mut pass, true, v);
        }
        self.formed[1 - self.current] = false;
        let out = self
            .c
            .staging
            .read(
                self.ctx,
                encoder,
                &[
                    (&self.solve_norms, norm_bytes),
                    (&self.c.status, 4 * v as u64),
                    (&self.c.norms, norm_bytes),
                ],
            )
            .map_err(crate::error::SystemError::from)?;
        let status: Vec<u32> = values(&out[1]);
        if status.contains(&RUNNING) {
            return Err(crate::error::SystemError::BlockSolve(
                "a dispatch did not complete (status left at running)".into(),
            ));
        }
        Ok((
            norms_from_bytes(&out[0]),
            status,
            Some(norms_from_bytes(&out[2])),
        ))
    }

    fn accept_trial(&mut self) {
        self.current = 1 - self.current;
    }

    fn commit(&mut self, alpha: &[T]) -> Result<(), crate::error::SystemError> {
        self.ctx
            .queue
            .write_buffer(&self.c.alpha, 0, bytemuck::cast_slice(alpha));
        let mut encoder = self.encoder("commit");
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            dispatch(
                &mut pass,
                &self.p.update,
                &self.slots[self.current].update,
                self.num_nodes * self.num_variants,
            );
        }
        self.ctx.queue.submit([encoder.finish()]);
        Ok(())
    }

    fn config(&mut self) -> Result<ConfigBatch<T>, crate::error::SystemError> {
        let (v, n) = (self.num_variants, self.num_nodes);
        let s = &self.slots[self.current];
        let size = std::mem::size_of::<T>() as u64;
        let out = self
            .c
            .staging
            .read(
                self.ctx,
                self.encoder("config"),
                &[
                    (&s.x, 3 * (n * v) as u64 * size),
                    (&s.rot, 9 * (n * v) as u64 * size),
                ],
            )
            .map_err(crate::error::SystemError::from)?;
        Ok(ConfigBatch {
            num_variants: v,
            num_nodes: n,
            x: values(&out[0]),
            rot: values(&out[1]),
            basis: Vec::new(),
            landed: Vec::new(),
        })
    }

    fn set_config(&mut self, config: &ConfigBatch<T>) -> Result<(), crate::error::SystemError> {
        let s = &self.slots[self.current];
        let q = &self.ctx.queue;
        q.write_buffer(&s.x, 0, bytemuck::cast_slice(&config.x));
        q.write_buffer(&s.rot, 0, bytemuck::cast_slice(&config.rot));
        self.formed[self.current] = false;
        Ok(())
    }

    fn set_shift(&mut self, shift: Option<&Shift<T>>) -> Result<(), crate::error::SystemError> {
        match shift {
            None => self.shifted = false,
            Some(sh) => {
                if self.shift.is_none() {
                    self.shift = Some(
                        self.shift_parts()
                            .map_err(crate::error::SystemError::from)?,
                    );
                }
                let parts = self.shift.as_mut().expect("made above");
                let q = &self.ctx.queue;
                q.write_buffer(&parts.shift, 0, bytemuck::cast_slice(&sh.shift));
                q.write_buffer(&parts.anchor, 0, bytemuck::cast_slice(&sh.anchor));
                // No rotations' shift: zeros (the kernel reads no anchor rotation then),
                // written only where the buffer held one.
                if !sh.rot_shift.is_empty() {
                    q.write_buffer(&parts.rot_shift, 0, bytemuck::cast_slice(&sh.rot_shift));
                    q.write_buffer(&parts.anchor_rot, 0, bytemuck::cast_slice(&sh.anchor_rot));
                    parts.rotations = true;
                } else if std::mem::take(&mut parts.rotations) {
                    let zero = vec![T::zero(); self.num_variants];
                    q.write_buffer(&parts.rot_shift, 0, bytemuck::cast_slice(&zero));
                }
                self.shifted = true;
            }
        }
        self.formed = [false; 2];
        Ok(())
    }

    fn set_landing_epochs(&mut self, epochs: &[u32]) -> Result<(), crate::error::SystemError> {
        self.ctx
            .queue
            .write_buffer(&self.epoch, 0, bytemuck::cast_slice(epochs));
        Ok(())
    }

    fn rebase(&mut self, tables: &BatchTables<T>) -> Result<(), crate::error::SystemError> {
        let q = &self.ctx.queue;
        if !tables.pair_base.is_empty() {
            q.write_buffer(
                &self.c.pair_base,
                0,
                bytemuck::cast_slice(&tables.pair_base),
            );
        }
        q.write_buffer(&self.c.chords, 0, bytemuck::cast_slice(&tables.chords));
        let mut encoder = self.encoder("rebase");
        encoder.clear_buffer(&self.slots[self.current].x, 0, None);
        q.submit([encoder.finish()]);
        self.formed[self.current] = false;
        Ok(())
    }
}

impl<T: GpuReal> crate::engine::ResidentTrials<T> for GpuStatic<T> {
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
        let r = self
            .rounds
            .form(self.ctx, &self.c, None, (alphas, search, first), &record);
        self.formed[1 - self.current] = false;
        r
    }
}
