//! Work in contiguous parts on scoped threads, the first part on the calling thread.
//!
//! The stages that share work between threads cut it into parts that each write only
//! their own slices, so the results do not depend on how many threads ran them.

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
