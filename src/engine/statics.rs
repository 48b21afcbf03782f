//! A batch's static Newton system on a kernel path ([`EngineStatic`]): the
//! [`StaticSystem`] that [`super::solve_static_ensemble`] steps through the load path.

use super::*;

/// A batch's static Newton system on a kernel path, for [`solve_loads`]: per variant its
/// loads, its restart point (kept on the host in f64, as displacements from the reference
/// and rotations) and its step floor. Saves, restores and load changes are gathered and
/// carried out together before the next kernel work (one read and one write of the
/// configuration); in f32 every save also moves the base to the current configuration.
pub(super) struct EngineStatic<'a, T> {
    pub(super) models: Vec<&'a Model>,
    pub(super) ensemble: Box<dyn ResidentStatic<T> + 'a>,
    pub(super) tables: BatchTables<T>,
    pub(super) loads: Vec<(Vec<f64>, Vec<f64>)>,
    pub(super) f_ref: Vec<f64>,
    f_ext: Vec<T>,
    params: Vec<T>,
    loads_changed: bool,
    evaluated: bool,
    /// Per variant: displacements from the reference (`3 n`) and rotations (`9 n`).
    pub(super) saved: Vec<(Vec<f64>, Vec<f64>)>,
    to_save: Vec<usize>,
    to_restore: Vec<usize>,
    /// Per variant: its relaxation's best state ([`StaticSystem::keep_best`]).
    pub(super) best: Kept,
    /// Per variant: its last equilibrium ([`StaticSystem::keep_equilibrium`]).
    pub(super) equilibrium: Kept,
    /// Per variant the landing epoch counter (one more at each target and restart), and
    /// whether the epochs the ensemble holds are stale.
    land_epoch: Vec<u32>,
    epochs_changed: bool,
    to_rebase: bool,
    /// Per variant: a relaxation's shifts and their anchors.
    pub(super) shifts: Vec<VariantShift>,
    /// Variants whose shift was set since the last flush (anchored at their restart point,
    /// where the load path leaves them before it sets a shift), with the momentum that
    /// carries the anchor on ([`StaticSystem::set_shift`]).
    to_anchor: Vec<(usize, f64)>,
    /// Variants whose rotations' shift was set since the last flush (anchored at their
    /// restart point's rotations, [`StaticSystem::set_rotation_shift`]).
    to_anchor_rot: Vec<usize>,
    /// Per variant: the restart point its anchor was last set at (positions, `3 n`; empty
    /// without a shift), `x₋` of [`StaticSystem::set_shift`].
    pub(super) anchor_base: Vec<Vec<f64>>,
    /// The shifts differ from what the ensemble holds.
    shift_changed: bool,
    /// Each variant's residual measure without its shift at the current states (kept
    /// until a state changes).
    unshifted: Option<Vec<f64>>,
    /// The first trial (α = 1, every variant) formed with the last solve
    /// ([`ResidentStatic::solve_with_trial`]), until a line search takes it or a change
    /// of every variant's state (a rebase, a shift) drops it.
    full_step: KeptTrial<T>,
    /// Variants restored or given new loads since that solve: their trials are stale.
    touched: Vec<bool>,
}

impl<'a, T: Real> EngineStatic<'a, T> {
    /// `saved`: the variants' restart points (none: their start states); `shifts`: their
    /// relaxations' shifts and anchors (none: no shift).
    pub(super) fn new(
        models: Vec<&'a Model>,
        ensemble: Box<dyn ResidentStatic<T> + 'a>,
        tables: BatchTables<T>,
        saved: Option<Vec<(Vec<f64>, Vec<f64>)>>,
        shifts: Option<Vec<VariantShift>>,
    ) -> Self {
        let (v, n, p) = (
            tables.num_variants,
            tables.num_nodes,
            tables.pair_node.len(),
        );
        let saved = saved.unwrap_or_else(|| {
            (0..v)
                .map(|j| {
                    let x = (0..3 * n)
                        .map(|k| tables.base[k * v + j] + tables.start.x[k * v + j].to_f64_lossy())
                        .collect();
                    let rot = (0..9 * n)
                        .map(|k| tables.start.rot[k * v + j].to_f64_lossy())
                        .collect();
                    (x, rot)
                })
                .collect()
        });
        let shifts = shifts.unwrap_or_else(|| vec![VariantShift::default(); v]);
        EngineStatic {
            shift_changed: shifts.iter().any(VariantShift::any),
            shifts,
            to_anchor: Vec::new(),
            to_anchor_rot: Vec::new(),
            anchor_base: vec![Vec::new(); v],
            unshifted: None,
            loads: models.iter().map(|m| split_loads(m)).collect(),
            f_ref: models.iter().map(|m| reference_force(m)).collect(),
            models,
            ensemble,
            f_ext: vec![T::zero(); 6 * n * v],
            params: vec![T::zero(); PARAMS_LEN * p],
            tables,
            loads_changed: true,
            evaluated: false,
            saved,
            to_save: Vec::new(),
            to_restore: Vec::new(),
            best: Kept::new(v),
            equilibrium: Kept::new(v),
            land_epoch: vec![1; v],
            epochs_changed: true,
            to_rebase: false,
            full_step: KeptTrial::new(),
            touched: vec![false; v],
        }
    }

    /// Carries out the gathered saves, restores (and f32 rebase) and load changes.
    pub(super) fn flush(&mut self) -> Result<(), crate::error::SystemError> {
        let v = self.tables.num_variants;
        let keeps = !self.best.to_keep.is_empty() || !self.equilibrium.to_keep.is_empty();
        if !self.to_save.is_empty() || !self.to_restore.is_empty() || keeps {
            let mut config = self.ensemble.config()?;
            // Variant `j`'s state now into `(x, rot)`, as `saved` holds it.
            let read = |j: usize, (x, rot): &mut (Vec<f64>, Vec<f64>)| {
                for (k, x) in x.iter_mut().enumerate() {
                    *x = self.tables.base[k * v + j] + config.x[k * v + j].to_f64_lossy();
                }
                for (k, r) in rot.iter_mut().enumerate() {
                    *r = config.rot[k * v + j].to_f64_lossy();
                }
            };
            // In the driver's order: a relaxation's best, then the equilibrium (which is
            // the best where the variant went back to it in between), then the save.
            for j in std::mem::take(&mut self.best.to_keep) {
                let best = self.best.states[j].get_or_insert_with(|| self.saved[j].clone());
                read(j, best);
            }
            for j in std::mem::take(&mut self.equilibrium.to_keep) {
                let kept = self.equilibrium.states[j].get_or_insert_with(|| self.saved[j].clone());
                match &self.best.states[j] {
                    Some(best) if self.best.to_go_back.contains(&j) => kept.clone_from(best),
                    _ => read(j, kept),
                }
            }
            for j in std::mem::take(&mut self.to_save) {
                read(j, &mut self.saved[j]);
                if std::mem::size_of::<T>() == 4 {
                    self.to_rebase = true;
                }
            }
            // After the saves: a variant sent back to a kept state has it as restart point.
            self.best.go_back(&mut self.saved);
            self.equilibrium.go_back(&mut self.saved);
            let restores = std::mem::take(&mut self.to_restore);
            for &j in &restores {
                let (x, rot) = &self.saved[j];
                for (k, x) in x.iter().enumerate() {
                    config.x[k * v + j] = T::from_f64_lossy(x - self.tables.base[k * v + j]);
                }
                for (k, r) in rot.iter().enumerate() {
                    config.rot[k * v + j] = T::from_f64_lossy(*r);
                }
            }
            if !restores.is_empty() {
                self.ensemble.set_config(&config)?;
                self.evaluated = false;
                self.unshifted = None;
            }
            if std::mem::take(&mut self.to_rebase) {
                // f32: the states become the motion from here (host sums in f64).
                let mut moved = self.tables.base.clone();
                for (b, w) in moved.iter_mut().zip(&config.x) {
                    *b += w.to_f64_lossy();
                }
                self.tables.set_base(self.models[0], moved);
                self.ensemble.rebase(&self.tables)?;
                self.full_step.drop_kept();
                self.evaluated = false;
                self.unshifted = None;
                // The anchors are held as displacements from the base.
                self.shift_changed |= self.shifts.iter().any(VariantShift::any);
            }
        }
        for (j, momentum) in std::mem::take(&mut self.to_anchor) {
            let VariantShift { s, anchor, .. } = &mut self.shifts[j];
            let base = &mut self.anchor_base[j];
            if *s == 0.0 {
                anchor.clear();
                base.clear();
            } else {
                let x = &self.saved[j].0;
                anchor.clone_from(x);
                crate::solve::continuation::carry_anchor(anchor, base, momentum);
                base.clone_from(x);
            }
            self.shift_changed = true;
        }
        for j in std::mem::take(&mut self.to_anchor_rot) {
            let VariantShift {
                s_rot, anchor_rot, ..
            } = &mut self.shifts[j];
            if *s_rot == 0.0 {
                anchor_rot.clear();
            } else {
                anchor_rot.clone_from(&self.saved[j].1);
            }
            self.shift_changed = true;
        }
        if std::mem::take(&mut self.shift_changed) {
            self.upload_shift()?;
            self.full_step.drop_kept();
        }
        if std::mem::take(&mut self.epochs_changed) {
            // As `solve_static`: a node lands once a load step, not in a relaxation, and
            // only in double precision.
            let lands = crate::physics::contact::lands_in(std::mem::size_of::<T>());
            let epochs: Vec<u32> = self
                .land_epoch
                .iter()
                .zip(&self.shifts)
                .map(|(&e, s)| if lands && s.s == 0.0 { e } else { 0 })
                .collect();
            self.ensemble.set_landing_epochs(&epochs)?;
        }
        if self.loads_changed {
            self.ensemble
                .set_loads(&self.f_ext, &self.params, &self.tables.rest)?;
            self.loads_changed = false;
            self.evaluated = false;
        }
        Ok(())
    }
}

/// A variant's relaxation shifts and their anchors ([`StaticSystem::set_shift`],
/// [`StaticSystem::set_rotation_shift`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct VariantShift {
    /// The translations' shift (N/m; 0: none).
    pub(super) s: f64,
    /// Its anchor (displacements from the reference, `3 n`; empty without a shift).
    pub(super) anchor: Vec<f64>,
    /// The rotations' shift (N·m/rad; 0: none; [`crate::solve::continuation::LoadPath::rotation_shift`]).
    pub(super) s_rot: f64,
    /// Its anchor rotations (`9 n`; empty without a shift).
    pub(super) anchor_rot: Vec<f64>,
}

/// A state per variant that the load path may send it back to ([`StaticSystem::back_to_best`],
/// [`StaticSystem::back_to_equilibrium`]), kept on the host as `EngineStatic::saved` is; the
/// keeps and returns are carried out at the next flush.
#[derive(Clone, Debug)]
pub(super) struct Kept {
    /// Per variant the state kept last (`None`: none yet).
    pub(super) states: Vec<Option<(Vec<f64>, Vec<f64>)>>,
    /// Per variant the loads of the state kept last, where the keep named them (an
    /// equilibrium's: [`StaticSystem::keep_equilibrium`]).
    pub(super) at: Vec<Option<LoadTarget>>,
    /// Variants whose current state is to be kept, and those to go back to theirs.
    to_keep: Vec<usize>,
    to_go_back: Vec<usize>,
}

impl Kept {
    fn new(v: usize) -> Self {
        Kept {
            states: vec![None; v],
            at: vec![None; v],
            to_keep: Vec::new(),
            to_go_back: Vec::new(),
        }
    }

    /// The kept states of variants `keep` (in that order; taken from `self`).
    pub(super) fn take_columns(&mut self, keep: &[usize]) -> Self {
        Kept {
            states: keep.iter().map(|&i| self.states[i].take()).collect(),
            at: keep.iter().map(|&i| self.at[i].take()).collect(),
            to_keep: Vec::new(),
            to_go_back: Vec::new(),
        }
    }

    /// Variant `j`'s current state is to be kept (at the next flush), at the loads `at`.
    fn keep(&mut self, j: usize, at: Option<LoadTarget>) {
        self.to_keep.push(j);
        self.at[j] = at;
    }

    /// Variant `j`'s kept state as a configuration (of `mesh`'s nodes) and its loads, taken
    /// out.
    pub(super) fn take_state(
        &mut self,
        j: usize,
        mesh: &Model,
    ) -> Option<(StaticState, Option<LoadTarget>)> {
        let (x, rot) = self.states[j].take()?;
        let state = state_from(mesh, |k| x[k], |k| rot[k]);
        Some((state, self.at[j].take()))
    }

    /// Variant `j` is to go back to its kept state (refused where none is kept or pending:
    /// `what` says which).
    fn send_back(&mut self, j: usize, what: &str) -> Result<(), crate::error::SystemError> {
        if self.states[j].is_none() && !self.to_keep.contains(&j) {
            return Err(crate::error::SystemError::Unsupported(format!(
                "no {what} was kept"
            )));
        }
        self.to_go_back.push(j);
        Ok(())
    }

    /// The variants sent back: their kept states as restart points in `saved`.
    fn go_back(&mut self, saved: &mut [(Vec<f64>, Vec<f64>)]) {
        for j in std::mem::take(&mut self.to_go_back) {
            if let Some(state) = &self.states[j] {
                saved[j].clone_from(state);
            }
        }
    }
}

impl VariantShift {
    /// Any shift at all.
    fn any(&self) -> bool {
        self.s != 0.0 || self.s_rot != 0.0
    }
}

impl<T: Real> EngineStatic<'_, T> {
    /// Gives the ensemble the shifts and anchors (none where no variant has a shift).
    fn upload_shift(&mut self) -> Result<(), crate::error::SystemError> {
        let (v, n) = (self.tables.num_variants, self.tables.num_nodes);
        self.evaluated = false;
        if !self.shifts.iter().any(VariantShift::any) {
            return self.ensemble.set_shift(None);
        }
        let mut anchor = vec![T::zero(); 3 * n * v];
        for (j, sh) in self.shifts.iter().enumerate() {
            if sh.s != 0.0 {
                for (k, a) in sh.anchor.iter().enumerate() {
                    anchor[k * v + j] = T::from_f64_lossy(a - self.tables.base[k * v + j]);
                }
            }
        }
        // The rotations' only where a variant has one (a relaxation at its ceiling).
        let rotations = self.shifts.iter().any(|sh| sh.s_rot != 0.0);
        let mut anchor_rot = vec![T::zero(); if rotations { 9 * n * v } else { 0 }];
        for (j, sh) in self.shifts.iter().enumerate() {
            if sh.s_rot != 0.0 {
                for (k, r) in sh.anchor_rot.iter().enumerate() {
                    anchor_rot[k * v + j] = T::from_f64_lossy(*r);
                }
            }
        }
        let shift = Shift {
            shift: self.shifts.iter().map(|s| T::from_f64_lossy(s.s)).collect(),
            anchor,
            rot_shift: if rotations {
                self.shifts
                    .iter()
                    .map(|s| T::from_f64_lossy(s.s_rot))
                    .collect()
            } else {
                Vec::new()
            },
            anchor_rot,
        };
        self.ensemble.set_shift(Some(&shift))
    }

    /// Every variant's residual measure at its current state without its shift: the
    /// residual of a trial at α = 0 with the shift taken off (the shift is given back at
    /// the next flush). A variant whose last step `Δ` is not finite gets NaN (its
    /// relaxation then goes on: no false equilibrium).
    fn unshifted_measures(&mut self) -> Result<Vec<f64>, crate::error::SystemError> {
        self.flush()?;
        let v = self.tables.num_variants;
        if self.shifts.iter().any(VariantShift::any) {
            self.ensemble.set_shift(None)?;
            self.shift_changed = true;
            self.evaluated = false;
        }
        self.full_step.forming(true);
        let r = self
            .ensemble
            .trial(&vec![T::zero(); v], &vec![true; v], true)?;
        Ok(r.residual_max
            .iter()
            .zip(&self.f_ref)
            .map(|(r, f_ref)| r.to_f64_lossy() / f_ref)
            .collect())
    }
}

impl<T: Real> NewtonSystem for EngineStatic<'_, T> {
    fn variants(&self) -> usize {
        self.tables.num_variants
    }
    fn solve(&mut self) -> Result<Probe, crate::error::SystemError> {
        self.flush()?;
        if !self.evaluated {
            self.ensemble.evaluate()?;
            self.evaluated = true;
        }
        let (now, status, full_step) = self.ensemble.solve_with_trial()?;
        self.full_step
            .keep(full_step, vec![1.0; self.tables.num_variants]);
        self.touched.iter_mut().for_each(|t| *t = false);
        let f = |x: &T| x.to_f64_lossy();
        Ok(Probe {
            measure: now
                .residual_max
                .iter()
                .zip(&self.f_ref)
                .map(|(r, f_ref)| f(r) / f_ref)
                .collect(),
            step: now.step_max.iter().map(f).collect(),
            slope: now.step_dot_residual.iter().map(f).collect(),
            norm: now.residual_square.iter().map(|x| f(x).sqrt()).collect(),
            solved: status.iter().map(|&s| s == SOLVED).collect(),
        })
    }
    fn trial(
        &mut self,
        alpha: &[f64],
        search: &[bool],
        first: bool,
    ) -> Result<TrialProbe, crate::error::SystemError> {
        self.flush()?;
        let touched = &self.touched;
        let request = (alpha, search, first);
        trial_on(self.ensemble.as_mut(), &mut self.full_step, request, &|j| {
            touched[j]
        })
    }
    fn trials_per_round(&self) -> usize {
        self.ensemble.trials_per_round()
    }
    fn trials(
        &mut self,
        alphas: &[Vec<f64>],
        search: &[bool],
        first: bool,
    ) -> Result<Vec<TrialProbe>, crate::error::SystemError> {
        self.flush()?;
        let request = (alphas, search, first);
        trials_on(self.ensemble.as_mut(), &mut self.full_step, request)
    }
    fn accept(
        &mut self,
        alpha: &[f64],
        trial_matches: bool,
    ) -> Result<(), crate::error::SystemError> {
        self.flush()?;
        self.unshifted = None;
        if self.full_step.take_trial(trial_matches) {
            // The trial's residual only: its tangent is formed when the next solve needs it.
            self.ensemble.accept_trial();
            self.evaluated = false;
        } else if alpha.iter().any(|&a| a != 0.0) {
            self.ensemble.commit(&negated::<T>(alpha))?;
            self.evaluated = false;
        }
        Ok(())
    }
}

impl<T: Real> StaticSystem for EngineStatic<'_, T> {
    fn set_target(
        &mut self,
        j: usize,
        target: &LoadTarget,
    ) -> Result<(), crate::error::SystemError> {
        let v = self.tables.num_variants;
        let p = self.tables.pair_node.len();
        let (gravity, other) = &self.loads[j];
        for (d, (g, o)) in gravity.iter().zip(other).enumerate() {
            self.f_ext[d * v + j] = T::from_f64_lossy(target.gravity * g + target.lambda * o);
        }
        for (k, site) in self.models[j].sites.iter().enumerate() {
            let q = loaded_params(&site.params, target);
            for (f, x) in q.to_array().into_iter().enumerate() {
                self.params[f * p + k * v + j] = T::from_f64_lossy(x);
            }
        }
        // Kinks grow with the bit loads, as in `loaded_model` (the CPU solve's).
        if !self.tables.rest.is_empty() {
            crate::kernels::beam::set_rest_column(
                &mut self.tables.rest,
                v,
                j,
                self.models[j],
                target.lambda,
            );
        }
        self.loads_changed = true;
        self.touched[j] = true;
        self.land_epoch[j] = self.land_epoch[j].wrapping_add(1).max(1);
        self.epochs_changed = true;
        Ok(())
    }
    fn save(&mut self, j: usize) -> Result<(), crate::error::SystemError> {
        self.to_save.push(j);
        Ok(())
    }
    fn restore(&mut self, j: usize) -> Result<(), crate::error::SystemError> {
        self.to_restore.push(j);
        self.touched[j] = true;
        self.land_epoch[j] = self.land_epoch[j].wrapping_add(1).max(1);
        self.epochs_changed = true;
        Ok(())
    }
    fn step_floor(&mut self, j: usize) -> Result<f64, crate::error::SystemError> {
        // From the last saved state (a save pending now is at most one step away).
        let v = self.tables.num_variants;
        let x = &self.saved[j].0;
        let size = std::mem::size_of::<T>();
        let largest = if size == 4 {
            x.iter().enumerate().fold(0.0f64, |m, (k, x)| {
                m.max((x - self.tables.base[k * v + j]).abs())
            })
        } else {
            x.iter().enumerate().fold(0.0f64, |m, (k, x)| {
                m.max((self.tables.node_ref[k] + x).abs())
            })
        };
        Ok(NewtonSettings::step_floor(size, largest))
    }
    fn relax_scale(&mut self, j: usize) -> Option<f64> {
        Some(crate::solve::statics::relax_scale(
            self.models[j],
            self.f_ref[j],
        ))
    }
    fn unshifted_measure(&mut self, j: usize) -> f64 {
        if self.unshifted.is_none() {
            // A failed read leaves the relaxation going (no false equilibrium).
            self.unshifted = self.unshifted_measures().ok();
        }
        self.unshifted.as_ref().map_or(f64::INFINITY, |m| m[j])
    }
    fn keep_best(&mut self, j: usize) -> Result<(), crate::error::SystemError> {
        self.best.keep(j, None);
        Ok(())
    }
    fn back_to_best(&mut self, j: usize) -> Result<(), crate::error::SystemError> {
        self.best.send_back(j, "relaxation state")?;
        self.restore(j)
    }
    fn keep_equilibrium(
        &mut self,
        j: usize,
        target: &LoadTarget,
    ) -> Result<(), crate::error::SystemError> {
        self.equilibrium.keep(j, Some(*target));
        Ok(())
    }
    fn back_to_equilibrium(&mut self, j: usize) -> Result<(), crate::error::SystemError> {
        self.equilibrium.send_back(j, "equilibrium")?;
        self.restore(j)
    }
    fn set_shift(
        &mut self,
        j: usize,
        s: f64,
        momentum: f64,
    ) -> Result<(), crate::error::SystemError> {
        if s == 0.0 && self.shifts[j].s == 0.0 {
            return Ok(());
        }
        self.shifts[j].s = s;
        self.to_anchor.push((j, momentum));
        self.epochs_changed = true;
        Ok(())
    }
    fn shifts_rotations(&self) -> bool {
        true
    }
    fn set_rotation_shift(&mut self, j: usize, s: f64) -> Result<(), crate::error::SystemError> {
        if s == 0.0 && self.shifts[j].s_rot == 0.0 {
            return Ok(());
        }
        self.shifts[j].s_rot = s;
        self.to_anchor_rot.push(j);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two variants of the paper's one-stabilizer case.
    fn two_variants() -> Vec<Model> {
        let case = crate::case::load_case(std::path::Path::new("cases/paper_one_stabilizer.toml"))
            .unwrap();
        vec![case.model.clone(), case.model]
    }

    /// The engine's static system of `models` on the twin kernels.
    fn twin_system(models: &[Model]) -> EngineStatic<'_, f64> {
        let tables = ensemble_tables::<f64>(models).unwrap();
        let ensemble = TwinPath.open(&models[0], &tables).unwrap();
        EngineStatic::new(models.iter().collect(), ensemble, tables, None, None)
    }

    /// Variant 1 of two moved by `d` from where it stands.
    fn moved(sys: &mut EngineStatic<f64>, d: f64) {
        let mut c = sys.ensemble.config().unwrap();
        for k in 0..c.x.len() / 2 {
            c.x[k * 2 + 1] += d;
        }
        sys.ensemble.set_config(&c).unwrap();
    }

    /// A relaxation's best state (`StaticSystem::keep_best`) is read at the next flush, and
    /// a variant sent back to it (`back_to_best`, after the driver's save of the state it
    /// leaves) has it as state and restart point; the other variant keeps its own.
    #[test]
    fn a_variant_sent_back_to_its_best_state_restarts_there() {
        let models = two_variants();
        let mut sys = twin_system(&models);
        let v = 2;
        let start = sys.ensemble.config().unwrap();
        // No best kept: refused.
        assert!(sys.back_to_best(1).is_err());
        sys.to_restore.clear();
        // The best kept at 1 mm; the state moves on to 3 mm and is saved there; back.
        moved(&mut sys, 1e-3);
        sys.keep_best(1).unwrap();
        sys.flush().unwrap();
        moved(&mut sys, 2e-3);
        sys.save(1).unwrap();
        sys.back_to_best(1).unwrap();
        sys.flush().unwrap();
        let now = sys.ensemble.config().unwrap();
        for k in 0..now.x.len() / v {
            assert_eq!(now.x[k * v], start.x[k * v], "variant 0 moved");
            let want = start.x[k * v + 1] + 1e-3;
            assert_eq!(now.x[k * v + 1], want, "variant 1 not at its best");
            assert_eq!(sys.saved[1].0[k], sys.tables.base[k * v + 1] + want);
        }
        // Kept, saved and sent back in one flush: the state it has.
        moved(&mut sys, 5e-3);
        sys.keep_best(1).unwrap();
        sys.save(1).unwrap();
        sys.back_to_best(1).unwrap();
        sys.flush().unwrap();
        let now = sys.ensemble.config().unwrap();
        for k in 0..now.x.len() / v {
            assert_eq!(now.x[k * v + 1], start.x[k * v + 1] + 1e-3 + 5e-3);
        }
    }

    /// A variant's last equilibrium (`StaticSystem::keep_equilibrium`) is read at the next
    /// flush, and a variant sent back to it (`back_to_equilibrium`, the start of a
    /// relaxation bracketing where its string stops) has it as state and restart point; in
    /// a flush that also sends it back to a relaxation's best (a relaxation that settled
    /// there), the equilibrium kept is that best, as the CPU solve keeps it.
    #[test]
    fn a_variant_sent_back_to_its_equilibrium_restarts_there() {
        let models = two_variants();
        let mut sys = twin_system(&models);
        let v = 2;
        let start = sys.ensemble.config().unwrap();
        // Variant 1's displacements now, to be kept.
        let now = |sys: &mut EngineStatic<f64>| sys.ensemble.config().unwrap().x;
        // Variant 1 at `kept` (as a restore writes it back), variant 0 where it started.
        let at = |sys: &mut EngineStatic<f64>, kept: &[f64]| {
            let now = sys.ensemble.config().unwrap();
            for k in 0..now.x.len() / v {
                assert_eq!(now.x[k * v], start.x[k * v], "variant 0 moved");
                let saved = sys.tables.base[k * v + 1] + kept[k * v + 1];
                assert_eq!(sys.saved[1].0[k], saved);
                assert_eq!(
                    now.x[k * v + 1],
                    saved - sys.tables.base[k * v + 1],
                    "variant 1 not where it should be"
                );
            }
        };
        let target = LoadTarget {
            gravity: 1.0,
            lambda: 0.5,
            friction: 0.5,
            exponent: 1.0,
        };
        assert!(sys.back_to_equilibrium(1).is_err(), "none kept");
        sys.to_restore.clear();
        // Kept at 1 mm and saved; a relaxation moves on to 3 mm and is saved there; back.
        moved(&mut sys, 1e-3);
        let equilibrium = now(&mut sys);
        sys.keep_equilibrium(1, &target).unwrap();
        sys.save(1).unwrap();
        sys.flush().unwrap();
        moved(&mut sys, 2e-3);
        sys.save(1).unwrap();
        sys.flush().unwrap();
        sys.back_to_equilibrium(1).unwrap();
        sys.flush().unwrap();
        at(&mut sys, &equilibrium);
        // A relaxation's best 1 mm on; it goes on 2 mm more, settles back at its best, which
        // is kept as the equilibrium, and the next relaxation starts from there.
        moved(&mut sys, 1e-3);
        let best = now(&mut sys);
        sys.keep_best(1).unwrap();
        sys.save(1).unwrap();
        sys.flush().unwrap();
        moved(&mut sys, 2e-3);
        sys.back_to_best(1).unwrap();
        sys.keep_equilibrium(1, &target).unwrap();
        sys.save(1).unwrap();
        sys.back_to_equilibrium(1).unwrap();
        sys.flush().unwrap();
        at(&mut sys, &best);
        assert_eq!(sys.equilibrium.states[1], sys.best.states[1]);
        // Taken out as a configuration, with the loads it was kept at: variant 1 as it
        // stands (where a stopped variant's string is reported from); none left to take.
        let config = sys.ensemble.config().unwrap();
        let here = state_of(&models[1], &sys.tables, &config, 1);
        let (state, loads) = sys.equilibrium.take_state(1, &models[1]).unwrap();
        assert_eq!(loads, Some(target));
        assert_eq!((state.u, state.rot), (here.u, here.rot));
        assert!(sys.equilibrium.take_state(1, &models[1]).is_none());
        assert!(sys.equilibrium.take_state(0, &models[0]).is_none());
    }

    /// A shift set with momentum anchors at the restart point carried on by the momentum
    /// times its move since the last anchor (`StaticSystem::set_shift`): at the restart
    /// point for the first anchor, after a restore (no move), and not at all without a
    /// shift; the other variant keeps none.
    #[test]
    fn a_shift_with_momentum_anchors_ahead_of_the_restart_point() {
        let models = two_variants();
        let mut sys = twin_system(&models);
        let v = 2;
        let anchored = |sys: &mut EngineStatic<f64>, s: f64| {
            sys.set_shift(1, s, 0.9).unwrap();
            sys.flush().unwrap();
            sys.shifts[1].anchor.clone()
        };
        sys.save(1).unwrap();
        let x0 = sys.saved[1].0.clone();
        assert_eq!(anchored(&mut sys, 1e3), x0);
        let mut c = sys.ensemble.config().unwrap();
        for k in 0..c.x.len() / v {
            c.x[k * v + 1] += 1e-3;
        }
        sys.ensemble.set_config(&c).unwrap();
        sys.save(1).unwrap();
        sys.flush().unwrap();
        let x1 = sys.saved[1].0.clone();
        let ahead: Vec<f64> = x1.iter().zip(&x0).map(|(a, b)| a + 0.9 * (a - b)).collect();
        assert!(ahead.iter().zip(&x1).all(|(a, x)| a != x));
        assert_eq!(anchored(&mut sys, 1e3), ahead);
        sys.restore(1).unwrap();
        assert_eq!(anchored(&mut sys, 4e3), x1);
        assert!(anchored(&mut sys, 0.0).is_empty());
        assert!(sys.anchor_base[1].is_empty());
        assert_eq!(sys.shifts[0], VariantShift::default());
    }
}
