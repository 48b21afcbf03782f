//! holewall: a rotating drillstring touching the borehole wall, simulated for many
//! parameter variants at once.
//!
//! The contact element of Le Phuoc Hao & Ta Quoc Dung (§2 of the seed paper, corrected as in
//! `docs/contact-element.md`) is written once in [`physics::contact`], evaluated on the CPU
//! by the twins in [`kernels`] (f64, the oracle) and on the GPU by the WGSL kernels in
//! `shaders/` through [`gpu`], f32 or f64.

#![warn(missing_docs)]

pub mod allocator;
pub mod atomic_file;
pub mod backend;
pub mod bha;
pub mod calibrate;
pub mod case;
pub mod cli;
pub mod corpus;
pub mod diagnose;
pub mod display_units;
pub mod engine;
pub mod ensemble;
pub mod error;
pub mod gpu;
pub mod kernels;
pub mod keys;
pub mod model;
pub mod output;
pub mod physics;
pub mod plots;
pub mod profile;
pub mod report_html;
pub mod rig;
pub mod run;
pub mod selfcheck;
pub mod solve;
pub mod strength;
pub mod study;
pub mod tally;
pub mod threads;
pub mod units;
pub mod uq;
pub mod well;
pub mod whirl;

pub use error::{Error, GpuError, InputError};
