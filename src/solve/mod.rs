//! Solvers: the chain linear algebra and the static equilibrium.

pub mod chain;
pub mod dynamics;
pub mod modal;
pub mod statics;
