//! The allocator's settings for a run, set once at the start of `main`.
//!
//! The CPU integrator allocates its per-iteration buffers afresh: the element responses
//! and the block matrices, about 0.5 MB each at 600 nodes. With glibc's defaults, such a
//! buffer lies above the mmap threshold, or is trimmed back to the system once freed at the
//! top of the main heap. Every Newton iteration then page-faults its buffers in again and
//! zeroes them.
//!
//! Measured on `holewall run` of dynamic corpus case 64 (595 nodes, 0.2 s simulated, on 2
//! cores): 34 s of wall time, 20 s of it in the kernel. With the thresholds raised, the
//! same run takes 15 s, with 0.8 s in the kernel. The rayon workers of `holewall bench
//! dynamic-corpus` allocate from their own arenas, and never paid this.
//!
//! Raising the thresholds keeps freed memory for reuse: a run holds at most the largest
//! set of buffers it ever had. The results are unchanged.

/// Raises glibc's mmap and trim thresholds (64 MB and 256 MB) so that the buffers a solve
/// frees are reused rather than returned to the system and faulted in again. Call it
/// before any other thread starts. A no-op elsewhere than Linux with glibc.
pub fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: `mallopt` only sets two of the allocator's parameters. It is called at the
    // start of `main`, before any other thread allocates.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 64 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 256 << 20);
    }
}
