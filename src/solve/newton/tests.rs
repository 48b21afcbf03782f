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
    let mut sys = Kink {
        x: 1.0,
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
        iterations: None,
        fold_stall: Some(FOLD_STALL_ITERATIONS),
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
