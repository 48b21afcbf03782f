//! [`NewtonSettings`]' constructors: statics, statics by spring law, dynamics, the step's
//! rounding floor.

use super::*;

impl NewtonSettings {
    /// Statics (load steps) in a precision of `size` bytes: `tolerance` on the residual
    /// with steps below 1 µm, the energy-slope line search.
    pub fn statics(max_iterations: usize, tolerance: f64, size: usize) -> Self {
        let u = unit_roundoff(size);
        NewtonSettings {
            max_iterations,
            tolerance: tolerance.max(400.0 * u),
            step_tolerance: 1e-6,
            small_residual: 1e-6f64.max(1e4 * u),
            step_test: StepTest::Taken,
            line_search: LineSearch {
                slope_test: true,
                max_halvings: 5,
                take_smallest: true,
                fallback_halvings: 5,
                memory: true,
            },
            noise_band_at_floor: size == 4,
            stall_iterations: STATIC_STALL_ITERATIONS,
            fold_level: if size == 8 { FOLD_LEVEL } else { 0.0 },
            first_halving: if size == 8 {
                FIRST_HALVING_ITERATIONS
            } else {
                usize::MAX
            },
        }
    }

    /// [`NewtonSettings::statics`] for models of which some have a soft spring law (an
    /// exponent below 1): the line search goes on to α = 2⁻²⁰ before it takes the 1/32
    /// step. A soft law's onset stiffness is `(2 − m) k_e δ_b^(m−1)` (60× k_e at m = 2/3 and
    /// the default blend): near a node's first contact the Newton direction descends only
    /// until that node crosses it, often far less than 1/32 of the step, and the shallow
    /// search that then takes 1/32 regardless cycles there (measured: a two-stabilizer well
    /// at m = 2/3 failed at 59 % of its load; 4 load-step cuts with the deep search). On
    /// linear and hard laws the shallow search is kept: there a deep one accepts tiny
    /// steps and crawls where the 1/32 step pushes through (a 1e10 N/m, μ = 0.9 variant
    /// failed its gravity step with the deep search).
    pub fn statics_for_law(
        max_iterations: usize,
        tolerance: f64,
        size: usize,
        soft_law: bool,
    ) -> Self {
        let mut s = NewtonSettings::statics(max_iterations, tolerance, size);
        if soft_law {
            s.line_search.max_halvings = 20;
        }
        s
    }

    /// Whether any site of `models` has a soft spring law (exponent below 1).
    pub fn any_soft_law<'a>(models: impl IntoIterator<Item = &'a crate::model::Model>) -> bool {
        models
            .into_iter()
            .any(|m| m.sites.iter().any(|s| s.params.spring_exponent < 1.0))
    }

    /// Dynamics (a time step's correction of the accelerations) in a precision of `size`
    /// bytes: the residual line search.
    pub fn dynamics(max_iterations: usize, tolerance: f64, size: usize) -> Self {
        let u = unit_roundoff(size);
        NewtonSettings {
            max_iterations,
            tolerance: tolerance.max(400.0 * u),
            step_tolerance: f64::INFINITY,
            small_residual: 1e-6f64.max(1e4 * u),
            step_test: StepTest::Next,
            line_search: LineSearch {
                slope_test: false,
                max_halvings: 24,
                take_smallest: false,
                fallback_halvings: 24,
                memory: true,
            },
            noise_band_at_floor: size == 4,
            stall_iterations: usize::MAX,
            fold_level: 0.0,
            first_halving: usize::MAX,
        }
    }

    /// The rounding floor of a step for a variant whose largest coordinate (f64: position
    /// from the origin; f32: displacement from its base) is `largest`.
    pub fn step_floor(size: usize, largest: f64) -> f64 {
        if size == 4 {
            100.0 * unit_roundoff(4) * (1.0 + largest)
        } else {
            1e-12 * (1.0 + largest)
        }
    }
}
