//! Work spread over threads: items are handed out one at a time from a shared counter, so a slow
//! item never idles the other threads, and results land by index, so the output order (and every
//! value) is the same whatever the thread count.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// Threads to use by default: every core the process may run on.
pub fn default_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// `f` applied to every item on up to `threads` threads; `done` is called after each item.
pub fn map<T: Sync, R: Send>(
    items: &[T],
    threads: usize,
    f: impl Fn(&T) -> R + Sync,
    done: impl Fn() + Sync,
) -> Vec<R> {
    let threads = threads.clamp(1, items.len().max(1));
    let next = AtomicUsize::new(0);
    let slots: Mutex<Vec<Option<R>>> = Mutex::new((0..items.len()).map(|_| None).collect());
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(item) = items.get(i) else { break };
                let r = f(item);
                if let Ok(mut s) = slots.lock() {
                    s[i] = Some(r);
                }
                done();
            });
        }
    });
    slots
        .into_inner()
        .unwrap_or_default()
        .into_iter()
        .flatten()
        .collect()
}

#[cfg(test)]
mod tests {
    #[test]
    fn results_keep_the_input_order_on_any_thread_count() {
        let items: Vec<u64> = (0..57).collect();
        let work =
            |x: &u64| (0..(x % 7) * 1000).fold(*x, |a, b| a.wrapping_mul(31).wrapping_add(b));
        let one = super::map(&items, 1, work, || {});
        let count = std::sync::atomic::AtomicUsize::new(0);
        let four = super::map(&items, 4, work, || {
            count.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        });
        assert_eq!(one, four);
        assert_eq!(count.into_inner(), 57);
        assert_eq!(one.len(), 57);
    }
}
