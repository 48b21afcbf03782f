//! The GPU path: wgpu context, shader composition, shared layouts, kernel runners.

pub mod assemble;
pub mod batch;
pub mod beam;
pub mod block_cr;
pub mod block_lu;
pub mod ceilings;
pub mod compose;
pub mod contact;
pub mod context;
pub mod dispatch;
pub mod dynamics;
pub mod kernel;
pub mod layout;
pub mod loops;
pub mod pass_clock;
pub mod path;
pub mod readback;
pub mod update;

pub use context::{list_adapters, AdapterSummary, GpuContext};
pub use path::GpuPath;
