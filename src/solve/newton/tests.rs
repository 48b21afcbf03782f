//! Tests of the Newton of V variants.

use super::*;

/// Independent scalar problems `r_j(x) = x³ + x − b_j` (one per variant).
struct Cubic {
    x: Vec<f64>,
    b: Vec<f64>,
    delta: Vec<f64>,
}

impl NewtonSystem for Cubic {
    fn variants(&self) -> usize {
        self.x.len()
    }
    fn solve(&mut self) -> Result<Probe, crate::error::SystemError> {
        let mut p = Probe::default();
        self.delta.clear();
        for (x, b) in self.x.iter().zip(&self.b) {
            let r = x * x * x + x - b;
            let d = -r / (3.0 * x * x + 1.0);
            self.delta.push(d);
            p.measure.push(r.abs() / b.abs().max(1.0));
            p.step.push(d.abs());
            p.slope.push(d * r);
            p.norm.push(r.abs());
            p.solved.push(true);
        }
        Ok(p)
    }
    fn trial(
        &mut self,
        alpha: &[f64],
        _: &[bool],
        _: bool,
    ) -> Result<TrialProbe, crate::error::SystemError> {
        let mut t = TrialProbe::default();
        for j in 0..self.x.len() {
            let x = self.x[j] + alpha[j] * self.delta[j];
            let r = x * x * x + x - self.b[j];
            t.slope.push(self.delta[j] * r);
            t.norm.push(r.abs());
        }
        Ok(t)
    }
    fn accept(&mut self, alpha: &[f64], _: bool) -> Result<(), crate::error::SystemError> {
        for j in 0..self.x.len() {
            self.x[j] += alpha[j] * self.delta[j];
        }
        Ok(())
    }
}

#[test]
fn variants_converge_independently_and_idle_ones_do_not_move() {
    let mut sys = Cubic {
        x: vec![0.0, 10.0, 3.0],
        b: vec![2.0, 1e3, 30.0],
        delta: vec![],
    };
    let mut newton = Newton::new(NewtonSettings::statics(40, 1e-12, 8), 3);
    newton.start(0, 1e-12, false);
    newton.start(1, 1e-12, true);
    // Variant 2 idle.
    let mut ended = Vec::new();
    while newton.any_running() {
        ended.extend(newton.iterate(&mut sys).unwrap());
    }
    assert_eq!(sys.x[2], 3.0);
    assert!((sys.x[0] - 1.0).abs() < 1e-12, "{}", sys.x[0]);
    let root = sys.x[1];
    assert!((root * root * root + root - 1e3).abs() < 1e-9);
    assert_eq!(ended.len(), 2);
    assert!(ended.iter().all(|(_, e)| matches!(e, Event::Converged(_))));
}

/// `r(x) = c + |x|`: a V with its least residual `c` at the kink and no root (the
/// residual of a load step past a fold, in one unknown). Newton crosses the kink each
/// step; its line search settles near `x = 0` at a residual of `c`.
struct Kink {
    x: f64,
    c: f64,
    delta: f64,
}

impl NewtonSystem for Kink {
    fn variants(&self) -> usize {
        1
    }
    fn solve(&mut self) -> Result<Probe, crate::error::SystemError> {
        let r = self.c + self.x.abs();
        let slope = if self.x < 0.0 { -1.0 } else { 1.0 };
        self.delta = -r / slope;
        Ok(Probe {
            measure: vec![r],
            step: vec![self.delta.abs()],
            slope: vec![self.delta * r],
            norm: vec![r],
            solved: vec![true],
        })
    }
    fn trial(
        &mut self,
        alpha: &[f64],
        _: &[bool],
        _: bool,
    ) -> Result<TrialProbe, crate::error::SystemError> {
        let r = self.c + (self.x + alpha[0] * self.delta).abs();
        Ok(TrialProbe {
            slope: vec![self.delta * r],
            norm: vec![r],
        })
    }
    fn accept(&mut self, alpha: &[f64], _: bool) -> Result<(), crate::error::SystemError> {
        self.x += alpha[0] * self.delta;
        Ok(())
    }
}

/// How a solve of [`Kink`] from `x = 1` ends, and after how many updates.
fn kink(c: f64, size: usize, limits: SolveLimits) -> (String, usize) {
    kink_from(1.0, c, size, limits)
}

/// How a solve of [`Kink`] from `x0` ends, and after how many updates.
fn kink_from(x0: f64, c: f64, size: usize, limits: SolveLimits) -> (String, usize) {
    let mut sys = Kink {
        x: x0,
        c,
        delta: 0.0,
    };
    let mut newton = Newton::new(NewtonSettings::statics(200, 1e-9, size), 1);
    newton.start_limited(0, 1e-12, false, limits);
    let mut ended = Vec::new();
    while newton.any_running() {
        ended.extend(newton.iterate(&mut sys).unwrap());
    }
    match &ended[..] {
        [(0, Event::Failed(why))] => (why.clone(), newton.state(0).0.updates),
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_solve_stalled_near_a_kink_ends_sooner_where_its_path_has_met_a_fold() {
    let fold = SolveLimits {
        fold_stall: Some(FOLD_STALL_ITERATIONS),
        ..SolveLimits::default()
    };
    // Below FOLD_LEVEL: the fold's stall.
    let (why, updates) = kink(1e-6, 8, fold);
    assert!(
        why.contains(&format!("did not halve in {FOLD_STALL_ITERATIONS} ")),
        "{why}"
    );
    assert!(updates < 2 * FOLD_STALL_ITERATIONS, "{updates}");
    // Without the limit, or above the level, or in f32: the plain stall.
    for (c, size, limits) in [
        (1e-6, 8, SolveLimits::default()),
        (1e-2, 8, fold),
        (1e-6, 4, fold),
    ] {
        let (why, updates) = kink(c, size, limits);
        assert!(
            why.contains(&format!("did not halve in {STATIC_STALL_ITERATIONS} ")),
            "{c} {size}: {why}"
        );
        assert!(updates >= STATIC_STALL_ITERATIONS, "{updates}");
    }
}

#[test]
fn a_solve_that_never_halves_its_first_residual_ends_sooner_in_f64() {
    // From the kink itself (x = 0: the least residual there is, c, above the level of the
    // fold's stall): the measure never comes below half its start.
    let first = SolveLimits {
        first_halving: true,
        ..SolveLimits::default()
    };
    let (why, updates) = kink_from(0.0, 1e-2, 8, first);
    assert!(
        why.contains(&format!("did not halve in {FIRST_HALVING_ITERATIONS} ")),
        "{why}"
    );
    assert_eq!(updates, FIRST_HALVING_ITERATIONS);
    // In f32 the plain stall; and in f64 where the start is above the kink (x = 1), the
    // residual halves on the first updates and the plain stall counts from there.
    let (why, updates) = kink_from(0.0, 1e-2, 4, first);
    assert!(
        why.contains(&format!("did not halve in {STATIC_STALL_ITERATIONS} ")),
        "{why}"
    );
    assert_eq!(updates, STATIC_STALL_ITERATIONS);
    let (why, updates) = kink_from(1.0, 1e-2, 8, first);
    assert!(
        why.contains(&format!("did not halve in {STATIC_STALL_ITERATIONS} ")),
        "{why}"
    );
    assert!(updates > STATIC_STALL_ITERATIONS, "{updates}");
    // A solve started without the limit: the plain stall.
    let (why, _) = kink_from(0.0, 1e-2, 8, SolveLimits::default());
    assert!(
        why.contains(&format!("did not halve in {STATIC_STALL_ITERATIONS} ")),
        "{why}"
    );
}

#[test]
fn a_solve_with_a_relative_limit_ends_once_its_residual_has_fallen_that_far() {
    // x³ + x = 1e3 from x = 10 (residual 10 of the scale 1e3 → 1e-2): Newton's quadratic
    // convergence takes it below 1e-12 in a few updates; with `relative` 0.5 it ends after
    // the first update that halves the starting measure, there and not before.
    let solve = |limits: SolveLimits| {
        let mut sys = Cubic {
            x: vec![10.0],
            b: vec![1e3],
            delta: vec![],
        };
        let mut newton = Newton::new(NewtonSettings::statics(40, 1e-12, 8), 1);
        newton.start_limited(0, 1e-12, false, limits);
        let mut measures = Vec::new();
        let mut ended = Vec::new();
        while newton.any_running() {
            let x = sys.x[0];
            measures.push((x * x * x + x - 1e3).abs() / 1e3);
            ended.extend(newton.iterate(&mut sys).unwrap());
        }
        let updates = match &ended[..] {
            [(0, Event::Converged(u))] => *u,
            other => panic!("{other:?}"),
        };
        (updates, measures)
    };
    let (full, m) = solve(SolveLimits::default());
    assert!(m[full] < 1e-12, "{m:?}");
    let relative = SolveLimits {
        relative: Some(0.5),
        ..SolveLimits::default()
    };
    let (inexact, m) = solve(relative);
    assert!(inexact >= 1 && inexact < full, "{inexact} {full}");
    // Ended at the first measure at or below half the start's, which is above tolerance.
    let first = m.iter().position(|&x| x <= 0.5 * m[0]).unwrap();
    assert_eq!(first, inexact, "{m:?}");
    assert!(m[inexact] > 1e-12, "{m:?}");
}

#[test]
fn a_failing_variant_stops_alone() {
    let mut sys = Cubic {
        x: vec![0.0, f64::NAN],
        b: vec![2.0, 1.0],
        delta: vec![],
    };
    let mut newton = Newton::new(NewtonSettings::dynamics(40, 1e-12, 8), 2);
    newton.start(0, 1e-12, false);
    newton.start(1, 1e-12, false);
    let mut ended = Vec::new();
    while newton.any_running() {
        ended.extend(newton.iterate(&mut sys).unwrap());
    }
    ended.sort_by_key(|e| e.0);
    assert!(matches!(ended[0].1, Event::Converged(_)));
    assert_eq!(ended[1].1, Event::Failed("residual is not finite".into()));
}

/// Independent scalar problems, one per variant: the residual `r(j, x)`, its derivative, and
/// the scale its measure is taken against.
trait Scalar {
    fn r(&self, j: usize, x: f64) -> f64;
    fn dr(&self, j: usize, x: f64) -> f64;
    fn scale(&self, _j: usize) -> f64 {
        1.0
    }
}

/// A [`Scalar`] problem at the points `x` as a [`NewtonSystem`].
struct Scalars<P> {
    p: P,
    x: Vec<f64>,
    delta: Vec<f64>,
}

impl<P: Scalar> NewtonSystem for Scalars<P> {
    fn variants(&self) -> usize {
        self.x.len()
    }
    fn solve(&mut self) -> Result<Probe, crate::error::SystemError> {
        let mut p = Probe::default();
        self.delta.clear();
        for (j, &x) in self.x.iter().enumerate() {
            let r = self.p.r(j, x);
            let d = -r / self.p.dr(j, x);
            self.delta.push(d);
            p.measure.push(r.abs() / self.p.scale(j));
            p.step.push(d.abs());
            p.slope.push(d * r);
            p.norm.push(r.abs());
            p.solved.push(true);
        }
        Ok(p)
    }
    fn trial(
        &mut self,
        alpha: &[f64],
        _: &[bool],
        _: bool,
    ) -> Result<TrialProbe, crate::error::SystemError> {
        let mut t = TrialProbe::default();
        for j in 0..self.x.len() {
            let r = self.p.r(j, self.x[j] + alpha[j] * self.delta[j]);
            t.slope.push(self.delta[j] * r);
            t.norm.push(r.abs());
        }
        Ok(t)
    }
    fn accept(&mut self, alpha: &[f64], _: bool) -> Result<(), crate::error::SystemError> {
        for j in 0..self.x.len() {
            self.x[j] += alpha[j] * self.delta[j];
        }
        Ok(())
    }
}

/// `r_j(x) = atan(x − b_j) + 10⁻⁴ x`: from a start far from the root the full Newton step
/// overshoots and the line search halves.
struct Atan {
    b: Vec<f64>,
}

impl Scalar for Atan {
    fn r(&self, j: usize, x: f64) -> f64 {
        (x - self.b[j]).atan() + x * 1e-4
    }
    fn dr(&self, j: usize, x: f64) -> f64 {
        1.0 / (1.0 + (x - self.b[j]).powi(2)) + 1e-4
    }
}

/// A system evaluated through [`NewtonSystem::trials`] in rounds of `per_round`, counting its
/// round trips (a solve, a trial, a round of trials each count one).
struct Rounds<S> {
    inner: S,
    per_round: usize,
    round_trips: usize,
    /// The α of every trial evaluated, in order.
    evaluated: Vec<Vec<f64>>,
}

impl<S: NewtonSystem> NewtonSystem for Rounds<S> {
    fn variants(&self) -> usize {
        self.inner.variants()
    }
    fn solve(&mut self) -> Result<Probe, crate::error::SystemError> {
        self.round_trips += 1;
        self.inner.solve()
    }
    fn trial(
        &mut self,
        alpha: &[f64],
        search: &[bool],
        first: bool,
    ) -> Result<TrialProbe, crate::error::SystemError> {
        self.round_trips += 1;
        self.evaluated.push(alpha.to_vec());
        self.inner.trial(alpha, search, first)
    }
    fn trials_per_round(&self) -> usize {
        self.per_round
    }
    fn trials(
        &mut self,
        alphas: &[Vec<f64>],
        search: &[bool],
        first: bool,
    ) -> Result<Vec<TrialProbe>, crate::error::SystemError> {
        self.round_trips += 1;
        self.evaluated.extend(alphas.iter().cloned());
        alphas
            .iter()
            .enumerate()
            .map(|(k, a)| self.inner.trial(a, search, first && k == 0))
            .collect()
    }
    fn accept(
        &mut self,
        alpha: &[f64],
        trial_matches: bool,
    ) -> Result<(), crate::error::SystemError> {
        self.inner.accept(alpha, trial_matches)
    }
}

/// The roots, the events, the updates, the round trips and the trials evaluated.
type RoundsRun = (Vec<f64>, Vec<(usize, Event)>, Vec<usize>, usize, usize);

/// Solves the problems `p` from `x0` with `settings`, trials in rounds of `per_round`: the
/// roots, the events, the updates, the round trips and the trials evaluated.
fn in_rounds<P: Scalar>(settings: NewtonSettings, p: P, x0: &[f64], per_round: usize) -> RoundsRun {
    let v = x0.len();
    let mut sys = Rounds {
        inner: Scalars {
            p,
            x: x0.to_vec(),
            delta: vec![],
        },
        per_round,
        round_trips: 0,
        evaluated: Vec::new(),
    };
    let mut newton = Newton::new(settings, v);
    for j in 0..v {
        newton.start(j, 1e-12, false);
    }
    let mut ended = Vec::new();
    while newton.any_running() {
        ended.extend(newton.iterate(&mut sys).unwrap());
    }
    let updates = (0..v).map(|j| newton.state(j).0.updates).collect();
    (
        sys.inner.x,
        ended,
        updates,
        sys.round_trips,
        sys.evaluated.len(),
    )
}

#[test]
fn trials_in_rounds_decide_as_trials_one_at_a_time() {
    // Starts far from the roots: Newton's full steps overshoot and the searches halve
    // several times (up to the dynamics' 24, the statics' 5 with its fallback).
    let x0 = [40.0, -30.0, 0.5, 1e3, 7.0, 3.0];
    let b = [2.0, 10.0, -5.0, 1.0, 0.1, 3.5];
    for settings in [
        NewtonSettings::dynamics(60, 1e-12, 8),
        NewtonSettings::statics(60, 1e-12, 8),
        NewtonSettings::statics_for_law(60, 1e-12, 8, true),
    ] {
        let atan = || Atan { b: b.to_vec() };
        let (x1, e1, u1, trips1, trials1) = in_rounds(settings, atan(), &x0, 1);
        assert!(trials1 > 2 * u1.iter().max().unwrap(), "the searches halve");
        for per_round in [2, 4, 8, 30] {
            let (x, e, u, trips, trials) = in_rounds(settings, atan(), &x0, per_round);
            // The same path to the bit: every decision as one trial at a time.
            let bits = |x: &[f64]| x.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&x), bits(&x1), "{per_round}");
            assert_eq!(e, e1, "{per_round}");
            assert_eq!(u, u1, "{per_round}");
            // Fewer round trips, paid for with speculative trials.
            assert!(trips < trips1, "{per_round}: {trips} ≥ {trips1}");
            assert!(trials >= trials1, "{per_round}");
        }
    }
}

/// `r_j(x) = s x − F_j + K max(0, x − w)²`: a soft spring pushed onto a stiff wall at `w`.
/// From `x = 0` (off the wall) the full Newton step lands far inside the wall; the search
/// takes the longest step that stays near it, and the next update's direction is as long
/// again: the solve crawls toward the wall, halving its step at each update (a soft-law
/// contact's onset in a static solve, issue 22).
struct Wall {
    f: Vec<f64>,
}

impl Wall {
    const S: f64 = 1.0;
    const K: f64 = 1e8;
    const W: f64 = 1.0;
}

impl Scalar for Wall {
    fn r(&self, j: usize, x: f64) -> f64 {
        let pen = (x - Self::W).max(0.0);
        Self::S * x - self.f[j] + Self::K * pen * pen
    }
    fn dr(&self, _j: usize, x: f64) -> f64 {
        Self::S + 2.0 * Self::K * (x - Self::W).max(0.0)
    }
    fn scale(&self, j: usize) -> f64 {
        self.f[j]
    }
}

#[test]
fn a_search_that_remembers_its_last_step_crawls_to_a_wall_on_fewer_trials() {
    // Loads 10²–3·10³ times what the soft spring carries at the wall.
    let f = [1e2, 1e3, 3e3];
    let mut plain = NewtonSettings::statics_for_law(200, 1e-10, 8, true);
    plain.line_search.memory = false;
    let mut memory = plain;
    memory.line_search.memory = true;
    let wall = || Wall { f: f.to_vec() };
    let start = [0.0; 3];
    let (x0, e0, u0, _, trials0) = in_rounds(plain, wall(), &start, 1);
    let (x1, e1, u1, _, trials1) = in_rounds(memory, wall(), &start, 1);
    for (j, f) in f.iter().enumerate() {
        // The root: s x + K (x − w)² = F.
        let pen = (-Wall::S + (Wall::S * Wall::S + 4.0 * Wall::K * (f - Wall::S * Wall::W)).sqrt())
            / (2.0 * Wall::K);
        for x in [x0[j], x1[j]] {
            assert!(
                (x - Wall::W - pen).abs() < 1e-9 * pen,
                "{j}: {x} against {}",
                Wall::W + pen
            );
        }
    }
    assert!(e0
        .iter()
        .chain(&e1)
        .all(|(_, e)| matches!(e, Event::Converged(_))));
    // The plain search crawls: many halvings at each update (a trial evaluates every
    // variant still searching).
    let updates0 = *u0.iter().max().unwrap();
    eprintln!("trials {trials0} → {trials1}, updates {u0:?} → {u1:?}");
    assert!(
        trials0 > 4 * updates0,
        "{trials0} trials, {updates0} updates"
    );
    // The search from one halving above the last update's step (up by bisection where
    // that passes) takes the steps the plain search takes: the same path to the bit, on a
    // third fewer trials or more (measured 71 → 39).
    let bits = |x: &[f64]| x.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&x1), bits(&x0));
    assert_eq!(u1, u0);
    assert!(3 * trials1 < 2 * trials0, "{trials1} against {trials0}");
    // In rounds, the same decisions.
    for per_round in [2, 4, 8] {
        let (x, e, u, _, _) = in_rounds(memory, wall(), &start, per_round);
        assert_eq!(bits(&x), bits(&x1), "{per_round}");
        assert_eq!((e, u), (e1.clone(), u1.clone()), "{per_round}");
    }
}
