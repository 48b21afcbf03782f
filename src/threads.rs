//! The rayon pool of a run, set up once at the start of `main`.
//!
//! A parallel loop called from a thread outside rayon's pool is handed to the pool's
//! workers while the caller sleeps, and the caller is woken when they are done. The CPU
//! static solve runs its element, contact-site and update loops once or twice per Newton
//! iteration, a few hundred microseconds of work each: on 2 cores the hand-offs and
//! wake-ups (futex, `sched_yield`) took what the second core gave. With the main thread one
//! of the pool's workers, it runs part of each loop itself and the other workers steal the
//! rest; nothing is handed over and nobody sleeps.
//!
//! Measured on user corpus well 841 (horizontal, sliding, 10 m elements, 754 nodes, 1,419
//! Newton iterations; `holewall static`, 2 cores): 2.15–2.51 s before, 1.64–1.76 s with the
//! main thread in the pool and the site and update loops parallel; `profile.csv` the same
//! bit for bit (every loop keeps its sums in element, site and node order).

/// Makes the calling thread (the main thread) worker 0 of rayon's global pool, with as many
/// workers as rayon starts by itself (`RAYON_NUM_THREADS`, else the cores). Call it first in
/// `main`, before anything uses rayon.
///
/// With one worker too (`RAYON_NUM_THREADS=1`, a task given one CPU): the main thread is
/// then the only worker, and every parallel loop runs in place on it. Left outside, each
/// loop was handed to the one pool thread while the main thread slept: drawn corpus well
/// 1511 (horizontal, sliding, 10 m elements, 1,261 Newton iterations; `holewall bench
/// corpus --seeds 1511`) took 4.2–4.3 s with `RAYON_NUM_THREADS=1` on 2 cores against 1.9
/// s on both; in place, 2.8 s, the same answer to the bit. No thread of holewall other than
/// the main one starts rayon work, which a main thread blocked outside rayon would leave
/// waiting.
pub fn main_thread_in_pool() {
    // `num_threads` left at rayon's default: `RAYON_NUM_THREADS` where a positive integer,
    // else the cores. Fails only if the pool was built already; it is then used as it is.
    let _ = rayon::ThreadPoolBuilder::new()
        .use_current_thread()
        .build_global();
}
