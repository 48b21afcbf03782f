//! Where an engine run's time goes: process-wide counters that the benchmarks read before
//! and after a run (issue 27: on a real GPU the dynamic engine's time was not in its
//! kernels, and a wall clock alone cannot say where it was).
//!
//! Counted: every read-back of device buffers ([`crate::gpu::readback`], the one place they
//! happen) with the time the host waited for it — from the submission to the bytes in hand,
//! so the device's work on everything submitted before it, the copy and the round trip —
//! and the bytes read; the device's own time in the passes it stamps; and the setup of every engine batch (its tables, the variants'
//! initial states, the upload) before its first step. The rest of a run's wall time is the
//! host's own: recording and submitting work, the Newton decisions between read-backs.
//! The counters only grow; [`Tally::since`] takes the difference of two snapshots.
//! Runs on other threads at the same time add to the same counters.

use std::sync::atomic::{AtomicU64, Ordering};

static READBACKS: AtomicU64 = AtomicU64::new(0);
static WAIT_NANOS: AtomicU64 = AtomicU64::new(0);
static BYTES_READ: AtomicU64 = AtomicU64::new(0);
static SETUP_NANOS: AtomicU64 = AtomicU64::new(0);
static OPEN_NANOS: AtomicU64 = AtomicU64::new(0);
static DEVICE_NANOS: AtomicU64 = AtomicU64::new(0);
static TRIAL_NANOS: AtomicU64 = AtomicU64::new(0);
static TRIALS: AtomicU64 = AtomicU64::new(0);
static STARTS_NANOS: AtomicU64 = AtomicU64::new(0);
static DYNAMICS_NANOS: AtomicU64 = AtomicU64::new(0);
static OBSERVE_NANOS: AtomicU64 = AtomicU64::new(0);

/// A phase of an ensemble job on the engine ([`add_phase`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Phase {
    /// The variants' static starts solved on the engine (and held in the hole).
    StaticStarts,
    /// The dynamic runs on the engine, observation included.
    Dynamics,
    /// Of those, observing the variants' states at every output step.
    Observing,
}

/// A snapshot of the counters.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Tally {
    /// Read-backs of device buffers (host round trips that wait for the device).
    pub readbacks: u64,
    /// Seconds the host waited in them.
    pub wait_s: f64,
    /// Bytes they read.
    pub bytes_read: u64,
    /// Seconds spent setting engine batches up before their first step.
    pub setup_s: f64,
    /// Of `setup_s`, opening the batches on their kernel path (on a GPU: allocating its
    /// buffers and uploading the tables and the state).
    pub open_s: f64,
    /// Seconds of the device's own work in the resident batches' stamped passes
    /// ([`crate::gpu::pass_clock`]; 0 where the adapter has no timestamps): of the waits,
    /// the part that is the kernels, not the round trip.
    pub device_s: f64,
    /// Of `device_s`, the line-search trials' passes.
    pub trial_device_s: f64,
    /// Line-search trials stamped (each trial of a round formed in one pass counts).
    pub trials: u64,
    /// Seconds of [`Phase::StaticStarts`].
    pub static_starts_s: f64,
    /// Seconds of [`Phase::Dynamics`].
    pub dynamics_s: f64,
    /// Seconds of [`Phase::Observing`].
    pub observing_s: f64,
}

impl Tally {
    /// The counters now.
    pub fn now() -> Self {
        Tally {
            readbacks: READBACKS.load(Ordering::Relaxed),
            wait_s: WAIT_NANOS.load(Ordering::Relaxed) as f64 * 1e-9,
            bytes_read: BYTES_READ.load(Ordering::Relaxed),
            setup_s: SETUP_NANOS.load(Ordering::Relaxed) as f64 * 1e-9,
            open_s: OPEN_NANOS.load(Ordering::Relaxed) as f64 * 1e-9,
            device_s: DEVICE_NANOS.load(Ordering::Relaxed) as f64 * 1e-9,
            trial_device_s: TRIAL_NANOS.load(Ordering::Relaxed) as f64 * 1e-9,
            trials: TRIALS.load(Ordering::Relaxed),
            static_starts_s: STARTS_NANOS.load(Ordering::Relaxed) as f64 * 1e-9,
            dynamics_s: DYNAMICS_NANOS.load(Ordering::Relaxed) as f64 * 1e-9,
            observing_s: OBSERVE_NANOS.load(Ordering::Relaxed) as f64 * 1e-9,
        }
    }

    /// What was counted between `before` and this snapshot.
    pub fn since(&self, before: &Tally) -> Tally {
        Tally {
            readbacks: self.readbacks - before.readbacks,
            wait_s: self.wait_s - before.wait_s,
            bytes_read: self.bytes_read - before.bytes_read,
            setup_s: self.setup_s - before.setup_s,
            open_s: self.open_s - before.open_s,
            device_s: self.device_s - before.device_s,
            trial_device_s: self.trial_device_s - before.trial_device_s,
            trials: self.trials - before.trials,
            static_starts_s: self.static_starts_s - before.static_starts_s,
            dynamics_s: self.dynamics_s - before.dynamics_s,
            observing_s: self.observing_s - before.observing_s,
        }
    }
}

fn nanos(d: std::time::Duration) -> u64 {
    u64::try_from(d.as_nanos()).unwrap_or(u64::MAX)
}

/// Counts one read-back of `bytes` for which the host waited `waited`.
pub fn add_readback(bytes: u64, waited: std::time::Duration) {
    READBACKS.fetch_add(1, Ordering::Relaxed);
    BYTES_READ.fetch_add(bytes, Ordering::Relaxed);
    WAIT_NANOS.fetch_add(nanos(waited), Ordering::Relaxed);
}

/// Counts `took` of an engine batch's setup, `opening` of it the opening on the kernel path.
pub fn add_setup(took: std::time::Duration, opening: std::time::Duration) {
    SETUP_NANOS.fetch_add(nanos(took), Ordering::Relaxed);
    OPEN_NANOS.fetch_add(nanos(opening), Ordering::Relaxed);
}

/// Counts `took` of the device's own work in stamped passes: those of `trials` line-search
/// trials (0: not trials).
pub fn add_device(took: std::time::Duration, trials: u64) {
    DEVICE_NANOS.fetch_add(nanos(took), Ordering::Relaxed);
    if trials > 0 {
        TRIAL_NANOS.fetch_add(nanos(took), Ordering::Relaxed);
        TRIALS.fetch_add(trials, Ordering::Relaxed);
    }
}

/// Counts `took` of an ensemble job's `phase`.
pub fn add_phase(phase: Phase, took: std::time::Duration) {
    let counter = match phase {
        Phase::StaticStarts => &STARTS_NANOS,
        Phase::Dynamics => &DYNAMICS_NANOS,
        Phase::Observing => &OBSERVE_NANOS,
    };
    counter.fetch_add(nanos(took), Ordering::Relaxed);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_snapshot_difference_counts_what_was_added_between() {
        let before = Tally::now();
        add_readback(48, std::time::Duration::from_millis(3));
        add_readback(16, std::time::Duration::from_millis(1));
        add_setup(
            std::time::Duration::from_millis(5),
            std::time::Duration::from_millis(1),
        );
        add_device(std::time::Duration::from_millis(2), 1);
        add_phase(Phase::Observing, std::time::Duration::from_millis(3));
        let d = Tally::now().since(&before);
        // Other tests may read back at the same time: at least what was added here.
        assert!(d.readbacks >= 2 && d.bytes_read >= 64);
        assert!(d.wait_s >= 4e-3 - 1e-12 && d.setup_s >= 5e-3 - 1e-12);
        assert!(d.open_s >= 1e-3 - 1e-12);
        assert!(d.device_s >= 2e-3 - 1e-12 && d.trial_device_s >= 2e-3 - 1e-12);
        assert!(d.trials >= 1);
        assert!(d.observing_s >= 3e-3 - 1e-12);
    }
}
