//! Shared test helpers.
#![allow(dead_code)]

use holewall::gpu::GpuContext;

/// The shared GPU context. With `HOLEWALL_REQUIRE_GPU=1` (CI) a missing adapter fails the
/// test; otherwise the test is skipped, loudly.
pub fn gpu() -> Option<&'static GpuContext> {
    match GpuContext::shared() {
        Ok(ctx) => Some(ctx),
        Err(e) => {
            if std::env::var("HOLEWALL_REQUIRE_GPU").as_deref() == Ok("1") {
                panic!("HOLEWALL_REQUIRE_GPU=1 but no GPU adapter: {e}");
            }
            eprintln!("\n*** SKIPPED: no GPU adapter ({e}); GPU tests did not run ***\n");
            None
        }
    }
}
