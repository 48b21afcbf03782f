//! Load stepping of a static solve, per variant: the one continuation policy that
//! `solve_static` (one variant, faer) and the ensemble engine (V variants, kernels) both
//! run, so a variant fails in the engine exactly where `solve_static` fails.
//!
//! Each variant carries its own load factor λ and step Δλ ([`LoadPath`]):
//! 1. With contact sites, gravity acts in full from the start (the string laid on the wall,
//!    prestressed, [`crate::solve::statics::StaticState::on_low_side`]) with bit loads and
//!    friction off (λ = 0). If that fails and some spring law is not linear, the same state
//!    is reached by continuation of the spring exponent from 1 to its own value (adaptive
//!    steps); with linear laws, by relaxation (below) where the system can relax, else by
//!    continuation in gravity γ from the laid start (steps of 1/4 grown after easy steps,
//!    cut down to 1/64). Without sites every load ramps with λ.
//! 2. λ → 1 in steps (bit loads, point loads and friction scaled by λ): a step taken in at
//!    most 6 iterations grows the next by 1.5. Where a step fails (a fold of the
//!    equilibrium path: a compressed string that snaps into a buckled shape, a contact
//!    onset each side of which has its root on the other) and the system can relax
//!    ([`StaticSystem::relax_scale`]: the CPU solve and the engine), the variant
//!    **relaxes** from the last equilibrium — at once where every spring law is linear; a
//!    soft or hard law first cuts the step in half from the last converged state, down to
//!    `RELAX_AFTER_STEP` (its load steps fail once their residual has not halved in
//!    [`crate::solve::newton::FIRST_HALVING_ITERATIONS`]); a system that cannot relax cuts
//!    down to `min_step` and fails there.
//!    Cutting first, down to `min_step`, cost corpus wells 0, 17 and 28 (horizontal,
//!    10 m elements) 12–13 failed steps of 20–80 iterations each and only found the fold
//!    more closely; relaxing at the first failure took them 1,085 / 1,509 / 1,058 → 683 /
//!    1,059 / 598 Newton iterations (docs/validation.md, stop 56). The relaxation goes to
//!    the full loads by proximal points (`Stage::Relax`): sub-solves of
//!    `r(x) + s (x − a) = 0` for the translations, each from and anchored at the last
//!    one's answer `a`, `s` lowered as they get easy (to `RELAX_FLOOR` × its start) and
//!    raised where one fails (not lowered again to a shift that failed lately), each
//!    solved inexactly (to `RELAX_SUB_REDUCTION` of its residual at the anchor; exactly
//!    while its measure goes round a cycle, `RELAX_CYCLE_REPEATS`), the
//!    anchor carried on by the last move's momentum after `RELAX_MOMENTUM_AFTER`
//!    sub-solves (`RELAX_MOMENTUM`; [`LoadPath::momentum`]), until an
//!    answer is an equilibrium without the shift ([`LoadPath::shift_settled`]; where the
//!    residual stalls below Newton's floor level, or hovers above a best that was below it,
//!    at that state: `RELAX_STALL_SUBS`); it fails at
//!    its budget (`RELAX_MAX_BUDGET`) or once that residual has stopped falling
//!    (`RELAX_STAGNANT_SUBS`). The shift
//!    keeps each sub-solve's tangent positive where the string's own is not, and accepts a
//!    step whose plain residual grows: the path crosses the fold as an overdamped string
//!    would. The same follows a gravity stage that failed.
//! 3. At λ = 1 one more full Newton step polishes the answer to rounding level (so it does
//!    not depend on the load path). In f32 the full load is solved a second time from its
//!    own converged state as base ([`LoadPath::new`]'s `refine`), and so is a relaxation's
//!    answer at the full loads, in f32 and f64 (`Stage::Refine`; where that solve fails,
//!    the first answer stands).
//!
//! [`solve_loads`] runs the paths of every variant of a [`StaticSystem`] through one
//! [`crate::solve::newton::Newton`], all variants advancing in the same evaluations: a variant that completes a
//! step starts its next one in the same iteration, one that fails is returned to its
//! restart point, and a finished one stops costing line searches.

mod driver;
mod progress;
mod relax;

pub use driver::{solve_loads, solve_loads_from, StaticSystem};
pub use progress::Progress;
use relax::*;
pub use relax::{
    carry_anchor, relax_stall_tolerance, rotations_shifted, LOCK_FOUND, ROTATIONS_SHIFTED,
};

use super::newton::{SolveLimits, FOLD_STALL_ITERATIONS};
use super::static_options::{StaticError, StaticOptions, GRAVITY_STAGE, LOAD_STAGE};

/// The loads a variant is solved for: each a factor of the full value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadTarget {
    /// Gravity factor γ.
    pub gravity: f64,
    /// Factor λ of the bit loads and point loads.
    pub lambda: f64,
    /// Factor of the friction coefficients.
    pub friction: f64,
    /// Spring exponent blend `s`: each site's exponent is `1 + s (m − 1)`.
    pub exponent: f64,
}

/// Gravity in full, no bit loads, no friction, linear laws: the first stage's loads.
const GRAVITY_ONLY: LoadTarget = LoadTarget {
    gravity: 1.0,
    lambda: 0.0,
    friction: 0.0,
    exponent: 1.0,
};

/// What follows the end of a step's solve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Next {
    /// Solve the path's next target ([`LoadPath::target`]).
    Step,
    /// The path is done (its last converged state is the answer).
    Finished,
    /// The variant failed ([`LoadPath::error`]).
    Failed,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Stage {
    Gravity,
    GravityRamp,
    Exponent {
        first: bool,
    },
    Load,
    /// Proximal-point relaxation to `target` after a stage failed there (module docs).
    Relax,
    Refine,
    Done,
    Failed,
}

/// The words a relaxation's log line carries (the corpus counts the wells it solved).
pub const RELAXED: &str = "relaxed by proximal points";

/// Whether a solve's `log` says its answer came by relaxation ([`RELAXED`]): the corpus's
/// `relaxed` column and `crate::diagnose::relaxed_warning` read it so.
pub fn relaxed(log: &[String]) -> bool {
    log.iter().any(|l| l.contains(RELAXED))
}

/// One variant's load path (module docs).
#[derive(Clone, Debug)]
pub struct LoadPath {
    stage: Stage,
    has_sites: bool,
    linear_law: bool,
    refine: bool,
    lambda: f64,
    step: f64,
    s: f64,
    s_step: f64,
    g: f64,
    g_step: f64,
    target: LoadTarget,
    min_step: f64,
    max_iterations: usize,
    tolerance: f64,
    /// A relaxation whose unshifted measure stalls below this settles
    /// ([`RELAX_STALL_SUBS`]).
    stall_tolerance: f64,
    gravity_reason: String,
    relax: Option<Relax>,
    /// Newton iterations of every completed step.
    pub iterations: Vec<usize>,
    /// Step cuts and stage changes, with why.
    pub log: Vec<String>,
    /// Why the variant failed, once it has.
    pub error: Option<StaticError>,
    /// Load steps that failed so far (a load path that has met a fold).
    load_failures: usize,
    /// After the relaxation to the full loads failed: where the string stops, bracketed
    /// ([`LoadPath::bracket`]).
    lock: Option<Lock>,
    /// The loads of the step that just converged to an equilibrium (not a relaxation's
    /// unsettled sub-solve), until [`LoadPath::take_equilibrium`] takes them.
    equilibrium: Option<LoadTarget>,
    /// The path failed where its bracket closed: the largest load factor with an
    /// equilibrium and the smallest without ([`LoadPath::stopped_between`]).
    stopped: Option<(f64, f64)>,
    /// The answer came by relaxation past a fold, or f32's second solve at full load
    /// failed from it: a small residual says less there (near a fold the tangent is nearly
    /// singular), so the f32 engine confirms such an answer in f64 (`engine::verify_f32`).
    pub doubtful: bool,
    /// The relaxation just settled at its best state ([`LoadPath::take_back_to_best`]).
    back_to_best: bool,
    /// A relaxation bracketing where the string stops starts from the equilibrium at the
    /// bracket's lower end ([`LoadPath::take_back_to_equilibrium`]).
    back_to_equilibrium: bool,
    /// A step of the path has converged to an equilibrium (not so a polish's path,
    /// [`LoadPath::at_full_load`], until its step converges): one to bracket from.
    any_equilibrium: bool,
    /// The system shifts rotations ([`LoadPath::allow_rotation_shift`]).
    rotations_shift: bool,
    /// [`StaticOptions::find_stop`].
    find_stop: bool,
}

impl LoadPath {
    /// A variant's path: `has_sites` (contact: gravity in full from the start),
    /// `linear_law` (every site's spring exponent is 1: no exponent continuation),
    /// `refine` (f32: full load solved again from its own converged state).
    pub fn new(options: &StaticOptions, has_sites: bool, linear_law: bool, refine: bool) -> Self {
        let step = 1.0 / options.initial_steps.max(1) as f64;
        let mut p = LoadPath {
            stage: if has_sites {
                Stage::Gravity
            } else {
                Stage::Load
            },
            has_sites,
            linear_law,
            refine,
            lambda: 0.0,
            step,
            s: 0.0,
            s_step: 1.0,
            g: 0.0,
            g_step: 0.25,
            target: LoadTarget {
                gravity: 1.0,
                lambda: 0.0,
                friction: 0.0,
                exponent: 1.0,
            },
            min_step: options.min_step,
            max_iterations: options.max_iterations,
            tolerance: relax_tolerance(options, refine),
            stall_tolerance: relax_stall_tolerance(options, refine),
            gravity_reason: String::new(),
            relax: None,
            rotations_shift: false,
            iterations: Vec::new(),
            log: Vec::new(),
            error: None,
            doubtful: false,
            back_to_best: false,
            back_to_equilibrium: false,
            any_equilibrium: false,
            lock: None,
            equilibrium: None,
            stopped: None,
            load_failures: 0,
            find_stop: options.find_stop,
        };
        p.set_target();
        p
    }

    /// A path that solves the full loads in one step from the state it is given (a
    /// polish of a nearby equilibrium; cut like any load step where that fails).
    pub fn at_full_load(options: &StaticOptions) -> Self {
        let mut p = LoadPath::new(options, true, true, false);
        p.stage = Stage::Load;
        p.step = 1.0;
        p.set_target();
        p
    }

    /// A model's path ([`LoadPath::new`] with its sites and spring laws).
    pub fn for_model(options: &StaticOptions, model: &crate::model::Model, refine: bool) -> Self {
        let linear = model.sites.iter().all(|s| s.params.spring_exponent == 1.0);
        LoadPath::new(options, !model.sites.is_empty(), linear, refine)
    }

    fn set_target(&mut self) {
        self.target = match self.stage {
            Stage::Gravity => GRAVITY_ONLY,
            Stage::GravityRamp => LoadTarget {
                gravity: (self.g + self.g_step).min(1.0),
                lambda: 0.0,
                friction: 0.0,
                exponent: 1.0,
            },
            Stage::Exponent { first } => LoadTarget {
                gravity: 1.0,
                lambda: 0.0,
                friction: 0.0,
                exponent: if first {
                    0.0
                } else {
                    (self.s + self.s_step).min(1.0)
                },
            },
            Stage::Load => {
                let lambda = (self.lambda + self.step).min(1.0);
                LoadTarget {
                    gravity: if self.has_sites { 1.0 } else { lambda },
                    lambda,
                    friction: lambda,
                    exponent: 1.0,
                }
            }
            Stage::Relax => match &self.relax {
                Some(r) => r.target,
                None => self.target,
            },
            Stage::Refine | Stage::Done | Stage::Failed => LoadTarget {
                gravity: 1.0,
                lambda: 1.0,
                friction: 1.0,
                exponent: 1.0,
            },
        };
    }

    /// The loads of the step being solved.
    pub fn target(&self) -> LoadTarget {
        self.target
    }

    /// The proximal shift of the sub-solve being run (N/m on the translations; 0 outside a
    /// relaxation).
    pub fn shift(&self) -> f64 {
        self.relaxing().map_or(0.0, |r| r.s)
    }

    /// The relaxation being run (none outside [`Stage::Relax`]).
    fn relaxing(&self) -> Option<&Relax> {
        self.relax.as_ref().filter(|_| self.stage == Stage::Relax)
    }

    /// A shifted sub-solve converged where the residual without the shift has the measure
    /// `measure` ([`StaticSystem::unshifted_measure`]): below the tolerance, the answer is
    /// an equilibrium and the relaxation ends there. Returns whether this sub-solve is the
    /// relaxation's best so far at or below the stall level ([`relax_stall_tolerance`]):
    /// the system is then to keep its state ([`StaticSystem::keep_best`]), the state the
    /// relaxation settles at should its iterates hover above that level from there on
    /// ([`LoadPath::take_back_to_best`]).
    pub fn shift_settled(&mut self, measure: f64) -> bool {
        match (&self.stage, self.relax.as_mut()) {
            (Stage::Relax, Some(r)) => r.settle(measure, self.tolerance, self.stall_tolerance),
            _ => false,
        }
    }

    /// The momentum that carries the next sub-solve's anchor on from the last
    /// ([`StaticSystem::set_shift`]; [`Relax::momentum`]); 0 outside a relaxation.
    pub fn momentum(&self) -> f64 {
        self.relaxing().map_or(0.0, Relax::momentum)
    }

    /// The Newton iterations the solve being run may take, where fewer than the settings'
    /// (a relaxation's shifted sub-solve: `RELAX_SUB_ITERATIONS`).
    pub fn iteration_limit(&self) -> Option<usize> {
        (self.shift() > 0.0).then_some(RELAX_SUB_ITERATIONS)
    }

    /// The limits of the solve being run: [`LoadPath::iteration_limit`], and in a load step
    /// of a path on which one has failed already (it has met a fold) the fold's shorter
    /// stall ([`crate::solve::newton::FOLD_LEVEL`]).
    pub fn limits(&self) -> SolveLimits {
        SolveLimits {
            iterations: self.iteration_limit(),
            fold_stall: (self.stage == Stage::Load && self.load_failures > 0)
                .then_some(FOLD_STALL_ITERATIONS),
            relative: (self.shift() > 0.0 && !self.relaxing().is_some_and(|r| r.cycling))
                .then_some(RELAX_SUB_REDUCTION),
            first_halving: self.stage == Stage::Load && !self.linear_law,
        }
    }

    /// Whether the step being solved ends the path with a polishing step.
    pub fn polish(&self) -> bool {
        match self.stage {
            Stage::Load => self.target.lambda >= 1.0 && !self.refine,
            Stage::Refine => true,
            _ => false,
        }
    }

    /// The loads at which the step that converged last left an equilibrium (a load step,
    /// a gravity step or a relaxation that settled; `None` after a relaxation's
    /// unsettled sub-solve), once: the driver keeps that state
    /// ([`StaticSystem::keep_equilibrium`]), which is where the string stands if the path
    /// later fails where it stops ([`LoadPath::stopped_between`]), and where each
    /// relaxation bracketing that starts ([`LoadPath::take_back_to_equilibrium`]).
    pub fn take_equilibrium(&mut self) -> Option<LoadTarget> {
        self.equilibrium.take()
    }

    /// Whether a relaxation bracketing where the string stops is to start from the
    /// equilibrium the system kept last, at the bracket's lower end
    /// ([`StaticSystem::back_to_equilibrium`]), not from where the last relaxation ended.
    pub fn take_back_to_equilibrium(&mut self) -> bool {
        std::mem::take(&mut self.back_to_equilibrium)
    }

    /// Whether the relaxation just settled at its best state, not at the last sub-solve's
    /// (its unshifted measure reached the stall level once, then hovered above it for
    /// [`RELAX_STALL_SUBS`] sub-solves without a 1 % gain): the system is to return there
    /// ([`StaticSystem::back_to_best`]) before the answer is polished.
    pub fn take_back_to_best(&mut self) -> bool {
        std::mem::take(&mut self.back_to_best)
    }

    /// Where a failed path bracketed where the string stops: the largest load factor at
    /// which it found an equilibrium and the smallest at which it found none (`None` for
    /// every other end).
    pub fn stopped_between(&self) -> Option<(f64, f64)> {
        self.stopped
    }

    /// Whether the path is finished (converged or failed).
    pub fn finished(&self) -> bool {
        matches!(self.stage, Stage::Done | Stage::Failed)
    }

    /// Load factor reached (0 … 1, for progress).
    pub fn progress(&self) -> f64 {
        match self.stage {
            Stage::Done | Stage::Failed => 1.0,
            Stage::Refine => 0.99,
            _ => self.lambda,
        }
    }

    /// The step converged in `iterations`: what follows.
    pub fn converged(&mut self, iterations: usize) -> Next {
        self.iterations.push(iterations);
        self.equilibrium = match (&self.stage, &self.relax) {
            (Stage::Relax, Some(r)) => r.settled.then_some(r.target),
            (Stage::Relax | Stage::Done | Stage::Failed, _) => None,
            _ => Some(self.target),
        };
        self.any_equilibrium |= self.equilibrium.is_some();
        match self.stage {
            Stage::Gravity => self.stage = Stage::Load,
            Stage::GravityRamp => {
                self.g = self.target.gravity;
                if self.g >= 1.0 {
                    self.log.push(format!(
                        "gravity step failed directly ({}); reached by continuation in gravity",
                        self.gravity_reason
                    ));
                    self.stage = Stage::Load;
                } else if iterations <= 6 {
                    self.g_step = (1.5 * self.g_step).min(1.0);
                }
            }
            Stage::Exponent { .. } => {
                self.s = self.target.exponent;
                if self.s >= 1.0 {
                    self.log.push(format!(
                        "gravity step failed directly ({}); reached by continuation of the spring exponent",
                        self.gravity_reason
                    ));
                    self.stage = Stage::Load;
                } else {
                    if iterations <= 6 && !matches!(self.stage, Stage::Exponent { first: true }) {
                        self.s_step = (1.5 * self.s_step).min(1.0);
                    }
                    self.stage = Stage::Exponent { first: false };
                }
            }
            Stage::Load => {
                self.lambda = self.target.lambda;
                if iterations <= 6 {
                    self.step = (self.step * 1.5).min(1.0);
                }
                if self.lambda >= 1.0 {
                    self.stage = if self.refine {
                        Stage::Refine
                    } else {
                        Stage::Done
                    };
                }
            }
            Stage::Relax => {
                let r = self.relax.as_mut().expect("a relaxation");
                r.subs += 1;
                r.iterations += iterations;
                if r.settled {
                    // A sub-solve whose answer is an equilibrium without the shift (or
                    // stalled just above the tolerance): an equilibrium at the target.
                    let stall = match (r.stalled, r.back_to_best) {
                        (Some(m), false) => format!(
                            "; its residual stalled at {m:.1e} of the force scale, above the \
                             tolerance {:.0e}",
                            self.tolerance
                        ),
                        (Some(m), true) => format!(
                            "; its residual fell to {m:.1e} of the force scale, above the \
                             tolerance {:.0e}, and hovered above that since: settled at that \
                             sub-solve's state",
                            self.tolerance
                        ),
                        (None, _) => String::new(),
                    };
                    self.back_to_best = r.back_to_best;
                    self.log.push(format!(
                        "{}; {RELAXED} to an equilibrium at λ = {} ({} sub-solves, {} Newton iterations{stall})",
                        r.reason, r.target.lambda, r.subs, r.iterations
                    ));
                    let target = r.target;
                    self.relax = None;
                    self.doubtful = true;
                    self.lambda = target.lambda;
                    if let Some(mut lock) = self.lock.take() {
                        lock.lo = self.lambda;
                        return self.bracket(lock);
                    }
                    // At the full loads the answer is solved once more without the shift
                    // and polished (`Stage::Refine`): a relaxation settles within the
                    // tolerance, which leaves a buckled string's soft modes µm apart
                    // between paths (the engine's twin and the CPU solve on a bent string,
                    // `tests/bend.rs`: 4.5e-6 m), where a polished answer is the same to
                    // rounding whatever path reached it.
                    self.stage = if self.lambda >= 1.0 {
                        Stage::Refine
                    } else {
                        Stage::Load
                    };
                    if self.stage == Stage::Load && target.lambda == 0.0 {
                        // From the gravity stage: the load steps start afresh.
                        self.step = self.step.max(self.min_step);
                    }
                } else if let Some(why) = r.exhausted(self.max_iterations) {
                    return self.failed(why);
                } else {
                    if iterations <= 5 {
                        r.s /= 4.0;
                    } else if iterations <= 15 {
                        r.s /= 2.0;
                    }
                    // The anchor settles onto the equilibrium (proximal points converge at
                    // the rate `s / (s + k)` per sub-solve along a stiffness `k`); a shift
                    // taken to 0 would leave a plain Newton solve, which two-cycles at a
                    // contact onset near the fold as the load step did.
                    // Not back below a shift that failed lately ([`Relax::failed_at`]).
                    r.s = r.s.max(2.0 * r.failed_at);
                    r.failed_at /= 2.0;
                    r.s = r.s.max(RELAX_FLOOR * r.s0);
                }
            }
            Stage::Refine => self.stage = Stage::Done,
            Stage::Done | Stage::Failed => {}
        }
        self.set_target();
        if self.finished() {
            Next::Finished
        } else {
            Next::Step
        }
    }

    /// The step failed (`reason`): what follows, from the last converged state
    /// ([`Next::Failed`]: the variant has failed, [`LoadPath::error`] says why).
    pub fn failed(&mut self, reason: String) -> Next {
        self.failed_at(reason, None, None)
    }

    /// Starts a relaxation to the loads `target` after a failure (`cause`) of the gravity
    /// stage (`gravity`) or of the load step being solved (`s0`: the system's shift scale).
    fn relax_after(&mut self, target: LoadTarget, s0: f64, cause: String, gravity: bool) -> Next {
        let reason = if gravity {
            format!("the gravity stage failed ({cause})")
        } else {
            format!(
                "load step λ {:.6} → {:.6} failed ({cause})",
                self.lambda, self.target.lambda
            )
        };
        self.relax = Some(Relax {
            target,
            s: s0,
            s0,
            subs: 0,
            iterations: 0,
            settled: false,
            best: f64::INFINITY,
            best_at: 0,
            stalled: None,
            back_to_best: false,
            since_best: Vec::new(),
            cycling: false,
            rotations: false,
            failed_at: 0.0,
            reason,
            cause,
            gravity,
            step: self.step,
        });
        self.stage = Stage::Relax;
        self.set_target();
        Next::Step
    }

    /// As [`LoadPath::failed`], with where the residual force was largest (MD, m) and,
    /// where the system can relax, its shift scale `relax` ([`StaticSystem::relax_scale`]).
    pub fn failed_at(&mut self, reason: String, at_md: Option<f64>, relax: Option<f64>) -> Next {
        // `at_smallest`: the step failed at `min_step` (the message names it), not after a
        // relaxation from it.
        let fail = |p: &mut LoadPath, step: f64, at_smallest: bool, reason: String| {
            let gravity = matches!(
                p.stage,
                Stage::Gravity | Stage::GravityRamp | Stage::Exponent { .. }
            );
            let stage = if gravity {
                format!(
                    "{GRAVITY_STAGE} (stage 1 of the load path: gravity in full, no bit \
                     loads, no friction)"
                )
            } else {
                format!(
                    "{LOAD_STAGE}, the step λ {:.4} → {:.4}",
                    p.lambda,
                    (p.lambda + step).min(1.0)
                )
            };
            p.error = Some(StaticError::LoadStep {
                stage,
                from: p.lambda,
                step: if gravity || !at_smallest { 0.0 } else { step },
                min: p.min_step,
                reason,
                at_md,
                stopped: None,
            });
            p.stage = Stage::Failed;
            Next::Failed
        };
        // The gravity stage's continuation gave up: relax to gravity in full, or fail.
        let give_up_gravity = |p: &mut LoadPath| -> Next {
            let why = std::mem::take(&mut p.gravity_reason);
            if let Some(s0) = relax {
                return p.relax_after(GRAVITY_ONLY, s0, why, true);
            }
            let step = p.step;
            fail(p, step, false, why)
        };
        match self.stage {
            Stage::Gravity => {
                if self.linear_law {
                    if let Some(s0) = relax {
                        // Relax to gravity in full at once: measured on the 500 corpus
                        // wells (`holewall bench corpus`), the continuation in gravity
                        // first solved no well the relaxation did not (486 / 500 either
                        // way, every hook load the same to 1e-6) and cost 8,486 Newton
                        // iterations more (13 wells; 321: 1,747 → 742).
                        return self.relax_after(GRAVITY_ONLY, s0, reason, true);
                    }
                    // A system that cannot relax: continuation in gravity from the laid
                    // start.
                    self.gravity_reason = reason;
                    self.stage = Stage::GravityRamp;
                    self.set_target();
                    return Next::Step;
                }
                // A soft law's onset stiffness is huge and contacts cycle in and out:
                // continue from the linear law to the case's exponent.
                self.gravity_reason = reason;
                self.stage = Stage::Exponent { first: true };
            }
            Stage::Exponent { first } => {
                if first || self.s_step / 2.0 < self.min_step {
                    self.log.push(format!(
                        "exponent continuation failed at s = {:.4}: {reason}",
                        self.s
                    ));
                    return give_up_gravity(self);
                }
                self.s_step /= 2.0;
                self.log.push(format!(
                    "exponent continuation {:.4} → {:.4} failed ({reason}); step cut to {:.3e}",
                    self.s, self.target.exponent, self.s_step
                ));
            }
            Stage::GravityRamp => {
                // Gravity steps below 1/64 have not been seen to help (corpus): give up there.
                if self.g_step / 2.0 < self.min_step.max(1.0 / 64.0) {
                    self.log.push(format!(
                        "continuation in gravity failed at γ = {:.4}: {reason}",
                        self.g
                    ));
                    return give_up_gravity(self);
                }
                self.g_step /= 2.0;
                self.log.push(format!(
                    "gravity step γ {:.4} → {:.4} failed ({reason}); step cut to {:.3e}",
                    self.g, self.target.gravity, self.g_step
                ));
            }
            Stage::Refine => {
                // The second solve at full load (f32's, or after a relaxation) did not
                // converge: the first answer stands.
                self.log.push(format!(
                    "full load solved again from its own state failed ({reason}); the first solution kept"
                ));
                self.doubtful = true;
                self.stage = Stage::Done;
                return Next::Finished;
            }
            Stage::Load => {
                self.load_failures += 1;
                // With linear spring laws the first load step that fails relaxes; with a
                // soft or hard law the step is cut down to `RELAX_AFTER_STEP` first.
                let relax = relax.filter(|_| {
                    self.linear_law || self.step / 2.0 < RELAX_AFTER_STEP.max(self.min_step)
                });
                if let Some(s0) = relax {
                    // The relaxation goes from the last equilibrium to the full loads at
                    // once: the sub-solves follow the string past the fold as far as it
                    // goes (measured on corpus well 17: relaxing to each failed step's
                    // loads instead took 18 relaxations and 3.3× the time; on the lock-up
                    // failure 419 it got from λ 0.25 to 0.5 and failed there, stop 63).
                    // Cutting the step down to `min_step` first only found where the fold is.
                    let target = LoadTarget {
                        lambda: 1.0,
                        friction: 1.0,
                        ..self.target
                    };
                    return self.relax_after(target, s0, reason, false);
                }
                if self.step / 2.0 < self.min_step {
                    return fail(self, self.step, true, reason);
                }
                self.log.push(format!(
                    "load step λ {:.6} → {:.6} failed ({reason}); step cut to {:.3e}",
                    self.lambda,
                    self.target.lambda,
                    self.step / 2.0
                ));
                self.step /= 2.0;
            }
            Stage::Relax => {
                let r = self.relax.as_mut().expect("a relaxation");
                r.subs += 1;
                r.iterations += RELAX_SUB_ITERATIONS.min(self.max_iterations);
                r.failed_at = r.s;
                r.s *= 4.0;
                let ends = r.exhausted(self.max_iterations);
                // Not in a failure's bracket (`self.lock`; `RELAX_ROTATION_SHIFT`).
                let again = ends.is_none()
                    && self.lock.is_none()
                    && r.rotations_at_ceiling(self.rotations_shift);
                if again {
                    let line = r.rotations_note(&reason);
                    self.log.push(line);
                } else if r.s > RELAX_CEILING * r.s0 || ends.is_some() {
                    // A sub-solve that failed as the relaxation ran out says both.
                    let reason = match ends {
                        Some(e) if !reason.contains(&e) => format!("{reason}; {e}"),
                        _ => reason,
                    };
                    let r = self.relax.take().expect("a relaxation");
                    self.log.push(format!(
                        "relaxation after \"{}\" stopped after {} sub-solves ({} Newton iterations): {reason}",
                        r.reason, r.subs, r.iterations
                    ));
                    self.stage = if r.gravity {
                        Stage::GravityRamp
                    } else {
                        Stage::Load
                    };
                    self.step = r.step;
                    if !r.gravity {
                        let lock = match self.lock.take() {
                            Some(lock) => Lock {
                                hi: r.target.lambda,
                                ..lock
                            },
                            None => Lock {
                                lo: self.lambda,
                                hi: r.target.lambda,
                                // The step that failed, named (the stage's words name
                                // the bracket instead).
                                why: format!(
                                    "{}; relaxation by proximal points found no equilibrium \
                                     at the full loads either ({} sub-solves, {} Newton \
                                     iterations; last: {reason})",
                                    r.reason, r.subs, r.iterations
                                ),
                                s0: r.s0,
                            },
                        };
                        return self.bracket(lock);
                    }
                    let why = format!(
                        "{}; relaxation by proximal points found no equilibrium past it either ({} sub-solves, {} Newton iterations; last: {reason})",
                        r.cause, r.subs, r.iterations
                    );
                    return fail(self, r.step, false, why);
                }
            }
            Stage::Done | Stage::Failed => return Next::Failed,
        }
        self.set_target();
        Next::Step
    }
}

#[cfg(test)]
mod tests;
