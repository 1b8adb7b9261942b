//! Work in contiguous parts on scoped threads, the first part on the calling thread.
//!
//! The stages that share work between threads cut it into parts that each write only
//! their own slices, so the results do not depend on how many threads ran them.

use std::sync::Mutex;
use std::sync::atomic::{AtomicU8, Ordering};

/// `items` cut before each of `cuts` after the first (ascending, the first 0, the last
/// `items.len()`): one slice per run.
pub fn split_at_cuts<'a, T>(mut items: &'a mut [T], cuts: &[usize]) -> Vec<&'a mut [T]> {
    let mut runs = Vec::with_capacity(cuts.len().saturating_sub(1));
    for w in cuts.windows(2) {
        let (run, rest) = std::mem::take(&mut items).split_at_mut(w[1] - w[0]);
        runs.push(run);
        items = rest;
    }
    runs
}

/// `work(i, part)` for every part, the first on this thread and the others on scoped
/// threads; the results in part order. One part starts no thread.
pub fn run_each<P: Send, R: Send>(parts: Vec<P>, work: impl Fn(usize, P) -> R + Sync) -> Vec<R> {
    if parts.len() <= 1 {
        return parts.into_iter().map(|p| work(0, p)).collect();
    }
    let work = &work;
    std::thread::scope(|scope| {
        let mut parts = parts.into_iter();
        let first = parts.next().expect("more than one part");
        let handles: Vec<_> = (parts.enumerate())
            .map(|(i, p)| scope.spawn(move || work(i + 1, p)))
            .collect();
        let mut results = vec![work(0, first)];
        for h in handles {
            results.push(h.join().expect("a worker thread panicked"));
        }
        results
    })
}

/// `work(first index, run)` over `threads` contiguous runs of `items` that start at
/// multiples of `align`; the results in run order.
pub fn in_runs<T: Send, R: Send>(
    items: &mut [T],
    threads: usize,
    align: usize,
    work: impl Fn(usize, &mut [T]) -> R + Sync,
) -> Vec<R> {
    let blocks = items.len().div_ceil(align);
    let threads = threads.clamp(1, blocks.max(1));
    let cuts: Vec<usize> = (0..=threads)
        .map(|t| (blocks * t / threads * align).min(items.len()))
        .collect();
    let parts = split_at_cuts(items, &cuts);
    run_each(parts, |t, run| work(cuts[t], run))
}

/// A second thread that runs jobs handed to it one at a time, in lock step with the
/// thread that hands them over: for work cut into short rounds (a few tens of
/// microseconds) that spawning a thread per round would swamp. It spins between jobs,
/// yielding once a wait grows long.
pub struct Partner<J, R> {
    state: AtomicU8,
    job: Mutex<Option<J>>,
    result: Mutex<Option<R>>,
}

const IDLE: u8 = 0;
const POSTED: u8 = 1;
const DONE: u8 = 2;
const QUIT: u8 = 3;
/// The partner thread ended without finishing its job (it panicked).
const DEAD: u8 = 4;

impl<J, R> Partner<J, R> {
    /// Hand the partner `job` (the last one's result must have been taken).
    pub fn send(&self, job: J) {
        *lock(&self.job) = Some(job);
        self.state.store(POSTED, Ordering::Release);
    }

    /// The result of the job last sent, once the partner has it.
    pub fn wait(&self) -> R {
        let state = spin_until(&self.state, |s| s == DONE || s == DEAD);
        assert!(state == DONE, "the partner thread panicked");
        self.state.store(IDLE, Ordering::Relaxed);
        lock(&self.result)
            .take()
            .expect("a finished job leaves its result")
    }
}

/// Run `body` on this thread with a [`Partner`] that runs `work` on each job sent to
/// it; the partner stops when `body` returns (or unwinds).
pub fn with_partner<J: Send, R: Send, T>(
    mut work: impl FnMut(J) -> R + Send,
    body: impl FnOnce(&Partner<J, R>) -> T,
) -> T {
    let partner = Partner {
        state: AtomicU8::new(IDLE),
        job: Mutex::new(None),
        result: Mutex::new(None),
    };
    /// Tells the other side this side is gone, however it leaves.
    struct Leave<'a>(&'a AtomicU8, u8);
    impl Drop for Leave<'_> {
        fn drop(&mut self) {
            self.0.store(self.1, Ordering::Release);
        }
    }
    std::thread::scope(|scope| {
        let p = &partner;
        scope.spawn(move || {
            let dead = Leave(&p.state, DEAD);
            loop {
                if spin_until(&p.state, |s| s == POSTED || s == QUIT) == QUIT {
                    // Not dead: it left as asked.
                    std::mem::forget(dead);
                    return;
                }
                let job = lock(&p.job).take().expect("a posted job");
                let result = work(job);
                *lock(&p.result) = Some(result);
                // The caller may have left meanwhile (unwinding): then so does the partner.
                if (p.state)
                    .compare_exchange(POSTED, DONE, Ordering::AcqRel, Ordering::Acquire)
                    .is_err()
                {
                    std::mem::forget(dead);
                    return;
                }
            }
        });
        let _quit = Leave(&partner.state, QUIT);
        body(&partner)
    })
}

/// Wait until `state` satisfies `done`, returning it: spinning at first, then yielding
/// the core between looks.
fn spin_until(state: &AtomicU8, done: impl Fn(u8) -> bool) -> u8 {
    let mut spins = 0u32;
    loop {
        let s = state.load(Ordering::Acquire);
        if done(s) {
            return s;
        }
        if spins < 1 << 14 {
            spins += 1;
            std::hint::spin_loop();
        } else {
            std::thread::yield_now();
        }
    }
}

/// The guarded value, whether or not a holder panicked.
fn lock<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_partner_runs_each_job_sent_in_turn() {
        let mut seen = Vec::new();
        let total = with_partner(
            |x: u64| {
                seen.push(x);
                x * x
            },
            |partner| {
                let mut total = 0;
                for x in 1..=100 {
                    partner.send(x);
                    total += partner.wait();
                }
                total
            },
        );
        assert_eq!(total, (1..=100u64).map(|x| x * x).sum::<u64>());
        assert_eq!(seen, (1..=100).collect::<Vec<_>>());
    }

    #[test]
    fn a_partner_that_panics_is_reported_not_waited_for() {
        let outcome = std::panic::catch_unwind(|| {
            with_partner(
                |x: u32| {
                    assert!(x < 3, "a job the partner cannot do");
                    x
                },
                |partner| {
                    for x in 0..5 {
                        partner.send(x);
                        partner.wait();
                    }
                },
            )
        });
        assert!(outcome.is_err());
    }
}
