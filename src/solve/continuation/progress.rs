//! What a static solve shows while it runs: the load factor reached and, for one variant,
//! the stage it is in — a relaxation that runs for minutes (a string that locks up) says
//! how far it has come and when it gives up, where the load factor alone stands still.

use super::RELAX_MAX_SUBS;
use super::{LoadPath, Stage};

/// The state of the load paths after a Newton iteration, as the progress callback of
/// [`super::solve_loads_from`] sees it. The words ([`Progress::note`]) are formed only when
/// asked for.
pub struct Progress<'a> {
    paths: &'a [LoadPath],
}

impl<'a> Progress<'a> {
    /// The progress of `paths` (one per variant).
    pub fn of(paths: &'a [LoadPath]) -> Self {
        Progress { paths }
    }

    /// The mean load factor reached (0 … 1; [`LoadPath::progress`]).
    pub fn fraction(&self) -> f64 {
        let n = self.paths.len().max(1) as f64;
        self.paths.iter().map(LoadPath::progress).sum::<f64>() / n
    }

    /// With one variant, the stage its path is in ([`LoadPath::stage_note`]); `None` for an
    /// ensemble.
    pub fn note(&self) -> Option<String> {
        match self.paths {
            [one] => one.stage_note(),
            _ => None,
        }
    }
}

impl LoadPath {
    /// The stage being solved, in words for a progress bar (`None` once finished): the load
    /// step, or the relaxation with its sub-solves, its best residual without the shift and
    /// the sub-solve at which it gives up without a 1 % gain (`Relax::stagnant_at`,
    /// at most [`RELAX_MAX_SUBS`]; its iteration budget may end it sooner), or the
    /// relaxations up from the last equilibrium that bracket where the string stops.
    pub fn stage_note(&self) -> Option<String> {
        let stage = match self.stage {
            Stage::Gravity => "gravity in full, the string on the low side".to_string(),
            Stage::GravityRamp => format!(
                "gravity by continuation, at {:.0} %",
                100.0 * self.target.gravity
            ),
            Stage::Exponent { .. } => format!(
                "the contact law's exponent by continuation, at {:.2}",
                self.target.exponent
            ),
            Stage::Load => format!("load step λ {:.3} → {:.3}", self.lambda, self.target.lambda),
            Stage::Relax => {
                let r = self.relax.as_ref()?;
                let to = match (&self.lock, r.gravity) {
                    (Some(lock), _) => format!(
                        "where the string stops, between λ {:.3} and {:.3}: relaxing to λ {:.3}",
                        lock.lo, lock.hi, r.target.lambda
                    ),
                    (None, true) => "relaxing to gravity in full".to_string(),
                    (None, false) => format!("relaxing to λ {:.3}", r.target.lambda),
                };
                let best = if r.best.is_finite() {
                    format!(
                        "best residual {:.1e} of the force scale at {}",
                        r.best, r.best_at
                    )
                } else {
                    "none converged yet".to_string()
                };
                let ends = r.stagnant_at().min(RELAX_MAX_SUBS);
                format!(
                    "{to}: sub-solve {}, ends by {ends} unless it gains 1 %; {best}; {} \
                     Newton iterations in it",
                    r.subs, r.iterations
                )
            }
            Stage::Refine => "the equilibrium polished without the shift".to_string(),
            Stage::Done | Stage::Failed => return None,
        };
        Some(stage)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::continuation::Next;
    use crate::solve::static_options::StaticOptions;

    /// The words follow the path: a load step, the relaxation to the full loads with its
    /// sub-solves and best residual, the bracket of where the string stops, nothing once
    /// failed; an ensemble has none, and its fraction is the mean.
    #[test]
    fn a_single_path_says_which_stage_it_is_in() {
        let mut p = LoadPath::new(&StaticOptions::default(), true, true, false);
        assert_eq!(p.converged(10), Next::Step);
        assert_eq!(p.converged(10), Next::Step);
        let note = Progress::of(std::slice::from_ref(&p)).note().unwrap();
        assert_eq!(note, "load step λ 0.250 → 0.500");
        assert_eq!(p.failed_at("no".into(), None, Some(1e6)), Next::Step);
        let note = p.stage_note().unwrap();
        assert!(
            note.starts_with("relaxing to λ 1.000: sub-solve 0, ends by 500 unless it gains 1 %; none converged yet; 0 Newton"),
            "{note}"
        );
        p.shift_settled(2.5e-3);
        assert_eq!(p.converged(4), Next::Step);
        let note = p.stage_note().unwrap();
        assert!(
            note.contains("sub-solve 1, ends by 500 unless it gains 1 %; best residual 2.5e-3 of the force scale at 0; 4 Newton"),
            "{note}"
        );
        // The relaxation stagnates and fails: the bracket relaxes a step up from 0.25.
        let mut subs = 0;
        while p.target().lambda == 1.0 {
            p.shift_settled(2.5e-3);
            assert_eq!(p.converged(1), Next::Step);
            subs += 1;
            assert!(subs < 1000, "the relaxation ends");
        }
        let note = p.stage_note().unwrap();
        assert!(
            note.starts_with("where the string stops, between λ 0.250 and 1.000: relaxing to λ 0.375: sub-solve 0,"),
            "{note}"
        );
        while !p.finished() {
            p.failed("no".into());
        }
        assert_eq!(p.stage_note(), None);
        let two = [
            p.clone(),
            LoadPath::new(&StaticOptions::default(), true, true, false),
        ];
        let both = Progress::of(&two);
        assert_eq!(both.note(), None);
        assert_eq!(both.fraction(), 0.5);
    }
}
