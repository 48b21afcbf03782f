//! The time-step control of every dynamic run: the CPU integrator ([`super::Dynamics::run`])
//! and the ensemble engine (`crate::engine::dynamic`) both step by these rules, so a run
//! that cuts its step takes the same steps on either (to the decisions, which are taken on
//! each path's own residuals).
//!
//! - A run is a **span** `[t0, t_end]` walked in steps of its level `h` (`dt` at the top),
//!   the last one shortened to end on `t_end` ([`next_step`]).
//! - A step whose Newton fails is **cut** to half ([`cut`]); the failed step's interval is
//!   walked again as a span of its own at the half step, and the run goes on from its end.
//!   Below `min_dt` the run fails.
//! - Each run has its **own step**: `dt`, or cut and not yet regrown. After a step that
//!   converged in at most [`EASY_ITERATIONS`] Newton iterations it doubles, up to `dt`
//!   ([`regrown`]). Where a span's next step is longer than the own step, that step's
//!   interval is walked as a span at the own step.
//!
//! So after a cut, the steps stay on the grid of their parent span: the top level's steps
//! end on multiples of `dt`, where the engine's variants are observed together.

use super::{DynamicError, DynamicState, Dynamics};

/// Newton iterations at or below which a converged step lets a cut step double.
pub const EASY_ITERATIONS: usize = 4;

/// A span's next step from `time` at level `h` towards `t_end`: `(step, end)`, the step
/// shortened to end on `t_end`; `None` once the span is done. Where what is left is `h`
/// to rounding (1e-9 of it), the step is `h` itself and ends on `t_end`: a span's end
/// computed another way (a sub-span's, a bounded run's chunk) does not leave a step an ulp
/// off `h` — which a run near stick-slip carries to other cuts.
pub fn next_step(time: f64, t_end: f64, h: f64) -> Option<(f64, f64)> {
    if time < t_end - 1e-12 * t_end.abs().max(1.0) {
        let rest = t_end - time;
        if rest <= h * (1.0 + 1e-9) {
            let step = if (rest - h).abs() <= 1e-9 * h {
                h
            } else {
                rest
            };
            Some((step, t_end))
        } else {
            Some((h, time + h))
        }
    } else {
        None
    }
}

/// Whether a run whose own step is `own` walks a span's step of `step` in sub-steps.
pub fn defers(own: f64, step: f64) -> bool {
    own < step * (1.0 - 1e-9)
}

/// The own step after a step that converged in `iterations` Newton iterations: doubled (up
/// to `dt`) after an easy one where it was cut; `None` where it stays.
pub fn regrown(own: f64, iterations: usize, dt: f64) -> Option<f64> {
    (iterations <= EASY_ITERATIONS && own < dt).then(|| (2.0 * own).min(dt))
}

/// The step after a failed `step`: its half, or `None` below `min_dt` (the run fails).
pub fn cut(step: f64, min_dt: f64) -> Option<f64> {
    let half = step / 2.0;
    (half >= min_dt).then_some(half)
}

impl Dynamics<'_> {
    /// Integrates to `t_end`, calling `observe` after every step, by the step control of
    /// this module: a failed step is cut to half and its interval walked again (logged), a
    /// cut step regrows after easy steps. The own step carries over to the next call.
    pub fn run(
        &mut self,
        s: &mut DynamicState,
        t_end: f64,
        observe: &mut dyn FnMut(&Dynamics, &DynamicState),
    ) -> Result<(), DynamicError> {
        let t0 = s.t;
        self.span(s, t0, t_end, self.options.dt, observe)
    }

    /// Walks `[t0, t_end]` in steps of `h` (this module).
    fn span(
        &mut self,
        s: &mut DynamicState,
        t0: f64,
        t_end: f64,
        h: f64,
        observe: &mut dyn FnMut(&Dynamics, &DynamicState),
    ) -> Result<(), DynamicError> {
        let mut time = t0;
        while let Some((step, t1)) = next_step(time, t_end, h) {
            if defers(self.own_step, step) {
                self.span(s, time, t1, self.own_step, observe)?;
            } else {
                match self.step(s, step) {
                    Ok(its) => {
                        self.iterations.push(its);
                        observe(self, s);
                        if let Some(h) = regrown(self.own_step, its, self.options.dt) {
                            self.own_step = h;
                            self.log
                                .push(format!("t = {:.6} s: step regrown to {h:.3e} s", s.t));
                        }
                    }
                    Err(reason) => {
                        let Some(half) = cut(step, self.options.min_dt) else {
                            return Err(DynamicError::Stalled {
                                t: s.t,
                                step,
                                min_dt: self.options.min_dt,
                                reason: reason.to_string(),
                            });
                        };
                        self.own_step = half;
                        self.log.push(format!(
                            "t = {:.6} s: step {step:.3e} s failed ({reason}); cut to {half:.3e} s",
                            s.t
                        ));
                        self.span(s, time, t1, half, observe)?;
                    }
                }
            }
            // On the span's grid (a sub-span's last step ends on it to rounding).
            s.t = t1;
            time = t1;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_span_ends_on_its_end_and_halves_regrow_to_dt() {
        let mut t = 0.0;
        let mut steps = Vec::new();
        while let Some((h, t1)) = next_step(t, 0.025, 0.01) {
            steps.push(h);
            t = t1;
        }
        assert_eq!(steps.len(), 3);
        assert!((steps[2] - 0.005).abs() < 1e-15);
        assert_eq!(t, 0.025);
        // 0.03 − 0.02 is 0.01 less an ulp: the step is 0.01 itself, ending on 0.03.
        assert_ne!(0.03 - 0.02, 0.01);
        assert_eq!(next_step(0.02, 0.03, 0.01), Some((0.01, 0.03)));
        assert_eq!(cut(0.01, 1e-7), Some(0.005));
        assert_eq!(cut(1.5e-7, 1e-7), None);
        assert_eq!(regrown(0.0025, 4, 0.01), Some(0.005));
        assert_eq!(regrown(0.0025, 5, 0.01), None);
        assert_eq!(regrown(0.008, 1, 0.01), Some(0.01));
        assert_eq!(regrown(0.01, 1, 0.01), None);
        assert!(defers(0.005, 0.01));
        assert!(!defers(0.01, 0.01 * (1.0 - 1e-12)));
    }
}
