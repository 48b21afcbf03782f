//! One model's static Newton system on the CPU ([`CpuStatic`]: f64, faer's block solve),
//! the [`crate::solve::continuation::StaticSystem`] that [`super::solve_static_from`] and
//! [`super::polish_static`] step through the load path.

use super::*;
use crate::physics::contact::lands_in;

/// One model's static Newton system on the CPU (faer), for [`solve_static_from`].
pub(super) struct CpuStatic<'a> {
    model: &'a Model,
    c: Constraints,
    walls: Vec<Option<Wall>>,
    f_gravity: Vec<f64>,
    f_other: Vec<f64>,
    f_ref: f64,
    /// The model with the target's friction and spring exponents.
    loaded: Model,
    /// External loads of the target.
    f_step: Vec<f64>,
    pub(super) state: StaticState,
    saved: StaticState,
    solver: ChainSolver,
    residual: Vec<f64>,
    tangent: BlockTridiagonal,
    trial: Vec<f64>,
    delta: Vec<f64>,
    trial_state: Option<(f64, StaticState, Vec<usize>)>,
    /// Per node: may still land on the wall in this target's solve.
    may_land: Vec<bool>,
    evaluated: bool,
    /// Proximal shift (N/m) and its anchor ([`crate::solve::continuation`]'s relaxation).
    shift: f64,
    anchor: Vec<Vec3<f64>>,
    /// The state the anchor was last set at (`x₋` of
    /// [`crate::solve::continuation::StaticSystem::set_shift`]).
    anchor_base: Vec<Vec3<f64>>,
    /// A relaxation's rotational shift (N·m/rad) and its anchor rotations
    /// ([`crate::solve::continuation::StaticSystem::set_rotation_shift`]).
    rotation_shift: f64,
    anchor_rot: Vec<Mat3<f64>>,
    /// The last equilibrium the load path reached, with its loads
    /// ([`StaticSystem::keep_equilibrium`]).
    pub(super) kept: Option<(StaticState, crate::solve::continuation::LoadTarget)>,
    /// A relaxation's best sub-solve ([`StaticSystem::keep_best`]).
    best: Option<StaticState>,
}

/// The first proximal shift of a relaxation of `model` (N/m; [`StaticSystem::relax_scale`]
/// of the CPU solve and the engine): the force scale `f_ref` over the shortest element.
///
/// [`StaticSystem::relax_scale`]: crate::solve::continuation::StaticSystem::relax_scale
pub fn relax_scale(model: &Model, f_ref: f64) -> f64 {
    let shortest = model
        .elements
        .iter()
        .map(|e| e.length0)
        .fold(f64::INFINITY, f64::min);
    f_ref / shortest.max(1e-3)
}

/// Adds a rotational proximal shift `s θ` to the moments' residual, `θ = log(R R_aᵀ)` each
/// node's rotation since its anchor `R_a` (spatial, as the Newton update
/// `R ← exp(Δθ) R` turns it), and `s I` to their tangent blocks (the exact derivative at
/// `θ = 0`; a proximal term needs no more).
fn add_rotation_shift(
    s: f64,
    rot: &[Mat3<f64>],
    anchor: &[Mat3<f64>],
    residual: &mut [f64],
    tangent: Option<&mut BlockTridiagonal>,
) {
    if s == 0.0 || anchor.len() != rot.len() {
        return;
    }
    for (i, (r, a)) in rot.iter().zip(anchor).enumerate() {
        let at: Mat3<f64> = std::array::from_fn(|p| std::array::from_fn(|q| a[q][p]));
        let theta =
            crate::physics::rotation::rotation_log(&crate::physics::rotation::mat_mul(r, &at));
        for k in 0..3 {
            residual[6 * i + 3 + k] += s * theta[k];
        }
    }
    if let Some(t) = tangent {
        for d in t.diag.iter_mut() {
            for (k, row) in d.iter_mut().enumerate().skip(3) {
                row[k] += s;
            }
        }
    }
}

/// Adds a proximal shift `s (u − a)` to the translations' residual (`u` the displacements) and `s I` to their
/// tangent blocks (before the constraints: `s I` is the same in any node basis).
fn add_shift(
    s: f64,
    x: &[Vec3<f64>],
    anchor: &[Vec3<f64>],
    residual: &mut [f64],
    tangent: Option<&mut BlockTridiagonal>,
) {
    if s == 0.0 {
        return;
    }
    for (i, (x, a)) in x.iter().zip(anchor).enumerate() {
        for k in 0..3 {
            residual[6 * i + k] += s * (x[k] - a[k]);
        }
    }
    if let Some(t) = tangent {
        for d in t.diag.iter_mut() {
            for (k, row) in d.iter_mut().take(3).enumerate() {
                row[k] += s;
            }
        }
    }
}

impl<'a> CpuStatic<'a> {
    pub(super) fn new(model: &'a Model, start: StaticState) -> Self {
        let (f_gravity, f_other) = split_loads(model);
        let n = model.nodes.len();
        let walls = walls(model);
        CpuStatic {
            may_land: landing_flags(&walls),
            model,
            c: constraints(model),
            walls,
            f_ref: reference_force(model),
            f_step: vec![0.0; 6 * n],
            f_gravity,
            f_other,
            loaded: model.clone(),
            saved: start.clone(),
            state: start,
            solver: ChainSolver::new(),
            residual: vec![0.0; 6 * n],
            tangent: BlockTridiagonal::zeros(n),
            trial: vec![0.0; 6 * n],
            delta: vec![0.0; 6 * n],
            trial_state: None,
            evaluated: false,
            shift: 0.0,
            anchor: Vec::new(),
            anchor_base: Vec::new(),
            rotation_shift: 0.0,
            anchor_rot: Vec::new(),
            kept: None,
            best: None,
        }
    }
}

/// Per node: may land on its wall ([`crate::physics::contact::landing_step`]; every contact
/// node, this solve being f64).
fn landing_flags(walls: &[Option<Wall>]) -> Vec<bool> {
    walls.iter().map(|w| w.is_some() && lands_in(8)).collect()
}

impl CpuStatic<'_> {
    /// Every contact node may land on its wall once more
    /// ([`crate::physics::contact::landing_step`]): at a new target, and at a step's
    /// restart.
    fn reset_landing(&mut self) {
        self.may_land = landing_flags(&self.walls);
    }

    /// The state and restart point set to `to`, a state kept earlier (`None`: none was;
    /// the error says `what`).
    fn go_back(
        &mut self,
        to: Option<StaticState>,
        what: &str,
    ) -> Result<(), crate::error::SystemError> {
        let to = to.ok_or_else(|| crate::error::SystemError::Unsupported(what.into()))?;
        self.saved.clone_from(&to);
        self.state = to;
        self.evaluated = false;
        self.reset_landing();
        Ok(())
    }

    /// The state moved by `α Δ`, and the nodes that landed on their wall in it.
    fn moved(&self, alpha: f64) -> (StaticState, Vec<usize>) {
        let mut landed = Vec::new();
        let s = update(
            &self.c,
            &self.walls,
            &self.state,
            &self.delta,
            alpha,
            // Not in a relaxation's sub-solves: their steps follow an overdamped string's
            // path across a fold, which a jump to the wall leaves (corpus well 90 at 1 m
            // elements failed its relaxation with it, 44's found another equilibrium).
            if self.shift > 0.0 {
                &[]
            } else {
                &self.may_land
            },
            &mut landed,
        );
        (s, landed)
    }
}

impl crate::solve::newton::NewtonSystem for CpuStatic<'_> {
    fn variants(&self) -> usize {
        1
    }
    fn solve(&mut self) -> Result<crate::solve::newton::Probe, crate::error::SystemError> {
        if !self.evaluated {
            assemble(
                &self.loaded,
                &self.state,
                1.0,
                &self.f_step,
                &mut self.residual,
                Some(&mut self.tangent),
            );
            add_shift(
                self.shift,
                &self.state.u,
                &self.anchor,
                &mut self.residual,
                Some(&mut self.tangent),
            );
            add_rotation_shift(
                self.rotation_shift,
                &self.state.rot,
                &self.anchor_rot,
                &mut self.residual,
                Some(&mut self.tangent),
            );
            constrain(&self.c, &mut self.residual, &mut self.tangent);
            self.evaluated = true;
        }
        let rhs: Vec<f64> = self.residual.iter().map(|x| -x).collect();
        let solved = match self.solver.solve(&self.tangent, &rhs) {
            Ok(d) => {
                self.delta = d;
                true
            }
            Err(_) => {
                self.delta.fill(0.0);
                false
            }
        };
        Ok(crate::solve::newton::Probe {
            measure: vec![residual_measure(&self.residual, self.f_ref)],
            step: vec![self.delta.iter().fold(0.0f64, |m, x| m.max(x.abs()))],
            slope: vec![dot_n(&self.delta, &self.residual)],
            norm: vec![dot_n(&self.residual, &self.residual).sqrt()],
            solved: vec![solved],
        })
    }
    fn trial(
        &mut self,
        alpha: &[f64],
        _: &[bool],
        _: bool,
    ) -> Result<crate::solve::newton::TrialProbe, crate::error::SystemError> {
        let (s, landed) = self.moved(alpha[0]);
        assemble(&self.loaded, &s, 1.0, &self.f_step, &mut self.trial, None);
        add_shift(self.shift, &s.u, &self.anchor, &mut self.trial, None);
        add_rotation_shift(
            self.rotation_shift,
            &s.rot,
            &self.anchor_rot,
            &mut self.trial,
            None,
        );
        constrain_residual(&self.c, &mut self.trial);
        self.trial_state = Some((alpha[0], s, landed));
        Ok(crate::solve::newton::TrialProbe {
            slope: vec![dot_n(&self.delta, &self.trial)],
            norm: vec![dot_n(&self.trial, &self.trial).sqrt()],
        })
    }
    fn accept(
        &mut self,
        alpha: &[f64],
        trial_matches: bool,
    ) -> Result<(), crate::error::SystemError> {
        if alpha[0] == 0.0 {
            return Ok(());
        }
        let (state, landed) = match self.trial_state.take() {
            Some((a, s, l)) if trial_matches && a == alpha[0] => (s, l),
            _ => self.moved(alpha[0]),
        };
        self.state = state;
        for i in landed {
            self.may_land[i] = false;
        }
        self.evaluated = false;
        Ok(())
    }
}

impl crate::solve::continuation::StaticSystem for CpuStatic<'_> {
    fn set_target(
        &mut self,
        _j: usize,
        target: &crate::solve::continuation::LoadTarget,
    ) -> Result<(), crate::error::SystemError> {
        self.loaded = loaded_model(self.model, target);
        self.reset_landing();
        for (f, (g, o)) in self
            .f_step
            .iter_mut()
            .zip(self.f_gravity.iter().zip(&self.f_other))
        {
            *f = target.gravity * g + target.lambda * o;
        }
        self.evaluated = false;
        Ok(())
    }
    fn save(&mut self, _j: usize) -> Result<(), crate::error::SystemError> {
        self.saved = self.state.clone();
        Ok(())
    }
    fn restore(&mut self, _j: usize) -> Result<(), crate::error::SystemError> {
        self.state = self.saved.clone();
        self.evaluated = false;
        self.reset_landing();
        Ok(())
    }
    fn worst_residual_md(&mut self, _j: usize) -> Option<f64> {
        let k = (0..self.residual.len())
            .filter(|k| k % 6 < 3)
            .max_by(|&a, &b| self.residual[a].abs().total_cmp(&self.residual[b].abs()))?;
        Some(self.model.nodes[k / 6].md)
    }
    fn relax_scale(&mut self, _j: usize) -> Option<f64> {
        Some(relax_scale(self.model, self.f_ref))
    }
    fn unshifted_measure(&mut self, _j: usize) -> f64 {
        let mut r = vec![0.0; self.residual.len()];
        assemble(&self.loaded, &self.state, 1.0, &self.f_step, &mut r, None);
        constrain_residual(&self.c, &mut r);
        residual_measure(&r, self.f_ref)
    }
    fn keep_equilibrium(
        &mut self,
        _j: usize,
        target: &crate::solve::continuation::LoadTarget,
    ) -> Result<(), crate::error::SystemError> {
        // Into the buffers of the last one kept: no allocation a converged step. Every field
        // by name, so a field added to the state cannot be left out unnoticed.
        match &mut self.kept {
            Some((state, t)) => {
                let StaticState { u, rot } = &self.state;
                state.u.clone_from(u);
                state.rot.clone_from(rot);
                *t = *target;
            }
            None => self.kept = Some((self.state.clone(), *target)),
        }
        Ok(())
    }
    fn back_to_equilibrium(&mut self, _j: usize) -> Result<(), crate::error::SystemError> {
        let kept = self.kept.as_ref().map(|(state, _)| state.clone());
        self.go_back(kept, "no equilibrium was kept")
    }
    fn keep_best(&mut self, _j: usize) -> Result<(), crate::error::SystemError> {
        match &mut self.best {
            Some(best) => best.clone_from(&self.state),
            None => self.best = Some(self.state.clone()),
        }
        Ok(())
    }
    fn back_to_best(&mut self, _j: usize) -> Result<(), crate::error::SystemError> {
        let best = self.best.clone();
        self.go_back(best, "no relaxation state was kept")
    }
    fn set_shift(
        &mut self,
        _j: usize,
        s: f64,
        momentum: f64,
    ) -> Result<(), crate::error::SystemError> {
        self.shift = s;
        if s == 0.0 {
            self.anchor.clear();
            self.anchor_base.clear();
        } else {
            self.anchor.clone_from(&self.state.u);
            crate::solve::continuation::carry_anchor(
                self.anchor.as_flattened_mut(),
                self.anchor_base.as_flattened(),
                momentum,
            );
            self.anchor_base.clone_from(&self.state.u);
        }
        self.evaluated = false;
        Ok(())
    }
    fn shifts_rotations(&self) -> bool {
        true
    }
    fn set_rotation_shift(&mut self, _j: usize, s: f64) -> Result<(), crate::error::SystemError> {
        self.rotation_shift = s;
        if s == 0.0 {
            self.anchor_rot.clear();
        } else {
            self.anchor_rot.clone_from(&self.state.rot);
        }
        self.evaluated = false;
        Ok(())
    }
    fn step_floor(&mut self, _j: usize) -> Result<f64, crate::error::SystemError> {
        // Of the positions from the origin, as the engine's f64 floor.
        let largest = (0..self.state.u.len())
            .flat_map(|i| self.state.position(self.model, i))
            .fold(0.0f64, |m, x| m.max(x.abs()));
        Ok(crate::solve::newton::NewtonSettings::step_floor(8, largest))
    }
}

fn dot_n(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod rotation_shift_tests {
    use super::*;

    /// The rotational shift adds `s θ` to each node's moment rows, `θ` its rotation since
    /// the anchor (`R = exp(θ) R_a`), nothing to the force rows, and `s` to its rotational
    /// diagonal; no anchor, nothing.
    #[test]
    fn the_rotational_shift_adds_s_theta_to_the_moments() {
        let anchor = [
            rotation_exp(&[0.1, -0.2, 0.3]),
            rotation_exp(&[0.0, 0.0, 0.0]),
        ];
        let theta = [[0.01, 0.02, -0.03], [-0.2, 0.1, 0.05]];
        let rot: Vec<Mat3<f64>> = (0..2)
            .map(|i| crate::physics::rotation::mat_mul(&rotation_exp(&theta[i]), &anchor[i]))
            .collect();
        let mut r = vec![0.0; 12];
        add_rotation_shift(7.0, &rot, &anchor, &mut r, None);
        for i in 0..2 {
            for k in 0..3 {
                assert_eq!(r[6 * i + k], 0.0);
                assert!(
                    (r[6 * i + 3 + k] - 7.0 * theta[i][k]).abs() < 1e-13,
                    "{r:?}"
                );
            }
        }
        let mut none = vec![0.0; 12];
        add_rotation_shift(7.0, &rot, &[], &mut none, None);
        assert!(none.iter().all(|&x| x == 0.0));
    }
}
