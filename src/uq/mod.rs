//! Uncertainty quantification (issue 14): the distributions of uncertain inputs, sampling
//! (random, Latin hypercube, scrambled Sobol), statistics of the quantities of interest and
//! their sensitivity to the inputs. Library code: `holewall ensemble` calls it, and so can
//! any program that builds variants of a case.

pub mod distribution;
pub mod report;
pub mod sampling;
pub mod sensitivity;
pub mod stats;

pub use distribution::{Distribution, DistributionError};
pub use sampling::{unit_samples, Sampling, SamplingError};
