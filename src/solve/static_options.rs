//! The settings of a static solve and why one fails: shared by the load path
//! ([`crate::solve::continuation`]) and the solve around it ([`crate::solve::statics`]),
//! so neither imports the other's.

use thiserror::Error;

use crate::model::Model;

/// Solver settings.
#[derive(Clone, Copy, Debug)]
pub struct StaticOptions {
    /// Load steps to start with (grown after easy steps, cut on failure).
    pub initial_steps: usize,
    /// Newton iterations per load step.
    pub max_iterations: usize,
    /// Converged when the largest residual force is below `tolerance` × the reference
    /// force (largest of total weight and WOB) and the largest moment below `tolerance` ×
    /// reference force × 1 m.
    pub tolerance: f64,
    /// Smallest load-step size before giving up.
    pub min_step: f64,
    /// Wall-clock budget (s): the solve stops between iterations once it is spent
    /// ([`StaticError::Budget`]); `None`: no limit.
    pub max_seconds: Option<f64>,
    /// Where the load path finds no equilibrium at the full loads, relax to loads between
    /// to bracket where the string stops (a lock-up: [`StaticError::stopped`], with the
    /// state where it stands); `false`: fail there at once, for a caller that needs only
    /// to know that the solve failed (the BHA tendency's trial curvatures: on unseen user
    /// well 3487 the bracket of one such failure took 5.7 s of the main job's 9.5 s).
    pub find_stop: bool,
}

impl Default for StaticOptions {
    /// [`crate::solve::settings::Settings`]' defaults (each documented there).
    fn default() -> Self {
        crate::solve::settings::Settings::default().statics()
    }
}

impl crate::solve::settings::Settings {
    /// The static solve's options.
    pub fn statics(&self) -> StaticOptions {
        StaticOptions {
            initial_steps: self.static_initial_steps,
            max_iterations: self.static_max_iterations,
            tolerance: self.static_tolerance,
            min_step: self.static_min_step,
            max_seconds: self.max_seconds,
            find_stop: true,
        }
    }
}

impl StaticOptions {
    /// The Newton settings of a static solve in a precision of `size` bytes for `models`
    /// (the deep line search where any has a soft law): the one place `solve_static`, the
    /// f64 polish and the ensemble engine take them from.
    pub fn newton<'a>(
        &self,
        size: usize,
        models: impl IntoIterator<Item = &'a Model>,
    ) -> crate::solve::newton::NewtonSettings {
        use crate::solve::newton::NewtonSettings;
        NewtonSettings::statics_for_law(
            self.max_iterations,
            self.tolerance,
            size,
            NewtonSettings::any_soft_law(models),
        )
    }
}

/// Why a static solve failed.
#[derive(Clone, Debug, Error)]
pub enum StaticError {
    /// A stage of the load path could not be completed (a load step even at the smallest
    /// step size).
    #[error("{stage} failed{}: {reason}{}", if *step > 0.0 { format!(" (step {step:.2e}, the smallest allowed {min:.2e})") } else { String::new() }, at_md.map(|md| format!("; the largest residual force was at MD {md:.1} m")).unwrap_or_default())]
    LoadStep {
        /// Which stage: laying the string under gravity, the spring-exponent continuation,
        /// or a step of the bit loads and friction (with its λ).
        stage: String,
        /// Load factor reached.
        from: f64,
        /// Step tried last (0: a stage without steps).
        step: f64,
        /// Minimum step.
        min: f64,
        /// The last failure.
        reason: String,
        /// Where the residual force was largest when it failed (MD, m), where known.
        at_md: Option<f64>,
        /// Where the string stands where its load path bracketed where it stops: the last
        /// equilibrium, at the largest load factor that has one (the CPU solve keeps it;
        /// `None` for every other failure).
        stopped: Option<Box<Stopped>>,
    },
    /// The wall-clock budget ran out before the full load was reached.
    #[error("stopped after {seconds:.1} s (the --max-seconds budget) at {:.1} % of the loads", 100.0 * reached)]
    Budget {
        /// Seconds spent.
        seconds: f64,
        /// Load factor reached.
        reached: f64,
    },
}

/// Where a string stands that stops on its way (a lock-up, [`StaticError::LoadStep`]'s
/// `stopped`): its load path found an equilibrium with the friction and the bit loads at
/// the fraction `lambda` of the operation's and none at `none_at`
/// ([`crate::solve::continuation::LoadPath::stopped_between`]).
#[derive(Clone, Debug)]
pub struct Stopped {
    /// The load factor of the equilibrium (friction coefficients, bit and point loads, and
    /// a bent sub's bend scaled by it; gravity in full).
    pub lambda: f64,
    /// The smallest load factor at which the path found no equilibrium.
    pub none_at: f64,
    /// The model at those loads (`solve::statics::model_at`).
    pub model: Model,
    /// The equilibrium there, the string as it stands when it stops: node displacements
    /// from their places on the hole axis and nodal rotations
    /// (`solve::statics::StaticState`'s; its section forces, contact and reactions:
    /// `solve::statics::stopped_solution`).
    pub u: Vec<crate::physics::vec3::Vec3<f64>>,
    /// See `u`.
    pub rot: Vec<crate::physics::rotation::Mat3<f64>>,
}

/// How a failure in the load path's first stage names it ([`StaticError::LoadStep`]'s
/// `stage`).
pub const GRAVITY_STAGE: &str = "laying the string in the hole under its own weight";

/// How a failure in the load path's second stage names it (followed by the failed step,
/// where one is named).
pub const LOAD_STAGE: &str = "applying the bit loads and friction (stage 2)";

impl StaticError {
    /// Whether the solve failed laying the string in the hole under gravity (the load
    /// path's first stage), before any bit load.
    pub fn in_gravity_stage(&self) -> bool {
        matches!(self, StaticError::LoadStep { stage, .. } if stage.starts_with(GRAVITY_STAGE))
    }

    /// Where the string stands, where the load path bracketed where it stops.
    pub fn stopped(&self) -> Option<&Stopped> {
        match self {
            StaticError::LoadStep { stopped, .. } => stopped.as_deref(),
            StaticError::Budget { .. } => None,
        }
    }

    /// [`StaticError::stopped`], to change.
    pub fn stopped_mut(&mut self) -> Option<&mut Stopped> {
        match self {
            StaticError::LoadStep { stopped, .. } => stopped.as_deref_mut(),
            StaticError::Budget { .. } => None,
        }
    }

    /// [`StaticError::stopped`], taken out of the error.
    pub fn take_stopped(&mut self) -> Option<Box<Stopped>> {
        match self {
            StaticError::LoadStep { stopped, .. } => stopped.take(),
            StaticError::Budget { .. } => None,
        }
    }

    /// The load factor reached before the failure.
    pub fn reached(&self) -> f64 {
        match self {
            StaticError::LoadStep { from, .. } => *from,
            StaticError::Budget { reached, .. } => *reached,
        }
    }
}
