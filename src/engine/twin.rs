//! The engine's CPU path: the twins of the kernels run in the engine's order on the same
//! field-major buffers ([`TwinPath`], the oracle the GPU path is tested against), and
//! [`twin_evaluate`], the evaluation chain both the static and the dynamic twin run. Split
//! from `engine/mod.rs` (issue 24: no file over 800 lines), behaviour unchanged.

use super::*;

/// The twins' run of [`evaluation`] on a configuration (`x` displacements from the base,
/// `rot`): the constrained system — its residual alone where `tangent` is false (the
/// beam stage forms forces only and the blocks are left empty, as the assembly built
/// `FORCE_ONLY` leaves them, static or dynamic). `dynamic`: the predicted trial state and the dynamic
/// assembly's inputs (the predictor itself is run by the caller, which owns the step's
/// state). `shift`: a relaxation's shift per variant and anchor (static only).
#[allow(clippy::too_many_arguments)]
pub(crate) fn twin_evaluate(
    model: &Model,
    t: &BatchTables<f64>,
    contact_batch: &mut ContactBatch<f64>,
    x: &[f64],
    rot: &[f64],
    f_ext: &[f64],
    tangent: bool,
    dynamic: Option<(
        &crate::kernels::dynamics::DynamicBatch<f64>,
        AssemblyDynamic,
    )>,
    shift: Option<&Shift<f64>>,
) -> ChainBatch<f64> {
    let (v, n) = (t.num_variants, t.num_nodes);
    let mut elements = None;
    let mut out = crate::kernels::contact::ContactOutputs::new(contact_batch.num_pairs());
    let mut system = None;
    for stage in evaluation(dynamic.is_some()) {
        match stage {
            Stage::Predict => {}
            Stage::Beam => {
                elements = Some(crate::kernels::beam::beam(
                    model, v, x, rot, &t.chords, &t.rest, tangent,
                ))
            }
            Stage::Sites => match &dynamic {
                Some((trial, _)) => crate::kernels::sites::gather_sites_dynamic(
                    &t.pair_node,
                    &t.pair_normals,
                    trial,
                    &t.pair_base,
                    &mut contact_batch.pair_state,
                ),
                None => gather_sites(
                    &t.pair_node,
                    x,
                    &t.pair_base,
                    v,
                    &mut contact_batch.pair_state,
                ),
            },
            Stage::Contact => contact(&t.terms, contact_batch, &mut out),
            Stage::Assemble => {
                let (elem_force, elem_tangent) = elements.take().unwrap_or_default();
                let inputs = AssemblyInputs {
                    num_variants: v,
                    num_nodes: n,
                    num_sites: t.num_sites,
                    elem_force,
                    elem_tangent,
                    contact: std::mem::take(&mut out.values),
                    contact_flag: std::mem::take(&mut out.contact),
                    node_site: t.node_site.clone(),
                    f_ext: f_ext.to_vec(),
                    basis: t.basis.clone(),
                    fixed: t.fixed.clone(),
                    dynamic: dynamic.as_ref().map(|(trial, d)| {
                        crate::kernels::assemble::DynamicInputs {
                            coefficients: d.coefficients,
                            mass: d.mass.to_vec(),
                            inertia0: d.inertia0.to_vec(),
                            rot: trial.rot.clone(),
                            vel: trial.vel.clone(),
                            vdot: trial.vdot.clone(),
                            pair_normals: t.pair_normals.clone(),
                            unbalance: d.unbalance.to_vec(),
                        }
                    }),
                    shift: shift.map(|sh| crate::kernels::assemble::ShiftInputs {
                        shift: sh.shift.clone(),
                        anchor: sh.anchor.clone(),
                        x: x.to_vec(),
                        rot_shift: sh.rot_shift.clone(),
                        anchor_rot: sh.anchor_rot.clone(),
                        rot: if sh.rot_shift.is_empty() {
                            Vec::new()
                        } else {
                            rot.to_vec()
                        },
                    }),
                };
                system = Some(if tangent {
                    assemble(&inputs)
                } else {
                    // A trial: the residual alone (the kernel built `FORCE_ONLY`).
                    ChainBatch {
                        num_variants: v,
                        num_nodes: n,
                        diag: Vec::new(),
                        upper: Vec::new(),
                        lower: Vec::new(),
                        rhs: crate::kernels::assemble::assemble_residual(&inputs),
                    }
                });
            }
        }
    }
    system.unwrap_or_else(|| unreachable!("the chain ends with the assembly"))
}

/// What the dynamic assembly adds to a twin evaluation.
pub(crate) struct AssemblyDynamic<'a> {
    /// `[hγ', h²β', a0]`.
    pub coefficients: [f64; 3],
    /// Lumped nodal mass, `n`.
    pub mass: &'a [f64],
    /// Rotary inertia at the reference orientation, `9 n`.
    pub inertia0: &'a [f64],
    /// Mass imbalance per node and variant, `3 n V` (empty: none).
    pub unbalance: &'a [f64],
}

/// The CPU twins, f64.
pub struct TwinPath;

struct TwinStatic<'a> {
    model: &'a Model,
    tables: BatchTables<f64>,
    contact: ContactBatch<f64>,
    f_ext: Vec<f64>,
    config: [ConfigBatch<f64>; 2],
    /// Each slot's system and whether its tangent is formed (trials form the residual only).
    system: [Option<(ChainBatch<f64>, bool)>; 2],
    current: usize,
    delta: Vec<f64>,
    /// What the update needs to make contact nodes follow their wall (kept in step with
    /// the loads and the base).
    walls: crate::kernels::update::UpdateWalls<f64>,
    /// A relaxation's shift (none: the assembly runs without it).
    shift: Option<Shift<f64>>,
}

impl TwinStatic<'_> {
    fn evaluate_slot(&mut self, slot: usize, tangent: bool) {
        let c = &self.config[slot];
        let system = twin_evaluate(
            self.model,
            &self.tables,
            &mut self.contact,
            &c.x,
            &c.rot,
            &self.f_ext,
            tangent,
            None,
            self.shift.as_ref(),
        );
        self.system[slot] = Some((system, tangent));
    }

    /// The update's walls from the current tables and law parameters.
    fn refresh_walls(&mut self) {
        let t = &self.tables;
        self.walls = crate::kernels::update::UpdateWalls {
            node_site: t.node_site.clone(),
            pair_base: t.pair_base.clone(),
            pair_normals: t.pair_normals.clone(),
            pair_params: self.contact.pair_params.clone(),
            epoch: std::mem::take(&mut self.walls.epoch),
        };
    }

    fn rhs(&self, slot: usize) -> Result<&[f64], crate::error::SystemError> {
        self.system[slot]
            .as_ref()
            .map(|s| s.0.rhs.as_slice())
            .ok_or(crate::error::SystemError::Order("system not evaluated"))
    }
}

impl ResidentStatic<f64> for TwinStatic<'_> {
    fn set_loads(
        &mut self,
        f_ext: &[f64],
        pair_params: &[f64],
        rest: &[f64],
    ) -> Result<(), crate::error::SystemError> {
        self.f_ext = f_ext.to_vec();
        self.tables.rest = rest.to_vec();
        self.contact.pair_params = pair_params.to_vec();
        self.system = [None, None];
        self.refresh_walls();
        Ok(())
    }
    fn evaluate(&mut self) -> Result<(), crate::error::SystemError> {
        self.evaluate_slot(self.current, true);
        Ok(())
    }
    fn solve(&mut self) -> Result<(Norms<f64>, Vec<u32>), crate::error::SystemError> {
        let sys = match &self.system[self.current] {
            Some((sys, true)) => sys,
            Some((_, false)) => {
                return Err(crate::error::SystemError::Order(
                    "tangent not formed (a trial's residual only)",
                ))
            }
            None => return Err(crate::error::SystemError::Order("system not evaluated")),
        };
        let (delta, status) = block_lu(sys);
        self.delta = delta;
        let ones = vec![1.0; self.tables.num_variants];
        let n = norms(
            &sys.rhs,
            &self.delta,
            &ones,
            self.tables.num_nodes,
            self.tables.num_variants,
        );
        Ok((n, status))
    }
    fn accept_trial(&mut self) {
        self.current = 1 - self.current;
    }
    fn commit(&mut self, alpha: &[f64]) -> Result<(), crate::error::SystemError> {
        update(
            &mut self.config[self.current],
            &self.walls,
            &self.delta,
            alpha,
        );
        self.system[self.current] = None;
        Ok(())
    }
    fn config(&mut self) -> Result<ConfigBatch<f64>, crate::error::SystemError> {
        Ok(self.config[self.current].clone())
    }
    fn set_config(&mut self, config: &ConfigBatch<f64>) -> Result<(), crate::error::SystemError> {
        let c = &mut self.config[self.current];
        c.x.copy_from_slice(&config.x);
        c.rot.copy_from_slice(&config.rot);
        self.system[self.current] = None;
        Ok(())
    }
    fn set_shift(&mut self, shift: Option<&Shift<f64>>) -> Result<(), crate::error::SystemError> {
        self.shift = shift.cloned();
        self.system = [None, None];
        Ok(())
    }
    fn set_landing_epochs(&mut self, epochs: &[u32]) -> Result<(), crate::error::SystemError> {
        self.walls.epoch = epochs.to_vec();
        Ok(())
    }
    fn rebase(&mut self, tables: &BatchTables<f64>) -> Result<(), crate::error::SystemError> {
        self.tables = tables.clone();
        self.refresh_walls();
        self.config[self.current].x.fill(0.0);
        self.system[self.current] = None;
        Ok(())
    }
}

impl ResidentTrials<f64> for TwinStatic<'_> {
    fn trial(
        &mut self,
        alpha: &[f64],
        search: &[bool],
        first: bool,
    ) -> Result<Norms<f64>, crate::error::SystemError> {
        let other = 1 - self.current;
        let mut moved = self.config[self.current].clone();
        update(&mut moved, &self.walls, &self.delta, alpha);
        if first {
            self.config[other] = moved;
        } else {
            // The searching variants' trials; the others keep theirs (as the GPU's masked
            // update leaves them).
            let v = self.tables.num_variants;
            let to = &mut self.config[other];
            for (k, x) in moved.x.iter().enumerate() {
                if search[k % v] {
                    to.x[k] = *x;
                }
            }
            for (k, r) in moved.rot.iter().enumerate() {
                if search[k % v] {
                    to.rot[k] = *r;
                }
            }
            for (k, m) in moved.landed.iter().enumerate() {
                if search[k % v] {
                    to.landed[k] = *m;
                }
            }
        }
        self.evaluate_slot(other, false);
        Ok(norms(
            self.rhs(other)?,
            &self.delta,
            alpha,
            self.tables.num_nodes,
            self.tables.num_variants,
        ))
    }
}

impl KernelPath<f64> for TwinPath {
    fn max_batch(&self, _model: &Model) -> usize {
        usize::MAX
    }
    fn open<'a>(
        &'a self,
        model: &'a Model,
        tables: &BatchTables<f64>,
    ) -> Result<Box<dyn ResidentStatic<f64> + 'a>, crate::error::SystemError> {
        let p = tables.pair_node.len();
        let mut contact = ContactBatch::new(1, p);
        contact.site_normals = tables.pair_normals.clone();
        contact.pair_state = tables.pair_state.clone();
        let mut twin = TwinStatic {
            model,
            tables: tables.clone(),
            contact,
            f_ext: Vec::new(),
            config: [tables.start.clone(), tables.start.clone()],
            system: [None, None],
            current: 0,
            delta: vec![0.0; 6 * tables.num_nodes * tables.num_variants],
            walls: Default::default(),
            shift: None,
        };
        twin.refresh_walls();
        Ok(Box::new(twin))
    }
    fn open_dynamic<'a>(
        &'a self,
        model: &'a Model,
        tables: &BatchTables<f64>,
        dynamic: &dynamic::DynamicTables<f64>,
    ) -> Result<Box<dyn dynamic::ResidentDynamic<f64> + 'a>, crate::error::SystemError> {
        Ok(Box::new(self.dynamic(model, tables, dynamic)))
    }
}
