//! A corpus well's flat row of `corpus.csv` (split from `corpus/mod.rs`).

use serde::Serialize;

use super::WellResult;

/// A flat row of `corpus.csv`: the well, then its outcome.
#[derive(Clone, Debug, Serialize)]
pub struct WellRow {
    seed: u64,
    trajectory: &'static str,
    turn: bool,
    total_md_m: f64,
    max_inclination_deg: f64,
    hole_in: f64,
    mode: String,
    wob_n: f64,
    element_m: f64,
    bha_element_m: f64,
    stabilizers: usize,
    bend_deg: f64,
    sites: String,
    wall_stiffness: f64,
    exponent: f64,
    nodes: usize,
    solved: bool,
    load_steps: usize,
    step_cuts: usize,
    relaxed: bool,
    iterations: usize,
    newton_iterations: usize,
    seconds: f64,
    fe_hook_load_n: f64,
    soft_hook_load_n: f64,
    helical_drag_n: f64,
    lock_up_md_m: f64,
    lock_up_fraction: f64,
    whirl_md_m: f64,
    fe_reached: f64,
    stopped_hook_load_n: f64,
    through_wall_mm: f64,
    span_sag_mm: f64,
    wall_sites: usize,
    past_yield: bool,
    hook_load_ratio: f64,
    fe_torque_nm: f64,
    soft_torque_nm: f64,
    torque_ratio: f64,
    error: String,
}

impl WellResult {
    /// The row of `corpus.csv`.
    pub fn row(&self) -> WellRow {
        let s = &self.spec;
        WellRow {
            seed: s.seed,
            trajectory: s.trajectory.name(),
            turn: s.turn,
            total_md_m: s.total_md,
            max_inclination_deg: s.max_inclination_deg,
            hole_in: s.hole_in,
            mode: s.mode.clone(),
            wob_n: s.wob_n,
            element_m: s.element_m,
            bha_element_m: s.bha_element_m,
            stabilizers: s.stabilizers,
            bend_deg: s.bend_deg,
            sites: s.sites.clone(),
            wall_stiffness: s.wall_stiffness,
            exponent: s.exponent,
            nodes: self.nodes,
            solved: self.solved,
            load_steps: self.load_steps,
            step_cuts: self.step_cuts,
            relaxed: self.relaxed,
            iterations: self.iterations,
            newton_iterations: self.newton_iterations,
            seconds: self.seconds,
            fe_hook_load_n: self.fe_hook_load_n,
            soft_hook_load_n: self.soft_hook_load_n,
            helical_drag_n: self.helical_drag_n,
            lock_up_md_m: self.lock_up_md_m,
            lock_up_fraction: self.lock_up_fraction,
            whirl_md_m: self.whirl_md_m,
            fe_reached: self.fe_reached,
            stopped_hook_load_n: self.stopped_hook_load_n,
            through_wall_mm: self.through_wall_mm,
            span_sag_mm: self.span_sag_mm,
            wall_sites: self.wall_sites,
            past_yield: self.past_yield,
            hook_load_ratio: self.hook_load_ratio,
            fe_torque_nm: self.fe_torque_nm,
            soft_torque_nm: self.soft_torque_nm,
            torque_ratio: self.torque_ratio,
            error: self.error.lines().next().unwrap_or_default().to_string(),
        }
    }
}
