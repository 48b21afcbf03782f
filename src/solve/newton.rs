//! The one Newton iteration of holewall: convergence test, line search, step acceptance,
//! and tolerances per precision, for many variants at once with a mask.
//!
//! Every solver calls it — `solve_static` and the CPU integrator (one variant each), the
//! static and dynamic ensemble engines (V variants, twin or GPU kernels) — through
//! [`NewtonSystem`], which knows how to evaluate and solve a problem and nothing about the
//! policy. The caller loops [`Newton::iterate`] (as diffsol's solvers let the caller loop
//! `step()`), starting and stopping variants as its own continuation or step control
//! decides: a variant that is not running gets `α = 0` (its state is not changed) and costs
//! no line search.
//!
//! The policy (the same constants everywhere):
//! - **Converged** when the residual measure (largest residual over the force scale) is
//!   below `tolerance` with a step below `step_tolerance`, or when the step is down at the
//!   variant's rounding floor (`1e-12` of its largest coordinate in f64; `100 ε₃₂` of its
//!   displacements in f32) with the residual below `small_residual` (1e-6 in f64, `1e4 ε₃₂`
//!   in f32), or, for a solve started with [`SolveLimits::relative`] (a relaxation's
//!   inexact sub-solve), once an update has brought the measure to that fraction of its
//!   value at the start. Statics test the step just taken ([`StepTest::Taken`]), dynamics the
//!   correction about to be taken ([`StepTest::Next`], applied on convergence).
//! - **Line search** per variant ([`LineSearch`]): the full step unless it fails the test,
//!   then halved. Statics accept a step whose energy slope `|Δ·r(α)|` does not exceed
//!   `|Δ·r(0)|` or that lowers `‖r‖₂` by `1e-4 α`, halving at most 5 times and taking the
//!   last (α = 1/32); dynamics accept only a lower `‖r‖₂`, halving up to 24 times and
//!   taking the full step when nothing shorter helps. A search whose full step fails
//!   goes on from one halving above the last update's step ([`LineSearch::memory`]):
//!   down from there as before where that fails, up by bisection toward the full step
//!   where it passes, so it takes the longest passing step of the halvings as the plain
//!   search does wherever the steps that pass are the short ones. In f32 a variant whose
//!   residual is at the precision's floor accepts a trial that keeps `‖r‖₂` within twice
//!   its value (its residual norm is rounding noise there, which halving cannot lower) —
//!   but not one that leaves the noise band: a full step along a soft direction (a pinned
//!   stabilizer with μ = 1 on a 1e10 N/m wall) can jump from 4e-4 of the force scale to 150.
//!   A system whose trials wait on a device ([`NewtonSystem::trials_per_round`] > 1: the
//!   GPU engines when `--trial-round` asks; one trial a submission is their default, see
//!   `crate::gpu::batch::trials_per_round`) is asked for the trials after the first in
//!   rounds of 2, 4, 8, … at once (a bisection up, one at a time); the decisions are taken
//!   over them in order, so every variant's steps are those of one trial at a time (issue
//!   27, item 3: fewer round trips).
//! - **Failure** per variant: a non-finite residual, a singular tangent, or no convergence
//!   within `max_iterations` updates, or (statics) a residual that has not halved in
//!   [`STATIC_STALL_ITERATIONS`] (in f64, in [`FIRST_HALVING_ITERATIONS`] where it has not
//!   halved once since the start of a solve started with [`SolveLimits::first_halving`]).
//!   The failing variant stops; the others go on.

/// Which step the convergence test looks at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StepTest {
    /// The update just taken (`α |Δ|`): statics.
    Taken,
    /// The correction about to be taken (`|Δ|`, α = 1), applied on convergence: dynamics.
    Next,
}

/// The line search.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineSearch {
    /// Also accept a step whose energy slope `|Δ·r(α)|` is at most `|Δ·r(0)|`.
    pub slope_test: bool,
    /// Trials after the full step (each halves α).
    pub max_halvings: usize,
    /// When no trial passes: take the small step `α = 2^−fallback_halvings` (`true`) or the
    /// full step.
    pub take_smallest: bool,
    /// The step taken when no trial passes and `take_smallest`.
    pub fallback_halvings: usize,
    /// After the full step fails, go on from one halving above the last update's: down
    /// from there where it fails, up by bisection toward the full step where it passes. A
    /// solve crawling toward a soft wall halves its step at about every update and paid
    /// for every halving again: well 221 (soft law, 10 m), 14,305 → 8,183 trials on the
    /// same 1,835 iterations; dynamic corpus 0–99 148.4 → 133.6 s, 98 of 100 identical
    /// (docs/performance.md, stop 60).
    pub memory: bool,
}

/// Newton settings: iterations, tolerances, line search.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonSettings {
    /// Updates before a variant fails.
    pub max_iterations: usize,
    /// Residual measure that converges (with a step below `step_tolerance`).
    pub tolerance: f64,
    /// Step below which `tolerance` converges (m or rad; ∞: no condition).
    pub step_tolerance: f64,
    /// Residual measure below which a step at the rounding floor converges.
    pub small_residual: f64,
    /// Which step the test looks at.
    pub step_test: StepTest,
    /// The line search.
    pub line_search: LineSearch,
    /// f32: a variant with its residual below `small_residual` accepts a trial that keeps
    /// `‖r‖₂` within twice its value (the rounding-noise band) without a decrease.
    pub noise_band_at_floor: bool,
    /// A solve fails once its residual measure has not halved in this many updates
    /// (`usize::MAX`: never; it then runs to `max_iterations`).
    pub stall_iterations: usize,
    /// A solve started with [`SolveLimits::fold_stall`] stalls after that many updates once
    /// its residual measure is below this level (0: never; f32, whose floor lies near it).
    pub fold_level: f64,
    /// A solve started with [`SolveLimits::first_halving`] whose residual measure has not
    /// halved once since its start fails after this many updates (`usize::MAX`: never;
    /// statics in f64: [`FIRST_HALVING_ITERATIONS`]).
    pub first_halving: usize,
}

/// Statics: a load step's Newton solve that has not halved its residual in this many
/// updates fails (and its step is cut) instead of running on to `max_iterations`. Near a
/// fold a solve two-cycles at a contact onset for its whole budget (corpus well 28: a
/// residual of 4.1e-7 ↔ 1.1e-5 of the force scale, 200 iterations a try, 12 tries down to
/// the smallest step). Measured with [`crate::solve::continuation`]'s jumps: 80 solves 49
/// of the first 50 corpus wells; 30 and 50, tried on wells 17 and 28 only, lose well 28.
pub const STATIC_STALL_ITERATIONS: usize = 80;

/// A load step's solve on a path that has met a fold ([`SolveLimits::fold_stall`]) stalls
/// after [`FOLD_STALL_ITERATIONS`] updates without halving once its residual measure is
/// below this level (f64; f32's floor, `1e4 u₃₂` ≈ 1.2e-3, lies above it). Past a fold a
/// step's equations have no root near the last equilibrium: Newton falls to 1e-5–1e-7 of
/// the force scale in a few iterations and then cycles between the sides of a contact
/// onset (corpus well 312 at 10 m elements: 52 failed tries, every one a stall, 20 of
/// them ending below this level), each try spending [`STATIC_STALL_ITERATIONS`]. Since stop 56
/// a path with linear spring laws relaxes at its first failed load step
/// (`crate::solve::continuation`), so this stall applies where the steps are still cut: a
/// soft or hard law, or a system that cannot relax.
pub const FOLD_LEVEL: f64 = 1e-4;

/// See [`FOLD_LEVEL`]. Measured (`holewall bench corpus`): on seeds 0–49, 49 / 50 solved
/// as with 80, Newton iterations 28,314 → 19,398 and solve time 139 → 113 s; on the 12
/// slowest wells at 10 m elements 64,762 → 39,744 iterations (well 226 solved, 134 lost:
/// its relaxation no longer settles). Applied to every load step from the start instead
/// (not only after a failed one) it cost corpus well 187, whose one slow step converges
/// after 20 flat iterations, 179 → 2,193 iterations; 10 instead of 20 lost nothing on
/// seeds 0–49 but slowed well 28 (1,966 → 3,086).
pub const FOLD_STALL_ITERATIONS: usize = 20;

/// Statics in f64: a load step on a path that cuts its failed steps (a soft or hard spring
/// law; [`SolveLimits::first_halving`]) fails once its residual measure has not halved in
/// this many updates from its start; one that has halved keeps [`STATIC_STALL_ITERATIONS`].
/// Traced on corpus seeds 0–59 of both styles (every load step's Newton measures; stop 79):
/// the 24 load steps that ran the full 80 iterations without once halving their residual
/// all failed (1,920 Newton iterations; drawn well 1511 spent 160 of its 1,381 so
/// before its steps were cut), while 21 that converged had not halved in their first 20
/// (they took 28–200). Applied to every load step, those fail and are cut — and on linear
/// laws, where a first failure relaxes, a well that solved by load steps comes out relaxed
/// (unseen drawn 2068: 77 → 204 iterations), its answer path-dependent; unseen drawn seeds
/// 2012–2071 went 50,926 → 52,320 Newton iterations. On soft and hard laws only
/// (`holewall bench corpus --wells 60 --first-seed S [--style user]`, docs/performance.md,
/// stop 79): drawn seeds 0–59 and 2012–2071 the same but one row (10,479; 50,926 → 51,038),
/// user seeds 0–59 15,997 → 15,274 and 1130–1189 24,144 → 21,135, the relaxed set 109,125
/// → 106,740; every well solved that solved before. Not in f32: a load step near that
/// precision's floor cannot halve its residual.
pub const FIRST_HALVING_ITERATIONS: usize = 20;

/// The unit roundoff of a float type of `size` bytes.
pub fn unit_roundoff(size: usize) -> f64 {
    if size == 4 {
        f64::from(f32::EPSILON)
    } else {
        f64::EPSILON
    }
}

mod settings;

/// What a solve at the current point gives per variant.
#[derive(Clone, Debug, Default)]
pub struct Probe {
    /// Residual measure: largest residual over the variant's force scale.
    pub measure: Vec<f64>,
    /// Largest component of the Newton step `Δ` (α = 1), in the unit of the step test.
    pub step: Vec<f64>,
    /// `Δ·r` at the current point.
    pub slope: Vec<f64>,
    /// `‖r‖₂` at the current point.
    pub norm: Vec<f64>,
    /// Whether the linear solve succeeded.
    pub solved: Vec<bool>,
}

/// What a trial point gives per variant.
#[derive(Clone, Debug, Default)]
pub struct TrialProbe {
    /// `Δ·r(α)`.
    pub slope: Vec<f64>,
    /// `‖r(α)‖₂`.
    pub norm: Vec<f64>,
}

/// A problem of V variants Newton can iterate on.
pub trait NewtonSystem {
    /// Variants V.
    fn variants(&self) -> usize;
    /// Evaluates (where its system is stale) and solves at the current point of every
    /// variant.
    fn solve(&mut self) -> Result<Probe, crate::error::SystemError>;
    /// Evaluates trial points `current + α Δ` for the variants in `search` (their
    /// [`TrialProbe`] entries are read; the others' may be anything). `first`: the first
    /// trial of a line search — every variant's trial point is set (α = 0: the current);
    /// later trials move only the variants in `search`, every other keeps the trial point
    /// it has (a variant whose step was accepted at an earlier trial of the search), so
    /// that [`NewtonSystem::accept`] may take the trial points as they stand. A system may
    /// evaluate more than `search` (one variant's systems do).
    fn trial(
        &mut self,
        alpha: &[f64],
        search: &[bool],
        first: bool,
    ) -> Result<TrialProbe, crate::error::SystemError>;
    /// Line-search trials this system evaluates at most in one round trip
    /// ([`NewtonSystem::trials`]; 1: one at a time). A system whose trials wait on a device
    /// (the GPU engines) may give more: [`Newton::advance`] then asks for the next halvings
    /// of the variants still searching together, speculatively, in rounds of 2, 4, 8, … up
    /// to this, and decides on them in order as it would one by one.
    fn trials_per_round(&self) -> usize {
        1
    }
    /// Evaluates the trials `alphas[0]`, `alphas[1]`, … in that order for the variants in
    /// `search` (the same for every one of them), each as [`NewtonSystem::trial`] would
    /// (`first` applies to the first of them); the candidate left is the last one's. The
    /// default evaluates them one at a time.
    fn trials(
        &mut self,
        alphas: &[Vec<f64>],
        search: &[bool],
        first: bool,
    ) -> Result<Vec<TrialProbe>, crate::error::SystemError> {
        alphas
            .iter()
            .enumerate()
            .map(|(k, a)| self.trial(a, search, first && k == 0))
            .collect()
    }
    /// Current `+= α Δ`. `trial_matches`: the last trial was at exactly these α (its
    /// evaluation may be kept).
    fn accept(
        &mut self,
        alpha: &[f64],
        trial_matches: bool,
    ) -> Result<(), crate::error::SystemError>;
}

/// How a variant's Newton solve ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    /// Converged after this many updates.
    Converged(usize),
    /// Failed: why.
    Failed(String),
}

#[derive(Clone, Debug, Default)]
struct Track {
    running: bool,
    polish: bool,
    finishing: bool,
    updates: usize,
    last_step: f64,
    /// Halvings of the last update's step (0: the full step).
    last_halvings: usize,
    floor: f64,
    /// Updates before this solve fails (`max_iterations` unless started with a limit).
    limit: usize,
    /// The smallest residual measure so far (halved at least) and the update it came at.
    best: f64,
    best_at: usize,
    /// Updates without the residual halving after which a solve already below
    /// [`NewtonSettings::fold_level`] stalls (a load step's solve at a fold), where shorter
    /// than the settings' `stall_iterations`.
    fold_stall: Option<usize>,
    /// Converged at this fraction of `start_measure` ([`SolveLimits::relative`]).
    relative: Option<f64>,
    /// [`SolveLimits::first_halving`].
    first_halving: bool,
    /// The residual measure at the solve's start (NaN before its first test).
    start_measure: f64,
}

/// What limits one solve beside the settings ([`Newton::start_limited`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolveLimits {
    /// Updates before the solve fails, where fewer than the settings' `max_iterations` (a
    /// relaxation's sub-solve).
    pub iterations: Option<usize>,
    /// Updates without the residual halving after which a solve whose residual is already
    /// below [`NewtonSettings::fold_level`] stalls (a load step: [`FOLD_STALL_ITERATIONS`]).
    pub fold_stall: Option<usize>,
    /// Converged once an update has brought the residual measure to this fraction of its
    /// value at the solve's start (an inexact sub-solve of a relaxation).
    pub relative: Option<f64>,
    /// The solve fails after [`NewtonSettings::first_halving`] updates where its residual
    /// measure has not halved once since its start (a load step on a path that cuts its
    /// steps where they fail: a soft or hard spring law).
    pub first_halving: bool,
}

/// One variant's Newton state ([`Newton::state`]).
#[derive(Clone, Debug, Default)]
pub struct NewtonState(Track);

/// The Newton iteration of V variants (see the module docs for its policy).
pub struct Newton {
    /// Settings.
    pub settings: NewtonSettings,
    tracks: Vec<Track>,
    /// Solves (evaluations of the tangent) so far, over all variants together.
    pub solves: usize,
    /// Trials (residual-only evaluations) so far.
    pub trials: usize,
    round: Round,
}

/// What [`Newton::test`] leaves for [`Newton::advance`].
#[derive(Clone, Debug, Default)]
struct Round {
    alpha: Vec<f64>,
    pending: Vec<bool>,
    /// At the precision's floor: the noise band accepts a trial.
    at_floor: Vec<bool>,
    ends: Vec<bool>,
    probe: Probe,
}

impl Newton {
    /// V idle variants.
    pub fn new(settings: NewtonSettings, variants: usize) -> Self {
        Newton {
            settings,
            tracks: vec![Track::default(); variants],
            solves: 0,
            trials: 0,
            round: Round::default(),
        }
    }

    /// Starts a solve of variant `j` from its current point; `floor` is its step's rounding
    /// floor ([`NewtonSettings::step_floor`]); `polish`: after converging, take one more
    /// step (to rounding level), then stop.
    pub fn start(&mut self, j: usize, floor: f64, polish: bool) {
        self.start_limited(j, floor, polish, SolveLimits::default());
    }

    /// As [`Newton::start`], failing after `limit` updates where given (fewer than the
    /// settings' `max_iterations`: a relaxation's sub-solve).
    pub fn start_limited(&mut self, j: usize, floor: f64, polish: bool, limits: SolveLimits) {
        self.tracks[j] = Track {
            running: true,
            polish,
            finishing: false,
            updates: 0,
            last_step: f64::INFINITY,
            last_halvings: 0,
            floor,
            limit: limits.iterations.map_or(self.settings.max_iterations, |l| {
                l.min(self.settings.max_iterations)
            }),
            best: f64::INFINITY,
            best_at: 0,
            fold_stall: limits.fold_stall,
            relative: limits.relative,
            first_halving: limits.first_halving,
            start_measure: f64::NAN,
        };
        if let Some(a) = self.round.alpha.get_mut(j) {
            *a = 0.0;
            self.round.pending[j] = false;
            self.round.ends[j] = false;
        }
    }

    /// Stops variant `j` without an event.
    pub fn stop(&mut self, j: usize) {
        self.tracks[j].running = false;
        if let Some(a) = self.round.alpha.get_mut(j) {
            *a = 0.0;
            self.round.pending[j] = false;
            self.round.ends[j] = false;
        }
    }

    /// Whether variant `j` is running.
    pub fn is_running(&self, j: usize) -> bool {
        self.tracks[j].running
    }

    /// Whether any variant is running.
    pub fn any_running(&self) -> bool {
        self.tracks.iter().any(|t| t.running)
    }

    /// How many variants are running.
    pub fn running_count(&self) -> usize {
        self.tracks.iter().filter(|t| t.running).count()
    }

    /// Variant `j`'s state between iterations, to carry it on in another [`Newton`]
    /// ([`Newton::resume`]) exactly where it stands (a chunk compacted to its running
    /// variants goes on bit for bit).
    pub fn state(&self, j: usize) -> NewtonState {
        NewtonState(self.tracks[j].clone())
    }

    /// Variant `j` goes on from `state` ([`Newton::state`]).
    pub fn resume(&mut self, j: usize, state: NewtonState) {
        self.tracks[j] = state.0;
    }

    /// One iteration of every running variant: [`Newton::test`], then
    /// [`Newton::advance`]. Returns the variants whose solve ended in it, with how.
    pub fn iterate(
        &mut self,
        sys: &mut dyn NewtonSystem,
    ) -> Result<Vec<(usize, Event)>, crate::error::SystemError> {
        let mut events = self.test(sys)?;
        events.extend(self.advance(sys)?);
        Ok(events)
    }

    /// First half of an iteration: solves at the current point of every variant and tests
    /// the running ones. Returns the variants whose solve ended (converged with the step
    /// just taken, or failed); the caller may [`Newton::start`] them again (new load,
    /// restored state) before [`Newton::advance`], which then leaves them in place.
    pub fn test(
        &mut self,
        sys: &mut dyn NewtonSystem,
    ) -> Result<Vec<(usize, Event)>, crate::error::SystemError> {
        let v = self.tracks.len();
        let s = self.settings;
        let probe = sys.solve()?;
        self.solves += 1;
        let mut events = Vec::new();
        self.round = Round {
            alpha: vec![0.0; v],
            pending: vec![false; v],
            at_floor: vec![false; v],
            ends: vec![false; v],
            probe: Probe::default(),
        };
        let round = &mut self.round;
        for (j, track) in self.tracks.iter_mut().enumerate() {
            if !track.running {
                continue;
            }
            let measure = probe.measure[j];
            if !measure.is_finite() {
                track.running = false;
                events.push((j, Event::Failed("residual is not finite".into())));
                continue;
            }
            if track.finishing {
                // The polishing step is taken: done.
                track.running = false;
                events.push((j, Event::Converged(track.updates)));
                continue;
            }
            let step = match s.step_test {
                StepTest::Taken => track.last_step,
                StepTest::Next => probe.step[j],
            };
            if track.updates == 0 {
                track.start_measure = measure;
            }
            let converged = (measure <= s.tolerance && step <= s.step_tolerance)
                || (step <= track.floor && measure <= s.small_residual)
                || track
                    .relative
                    .is_some_and(|eta| track.updates > 0 && measure <= eta * track.start_measure);
            if converged && s.step_test == StepTest::Taken && !track.polish {
                track.running = false;
                events.push((j, Event::Converged(track.updates)));
                continue;
            }
            if !probe.solved[j] {
                track.running = false;
                events.push((j, Event::Failed("singular tangent".into())));
                continue;
            }
            round.at_floor[j] = s.noise_band_at_floor && measure <= s.small_residual;
            if converged {
                round.alpha[j] = 1.0;
                track.polish = false;
                if s.step_test == StepTest::Taken {
                    // Statics: one more step (the polish), with the search, then stop.
                    track.finishing = true;
                    round.pending[j] = true;
                } else {
                    // Dynamics: the converged correction is applied, and the solve ends.
                    round.ends[j] = true;
                }
                continue;
            }
            if measure < 0.5 * track.best {
                track.best = measure;
                track.best_at = track.updates;
            }
            let stall = match track.fold_stall {
                Some(f) if track.best < s.fold_level => s.stall_iterations.min(f),
                // Not halved once since the start (`best` is the start's measure).
                _ if track.first_halving && track.best_at == 0 => {
                    s.stall_iterations.min(s.first_halving)
                }
                _ => s.stall_iterations,
            };
            if track.updates >= track.best_at.saturating_add(stall) {
                track.running = false;
                events.push((
                    j,
                    Event::Failed(format!(
                        "Newton stalled: its residual did not halve in {stall} iterations ({measure:.3e} of the force scale)"
                    )),
                ));
                continue;
            }
            if track.updates >= track.limit {
                track.running = false;
                events.push((
                    j,
                    Event::Failed(format!(
                        "Newton did not converge in {} iterations (residual {measure:.3e} of the force scale)",
                        track.limit
                    )),
                ));
                continue;
            }
            round.alpha[j] = 1.0;
            round.pending[j] = true;
        }
        round.probe = probe;
        Ok(events)
    }

    /// Second half of an iteration: the line search of every running variant (all in the
    /// same trials) and the update. Variants (re)started since [`Newton::test`] stay
    /// where they are. Returns the variants whose solve ended in it.
    pub fn advance(
        &mut self,
        sys: &mut dyn NewtonSystem,
    ) -> Result<Vec<(usize, Event)>, crate::error::SystemError> {
        let v = self.tracks.len();
        let s = self.settings;
        let Round {
            mut alpha,
            mut pending,
            at_floor,
            ends,
            probe,
        } = std::mem::take(&mut self.round);
        if alpha.len() != v {
            return Err(crate::error::SystemError::Order(
                "Newton::advance without Newton::test",
            ));
        }
        let mut events = Vec::new();
        let mut last_finite = vec![true; v];
        let mut fallback_finite = vec![false; v];
        // The α at which each variant's candidate was last evaluated (the first trial sets
        // every variant's; later ones the searching variants'): the trial's evaluation may be
        // kept where every candidate is at its variant's final α.
        let mut candidate: Vec<Option<f64>> = vec![None; v];
        let last_trial = s.line_search.max_halvings;
        let mut search = vec![Search::default(); v];
        let mut trial = 0;
        let mut rounds = 0u32;
        while pending.iter().any(|&p| p) {
            // The first trial alone (most variants take the full step; a system may have it
            // from its solve), then the next trials of the variants still searching in
            // rounds of 2, 4, 8, … up to the system's size: each variant's trials and
            // decisions are those of a search one trial at a time, the later ones of a round
            // speculative (a variant whose search turns within a round leaves the rest of
            // the round's trials unread). (Traced on a dynamic ensemble, V = 256: of the
            // searches, 67 % take the full step, 21 % the first halving, 5 % the second, 7 %
            // the third to sixth; by that count rounds of 2 then 4 cost 24 % more trials than
            // one at a time, a round of 8 at once 140 %.)
            let left = (0..v)
                .filter(|&j| pending[j])
                .map(|j| match search[j].up {
                    Some(_) => 1,
                    None => last_trial + 1 - search[j].depth,
                })
                .max()
                .unwrap_or(1);
            let round = if trial == 0 {
                1
            } else {
                let grown = 1usize << rounds.min(16);
                grown.min(sys.trials_per_round()).clamp(1, left)
            };
            rounds += 1;
            let alphas: Vec<Vec<f64>> = (0..round)
                .map(|k| {
                    (0..v)
                        .map(|j| {
                            // A bisection up has one trial a round (its next depends on it).
                            if pending[j] && search[j].up.is_none() {
                                halved((search[j].depth + k).min(last_trial))
                            } else {
                                alpha[j]
                            }
                        })
                        .collect()
                })
                .collect();
            // Only the variants still searching pay for a trial (issue 27).
            let searching = pending.clone();
            let probes = if round == 1 {
                vec![sys.trial(&alphas[0], &searching, trial == 0)?]
            } else {
                sys.trials(&alphas, &searching, false)?
            };
            if probes.len() != round {
                return Err(crate::error::SystemError::Order(
                    "a round of trials returned another count",
                ));
            }
            self.trials += round;
            for j in 0..v {
                if searching[j] || trial == 0 {
                    candidate[j] = Some(alphas[round - 1][j]);
                }
            }
            for (k, r) in probes.iter().enumerate() {
                for j in 0..v {
                    if !pending[j] || alphas[k][j] != alpha[j] {
                        continue;
                    }
                    let t = search[j].depth;
                    let last = t == last_trial;
                    let a = alpha[j];
                    let finite = r.slope[j].is_finite() && r.norm[j].is_finite();
                    let slope_ok =
                        s.line_search.slope_test && r.slope[j].abs() <= probe.slope[j].abs();
                    let norm_ok = r.norm[j] <= (1.0 - 1e-4 * a) * probe.norm[j];
                    let band_ok = at_floor[j] && r.norm[j] <= 2.0 * probe.norm[j];
                    let pass = finite && (slope_ok || norm_ok || band_ok);
                    let sj = &mut search[j];
                    if let Some((failed, passed)) = &mut sj.up {
                        // Up from a step that passed: the longest that passes, by bisection.
                        if pass {
                            *passed = t;
                        } else {
                            *failed = t;
                        }
                        if *passed - *failed > 1 {
                            sj.depth = (*failed + *passed) / 2;
                        } else {
                            pending[j] = false;
                            sj.depth = *passed;
                        }
                        alpha[j] = halved(sj.depth);
                        continue;
                    }
                    last_finite[j] = finite;
                    if t == s.line_search.fallback_halvings {
                        fallback_finite[j] = finite;
                    }
                    if pass {
                        if sj.jumped_to == Some(t) && t > 1 {
                            // The first step tried after the jump passed: a longer one may.
                            sj.up = Some((0, t));
                            sj.depth = t / 2;
                            alpha[j] = halved(sj.depth);
                        } else {
                            pending[j] = false;
                        }
                    } else if last {
                        pending[j] = false;
                        let skipped = sj
                            .jumped_to
                            .is_some_and(|d| d > s.line_search.fallback_halvings);
                        if !s.line_search.take_smallest {
                            alpha[j] = 1.0;
                        } else if (fallback_finite[j] || skipped)
                            && t != s.line_search.fallback_halvings
                        {
                            // The fallback step (its residual was finite, or it was jumped
                            // over: taken untried, a residual it makes non-finite fails the
                            // next test); else the smallest.
                            alpha[j] = halved(s.line_search.fallback_halvings);
                            last_finite[j] = true;
                        }
                    } else {
                        sj.depth = if t == 0 && s.line_search.memory {
                            // From one halving above the last update's.
                            let d = self.tracks[j]
                                .last_halvings
                                .saturating_sub(1)
                                .clamp(1, last_trial);
                            sj.jumped_to = Some(d);
                            d
                        } else {
                            t + 1
                        };
                        alpha[j] = halved(sj.depth);
                    }
                }
            }
            trial += round;
        }
        let mut trial_matches = (0..v).all(|j| candidate[j] == Some(alpha[j]));
        for (j, track) in self.tracks.iter_mut().enumerate() {
            if track.running && alpha[j] != 0.0 && s.line_search.take_smallest && !last_finite[j] {
                // Every trial down to the smallest α gave a non-finite residual.
                track.running = false;
                alpha[j] = 0.0;
                trial_matches = false;
                events.push((j, Event::Failed("residual is not finite".into())));
            }
        }
        sys.accept(&alpha, trial_matches)?;
        for (j, track) in self.tracks.iter_mut().enumerate() {
            if !track.running || alpha[j] == 0.0 {
                continue;
            }
            if !track.finishing {
                track.updates += 1;
            }
            track.last_step = probe.step[j] * alpha[j];
            track.last_halvings = (-alpha[j].log2()).round().max(0.0) as usize;
            if ends[j] {
                track.running = false;
                events.push((j, Event::Converged(track.updates)));
            }
        }
        Ok(events)
    }
}

/// One variant's line search in [`Newton::advance`].
#[derive(Clone, Copy, Debug, Default)]
struct Search {
    /// Halvings of its next trial.
    depth: usize,
    /// Going up (to longer steps, from a short one that passed: [`LineSearch::memory`]) by
    /// bisection between the longest step that failed and the shortest that passed
    /// (halvings).
    up: Option<(usize, usize)>,
    /// The halvings it jumped to after the full step failed.
    jumped_to: Option<usize>,
}

/// `2^−d`: the step after `d` halvings.
fn halved(d: usize) -> f64 {
    0.5f64.powi(d as i32)
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests;
