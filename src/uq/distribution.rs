//! Distributions of an uncertain input, each by its quantile function (inverse CDF): every
//! sampling method draws points in the unit cube and maps them through it, so Latin
//! hypercube strata and Sobol nets carry over to the inputs. Quantiles of the normal,
//! lognormal and triangular laws come from `statrs`.

use statrs::distribution::{ContinuousCDF, LogNormal, Normal, Triangular};

/// The distribution of one uncertain input (values in SI).
#[derive(Clone, Debug, PartialEq)]
pub enum Distribution {
    /// Uniform on `[min, max]`.
    Uniform {
        /// Lower bound.
        min: f64,
        /// Upper bound.
        max: f64,
    },
    /// Normal with `mean` and standard deviation `sd`, optionally truncated to
    /// `[min, max]` (either may be infinite).
    Normal {
        /// Mean of the untruncated law.
        mean: f64,
        /// Standard deviation of the untruncated law (> 0).
        sd: f64,
        /// Truncation bounds.
        min: f64,
        /// See `min`.
        max: f64,
    },
    /// Lognormal: `ln x` normal with median `median` (`e^μ`) and standard deviation `sigma`.
    LogNormal {
        /// Median (> 0).
        median: f64,
        /// Standard deviation of `ln x` (> 0).
        sigma: f64,
    },
    /// Triangular on `[min, max]` with its peak at `mode`.
    Triangular {
        /// Lower bound.
        min: f64,
        /// Peak.
        mode: f64,
        /// Upper bound.
        max: f64,
    },
    /// Discrete values with weights (normalised here).
    Discrete {
        /// Values.
        values: Vec<f64>,
        /// Weights (> 0), one per value.
        weights: Vec<f64>,
    },
}

/// In words, for messages: `normal (mean 20000, sd 5000)`, `uniform on [0.2, 0.4]`.
impl std::fmt::Display for Distribution {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use crate::units::show;
        let bounds = |min: f64, max: f64| match (min.is_finite(), max.is_finite()) {
            (true, true) => format!(", truncated to [{}, {}]", show(min), show(max)),
            (true, false) => format!(", truncated below at {}", show(min)),
            (false, true) => format!(", truncated above at {}", show(max)),
            (false, false) => String::new(),
        };
        match self {
            Distribution::Uniform { min, max } => {
                write!(f, "uniform on [{}, {}]", show(*min), show(*max))
            }
            Distribution::Normal { mean, sd, min, max } => write!(
                f,
                "normal (mean {}, sd {}{})",
                show(*mean),
                show(*sd),
                bounds(*min, *max)
            ),
            Distribution::LogNormal { median, sigma } => write!(
                f,
                "lognormal (median {}, sd of ln x {})",
                show(*median),
                show(*sigma)
            ),
            Distribution::Triangular { min, mode, max } => write!(
                f,
                "triangular (min {}, mode {}, max {})",
                show(*min),
                show(*mode),
                show(*max)
            ),
            Distribution::Discrete { values, .. } => write!(
                f,
                "discrete over [{}]",
                values
                    .iter()
                    .map(|v| show(*v))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        }
    }
}

/// Why a distribution cannot be read ([`crate::case`]'s `[ensemble.uncertain]`) or is not
/// a distribution ([`Distribution::check`]).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DistributionError {
    /// Not a distribution this module has.
    #[error(
        "unknown distribution {0:?}; allowed: uniform, normal, lognormal, triangular, discrete"
    )]
    Unknown(String),
    /// A parameter the distribution needs is missing.
    #[error("{dist} needs {field}")]
    Needs {
        /// The distribution.
        dist: String,
        /// The missing parameter.
        field: &'static str,
    },
    /// A parameter the distribution does not take.
    #[error("{dist} takes no {field}")]
    TakesNo {
        /// The distribution.
        dist: String,
        /// The parameter given.
        field: &'static str,
    },
    /// A value that is not a value of its key.
    #[error("{field}: {source}")]
    Value {
        /// The parameter (`min`, `values`, …).
        field: &'static str,
        /// Why.
        source: crate::keys::KeyError,
    },
    /// A parameter that is not finite.
    #[error("{0} must be finite")]
    NotFinite(&'static str),
    /// A parameter that must be positive (and finite).
    #[error("{what} must be positive and finite, not {value}")]
    NotPositive {
        /// The parameter.
        what: &'static str,
        /// Its value.
        value: f64,
    },
    /// `min ≥ max`.
    #[error("min ({min}) must be below max ({max})")]
    MinNotBelowMax {
        /// The lower bound.
        min: f64,
        /// The upper bound.
        max: f64,
    },
    /// A normal law's truncation that holds no probability.
    #[error("the truncation [{min}, {max}] holds no probability of the normal law")]
    EmptyTruncation {
        /// The lower bound.
        min: f64,
        /// The upper bound.
        max: f64,
    },
    /// A triangular law's points out of order.
    #[error("need min ≤ mode ≤ max and min < max ({min}, {mode}, {max})")]
    Triangular {
        /// The lower bound.
        min: f64,
        /// The mode.
        mode: f64,
        /// The upper bound.
        max: f64,
    },
    /// A discrete law without values.
    #[error("no values")]
    NoValues,
    /// A discrete law's weights not one per value.
    #[error("{weights} weights for {values} values")]
    WeightCount {
        /// Weights given.
        weights: usize,
        /// Values given.
        values: usize,
    },
}

impl Distribution {
    /// Checks the parameters; the error names what is wrong.
    pub fn check(&self) -> Result<(), DistributionError> {
        use DistributionError as E;
        let finite = |x: f64, what: &'static str| {
            if x.is_finite() {
                Ok(())
            } else {
                Err(E::NotFinite(what))
            }
        };
        let ordered = |min: f64, max: f64| {
            if min < max {
                Ok(())
            } else {
                Err(E::MinNotBelowMax { min, max })
            }
        };
        let positive = |x: f64, what: &'static str| {
            if x.is_finite() && x > 0.0 {
                Ok(())
            } else {
                Err(E::NotPositive { what, value: x })
            }
        };
        match self {
            Distribution::Uniform { min, max } => {
                finite(*min, "min")?;
                finite(*max, "max")?;
                ordered(*min, *max)?;
            }
            Distribution::Normal { mean, sd, min, max } => {
                finite(*mean, "mean")?;
                positive(*sd, "sd")?;
                ordered(*min, *max)?;
                let n = Normal::new(*mean, *sd).map_err(|_| E::NotPositive {
                    what: "sd",
                    value: *sd,
                })?;
                if n.cdf(*max) - n.cdf(*min) < 1e-12 {
                    return Err(E::EmptyTruncation {
                        min: *min,
                        max: *max,
                    });
                }
            }
            Distribution::LogNormal { median, sigma } => {
                positive(*median, "median")?;
                positive(*sigma, "sigma")?;
            }
            Distribution::Triangular { min, mode, max } => {
                finite(*min, "min")?;
                finite(*max, "max")?;
                if !(min < max && (*min..=*max).contains(mode)) {
                    return Err(E::Triangular {
                        min: *min,
                        mode: *mode,
                        max: *max,
                    });
                }
            }
            Distribution::Discrete { values, weights } => {
                if values.is_empty() {
                    return Err(E::NoValues);
                }
                if weights.len() != values.len() {
                    return Err(E::WeightCount {
                        weights: weights.len(),
                        values: values.len(),
                    });
                }
                if weights.iter().any(|w| !(w.is_finite() && *w > 0.0)) {
                    return Err(E::NotPositive {
                        what: "every weight",
                        value: weights
                            .iter()
                            .copied()
                            .find(|w| !(w.is_finite() && *w > 0.0))
                            .unwrap_or(f64::NAN),
                    });
                }
                if values.iter().any(|v| !v.is_finite()) {
                    return Err(E::NotFinite("every value"));
                }
            }
        }
        Ok(())
    }

    /// The value at probability `p` in (0, 1): the quantile function.
    pub fn quantile(&self, p: f64) -> f64 {
        let p = p.clamp(f64::MIN_POSITIVE, 1.0 - f64::EPSILON / 2.0);
        match self {
            Distribution::Uniform { min, max } => min + p * (max - min),
            Distribution::Normal { mean, sd, min, max } => {
                let n = Normal::new(*mean, *sd).unwrap_or_else(|_| unreachable!("checked"));
                let (a, b) = (n.cdf(*min), n.cdf(*max));
                n.inverse_cdf(a + p * (b - a)).clamp(*min, *max)
            }
            Distribution::LogNormal { median, sigma } => LogNormal::new(median.ln(), *sigma)
                .unwrap_or_else(|_| unreachable!("checked"))
                .inverse_cdf(p),
            Distribution::Triangular { min, mode, max } => {
                if min == mode || mode == max {
                    // statrs refuses a peak at an end; the formula covers it.
                    let f = (mode - min) / (max - min);
                    if p < f {
                        min + (p * (max - min) * (mode - min)).sqrt()
                    } else {
                        max - ((1.0 - p) * (max - min) * (max - mode)).sqrt()
                    }
                } else {
                    Triangular::new(*min, *max, *mode)
                        .unwrap_or_else(|_| unreachable!("checked"))
                        .inverse_cdf(p)
                }
            }
            Distribution::Discrete { values, weights } => {
                let total: f64 = weights.iter().sum();
                let mut acc = 0.0;
                for (v, w) in values.iter().zip(weights) {
                    acc += w / total;
                    if p < acc {
                        return *v;
                    }
                }
                *values.last().unwrap_or(&f64::NAN)
            }
        }
    }

    /// Mean and variance of the law (the truncated normal's by its closed form).
    pub fn moments(&self) -> (f64, f64) {
        match self {
            Distribution::Uniform { min, max } => ((min + max) / 2.0, (max - min).powi(2) / 12.0),
            Distribution::Normal { mean, sd, min, max } => {
                let n = Normal::new(0.0, 1.0).unwrap_or_else(|_| unreachable!());
                let (a, b) = ((min - mean) / sd, (max - mean) / sd);
                let z = n.cdf(b) - n.cdf(a);
                let pdf = |x: f64| {
                    if x.is_finite() {
                        (-0.5 * x * x).exp() / (2.0 * std::f64::consts::PI).sqrt()
                    } else {
                        0.0
                    }
                };
                let xpdf = |x: f64| if x.is_finite() { x * pdf(x) } else { 0.0 };
                let m = mean + sd * (pdf(a) - pdf(b)) / z;
                let v = sd * sd * (1.0 + (xpdf(a) - xpdf(b)) / z - ((pdf(a) - pdf(b)) / z).powi(2));
                (m, v)
            }
            Distribution::LogNormal { median, sigma } => {
                let m = median * (sigma * sigma / 2.0).exp();
                (m, m * m * ((sigma * sigma).exp() - 1.0))
            }
            Distribution::Triangular { min, mode, max } => {
                let (a, c, b) = (*min, *mode, *max);
                (
                    (a + b + c) / 3.0,
                    (a * a + b * b + c * c - a * b - a * c - b * c) / 18.0,
                )
            }
            Distribution::Discrete { values, weights } => {
                let total: f64 = weights.iter().sum();
                let m: f64 = values.iter().zip(weights).map(|(v, w)| v * w).sum::<f64>() / total;
                let v = values
                    .iter()
                    .zip(weights)
                    .map(|(x, w)| w * (x - m).powi(2))
                    .sum::<f64>()
                    / total;
                (m, v)
            }
        }
    }

    /// The smallest and largest value it can give.
    pub fn support(&self) -> (f64, f64) {
        match self {
            Distribution::Uniform { min, max } | Distribution::Triangular { min, max, .. } => {
                (*min, *max)
            }
            Distribution::Normal { min, max, .. } => (*min, *max),
            Distribution::LogNormal { .. } => (0.0, f64::INFINITY),
            Distribution::Discrete { values, .. } => (
                values.iter().copied().fold(f64::INFINITY, f64::min),
                values.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            ),
        }
    }
}
