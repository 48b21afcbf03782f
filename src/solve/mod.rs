//! Solvers: the chain linear algebra and the static equilibrium.

pub mod chain;
pub mod continuation;
pub mod dynamics;
pub mod modal;
pub mod newton;
pub mod settings;
pub mod static_options;
pub mod statics;
