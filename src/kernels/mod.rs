//! CPU twins of the WGSL kernels in `shaders/`: same names, same data layout, same loop
//! index (`i` here where the shader has `gid.x`). They are the oracle the GPU results are
//! tested against and the fallback where no adapter exists.
//!
//! | WGSL kernel | CPU twin |
//! |---|---|
//! | `shaders/contact.wgsl` | [`contact`] |
//! | `shaders/block_lu.wgsl` | [`block_lu`] |
//! | `shaders/block_cr.wgsl` | [`block_cr`] |
//! | `shaders/assemble.wgsl` | [`assemble`] |
//! | `shaders/update.wgsl` | [`update`] |
//! | `shaders/beam.wgsl` | [`beam`] |
//! | `shaders/sites.wgsl` | [`sites`] |
//! | `shaders/dynamics.wgsl` | [`dynamics`] |
//!
//! [`tridiagonal`] holds the block-tridiagonal matrix they and the solvers share.

pub mod assemble;
pub mod beam;
pub mod block_cr;
pub mod block_lu;
pub mod contact;
pub mod dynamics;
pub mod sites;
pub mod tridiagonal;
pub mod update;

/// Every (shader, twin) pair; a test fails if a shader under `shaders/` is missing here.
pub const TWINS: &[(&str, &str)] = &[
    ("contact.wgsl", "src/kernels/contact.rs"),
    ("block_lu.wgsl", "src/kernels/block_lu.rs"),
    ("block_cr.wgsl", "src/kernels/block_cr.rs"),
    ("assemble.wgsl", "src/kernels/assemble.rs"),
    ("update.wgsl", "src/kernels/update.rs"),
    ("beam.wgsl", "src/kernels/beam.rs"),
    ("sites.wgsl", "src/kernels/sites.rs"),
    ("dynamics.wgsl", "src/kernels/dynamics.rs"),
];
