//! A dynamic batch's time step as the one Newton's system ([`crate::solve::newton`]):
//! split from `engine/dynamic/mod.rs` (issue 24: no file over 800 lines).

use super::{Iteration, ResidentDynamic};
use crate::engine::{negated, trial_on, trials_on, KeptTrial};
use crate::kernels::block_lu::SOLVED;
use crate::physics::Real;
use crate::solve::newton::{NewtonSystem, Probe, TrialProbe};

/// A dynamic batch's step as a Newton system: the unknown is `v̇_{n+1}` of every variant.
pub(super) struct DynamicStep<'e, T> {
    pub(super) ensemble: &'e mut dyn ResidentDynamic<T>,
    pub(super) f_ref: Vec<f64>,
    pub(super) hhb: f64,
    /// The variants Newton is iterating on (set before each iteration).
    pub(super) running: Vec<bool>,
    /// The first trial formed with the last iteration ([`Iteration::full_step`]: α = 1 for
    /// the variants iterating, 0 for the others), until a line search takes it or the next
    /// iteration.
    pub(super) full_step: KeptTrial<T>,
}

impl<T: Real> NewtonSystem for DynamicStep<'_, T> {
    fn variants(&self) -> usize {
        self.f_ref.len()
    }
    fn solve(&mut self) -> Result<Probe, crate::error::SystemError> {
        let Iteration {
            norms,
            status,
            inertial,
            full_step,
        } = self.ensemble.iterate(&self.running)?;
        let formed = self
            .running
            .iter()
            .map(|&r| f64::from(u8::from(r)))
            .collect();
        self.full_step.keep(full_step, formed);
        let f = |x: &T| x.to_f64_lossy();
        Ok(Probe {
            // Scale: the loads, or the inertial forces if larger (a whirling string).
            measure: (0..self.f_ref.len())
                .map(|j| f(&norms.residual_max[j]) / self.f_ref[j].max(f(&inertial[j])))
                .collect(),
            step: norms.step_max.iter().map(|x| f(x) * self.hhb).collect(),
            slope: norms.step_dot_residual.iter().map(f).collect(),
            norm: norms.residual_square.iter().map(|x| f(x).sqrt()).collect(),
            solved: status.iter().map(|&s| s == SOLVED).collect(),
        })
    }
    fn trial(
        &mut self,
        alpha: &[f64],
        search: &[bool],
        first: bool,
    ) -> Result<TrialProbe, crate::error::SystemError> {
        let request = (alpha, search, first);
        trial_on(self.ensemble, &mut self.full_step, request, &|_| false)
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
        trials_on(self.ensemble, &mut self.full_step, (alphas, search, first))
    }
    fn accept(
        &mut self,
        alpha: &[f64],
        trial_matches: bool,
    ) -> Result<(), crate::error::SystemError> {
        if self.full_step.take_trial(trial_matches) {
            // The trial at these α is the new unknown.
            self.ensemble.accept_trial()?;
        } else if alpha.iter().any(|&a| a != 0.0) {
            self.ensemble.correct(&negated::<T>(alpha))?;
        }
        Ok(())
    }
}
