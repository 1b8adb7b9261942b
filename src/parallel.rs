//! Work in contiguous parts on scoped threads, the first part on the calling thread.
//!
//! The stages that share work between threads cut it into parts that each write only
//! their own slices, so the results do not depend on how many threads ran them.

use std::sync::atomic::{AtomicU8, AtomicU32, Ordering};
use std::sync::{Condvar, Mutex};

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

/// `each(lane)` for every lane of `rest` on a scoped thread of its own while `first`
/// runs on this thread; returns when all are done. For stages that keep one lane of
/// buffers per thread from step to step (the islands' projection, the contact groups'):
/// nothing is allocated here but the threads.
pub fn alongside<L: Send>(rest: &mut [L], each: impl Fn(&mut L) + Sync, first: impl FnOnce()) {
    let each = &each;
    std::thread::scope(|scope| {
        for lane in rest.iter_mut() {
            scope.spawn(move || each(lane));
        }
        first();
    });
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
/// microseconds) that spawning a thread per round would swamp. Each side spins a few
/// microseconds for the other, then sleeps until woken: spinning on, a busy machine
/// (a game's own threads) would take the core the other side needs.
pub struct Partner<J, R> {
    state: Signal,
    job: Mutex<Option<J>>,
    result: Mutex<Option<R>>,
}

/// A state both sides watch: spun on briefly, then slept on.
struct Signal {
    state: AtomicU8,
    /// Threads asleep on `wake` (or about to be).
    sleepers: AtomicU32,
    lock: Mutex<()>,
    wake: Condvar,
}

impl Signal {
    fn new() -> Signal {
        Signal {
            state: AtomicU8::new(IDLE),
            sleepers: AtomicU32::new(0),
            lock: Mutex::new(()),
            wake: Condvar::new(),
        }
    }

    fn load(&self) -> u8 {
        self.state.load(Ordering::SeqCst)
    }

    /// Set the state and wake whoever sleeps on it.
    fn store(&self, state: u8) {
        self.state.store(state, Ordering::SeqCst);
        self.notify();
    }

    /// Set the state from `from` to `to`, if it is still `from`.
    fn swap_from(&self, from: u8, to: u8) -> bool {
        let swapped = (self.state)
            .compare_exchange(from, to, Ordering::SeqCst, Ordering::SeqCst)
            .is_ok();
        if swapped {
            self.notify();
        }
        swapped
    }

    fn notify(&self) {
        // A sleeper counts itself before it last looks at the state, both sequentially
        // consistent: either it sees the new state or it is counted here.
        if self.sleepers.load(Ordering::SeqCst) > 0 {
            drop(lock(&self.lock));
            self.wake.notify_all();
        }
    }

    /// Wait until the state satisfies `done`, returning it: spinning a few
    /// microseconds, then asleep.
    fn until(&self, done: impl Fn(u8) -> bool) -> u8 {
        for _ in 0..SPINS {
            let s = self.load();
            if done(s) {
                return s;
            }
            std::hint::spin_loop();
        }
        let mut guard = lock(&self.lock);
        self.sleepers.fetch_add(1, Ordering::SeqCst);
        let s = loop {
            let s = self.load();
            if done(s) {
                break s;
            }
            guard = self
                .wake
                .wait(guard)
                .unwrap_or_else(std::sync::PoisonError::into_inner);
        };
        self.sleepers.fetch_sub(1, Ordering::SeqCst);
        s
    }
}

/// Looks at the state before sleeping: a few microseconds, about the gap between two
/// jobs of a sweep that is not waiting on the other side.
const SPINS: u32 = 1 << 11;

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
        self.state.store(POSTED);
    }

    /// The result of the job last sent, once the partner has it.
    pub fn wait(&self) -> R {
        let state = self.state.until(|s| s == DONE || s == DEAD);
        assert!(state == DONE, "the partner thread panicked");
        self.state.state.store(IDLE, Ordering::SeqCst);
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
        state: Signal::new(),
        job: Mutex::new(None),
        result: Mutex::new(None),
    };
    /// Tells the other side this side is gone, however it leaves.
    struct Leave<'a>(&'a Signal, u8);
    impl Drop for Leave<'_> {
        fn drop(&mut self) {
            self.0.store(self.1);
        }
    }
    std::thread::scope(|scope| {
        let p = &partner;
        scope.spawn(move || {
            let dead = Leave(&p.state, DEAD);
            loop {
                if p.state.until(|s| s == POSTED || s == QUIT) == QUIT {
                    // Not dead: it left as asked.
                    std::mem::forget(dead);
                    return;
                }
                let job = lock(&p.job).take().expect("a posted job");
                let result = work(job);
                *lock(&p.result) = Some(result);
                // The caller may have left meanwhile (unwinding): then so does the partner.
                if !p.state.swap_from(POSTED, DONE) {
                    std::mem::forget(dead);
                    return;
                }
            }
        });
        let _quit = Leave(&partner.state, QUIT);
        body(&partner)
    })
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
    fn both_sides_sleep_through_long_waits_and_are_woken() {
        // Jobs far longer than the spin, and gaps between jobs as long: each side ends
        // up asleep waiting for the other.
        let pause = std::time::Duration::from_millis(3);
        let total = with_partner(
            |x: u32| {
                std::thread::sleep(pause);
                x + 1
            },
            |partner| {
                let mut total = 0;
                for x in 0..5 {
                    std::thread::sleep(pause);
                    partner.send(x);
                    total += partner.wait();
                }
                total
            },
        );
        assert_eq!(total, 15);
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
