//! Where an engine run's time goes: counters of the calling thread that the benchmarks read before
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
//!
//! The counters are the calling thread's own: an engine run records its read-backs, passes
//! and phases on the thread that drives it (the device's submissions and waits, and the
//! job's phase clocks, are all taken there; rayon workers only compute), so two jobs run
//! at once on two threads — tests in parallel, a library user's own threads — each read
//! their own figures, not the sum of both.

use std::cell::Cell;

/// This thread's counters (nanoseconds or counts).
#[derive(Default)]
struct Counters {
    readbacks: Cell<u64>,
    wait_nanos: Cell<u64>,
    bytes_read: Cell<u64>,
    setup_nanos: Cell<u64>,
    open_nanos: Cell<u64>,
    device_nanos: Cell<u64>,
    trial_nanos: Cell<u64>,
    trials: Cell<u64>,
    starts_nanos: Cell<u64>,
    dynamics_nanos: Cell<u64>,
    observe_nanos: Cell<u64>,
}

thread_local! {
    static COUNTERS: Counters = Counters::default();
}

fn add(counter: impl Fn(&Counters) -> &Cell<u64>, amount: u64) {
    COUNTERS.with(|c| {
        let cell = counter(c);
        cell.set(cell.get().saturating_add(amount));
    });
}

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
    /// This thread's counters now.
    pub fn now() -> Self {
        COUNTERS.with(|c| {
            let s = |n: &Cell<u64>| n.get() as f64 * 1e-9;
            Tally {
                readbacks: c.readbacks.get(),
                wait_s: s(&c.wait_nanos),
                bytes_read: c.bytes_read.get(),
                setup_s: s(&c.setup_nanos),
                open_s: s(&c.open_nanos),
                device_s: s(&c.device_nanos),
                trial_device_s: s(&c.trial_nanos),
                trials: c.trials.get(),
                static_starts_s: s(&c.starts_nanos),
                dynamics_s: s(&c.dynamics_nanos),
                observing_s: s(&c.observe_nanos),
            }
        })
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
    add(|c| &c.readbacks, 1);
    add(|c| &c.bytes_read, bytes);
    add(|c| &c.wait_nanos, nanos(waited));
}

/// Counts `took` of an engine batch's setup, `opening` of it the opening on the kernel path.
pub fn add_setup(took: std::time::Duration, opening: std::time::Duration) {
    add(|c| &c.setup_nanos, nanos(took));
    add(|c| &c.open_nanos, nanos(opening));
}

/// Counts `took` of the device's own work in stamped passes: those of `trials` line-search
/// trials (0: not trials).
pub fn add_device(took: std::time::Duration, trials: u64) {
    add(|c| &c.device_nanos, nanos(took));
    if trials > 0 {
        add(|c| &c.trial_nanos, nanos(took));
        add(|c| &c.trials, trials);
    }
}

/// Counts `took` of an ensemble job's `phase`.
pub fn add_phase(phase: Phase, took: std::time::Duration) {
    let n = nanos(took);
    match phase {
        Phase::StaticStarts => add(|c| &c.starts_nanos, n),
        Phase::Dynamics => add(|c| &c.dynamics_nanos, n),
        Phase::Observing => add(|c| &c.observe_nanos, n),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn a_snapshot_difference_counts_exactly_what_this_thread_added_between() {
        let before = Tally::now();
        add_readback(48, Duration::from_millis(3));
        add_readback(16, Duration::from_millis(1));
        add_setup(Duration::from_millis(5), Duration::from_millis(1));
        add_device(Duration::from_millis(2), 1);
        add_device(Duration::from_millis(4), 0);
        add_phase(Phase::StaticStarts, Duration::from_millis(7));
        add_phase(Phase::Dynamics, Duration::from_millis(9));
        add_phase(Phase::Observing, Duration::from_millis(3));
        // Another thread's work at the same time (another job) is not this thread's.
        std::thread::spawn(|| {
            add_readback(1000, Duration::from_millis(50));
            add_device(Duration::from_millis(50), 3);
            add_phase(Phase::Dynamics, Duration::from_millis(50));
        })
        .join()
        .expect("the other thread ran");
        let d = Tally::now().since(&before);
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
        assert_eq!((d.readbacks, d.bytes_read, d.trials), (2, 64, 1));
        assert!(close(d.wait_s, 4e-3) && close(d.setup_s, 5e-3) && close(d.open_s, 1e-3));
        assert!(close(d.device_s, 6e-3) && close(d.trial_device_s, 2e-3));
        assert!(close(d.static_starts_s, 7e-3) && close(d.dynamics_s, 9e-3));
        assert!(close(d.observing_s, 3e-3));
    }
}
