//! Solvers: the chain linear algebra, the static equilibrium (FE and soft string), the
//! dynamics.

pub mod chain;
pub mod continuation;
pub mod dynamics;
pub mod modal;
pub mod newton;
pub mod settings;
pub mod soft_string;
pub mod static_options;
pub mod statics;
