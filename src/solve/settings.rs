//! Every solver setting of a run in one struct, each field documented with its default (in
//! the manner of rapier's `IntegrationParameters`): the static solve's options
//! ([`Settings::statics`] → [`crate::solve::static_options::StaticOptions`], and through
//! them its Newton settings) and the integrator's ([`Settings::dynamics`] →
//! [`crate::solve::dynamics::DynamicOptions`]) are derived from it (those two methods live
//! beside the structs they build, so this module imports neither), a default lives in one
//! place and every path (the commands, the ensemble on the CPU and the GPU, the studies)
//! takes the same ones from a case ([`crate::case::Case::settings`]).

use crate::physics::mass::MassKind;

/// The solver settings of a run (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Statics: load steps to start with (grown after easy steps, cut on failure). Default 4.
    pub static_initial_steps: usize,
    /// Statics: Newton iterations per load step. Default 200: contact statics converge
    /// slowly where many nodes leave or reach the wall in one step (one node per iteration
    /// along a string): 200 solves 137 of the first 150 corpus wells, 100 solves 127 and 40
    /// solved 109 (`holewall bench corpus`).
    pub static_max_iterations: usize,
    /// Statics: converged when the largest residual force is below this × the reference
    /// force (largest of total weight and WOB) and the largest moment below this ×
    /// reference force × 1 m. Default 1e-9.
    pub static_tolerance: f64,
    /// Statics: the smallest load step before a path relaxes or fails. Default 1e-4.
    pub static_min_step: f64,
    /// Dynamics: time step (s). Default 1e-3 (a case's `[dynamics] time_step`).
    pub time_step: f64,
    /// Dynamics: the smallest cut step before the run fails (s). Default 1e-7.
    pub min_time_step: f64,
    /// Dynamics: the generalised-α scheme's spectral radius at infinite frequency ρ∞
    /// (Chung–Hulbert, α_m = (2ρ∞ − 1)/(ρ∞ + 1), α_f = ρ∞/(ρ∞ + 1)). Default 0.8 (a case's
    /// `rho_inf`).
    pub rho_inf: f64,
    /// Dynamics: Newton iterations per time step. Default 30.
    pub dynamic_max_iterations: usize,
    /// Dynamics: converged when the residual is below this × the reference force. Default
    /// 1e-8.
    pub dynamic_tolerance: f64,
    /// Dynamics: Rayleigh damping `C = a0 M + a1 K₀` as (a0 in 1/s, a1 in s). Default (0, 0).
    pub rayleigh: (f64, f64),
    /// Dynamics: time to ramp the rotary table from rest to the operation's speed (s).
    /// Default 0.
    pub ramp_time: f64,
    /// Dynamics: lumped or consistent mass. Default lumped.
    pub mass: MassKind,
    /// Dynamics: rate at which the hook lowers a clamped top (m/s, ROP). Default 0.
    pub rop: f64,
    /// Wall-clock budget of the static solve (s): it stops between iterations once spent.
    /// Default none (a command's `--max-seconds`).
    pub max_seconds: Option<f64>,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            static_initial_steps: 4,
            static_max_iterations: 200,
            static_tolerance: 1e-9,
            static_min_step: 1e-4,
            time_step: 1e-3,
            min_time_step: 1e-7,
            rho_inf: 0.8,
            dynamic_max_iterations: 30,
            dynamic_tolerance: 1e-8,
            rayleigh: (0.0, 0.0),
            ramp_time: 0.0,
            mass: MassKind::Lumped,
            rop: 0.0,
            max_seconds: None,
        }
    }
}

impl Settings {
    /// These settings with the static solve's wall-clock budget `max_seconds`.
    pub fn with_max_seconds(self, max_seconds: Option<f64>) -> Self {
        Settings {
            max_seconds,
            ..self
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::dynamics::AlphaParams;

    #[test]
    fn the_options_derived_from_the_settings_carry_every_field() {
        let s = Settings {
            static_initial_steps: 7,
            static_max_iterations: 33,
            static_tolerance: 2e-7,
            static_min_step: 3e-3,
            time_step: 2e-4,
            min_time_step: 5e-9,
            rho_inf: 0.6,
            dynamic_max_iterations: 11,
            dynamic_tolerance: 4e-7,
            rayleigh: (0.5, 1e-4),
            ramp_time: 2.5,
            mass: MassKind::Consistent,
            rop: 0.01,
            max_seconds: Some(9.0),
        };
        let st = s.statics();
        assert_eq!(
            (
                st.initial_steps,
                st.max_iterations,
                st.tolerance,
                st.min_step,
                st.max_seconds
            ),
            (7, 33, 2e-7, 3e-3, Some(9.0))
        );
        let d = s.dynamics();
        assert_eq!(
            (d.dt, d.min_dt, d.max_iterations, d.tolerance),
            (2e-4, 5e-9, 11, 4e-7)
        );
        assert_eq!(d.alpha, AlphaParams::chung_hulbert(0.6));
        assert_eq!((d.rayleigh, d.ramp_time, d.rop), ((0.5, 1e-4), 2.5, 0.01));
        assert_eq!(d.mass, MassKind::Consistent);
        assert!(d.load_factor.is_none());
        assert_eq!(
            Settings::default().with_max_seconds(Some(1.0)).max_seconds,
            Some(1.0)
        );
    }
}
