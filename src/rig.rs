//! The rig's hoisting system (issue 26): what the weight indicator reads for a given load
//! on the hook.
//!
//! The string load the solvers return is the effective axial force at the top of the
//! string. The rig measures something else: the travelling block, hook and top drive hang on
//! the drilling line too (the **block weight**), and the usual weight indicator senses the
//! **dead-line** tension and is calibrated at rest as `n · T_dead` (`n` lines strung between
//! crown and travelling block), which differs from the load on the hook while the block moves
//! because each sheave the line runs over loses a fraction of the tension.
//!
//! The model is Bourgoyne et al.'s (*Applied Drilling Engineering*, SPE Textbook Series 2,
//! 1986, §1.2 "Hoisting system"): every sheave the line runs over passes on `K` times the
//! tension (the **sheave efficiency**; 0.9615 for roller bearings, their value). Hoisting with
//! the fast-line tension `F_f`, line `i` (from the fast line, `i = 1 … n`) carries `F_f K^i`,
//! so the load `W = F_f K (1 − K^n)/(1 − K)` and the block-and-tackle efficiency
//! `E = W/(n F_f) = K (1 − K^n) / (n (1 − K))` (their Table 1.2: 0.874, 0.842, 0.811, 0.782
//! for 6, 8, 10, 12 lines). The dead line does not move, so its sheave does not turn and the
//! dead-line tension is that of line `n`, `F_f K^n`. Lowering, the friction acts the other
//! way: line `i` carries `F_f K^−i`. At rest every line carries `W/n`. (Luke and
//! Juvkam-Wold, *Determination of true hook load and line tension under dynamic conditions*,
//! SPE Drilling & Completion 1993, measured this dead-line error on a rig.)
//!
//! So a dead-line weight indicator reads `n K^(n−1) (1 − K)/(1 − K^n) · W` hoisting (less
//! than `W`) and `n K^−n / Σ K^−i · W` lowering (more), and `W` at rest; a hook load cell
//! reads `W` always. `W` is the string load plus the block weight; a tared indicator (zeroed
//! with the block hanging) subtracts the block weight from its reading.

use serde::Serialize;

/// What senses the load.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Indicator {
    /// A dead-line anchor's load cell, calibrated at rest as `n · T_dead`.
    DeadLine,
    /// A load cell in the hook (or the top drive's): reads the load on the lines.
    Hook,
}

/// Which way the block moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Travel {
    /// Pulling out: tripping out, back-reaming.
    Hoisting,
    /// Running in: tripping in, reaming, sliding.
    Lowering,
    /// Block at rest: rotating off bottom, drilling.
    AtRest,
}

impl Travel {
    /// From the string's axial speed (m/s, + running in, as `Model::axial_speed`).
    pub fn of_axial_speed(v: f64) -> Travel {
        if v < 0.0 {
            Travel::Hoisting
        } else if v > 0.0 {
            Travel::Lowering
        } else {
            Travel::AtRest
        }
    }
}

/// The rig's hoisting system (`[rig]`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Rig {
    /// Travelling block, hook and top drive (N).
    pub block_weight_n: f64,
    /// Lines strung between crown and travelling block.
    pub lines: u32,
    /// Sheave efficiency `K`.
    pub sheave_efficiency: f64,
    /// What senses the load.
    pub indicator: Indicator,
    /// Whether the indicator was zeroed with the block hanging (reads the string only).
    pub tared: bool,
}

impl Default for Rig {
    /// No block weight, 10 lines, `K = 0.9615`, a dead-line indicator, not tared.
    fn default() -> Self {
        Rig {
            block_weight_n: 0.0,
            lines: 10,
            sheave_efficiency: 0.9615,
            indicator: Indicator::DeadLine,
            tared: false,
        }
    }
}

/// What the rig carries and reads for one string load.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RigReading {
    /// Which way the block moves.
    pub travel: Travel,
    /// The string's load at the hook (N): the effective axial force at the top.
    pub string_load_n: f64,
    /// Load on the lines (N): string load plus block weight.
    pub hook_load_n: f64,
    /// Fast-line tension (N).
    pub fast_line_n: f64,
    /// Dead-line tension (N).
    pub dead_line_n: f64,
    /// What the weight indicator shows (N).
    pub weight_indicator_n: f64,
}

impl Rig {
    /// Block-and-tackle efficiency hoisting, `E = K (1 − K^n)/(n (1 − K))` (ADE §1.2).
    pub fn efficiency(&self) -> f64 {
        let (k, n) = (self.sheave_efficiency, self.lines as f64);
        if k >= 1.0 {
            return 1.0;
        }
        k * (1.0 - k.powf(n)) / (n * (1.0 - k))
    }

    /// Line tensions and the indicator's reading for `string_load` (N) while the block
    /// moves as `travel`.
    pub fn reading(&self, string_load: f64, travel: Travel) -> RigReading {
        let w = string_load + self.block_weight_n;
        let n = self.lines as i32;
        let k = self.sheave_efficiency;
        // Tension of line i per unit fast-line tension: K^i hoisting, K^−i lowering.
        let ratio = match travel {
            Travel::Hoisting => k,
            Travel::Lowering => 1.0 / k,
            Travel::AtRest => 1.0,
        };
        let sum: f64 = (1..=n).map(|i| ratio.powi(i)).sum();
        let fast = w / sum;
        let dead = fast * ratio.powi(n);
        let sensed = match self.indicator {
            Indicator::DeadLine => self.lines as f64 * dead,
            Indicator::Hook => w,
        };
        RigReading {
            travel,
            string_load_n: string_load,
            hook_load_n: w,
            fast_line_n: fast,
            dead_line_n: dead,
            weight_indicator_n: sensed - if self.tared { self.block_weight_n } else { 0.0 },
        }
    }
}

/// The y axis of a hook-load plot (kN): the weight indicator's reading where the case has a
/// `[rig]`, else the string's load.
pub fn hook_load_axis(rig: Option<Rig>) -> String {
    match rig {
        Some(r) if r.tared => "weight indicator, block tared (kN)".to_string(),
        Some(r) => format!(
            "weight indicator, incl. {:.0} kN block (kN)",
            r.block_weight_n * 1e-3
        ),
        None => "hook load (kN)".to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bourgoyne et al.'s Table 1.2 (K = 0.9615): 0.874, 0.842, 0.811, 0.782 for 6 … 12
    /// lines, to their three digits.
    #[test]
    fn efficiency_matches_the_textbook_table() {
        for (n, e) in [(6, 0.874), (8, 0.842), (10, 0.811), (12, 0.782)] {
            let rig = Rig {
                lines: n,
                ..Rig::default()
            };
            assert!(
                (rig.efficiency() - e).abs() < 6e-4,
                "{n}: {}",
                rig.efficiency()
            );
        }
    }

    /// The lines carry the load; the fast line is `W/(E n)` hoisting; at rest the
    /// indicator reads the hook load; hoisting it reads low, lowering high, by the closed
    /// forms of the module's doc.
    #[test]
    fn line_tensions_balance_and_the_indicator_errs_by_the_closed_form() {
        let rig = Rig {
            block_weight_n: 300e3,
            lines: 10,
            ..Rig::default()
        };
        let (s, k, n) = (1.2e6, rig.sheave_efficiency, 10.0);
        let w = s + 300e3;
        let up = rig.reading(s, Travel::Hoisting);
        assert!((up.fast_line_n - w / (rig.efficiency() * n)).abs() < 1e-9 * w);
        let closed = n * k.powf(n - 1.0) * (1.0 - k) / (1.0 - k.powf(n)) * w;
        assert!((up.weight_indicator_n - closed).abs() < 1e-9 * w);
        assert!(up.weight_indicator_n < w);
        let down = rig.reading(s, Travel::Lowering);
        let sum: f64 = (1..=10).map(|i| k.powi(-i)).sum();
        assert!((down.weight_indicator_n - n * k.powf(-n) / sum * w).abs() < 1e-9 * w);
        assert!(down.weight_indicator_n > w);
        let rest = rig.reading(s, Travel::AtRest);
        assert!((rest.weight_indicator_n - w).abs() < 1e-9 * w);
        assert_eq!(rest.hook_load_n, w);
        let tared = Rig { tared: true, ..rig }.reading(s, Travel::AtRest);
        assert!((tared.weight_indicator_n - s).abs() < 1e-9 * w);
        let cell = Rig {
            indicator: Indicator::Hook,
            ..rig
        }
        .reading(s, Travel::Hoisting);
        assert!((cell.weight_indicator_n - w).abs() < 1e-9 * w);
    }
}
