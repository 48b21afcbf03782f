//! The relaxation's state and constants ([`super::Stage::Relax`]): its budget, its
//! sub-solves, when it settles, stops or starts, and the bracket of where the string stops
//! after it failed. The policy that drives them is [`super::LoadPath`]'s.

use super::{LoadTarget, Next, Stage};
use crate::solve::newton::NewtonSettings;
use crate::solve::static_options::StaticOptions;
use crate::solve::static_options::{StaticError, LOAD_STAGE};

/// Sub-solves a relaxation may take before the variant fails (a run of one- or
/// two-iteration sub-solves at the smallest shift that never settles would otherwise spend
/// the iteration budget many times over). Corpus well 126 (horizontal, sliding, 5 m
/// elements) settles after 499 (1,492 Newton iterations); at 400 it failed. Raised from
/// 1,000 with [`RELAX_MAX_BUDGET`].
pub(super) const RELAX_MAX_SUBS: usize = 5000;
/// Newton iterations a relaxation may take before the variant fails, in units of a step's
/// `max_iterations` (a failed sub-solve counted in full). 15 (3,000 iterations) ended
/// every relaxation of the 14 corpus wells that failed (`holewall bench corpus --wells
/// 500`); at 100 (20,000) five of them settle at the full load, after 4,581–13,689 Newton
/// iterations (wells 173, 263, 381, 44 and 195; 18–156 s): a buckled string's soft lateral
/// modes converge at `s / (s + k)` per sub-solve. The cost falls on wells that fail anyway:
/// 200–620 s instead of 30–160 s (bounded by `--max-seconds`). A relaxation that settles
/// within the old budget takes the same path.
pub(super) const RELAX_MAX_BUDGET: usize = 100;
/// A relaxation fails once its unshifted measure ([`super::LoadPath::shift_settled`]) has not
/// improved by 1 % in this many sub-solves. On the lock-up failures of the corpus the
/// measure stops falling within a few hundred sub-solves and the relaxation then spent the
/// rest of [`RELAX_MAX_BUDGET`]: corpus well 419 (horizontal, tripping in, 2 m elements)
/// had its best (6.5e-6 of the force scale) at sub-solve 244 and ran on to 1,364 sub-solves
/// and 20,031 Newton iterations; with this bound 11,884. The longest run without a 1 % gain
/// in a relaxation that settled, over the 54 of the relaxed wells of seeds 0–499 and the
/// unseen 754 (`holewall bench corpus --wells 1 --first-seed S`): 359 sub-solves (well 44),
/// then 98 (283) and 75 (90); their paths are unchanged (docs/performance.md, stop 64).
pub(super) const RELAX_STAGNANT_SUBS: usize = 500;
/// Newton iterations of a shifted sub-solve before it fails (and the shift is raised): the
/// shift makes each a well-posed problem that converges in a few, or does not at all. A
/// sub-solve that fails mostly two-cycles at a contact onset from its first updates on, and
/// the failed ones cost more than those that converge (traced at 30 on the relaxed wells of
/// corpus seeds 0–499: 419, 12,720 Newton iterations in 424 failed sub-solves against
/// 7,281 in the rest; 44, 4,260 against 3,447), while 96 % of those that converge take 20
/// or fewer. Measured on the 61 relaxed wells of seeds 0–499 and the unseen 754 (`holewall
/// bench corpus --wells 1 --first-seed S`; stop 65): at 30, 73,135 Newton iterations; at
/// 25, 74,248; at 20, 66,359 (all 62 solved; 754 797 → 701, 283 8,104 → 5,669, 44 8,713
/// → 5,442, 173 3,620 → 1,645; 195 5,631 → 7,374); at 15, 53,313 on the 59 it solves, but
/// wells 90, 195 and 263 fail. The lock-ups fail at the same brackets with fewer (795 24,341 →
/// 18,865, 214 32,587 → 25,093).
pub(super) const RELAX_SUB_ITERATIONS: usize = 20;
/// A shifted sub-solve ends once an update has brought its residual measure to this
/// fraction of its value at the anchor (or below the tolerance): the proximal points are
/// solved inexactly, as pseudo-transient continuation takes a Newton step or two per
/// pseudo-time step, since only the last one, the equilibrium, needs to be exact (its
/// unshifted measure is tested against the tolerance, [`super::LoadPath::shift_settled`]).
/// Measured on the 11 slow relaxed wells at 10 m elements (corpus seeds 525, 283, 134,
/// 221, 312, 206, 28, 294, 226, 17, 0; `holewall bench corpus --wells 1 --first-seed S`),
/// with the shift's memory ([`Relax::failed_at`]): 24,854 Newton iterations solved to the
/// tolerance, 20,198 at 0.5, 21,150 at 0.9; 0.1 without the memory 29,112 against 30,450.
pub(super) const RELAX_SUB_REDUCTION: f64 = 0.5;
/// A relaxation settles where its unshifted measure has not improved by 1 % in this many
/// sub-solves and is below the residual a Newton solve accepts at its rounding floor
/// (`super::relax_stall_tolerance`; 1e-6 of the force scale in f64) — or, where the
/// measure now hovers above that level but its best (the last 1 % gain) was at or below
/// it, at the best sub-solve's state, which the system keeps for it (stop 77: unseen user
/// well 0 with the written-out tangent reached 8.8e-7 at sub-solve 957, hovered above 1e-6
/// for the next 500 and failed; on the relaxed set, docs/performance.md, stop 77, 123,744
/// → 120,447 Newton iterations with the dual-number tangent, every well solved). Measured on corpus well 0 (horizontal, sliding, 532 nodes): the measure fell
/// to 1.7e-9 of the force scale in 156 sub-solves and stayed at 1.98e-9 (2 mN of a 1 MN
/// force scale) for the next 840 until the sub-solve bound ended it — the smallest residual
/// sits at a contact onset's kink, as the load step's two-cycle did; on well 126, which
/// settles, the measure stalled near 1e-6 for 130 sub-solves before falling on to 1e-9.
/// 20, not 50 (stop 56): the same paths and answers (hook loads within 0.1 N), 60 Newton
/// iterations fewer on each of corpus wells 0, 17, 28 and 68 at 10 m elements (683 → 623,
/// 1,059 → 999, 598 → 538, 580 → 520) — 5–10 % of them once the failed load steps before
/// a relaxation were gone (stop 50 measured 2.4 % with them).
pub(super) const RELAX_STALL_SUBS: usize = 20;
/// A relaxation whose unshifted measure, since its last 1 % gain, has repeated itself
/// with a period of 2 to [`RELAX_CYCLE_LONGEST`] converged sub-solves this many times over
/// (each value within [`RELAX_CYCLE_MATCH`] of the one a period before, the values spanning
/// a factor of at least [`RELAX_CYCLE_SPAN`]) goes round a cycle: its sub-solves are then
/// solved exactly (to the tolerance, within [`RELAX_SUB_ITERATIONS`]) rather than to
/// [`RELAX_SUB_REDUCTION`] of their start, until its next 1 % gain ([`Relax::settle`]).
/// Inexact sub-solves next to a contact's onset can cycle: unseen user well 2047
/// (horizontal, rotating with a 0.71° motor, 1 m elements, 5,467 nodes) reached 4.4e-6 of
/// the force scale and then went round a cycle of six to eight sub-solves (1.6e-5 → 1.1e-4
/// → 1.6e-5, growing by about 1 % a cycle; the largest residual always at the node 2.3 m
/// above the bit, beside the bend) until [`RELAX_STAGNANT_SUBS`] failed it; momentum off
/// made no difference. Switching to exact sub-solves after a fixed number of stagnant ones
/// instead solved 2047 at every number tried but lost other wells that crawl (lock-ups
/// that solve) at most of them (docs/performance.md, stop 84): a crawl is not a cycle, and
/// neither drawn 263 nor user 1982 repeats its measure so (their traces; 0 detections).
pub(super) const RELAX_CYCLE_REPEATS: usize = 3;
/// The longest period [`RELAX_CYCLE_REPEATS`] looks for (converged sub-solves).
pub(super) const RELAX_CYCLE_LONGEST: usize = 12;
/// How close a cycle's values come back ([`RELAX_CYCLE_REPEATS`]; relative).
pub(super) const RELAX_CYCLE_MATCH: f64 = 0.1;
/// The least span (largest over smallest) of a cycle's values ([`RELAX_CYCLE_REPEATS`]): a
/// crawl's near-constant measure is not a cycle.
pub(super) const RELAX_CYCLE_SPAN: f64 = 3.0;

/// The momentum of a relaxation's anchor once it has taken [`RELAX_MOMENTUM_AFTER`]
/// sub-solves ([`Relax::momentum`]): an inertial proximal point iteration (the anchor
/// carried on by `β` times the last sub-solve's move, as the heavy ball of Polyak and the
/// inertial proximal method of Alvarez and Attouch), whose slow modes — a buckled string's
/// soft lateral modes, stiffness `k` well below the shift `s` — close at about
/// `k / (s (1 − β))` a sub-solve instead of `k / s`: ten times as fast at 0.9. Measured
/// (`holewall bench corpus --seeds …`, the relaxed set of docs/performance.md, stop 78):
/// at 0.9 from the 20th sub-solve, 68,481 → 62,328 Newton iterations on its 64 drawn wells
/// and 51,966 → 46,797 on its 38 user wells, all 102 solved; the slowest at 10 m elements,
/// drawn 283, 7,790 → 4,218 and user 94, 5,879 → 1,710. At 0.9 from the first sub-solve:
/// the user wells 40,503, but the drawn 72,447 and well 90 lost (short relaxations near a
/// contact onset overshoot); from the 20th, a relaxation that settles sooner keeps its path.
/// On the five slowest wells at 10 m elements (drawn 283, 1511; user 94, 461, 471) 20,573
/// Newton iterations without momentum, 11,847 with it from the 20th sub-solve, 12,139 from
/// the first; restarting it wherever the unshifted measure rose kept less of the gain
/// (15,278), as did growing it as `(m − 1) / (m + 2)` over the `m` sub-solves since a rise
/// or a failure, Nesterov's schedule (14,176; restarted at failures only, 16,852).
pub(super) const RELAX_MOMENTUM: f64 = 0.9;
/// Sub-solves a relaxation takes before its anchor carries momentum ([`RELAX_MOMENTUM`]).
pub(super) const RELAX_MOMENTUM_AFTER: usize = 20;

/// Carries a proximal shift's anchor on, in place ([`super::StaticSystem::set_shift`]):
/// `anchor`, set to the state `x`, becomes `x + β (x − x₋)` on flat coordinates; it stays
/// at `x` where `β` is 0 or there is no earlier anchor state (`base` empty).
pub fn carry_anchor(anchor: &mut [f64], base: &[f64], beta: f64) {
    if beta == 0.0 || base.len() != anchor.len() {
        return;
    }
    for (a, b) in anchor.iter_mut().zip(base) {
        *a += beta * (*a - b);
    }
}

/// The smallest shift, `s0 ×` this: the proximal points converge at the rate `s / (s + k)`
/// per sub-solve along a stiffness `k`, and a buckled string's lateral modes are soft (a
/// span's `EI / L³` less its compression's share), so a high floor costs hundreds of
/// sub-solves. Measured (`holewall bench corpus --wells 500`) when the relaxation started
/// at the first step that failed at `min_step` (the two jumps to the rest of the load that
/// came before it dropped; it starts at the first failed step now): 1e-5 instead of 1e-3
/// — 486 / 500 solved against 478, every gravity-stage failure gone, Newton iterations
/// 285,931 → 175,519; on the slow wells at 10 m elements (0, 17, 221, 226, 294, 312)
/// sub-solves 367–682 → 59–119. 1e-7 measured the same as 1e-5 on those wells.
pub(super) const RELAX_FLOOR: f64 = 1e-5;
/// With a soft or hard spring law, a failed load step is cut in half down to this size
/// before the path relaxes (linear laws relax at the first failure). A soft law's onset
/// needs small steps: `tests/case_files.rs`
/// `soft_spring_laws_solve_a_two_stabilizer_deviated_well` (m = 0.1) solves by cuts down to
/// a step of 0.026, and relaxing where a step of 0.053 failed (or at the first failure)
/// runs its relaxation out (5,001 sub-solves, no equilibrium). Cutting on down to
/// `min_step` (1e-4, before stop 63) only located the fold where there is one: on the 46
/// soft-law (m = 2/3) wells of the 500-well corpus (`holewall bench corpus --wells 1
/// --first-seed S`) 15,888 → 16,144 Newton iterations, 30.3 → 30.0 s, all 46 solved; well
/// 221 (10 m elements, relaxed past a fold) 1,428 → 994 iterations, 2.3 → 1.5 s, well 134
/// 1,454 → 1,249, 376 1,539 → 1,198, the lock-up 283 6,994 → 8,104; the 51 hard-law (m =
/// 3/2) wells 4,635 → 4,478, 13.6 → 13.4 s. The same wells with m = 0.3 (stiffness scaled
/// to the same force at 1 mm) all solve either way (221 584 → 432 iterations of converged
/// steps). At 1 (relax at the first failure) the m = 2/3 wells took 14,143 iterations, but
/// the m = 0.1 case fails; at 1/16 13,736, and it fails.
pub(super) const RELAX_AFTER_STEP: f64 = 1.0 / 64.0;
/// A shift above `s0 ×` this ends a relaxation that cannot make progress — or, the first
/// time, on a system that can ([`super::StaticSystem::shifts_rotations`]), starts it again
/// from `s0` with the rotations shifted too ([`RELAX_ROTATION_SHIFT`]).
pub(super) const RELAX_CEILING: f64 = 1e6;
/// The rotations' shift (N·m/rad) per unit of the translations' (N/m), in m², of a
/// relaxation whose translational shift reached [`RELAX_CEILING`]: sub-solves that fail
/// even at a translational shift of a million times its start fail in the rotations,
/// which that shift does not touch. Unseen user well 3163 (horizontal, drilling with a
/// 1.66° motor 1.4 m above the bit, 1 m BHA elements) at 30 and 35 m pipe elements ended
/// its relaxation there after 12 sub-solves and failed (it solves at 5–32 m and 40 m); with
/// the rotations shifted from the start at 0.01, 0.1 and 1 m² it solved at 30 m (117,
/// 171, 904 sub-solves; 187.36 kN against the soft string's 187.40), at 100 m² it failed.
/// Shifting them in every relaxation moved every relaxed path and lost user well 0
/// (docs/performance.md, stop 87); from the ceiling on, only relaxations that end there
/// otherwise change — not those bracketing where a failed path stops, where it took the
/// lock-up 2915 from 38,048 Newton iterations to 74,657 and failed as before.
pub(super) const RELAX_ROTATION_SHIFT: f64 = 0.01;
/// Where the relaxation to the full loads failed, relaxations up from the last equilibrium
/// in steps of this width of the load factor bracket where the string stops
/// ([`super::LoadPath::bracket`]; at most seven from a failure at the first step).
pub(super) const LOCK_BRACKET: f64 = 0.125;
/// The words of the log line of a relaxation that reached its ceiling and shifted the
/// rotations too ([`RELAX_ROTATION_SHIFT`]; the corpus counts the wells it solved).
pub const ROTATIONS_SHIFTED: &str = "the rotations shifted too from there";

/// Whether a solve's `log` says a relaxation shifted its rotations ([`ROTATIONS_SHIFTED`]).
pub fn rotations_shifted(log: &[String]) -> bool {
    log.iter().any(|l| l.contains(ROTATIONS_SHIFTED))
}

/// The words of a failure whose load path bracketed where the string stops
/// (`super::LoadPath::bracket`); `crate::diagnose::static_failure` reads them.
pub const LOCK_FOUND: &str = "relaxations up from the last equilibrium found one at";

/// A relaxation's state ([`super::Stage::Relax`]).
#[derive(Clone, Debug)]
pub(super) struct Relax {
    /// The loads relaxed to (the failed step's).
    pub(super) target: LoadTarget,
    /// Shift now (N/m; never below [`RELAX_FLOOR`] × `s0`).
    pub(super) s: f64,
    /// The starting shift (the system's scale).
    pub(super) s0: f64,
    /// Sub-solves so far.
    pub(super) subs: usize,
    /// Newton iterations so far.
    pub(super) iterations: usize,
    /// The last sub-solve's answer is an equilibrium without the shift
    /// ([`super::LoadPath::shift_settled`]).
    pub(super) settled: bool,
    /// The smallest unshifted measure so far (improved by at least 1 %) and the sub-solve
    /// it came at.
    pub(super) best: f64,
    pub(super) best_at: usize,
    /// Settled on a stall: the unshifted measure it stalled at.
    pub(super) stalled: Option<f64>,
    /// Settled at the best sub-solve's state, not the last one's: the driver is to return
    /// the system there ([`super::LoadPath::take_back_to_best`]).
    pub(super) back_to_best: bool,
    /// The unshifted measures of the converged sub-solves since the best, the last
    /// `(RELAX_CYCLE_REPEATS + 1) × RELAX_CYCLE_LONGEST` of them ([`RELAX_CYCLE_REPEATS`]).
    pub(super) since_best: Vec<f64>,
    /// They go round a cycle: the sub-solves are solved exactly until the next best.
    pub(super) cycling: bool,
    /// The rotations are shifted too ([`RELAX_ROTATION_SHIFT`]; since the translational
    /// shift reached [`RELAX_CEILING`]).
    pub(super) rotations: bool,
    /// The shift of the last sub-solve that failed, halved at each one that converges
    /// since (0: none): the shift is not lowered below twice it, so the next try at that
    /// shift comes after two sub-solves that converge, not one, and from a failure on
    /// easy sub-solves halve the shift rather than quarter it. Without it the shift
    /// ping-ponged (quartered after an easy sub-solve, the next failing after its 30
    /// iterations, raised fourfold, …): corpus well 525 (horizontal, sliding, 10 m
    /// elements) ran 81 failed sub-solves, 2,430 of its relaxation's 3,602 Newton
    /// iterations, and 32 with it (2,811 Newton iterations in all against 4,583); the 11
    /// slow wells named at [`RELAX_SUB_REDUCTION`]: 30,450 → 24,854 Newton iterations.
    pub(super) failed_at: f64,
    /// The failure that started it, with its stage (for the log).
    pub(super) reason: String,
    /// That failure's cause alone: the message if the relaxation fails too, whose stage
    /// ([`StaticError::LoadStep`]'s) already names the step.
    pub(super) cause: String,
    pub(super) gravity: bool,
    pub(super) step: f64,
}

impl Relax {
    /// A sub-solve converged with the unshifted measure `measure`
    /// ([`super::LoadPath::shift_settled`]): whether it settles (below `tolerance`, or
    /// stalled at or below `stall`: [`RELAX_STALL_SUBS`]), and whether the system is to
    /// keep its state as the best so far at or below `stall`.
    pub(super) fn settle(&mut self, measure: f64, tolerance: f64, stall: f64) -> bool {
        let mut keep = false;
        self.settled = measure < tolerance;
        if measure < 0.99 * self.best {
            self.best = measure;
            self.best_at = self.subs;
            keep = measure <= stall;
            self.since_best.clear();
            self.cycling = false;
        }
        self.since_best.push(measure);
        // `goes_round` looks at no more than the last (repeats + 1) × the longest period.
        let kept = (RELAX_CYCLE_REPEATS + 1) * RELAX_CYCLE_LONGEST;
        if self.since_best.len() > kept {
            self.since_best.drain(..self.since_best.len() - kept);
        }
        self.cycling = self.cycling || goes_round(&self.since_best);
        if !self.settled && self.subs >= self.best_at + RELAX_STALL_SUBS {
            if measure <= stall {
                self.settled = true;
                self.stalled = Some(measure);
            } else if self.best <= stall {
                // The iterates hover above the level they reached once: back to that
                // state, which the system kept (`keep` of the best's call).
                self.settled = true;
                self.stalled = Some(self.best);
                self.back_to_best = true;
            }
        }
        keep
    }

    /// The momentum `β` of the next sub-solve's anchor (`a = x + β (x − x₋)`,
    /// [`super::StaticSystem::set_shift`]): 0 for the first [`RELAX_MOMENTUM_AFTER`]
    /// sub-solves, [`RELAX_MOMENTUM`] from there. A sub-solve that failed leaves the state
    /// where its anchor was set (`x = x₋`), so the next one starts without momentum.
    pub(super) fn momentum(&self) -> f64 {
        if self.subs >= RELAX_MOMENTUM_AFTER {
            RELAX_MOMENTUM
        } else {
            0.0
        }
    }

    /// The sub-solve at which the relaxation stops without a 1 % gain of its unshifted
    /// measure ([`RELAX_STAGNANT_SUBS`] after its best; [`Relax::exhausted`], and the
    /// progress bar's note).
    pub(super) fn stagnant_at(&self) -> usize {
        self.best_at + RELAX_STAGNANT_SUBS
    }

    /// Why the relaxation stops without an equilibrium, where it does: its budget
    /// ([`RELAX_MAX_BUDGET`], [`RELAX_MAX_SUBS`]) ran out, or its unshifted measure has not
    /// improved by 1 % in [`RELAX_STAGNANT_SUBS`] sub-solves.
    pub(super) fn exhausted(&self, max_iterations: usize) -> Option<String> {
        if self.iterations >= RELAX_MAX_BUDGET * max_iterations || self.subs >= RELAX_MAX_SUBS {
            Some(format!(
                "the relaxation's budget of {} Newton iterations or {RELAX_MAX_SUBS} sub-solves ran out",
                RELAX_MAX_BUDGET * max_iterations
            ))
        } else if self.subs >= self.stagnant_at() {
            Some(format!(
                "its residual without the shift has not fallen by 1 % in {RELAX_STAGNANT_SUBS} \
                 sub-solves (at best {:.1e} of the force scale, {} sub-solves in)",
                self.best, self.best_at
            ))
        } else {
            None
        }
    }
}

impl Relax {
    /// A sub-solve failed and the shift passed [`RELAX_CEILING`]: where the system shifts
    /// rotations (`allowed`) and they are not shifted yet, the relaxation starts again from
    /// its first shift with them shifted too (and says so, [`Relax::rotations_note`]).
    pub(super) fn rotations_at_ceiling(&mut self, allowed: bool) -> bool {
        if !allowed || self.rotations || self.s <= RELAX_CEILING * self.s0 {
            return false;
        }
        self.rotations = true;
        self.s = self.s0;
        self.failed_at = 0.0;
        true
    }

    /// The log's line for [`Relax::rotations_at_ceiling`], with the last failure `reason`
    /// (it ends with [`ROTATIONS_SHIFTED`]).
    pub(super) fn rotations_note(&self, reason: &str) -> String {
        format!(
            "relaxation after \"{}\": its shift passed {RELAX_CEILING:.0e} times its start after \
             {} sub-solves ({reason}); {ROTATIONS_SHIFTED}",
            self.reason, self.subs
        )
    }
}

impl super::LoadPath {
    /// The rotations' proximal shift of the sub-solve being run (N·m/rad; 0 but in a
    /// relaxation whose translational shift reached its ceiling, [`RELAX_ROTATION_SHIFT`]).
    pub fn rotation_shift(&self) -> f64 {
        self.relaxing()
            .filter(|r| r.rotations)
            .map_or(0.0, |r| RELAX_ROTATION_SHIFT * r.s)
    }

    /// Whether the system shifts rotations ([`super::StaticSystem::shifts_rotations`]): set
    /// by [`super::solve_loads`] before the paths run.
    pub fn allow_rotation_shift(&mut self, yes: bool) {
        self.rotations_shift = yes;
    }

    /// After the relaxation to the full loads failed (the string may stop on its way in):
    /// relaxations up from the largest load with an equilibrium (`lock.lo`) in steps of
    /// [`LOCK_BRACKET`], each from the equilibrium the last one reached
    /// ([`super::LoadPath::take_back_to_equilibrium`]), until one finds none (`lock.hi`) or
    /// the next would pass the full loads' failure; then the path fails, its message saying
    /// where between the two the string stops: the first step up from an equilibrium that
    /// reaches none, as the string is run in with its friction growing. A path that has
    /// reached no equilibrium (a polish, [`super::LoadPath::at_full_load`]) fails at once, as
    /// one without [`StaticOptions::find_stop`] does.
    ///
    /// Until stop 92 the relaxations halved the interval, each from where the last one
    /// ended: after one that failed, a string that had slid on without an equilibrium, from
    /// which the next failed where a relaxation from the equilibrium below settles — and a
    /// relaxation across a wide interval fails where short steps from equilibria pass.
    /// Corpus well 242 at 10 m elements with open-hole friction 0.7 stopped between 0.625 and
    /// 0.719 on the CPU and 0.5 and 0.625 on the engine's twin; halving from the equilibrium
    /// below, between 0.531 and 0.625 on the CPU and above 0.875 on the twin; in steps, above
    /// 0.875 on both (docs/performance.md, stop 92). Corpus well 419 (tripping in, 2 m elements) fails
    /// at its first step, yet the case with its friction scaled to 0.4–0.7 solves on a
    /// path of its own (docs/performance.md, stop 64). Where [`StaticOptions::find_stop`]
    /// is off, the path fails at once, saying why the relaxation failed.
    pub(super) fn bracket(&mut self, lock: Lock) -> Next {
        let closed = lock.hi - lock.lo <= LOCK_BRACKET * (1.0 + 1e-9);
        let bracketing = self.find_stop && self.any_equilibrium;
        if closed || !bracketing {
            // Without `find_stop`, or without an equilibrium on the path to step up from (a
            // polish from a state it was given), the first failure as it is.
            let reason = if bracketing {
                self.log.push(format!(
                    // "The load path", not "the string": a string that is not run in or
                    // out (turning on or off bottom) does not stop (crate::diagnose::stops).
                    "where the load path stops: an equilibrium at λ = {:.4}, none found at λ = {:.4}",
                    lock.lo, lock.hi
                ));
                self.stopped = Some((lock.lo, lock.hi));
                format!(
                    "{}; {LOCK_FOUND} λ = {:.4} and none at λ = {:.4}",
                    lock.why, lock.lo, lock.hi
                )
            } else {
                lock.why
            };
            self.error = Some(StaticError::LoadStep {
                stage: LOAD_STAGE.into(),
                from: lock.lo,
                step: 0.0,
                min: self.min_step,
                reason,
                at_md: None,
                stopped: None,
            });
            self.stage = Stage::Failed;
            return Next::Failed;
        }
        let up = lock.lo + LOCK_BRACKET;
        let target = LoadTarget {
            lambda: up,
            friction: up,
            ..self.target
        };
        let (s0, from) = (lock.s0, lock.lo);
        self.lock = Some(lock);
        self.back_to_equilibrium = true;
        let next = self.relax_after(target, s0, String::new(), false);
        if let Some(r) = self.relax.as_mut() {
            r.reason =
                format!("where the load path stops: relaxation from λ = {from:.4} to {up:.4}");
            r.cause = r.reason.clone();
        }
        next
    }
}

/// Whether the last of `measures` repeat themselves as a cycle ([`RELAX_CYCLE_REPEATS`]).
pub(super) fn goes_round(measures: &[f64]) -> bool {
    (2..=RELAX_CYCLE_LONGEST).any(|p| {
        let w = RELAX_CYCLE_REPEATS * p;
        if measures.len() < w + p {
            return false;
        }
        let n = measures.len();
        let last = &measures[n - w..];
        let (lo, hi) = last.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &m| {
            (lo.min(m), hi.max(m))
        });
        hi >= RELAX_CYCLE_SPAN * lo
            && (n - w..n)
                .all(|i| (measures[i] - measures[i - p]).abs() <= RELAX_CYCLE_MATCH * measures[i])
    })
}

/// Where a path whose relaxation to the full loads failed stops (`super::LoadPath::bracket`).
#[derive(Clone, Debug)]
pub(super) struct Lock {
    /// The largest load factor at which the path has an equilibrium.
    pub(super) lo: f64,
    /// The smallest at which a relaxation found none.
    pub(super) hi: f64,
    /// The full-load relaxation's failure, for the message.
    pub(super) why: String,
    /// The shift scale the relaxations start from.
    pub(super) s0: f64,
}

/// The residual measure below which a relaxation's answer is an equilibrium: in f64 (the
/// CPU solve, the twins, the GPU f64) the solve's tolerance; in f32 (the refining path)
/// the residual an f32 Newton accepts at its rounding floor
/// ([`NewtonSettings::small_residual`]) — measured on the 60 m test bed
/// (`tests/engine_relax.rs`), f32's unshifted residual after a sub-solve stays at
/// 1.0–1.9e-4 of the force scale, above its Newton tolerance 2.4e-5, and a relaxation held
/// to that never settles. The f32 path's closing full-load solve and its f64 check
/// (`engine::verify_f32`) follow.
pub(super) fn relax_tolerance(options: &StaticOptions, f32: bool) -> f64 {
    if f32 {
        relax_stall_tolerance(options, true)
    } else {
        options.tolerance
    }
}

/// The residual measure below which a relaxation whose unshifted measure has stalled
/// ([`RELAX_STALL_SUBS`] sub-solves without a 1 % gain) settles: the residual a Newton
/// solve of that precision accepts once its step is at the rounding floor
/// ([`NewtonSettings::small_residual`]: 1e-6 of the force scale in f64; in f32 that is
/// also [`relax_tolerance`]) — a proximal iteration that can no longer lower its residual
/// stands where a Newton solve that can no longer move would. It was `100 ×` the
/// tolerance (1e-7) until stop 76: unseen corpus well 1827 (horizontal, sliding, 5 m
/// elements, a 5.9e8 N/m wall) stalled at 6.3e-7 and failed after 799 sub-solves, where its
/// neighbours in mesh (2.5, 3 and 10 m) and wall stiffness (5.9e7) solve; at 1e-6 it
/// settles after 228 (hook load 36.5 kN, between theirs). On the relaxed set (102 wells,
/// docs/performance.md, stop 76) 139,939 → 123,744 Newton iterations, all 102 solved, 95
/// with the same path; the hook loads of the other seven within 1 N but drawn 44 (77 N)
/// and 195 (0.9 kN of 32 kN, another member of its family of equilibria).
pub fn relax_stall_tolerance(options: &StaticOptions, f32: bool) -> f64 {
    let size = if f32 { 4 } else { 8 };
    NewtonSettings::statics(options.max_iterations, options.tolerance, size).small_residual
}
