//! The driver of the load paths ([`super`]): every variant of a [`StaticSystem`] stepped
//! through its loads by one [`Newton`], each path's policy ([`LoadPath`]) deciding what
//! follows a step's end.

use super::{LoadPath, LoadTarget, Next, Progress};
use crate::solve::newton::{Event, Newton, NewtonSettings, NewtonState, NewtonSystem};

/// A static problem of V variants that [`solve_loads`] can step through its loads.
pub trait StaticSystem: NewtonSystem {
    /// Sets variant `j`'s loads (effective from the next solve).
    fn set_target(
        &mut self,
        j: usize,
        target: &LoadTarget,
    ) -> Result<(), crate::error::SystemError>;
    /// Keeps variant `j`'s current state as its restart point (a step completed).
    fn save(&mut self, j: usize) -> Result<(), crate::error::SystemError>;
    /// Returns variant `j` to its restart point.
    fn restore(&mut self, j: usize) -> Result<(), crate::error::SystemError>;
    /// The rounding floor of a step of variant `j` ([`NewtonSettings::step_floor`]).
    fn step_floor(&mut self, j: usize) -> Result<f64, crate::error::SystemError>;
    /// Where variant `j`'s residual force is largest now (MD, m), for a failure's
    /// message; `None` where the system does not keep it at hand.
    fn worst_residual_md(&mut self, _j: usize) -> Option<f64> {
        None
    }
    /// The first proximal shift of a relaxation of variant `j` (N/m on the translations;
    /// `super::Stage::Relax`); `None` where the system cannot relax (its variants fail where a
    /// step fails at the smallest size).
    fn relax_scale(&mut self, _j: usize) -> Option<f64> {
        None
    }
    /// Variant `j`'s residual measure at its current state without the shift (a
    /// relaxation has settled where it is below the tolerance).
    fn unshifted_measure(&mut self, _j: usize) -> f64 {
        f64::INFINITY
    }
    /// Keeps variant `j`'s current state, an equilibrium at the loads `target`
    /// ([`LoadPath::take_equilibrium`]): where its string stands should its path fail
    /// where the string stops, and where the relaxations bracketing that start
    /// ([`StaticSystem::back_to_equilibrium`]).
    fn keep_equilibrium(
        &mut self,
        j: usize,
        target: &LoadTarget,
    ) -> Result<(), crate::error::SystemError>;
    /// Returns variant `j`'s state and restart point to the equilibrium
    /// [`StaticSystem::keep_equilibrium`] kept last ([`LoadPath::take_back_to_equilibrium`]).
    fn back_to_equilibrium(&mut self, j: usize) -> Result<(), crate::error::SystemError>;
    /// Keeps variant `j`'s current state, a relaxation's best sub-solve so far
    /// ([`LoadPath::shift_settled`]), for [`StaticSystem::back_to_best`].
    fn keep_best(&mut self, j: usize) -> Result<(), crate::error::SystemError>;
    /// Whether the system shifts rotations as well as translations
    /// ([`StaticSystem::set_rotation_shift`]); those that do not decline it, and a
    /// relaxation whose translational shift reaches its ceiling ends there.
    fn shifts_rotations(&self) -> bool {
        false
    }
    /// Sets variant `j`'s rotational proximal shift `s` (N·m/rad; 0: none), anchored at its
    /// current rotations ([`LoadPath::rotation_shift`]): the moment residual gains `s θ`,
    /// `θ` the rotation since the anchor, the rotational diagonal blocks `s I`.
    fn set_rotation_shift(&mut self, _j: usize, s: f64) -> Result<(), crate::error::SystemError> {
        if s == 0.0 {
            Ok(())
        } else {
            Err(crate::error::SystemError::Unsupported(
                "this system shifts translations only".into(),
            ))
        }
    }
    /// Returns variant `j`'s state and restart point to the state [`StaticSystem::keep_best`]
    /// kept last ([`LoadPath::take_back_to_best`]).
    fn back_to_best(&mut self, j: usize) -> Result<(), crate::error::SystemError>;
    /// Sets variant `j`'s proximal shift `s` (0: none), anchored at its current state `x`
    /// carried on by `momentum` times its move since the last anchor's state `x₋`:
    /// `a = x + β (x − x₋)` on the translations (β 0: at `x`; [`LoadPath::momentum`]); the
    /// residual gains `s (x − a)` on the translations, the tangent `s I`.
    fn set_shift(
        &mut self,
        _j: usize,
        s: f64,
        _momentum: f64,
    ) -> Result<(), crate::error::SystemError> {
        if s == 0.0 {
            Ok(())
        } else {
            Err(crate::error::SystemError::Unsupported(
                "this system cannot relax".into(),
            ))
        }
    }
}

/// Runs every variant's load path to its end through one [`Newton`]; `progress` sees the
/// paths after each iteration ([`Progress`]: the mean load factor reached, and one
/// variant's stage in words). Returns the Newton's solve count.
pub fn solve_loads(
    sys: &mut dyn StaticSystem,
    paths: &mut [LoadPath],
    settings: NewtonSettings,
    progress: &mut dyn FnMut(&Progress),
) -> Result<usize, crate::error::SystemError> {
    let mut solves = 0;
    solve_loads_from(
        sys,
        paths,
        settings,
        None,
        &|_, _| false,
        &mut solves,
        progress,
    )?;
    Ok(solves)
}

/// As [`solve_loads`], resuming (`resume`: each variant's Newton state, the system built
/// on their current states and restart points) or from the start (every variant's state
/// saved as its first restart point), until every path is finished or, between
/// iterations, `stop(running, variants)` says so. Returns each variant's Newton state then
/// (for [`solve_loads_from`] on a compacted system); adds the solves to `solves`.
#[allow(clippy::too_many_arguments)]
pub fn solve_loads_from(
    sys: &mut dyn StaticSystem,
    paths: &mut [LoadPath],
    settings: NewtonSettings,
    resume: Option<&[NewtonState]>,
    stop: &dyn Fn(usize, usize) -> bool,
    solves: &mut usize,
    progress: &mut dyn FnMut(&Progress),
) -> Result<Vec<NewtonState>, crate::error::SystemError> {
    let v = sys.variants();
    let mut newton = Newton::new(settings, v);
    let rotations = sys.shifts_rotations();
    for (j, path) in paths.iter_mut().enumerate() {
        path.allow_rotation_shift(rotations);
        if path.finished() {
            continue;
        }
        sys.set_target(j, &path.target())?;
        match resume {
            Some(states) => newton.resume(j, states[j].clone()),
            None => {
                sys.save(j)?;
                let floor = sys.step_floor(j)?;
                newton.start_limited(j, floor, path.polish(), path.limits());
            }
        }
    }
    while newton.any_running() {
        let events = newton.test(sys)?;
        next_steps(sys, paths, &mut newton, events)?;
        let events = newton.advance(sys)?;
        next_steps(sys, paths, &mut newton, events)?;
        progress(&Progress::of(paths));
        if stop(newton.running_count(), v) {
            break;
        }
    }
    *solves += newton.solves;
    Ok((0..v).map(|j| newton.state(j)).collect())
}

/// Variants whose solve ended: the next step of their path from the state it needs.
fn next_steps(
    sys: &mut dyn StaticSystem,
    paths: &mut [LoadPath],
    newton: &mut Newton,
    events: Vec<(usize, Event)>,
) -> Result<(), crate::error::SystemError> {
    for (j, event) in events {
        let path = &mut paths[j];
        let (next, converged) = match event {
            Event::Converged(its) => {
                if path.shift() > 0.0 && path.shift_settled(sys.unshifted_measure(j)) {
                    sys.keep_best(j)?;
                }
                let next = path.converged(its);
                if path.take_back_to_best() {
                    // Before the equilibrium is kept and the restart point saved: both
                    // are then the best state.
                    sys.back_to_best(j)?;
                }
                if let Some(target) = path.take_equilibrium() {
                    sys.keep_equilibrium(j, &target)?;
                }
                (next, true)
            }
            Event::Failed(reason) => {
                let at = sys.worst_residual_md(j);
                let relax = sys.relax_scale(j);
                (path.failed_at(reason, at, relax), false)
            }
        };
        match (next, converged) {
            (Next::Step, true) => sys.save(j)?,
            (Next::Step | Next::Finished, false) => sys.restore(j)?,
            _ => {}
        }
        if path.take_back_to_equilibrium() {
            // After the save or restore: the equilibrium is then the restart point too.
            sys.back_to_equilibrium(j)?;
        }
        if next == Next::Step {
            sys.set_target(j, &path.target())?;
            sys.set_shift(j, path.shift(), path.momentum())?;
            sys.set_rotation_shift(j, path.rotation_shift())?;
            let floor = sys.step_floor(j)?;
            newton.start_limited(j, floor, path.polish(), path.limits());
        }
    }
    Ok(())
}
