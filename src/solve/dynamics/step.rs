//! One generalised-α step of the CPU integrator as a Newton system ([`CpuStep`]). Split
//! from `solve/dynamics.rs` (issue 24: no file over 800 lines), behaviour unchanged.

use super::*;

/// One generalised-α step of the CPU integrator as a Newton system (one variant): the
/// unknown is `v̇_{n+1}`; the predictor gives the trial state from it, with the top's
/// prescribed kinematics (table, hook).
pub(super) struct CpuStep<'s, 'a> {
    pub(super) d: &'s mut Dynamics<'a>,
    pub(super) s: &'s DynamicState,
    pub(super) c: crate::solve::statics::Constraints,
    pub(super) h: f64,
    pub(super) hg: f64,
    pub(super) hhb: f64,
    pub(super) table: (f64, f64, f64),
    pub(super) hook: (f64, f64, f64),
    pub(super) driven: bool,
    pub(super) lowered: bool,
    /// The unknown.
    pub(super) vdot: Vec<f64>,
    /// The Newton correction (global axes).
    pub(super) dv: Vec<f64>,
    pub(super) trial: DynamicState,
}

impl<'s, 'a> CpuStep<'s, 'a> {
    pub(super) fn new(d: &'s mut Dynamics<'a>, s: &'s DynamicState, h: f64) -> Self {
        let p = d.options.alpha;
        let ratio = (1.0 - p.alpha_f) / (1.0 - p.alpha_m);
        let t1 = s.t + h;
        let (driven, lowered) = d.top_motion();
        let mut trial = s.clone();
        trial.t = t1;
        let mut step = CpuStep {
            c: constraints(d.model),
            table: d.table(t1),
            hook: d.hook(t1),
            driven,
            lowered,
            hg: h * p.gamma * ratio,
            hhb: h * h * p.beta * ratio,
            h,
            vdot: s.vdot.clone(),
            dv: vec![0.0; s.vdot.len()],
            trial,
            s,
            d,
        };
        // Predictor: v̇_{n+1} = v̇_n, with the top's prescribed accelerations.
        let mut vdot = std::mem::take(&mut step.vdot);
        step.prescribe(&mut vdot);
        step.vdot = vdot;
        step
    }

    /// The top node's prescribed accelerations written into `vd`.
    pub(super) fn prescribe(&self, vd: &mut [f64]) {
        for k in 0..6 {
            if self.c.fixed[0][k] {
                vd[k] = 0.0;
            }
        }
        let n0 = self.d.model.nodes[0].hole_axis;
        for k in 0..3 {
            if self.driven {
                vd[3 + k] = self.table.2 * n0[k];
            }
            if self.lowered {
                vd[k] = self.hook.2 * n0[k];
            }
        }
    }

    /// The state at `t_{n+1}` for the unknown `vdot`, the top's kinematics exact.
    pub(super) fn predict(&self, tr: &mut DynamicState, vdot: &[f64]) {
        let p = self.d.options.alpha;
        let (s, h) = (self.s, self.h);
        let n = self.d.model.nodes.len();
        let ratio = (1.0 - p.alpha_f) / (1.0 - p.alpha_m);
        for dof in 0..6 * n {
            let a1 = ratio * vdot[dof]
                + (p.alpha_f * s.vdot[dof] - p.alpha_m * s.a[dof]) / (1.0 - p.alpha_m);
            tr.vdot[dof] = vdot[dof];
            tr.a[dof] = a1;
            tr.v[dof] = s.v[dof] + h * ((1.0 - p.gamma) * s.a[dof] + p.gamma * a1);
        }
        // Every node in parallel (each moves alone).
        use rayon::prelude::*;
        let a = &tr.a;
        let q = &mut tr.q;
        (q.u.par_iter_mut(), q.rot.par_iter_mut())
            .into_par_iter()
            .enumerate()
            .with_min_len(64)
            .for_each(|(i, (u, rot))| {
                let dq: [f64; 6] = std::array::from_fn(|k| {
                    s.v[6 * i + k] + h * ((0.5 - p.beta) * s.a[6 * i + k] + p.beta * a[6 * i + k])
                });
                for k in 0..3 {
                    u[k] = s.q.u[i][k] + h * dq[k];
                }
                *rot = mat_mul(
                    &rotation_exp(&[h * dq[3], h * dq[4], h * dq[5]]),
                    &s.q.rot[i],
                );
            });
        // The table turns the top about its hole axis n₀, and the hook lowers it along n₀.
        let top = &self.d.model.nodes[0];
        let n0 = top.hole_axis;
        if self.driven {
            tr.q.rot[0] = rotation_exp(&crate::physics::vec3::scale(&n0, self.table.0));
            for k in 0..3 {
                tr.v[3 + k] = self.table.1 * n0[k];
            }
        }
        if self.lowered {
            for k in 0..3 {
                tr.q.u[0][k] = self.hook.0 * n0[k];
                tr.v[k] = self.hook.1 * n0[k];
            }
        }
    }

    /// The unknown moved by `α Δ`, the top's accelerations kept.
    pub(super) fn moved(&self, alpha: f64) -> Vec<f64> {
        let mut v: Vec<f64> = self
            .vdot
            .iter()
            .zip(&self.dv)
            .map(|(x, d)| x + alpha * d)
            .collect();
        self.prescribe(&mut v);
        v
    }
}

impl crate::solve::newton::NewtonSystem for CpuStep<'_, '_> {
    fn variants(&self) -> usize {
        1
    }
    fn solve(&mut self) -> Result<crate::solve::newton::Probe, crate::error::SystemError> {
        let mut trial = std::mem::replace(&mut self.trial, self.s.clone());
        self.predict(&mut trial, &self.vdot);
        let (mut r, mut mat) = self.d.residual_and_matrix(&trial, self.hg, self.hhb, true);
        self.trial = trial;
        constrain(&self.c, &mut r, &mut mat);
        // Scale: the loads, or the inertial forces if larger (a whirling string).
        let n = self.d.model.nodes.len();
        let inertial = (0..n).fold(0.0f64, |m, i| {
            (0..3).fold(m, |m, k| {
                m.max((self.d.mass[i] * self.trial.vdot[6 * i + k]).abs())
            })
        });
        let measure = r.iter().fold(0.0f64, |m, x| m.max(x.abs())) / self.d.f_ref.max(inertial);
        let rhs: Vec<f64> = r.iter().map(|x| -x).collect();
        let solved = match self.d.solver.solve(&mat, &rhs) {
            Ok(mut dv) => {
                // Held nodes (the bit) solve in their hole frame: back to global axes.
                to_global(&self.c, &mut dv);
                self.dv = dv;
                true
            }
            Err(_) => {
                self.dv.fill(0.0);
                false
            }
        };
        Ok(crate::solve::newton::Probe {
            measure: vec![measure],
            step: vec![self.dv.iter().fold(0.0f64, |m, x| m.max(x.abs())) * self.hhb],
            slope: vec![dot_n(&self.dv, &r)],
            norm: vec![dot_n(&r, &r).sqrt()],
            solved: vec![solved],
        })
    }
    fn trial(
        &mut self,
        alpha: &[f64],
        _: &[bool],
        _: bool,
    ) -> Result<crate::solve::newton::TrialProbe, crate::error::SystemError> {
        let cand = self.moved(alpha[0]);
        let mut probe = self.trial.clone();
        self.predict(&mut probe, &cand);
        let (mut rc, _) = self.d.residual_and_matrix(&probe, self.hg, self.hhb, false);
        constrain_residual(&self.c, &mut rc);
        Ok(crate::solve::newton::TrialProbe {
            slope: vec![dot_n(&self.dv, &rc)],
            norm: vec![dot_n(&rc, &rc).sqrt()],
        })
    }
    fn accept(
        &mut self,
        alpha: &[f64],
        _trial_matches: bool,
    ) -> Result<(), crate::error::SystemError> {
        if alpha[0] != 0.0 {
            self.vdot = self.moved(alpha[0]);
        }
        Ok(())
    }
}
