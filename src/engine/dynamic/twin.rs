//! The dynamic engine's CPU path: [`TwinDynamic`], the kernels' twins run in the engine's
//! order on a dynamic batch (the oracle of the GPU's dynamic batch). Split from
//! `engine/dynamic.rs` (issue 24: no file over 800 lines), behaviour unchanged.

use super::*;

/// The twins' dynamic batch (f64).
pub struct TwinDynamic<'a> {
    model: &'a Model,
    tables: BatchTables<f64>,
    dynamic: DynamicTables<f64>,
    contact: ContactBatch<f64>,
    coefficients: Option<StepCoefficients<f64>>,
    top: Vec<f64>,
    state: DynamicBatch<f64>,
    unknown: Vec<f64>,
    trial: DynamicBatch<f64>,
    delta: Vec<f64>,
}

impl<'a> TwinDynamic<'a> {
    /// Holds a batch on the CPU twins.
    pub fn new(model: &'a Model, tables: &BatchTables<f64>, dynamic: &DynamicTables<f64>) -> Self {
        let p = tables.pair_node.len();
        let mut contact = ContactBatch::new(1, p);
        contact.site_normals = tables.pair_normals.clone();
        contact.pair_state = tables.pair_state.clone();
        contact.pair_params = dynamic.pair_params.clone();
        TwinDynamic {
            model,
            tables: tables.clone(),
            dynamic: dynamic.clone(),
            contact,
            coefficients: None,
            top: Vec::new(),
            state: dynamic.start.clone(),
            unknown: dynamic.start.vdot.clone(),
            trial: dynamic.start.clone(),
            delta: vec![0.0; 6 * tables.num_nodes * tables.num_variants],
        }
    }

    /// Predicts the trial at `vdot` and assembles its system (`tangent`) or its residual.
    fn evaluate_at(
        &mut self,
        mut vdot: Vec<f64>,
        tangent: bool,
    ) -> Result<ChainBatch<f64>, crate::error::SystemError> {
        let c = self
            .coefficients
            .ok_or(crate::error::SystemError::Order("no step begun"))?;
        predict(&c, &self.top, &self.state, &mut vdot, &mut self.trial);
        let p = options_coefficients(&c);
        let tr = &self.trial;
        Ok(crate::engine::twin_evaluate(
            self.model,
            &self.tables,
            &mut self.contact,
            &tr.u,
            &tr.rot,
            &self.dynamic.f_ext,
            tangent,
            Some((
                tr,
                crate::engine::AssemblyDynamic {
                    coefficients: [p.0, p.1, self.dynamic.a0],
                    mass: &self.dynamic.mass,
                    inertia0: &self.dynamic.inertia0,
                    unbalance: &self.dynamic.unbalance,
                },
            )),
            None,
        ))
    }
}

/// `(hγ', h²β')` of a step.
pub fn options_coefficients<T: Real>(c: &StepCoefficients<T>) -> (T, T) {
    let one = T::one();
    let ratio = (one - c.alpha_f) / (one - c.alpha_m);
    (c.h * c.gamma * ratio, c.h * c.h * c.beta * ratio)
}

impl ResidentDynamic<f64> for TwinDynamic<'_> {
    fn begin_step(
        &mut self,
        c: &StepCoefficients<f64>,
        top: &[f64],
    ) -> Result<(), crate::error::SystemError> {
        self.coefficients = Some(*c);
        self.top = top.to_vec();
        self.unknown = self.state.vdot.clone();
        Ok(())
    }
    fn iterate(&mut self, _: &[bool]) -> Result<Iteration<f64>, crate::error::SystemError> {
        // Every variant is evaluated and solved (the GPU forms the running ones alone; the
        // others' unknowns do not move, and their outputs are not read).
        let sys = self.evaluate_at(self.unknown.clone(), true)?;
        // The top's prescribed accelerations, as the predictor wrote them.
        self.unknown = self.trial.vdot.clone();
        let (delta, status) = block_lu(&sys);
        self.delta = delta;
        let (v, n) = (self.tables.num_variants, self.tables.num_nodes);
        let norms = norms(&sys.rhs, &self.delta, &vec![1.0; v], n, v);
        let inertial = inertial_scale(&self.dynamic.mass, &self.unknown, n, v);
        Ok(Iteration {
            norms,
            status,
            inertial,
            full_step: None,
        })
    }
    fn correct(&mut self, alpha: &[f64]) -> Result<(), crate::error::SystemError> {
        let (v, n) = (self.tables.num_variants, self.tables.num_nodes);
        self.unknown = accelerate(&self.tables.basis, &self.unknown, &self.delta, alpha, n, v);
        Ok(())
    }
    fn accept_trial(&mut self) -> Result<(), crate::error::SystemError> {
        // The candidate with the top's prescribed accelerations, as the predictor wrote it
        // (the trial formed its residual only: the next iteration evaluates its system).
        self.unknown = self.trial.vdot.clone();
        Ok(())
    }
    fn end_step(&mut self) -> Result<(), crate::error::SystemError> {
        let c = self
            .coefficients
            .ok_or(crate::error::SystemError::Order("no step begun"))?;
        let mut vdot = self.unknown.clone();
        let mut next = self.state.clone();
        predict(&c, &self.top, &self.state, &mut vdot, &mut next);
        self.state = next;
        Ok(())
    }
    fn state(&mut self) -> Result<DynamicBatch<f64>, crate::error::SystemError> {
        Ok(self.state.clone())
    }
    fn set_state(&mut self, state: &DynamicBatch<f64>) -> Result<(), crate::error::SystemError> {
        self.state = state.clone();
        Ok(())
    }
}

impl crate::engine::ResidentTrials<f64> for TwinDynamic<'_> {
    fn trial(
        &mut self,
        alpha: &[f64],
        _: &[bool],
        _: bool,
    ) -> Result<Norms<f64>, crate::error::SystemError> {
        // Every variant is moved and evaluated: the searching ones' residuals are those the
        // GPU forms for them alone, the others' trial points those it keeps (each at its
        // accepted α).
        let (v, n) = (self.tables.num_variants, self.tables.num_nodes);
        let cand = accelerate(&self.tables.basis, &self.unknown, &self.delta, alpha, n, v);
        let sys = self.evaluate_at(cand, false)?;
        Ok(norms(&sys.rhs, &self.delta, alpha, n, v))
    }
}

impl TwinPath {
    /// The twins' dynamic batch.
    pub fn dynamic<'a>(
        &self,
        model: &'a Model,
        tables: &BatchTables<f64>,
        dynamic: &DynamicTables<f64>,
    ) -> TwinDynamic<'a> {
        TwinDynamic::new(model, tables, dynamic)
    }
}
