//! A Gauss–Seidel sweep's colours, one after another, in one parallel region.
//!
//! A sweep visits colour after colour; each colour's rows read only rows of other colours, so a
//! colour splits across threads, but the next colour must wait for all of it. Started as one
//! parallel loop per colour, every colour paid for a task hand-over and, from outside the pool,
//! for waking a thread and being woken: on the cotton T-shirt (about 250 rows a colour, 10 µs
//! of work) a sweep on two threads took as long as on one. Here a sweep is one region: its
//! participants go through the colours together, each colour split into a share per thread; a
//! participant that has taken every share of a colour it can waits (spinning, then yielding)
//! until the shares of that colour are finished, then goes on to the next.
//!
//! Nothing can deadlock: a participant waits only for shares that other participants have
//! taken and are computing, and `run` must not start rayon work of its own (a thread waiting
//! in it could pick up another participant of the same sweep, which would wait for the share
//! that thread holds). A thread of the pool that never joins simply leaves its shares to the
//! others. Every row is computed from the same values whatever thread runs it, so a sweep gives
//! the same bits on any number of threads.

use super::grain;
use std::cell::UnsafeCell;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// The colour of each of `n` vertices that `order` lists colour after colour, colour k from
/// `colour_offsets[k]` (`u32::MAX` for a vertex it does not list). Panics if `order` lists a
/// vertex twice (two rows of a sweep would write it at once) or one past `n`.
pub fn colour_of_each(order: &[u32], colour_offsets: &[u32], n: usize) -> Vec<u32> {
    let mut colour = vec![u32::MAX; n];
    for (k, w) in colour_offsets.windows(2).enumerate() {
        for &i in &order[w[0] as usize..w[1] as usize] {
            let slot = (colour.get_mut(i as usize))
                .unwrap_or_else(|| panic!("the colour order lists vertex {i} of {n}"));
            assert_eq!(*slot, u32::MAX, "the colour order lists vertex {i} twice");
            *slot = k as u32;
        }
    }
    colour
}

/// Runs `run(k, rows)` on every row of `colours` (row ranges, colour k the k-th given): the
/// rows of a colour after every row of the colours before it, the rows of one colour in any order, on any
/// thread. A colour splits into up to one chunk per thread of about `grain::COLOUR_ROWS` rows
/// or more; on one thread, or when no colour is long enough to split, it is a plain loop on
/// the calling thread. `run` must not start rayon work (see the module's notes).
///
/// Participant p takes the p-th chunk of every colour when it gets there first, then any
/// chunk nobody has taken. Participant 0 is the calling thread and the others are usually
/// taken by the same threads of the pool from one sweep to the next, so a thread mostly meets
/// the same rows (and, the rows of a colour being in particle order, mostly the same part of
/// the mesh) sweep after sweep, where they are still in its cache; a participant that starts
/// late loses nothing.
pub fn colour_after_colour(colours: &[Range<usize>], run: impl Fn(usize, Range<usize>) + Sync) {
    let threads = rayon::current_num_threads();
    let parallel = (colours.iter())
        .map(|r| chunk_count(r.len(), threads))
        .max()
        .unwrap_or(0);
    if parallel < 2 {
        for (k, rows) in colours.iter().enumerate() {
            run(k, rows.clone());
        }
        return;
    }
    let (chunks, by_colour) = chunks(colours, threads);
    let taken: Vec<AtomicBool> = chunks.iter().map(|_| AtomicBool::new(false)).collect();
    let done = AtomicUsize::new(0);
    let work = |p: usize| {
        for (c, colour) in by_colour.iter().enumerate() {
            wait_until(&done, colour.start);
            let own = (colour.start + p < colour.end).then_some(colour.start + p);
            for k in own.into_iter().chain(colour.clone()) {
                if !taken[k].swap(true, Ordering::Relaxed) {
                    let _finished = Finished(&done);
                    run(c, chunks[k].clone());
                }
            }
        }
    };
    rayon::scope(|scope| {
        for p in 1..parallel {
            scope.spawn(move |_| work(p));
        }
        work(0);
    });
}

/// Counts a chunk as finished when dropped: after its rows, or while a panic unwinds, so that
/// the threads waiting for it go on and the panic reaches the caller.
struct Finished<'a>(&'a AtomicUsize);

impl Drop for Finished<'_> {
    fn drop(&mut self) {
        // Release: the chunk's writes happen before any read by a chunk that waits for it.
        self.0.fetch_add(1, Ordering::Release);
    }
}

/// How many chunks a colour of `len` rows splits into on `threads` threads.
fn chunk_count(len: usize, threads: usize) -> usize {
    (len / grain::COLOUR_ROWS).clamp(1, threads)
}

/// The sweep's chunks (row ranges, colour after colour) and each colour's chunks (indices).
fn chunks(colours: &[Range<usize>], threads: usize) -> (Vec<Range<usize>>, Vec<Range<usize>>) {
    let (mut chunks, mut by_colour) = (Vec::new(), Vec::new());
    for rows in colours {
        let first = chunks.len();
        let size = rows.len().div_ceil(chunk_count(rows.len(), threads));
        let mut start = rows.start;
        while start < rows.end {
            let end = (start + size).min(rows.end);
            chunks.push(start..end);
            start = end;
        }
        by_colour.push(first..chunks.len());
    }
    (chunks, by_colour)
}

/// Waits until `done` reaches `count`: spinning a while (a chunk lasts microseconds), then
/// yielding the core to whatever else runs on it.
fn wait_until(done: &AtomicUsize, count: usize) {
    let mut spins = 0u32;
    // Acquire: the finished chunks' writes are visible after the wait.
    while done.load(Ordering::Acquire) < count {
        if spins < 256 {
            std::hint::spin_loop();
            spins += 1;
        } else {
            std::thread::yield_now();
        }
    }
}

/// A slice whose elements threads read and write through shared references, as a colour
/// sweep does: each element written by one row, read by rows of other colours only.
pub struct Cells<'a, T>(&'a [SyncCell<T>]);

#[repr(transparent)]
struct SyncCell<T>(UnsafeCell<T>);

// SAFETY: the cells are only touched through `Cells::get` and `Cells::set`, whose callers
// promise that no element is written while another thread reads or writes it.
unsafe impl<T: Send> Sync for SyncCell<T> {}

impl<'a, T: Copy + Send> Cells<'a, T> {
    /// Shares `slice` for the length of the borrow.
    pub fn new(slice: &'a mut [T]) -> Self {
        let len = slice.len();
        let ptr = slice.as_mut_ptr() as *const SyncCell<T>;
        // SAFETY: SyncCell<T> is a transparent UnsafeCell<T>, which has T's layout, and the
        // exclusive borrow of `slice` is held for 'a, so nothing else reaches the elements.
        Cells(unsafe { std::slice::from_raw_parts(ptr, len) })
    }

    /// Element `i`.
    ///
    /// # Safety
    /// No thread writes element `i` while this reads it.
    #[inline]
    pub unsafe fn get(&self, i: usize) -> T {
        *self.0[i].0.get()
    }

    /// The elements as a slice.
    ///
    /// # Safety
    /// No thread writes any element while the slice is in use.
    #[inline]
    pub unsafe fn as_slice(&self) -> &[T] {
        std::slice::from_raw_parts(self.0.as_ptr() as *const T, self.0.len())
    }

    /// Writes element `i`.
    ///
    /// # Safety
    /// No other thread reads or writes element `i` while this writes it.
    #[inline]
    pub unsafe fn set(&self, i: usize, value: T) {
        *self.0[i].0.get() = value;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::mpsc;

    /// Runs a sweep of `colours` on `pool`, recording for each row the order in which it ran
    /// and, per colour, how many rows of the colours before it had run when its first row began.
    fn record(pool: &rayon::ThreadPool, colours: &[Range<usize>]) -> (Vec<usize>, Vec<usize>) {
        let n = colours.last().map_or(0, |c| c.end);
        let clock = AtomicUsize::new(0);
        let ran: Vec<AtomicUsize> = (0..n).map(|_| AtomicUsize::new(usize::MAX)).collect();
        let counts: Vec<AtomicUsize> = (0..n).map(|_| AtomicUsize::new(0)).collect();
        pool.install(|| {
            colour_after_colour(colours, |_, rows| {
                for r in rows {
                    counts[r].fetch_add(1, Ordering::Relaxed);
                    ran[r].store(clock.fetch_add(1, Ordering::SeqCst), Ordering::SeqCst);
                }
            })
        });
        let counts: Vec<usize> = counts.iter().map(|c| c.load(Ordering::Relaxed)).collect();
        assert!(
            counts.iter().all(|&c| c == 1),
            "every row runs once: {counts:?}"
        );
        let ran: Vec<usize> = ran.iter().map(|r| r.load(Ordering::SeqCst)).collect();
        let before = (colours.iter())
            .map(|c| (ran[c.clone()].iter().min().copied()).unwrap_or(0))
            .collect();
        (ran, before)
    }

    fn colours(lengths: &[usize]) -> Vec<Range<usize>> {
        let mut start = 0;
        (lengths.iter())
            .map(|&len| {
                start += len;
                start - len..start
            })
            .collect()
    }

    #[test]
    fn every_colour_waits_for_all_rows_before_it() {
        // Colours long enough to split three ways, one too short to split, and an empty one.
        let colours = colours(&[1000, 10, 0, 700, 1000]);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap();
        for _ in 0..20 {
            let (ran, first) = record(&pool, &colours);
            for (c, rows) in colours.iter().enumerate().filter(|(_, r)| !r.is_empty()) {
                let earlier = colours[..c].iter().flat_map(|r| r.clone());
                let last_before = earlier.map(|r| ran[r]).max();
                assert!(
                    last_before.is_none_or(|t| t < first[c]),
                    "colour {c} ({rows:?}) started before the colours before it ended"
                );
            }
        }
    }

    #[test]
    fn the_chunks_cover_each_colour_once_at_most_one_per_thread() {
        let colours = colours(&[1000, 10, 0, 130, 127]);
        let (chunks, by_colour) = chunks(&colours, 3);
        for (rows, indices) in colours.iter().zip(&by_colour) {
            let covered: Vec<usize> = chunks[indices.clone()]
                .iter()
                .flat_map(|r| r.clone())
                .collect();
            assert_eq!(covered, rows.clone().collect::<Vec<_>>());
            assert!(indices.len() <= 3);
            assert!(chunks[indices.clone()]
                .iter()
                .all(|r| r.len() >= grain::COLOUR_ROWS || indices.len() == 1));
        }
        assert_eq!(
            by_colour.iter().map(|c| c.len()).collect::<Vec<_>>(),
            [3, 1, 0, 2, 1]
        );
    }

    #[test]
    fn a_sweep_ends_while_a_thread_of_the_pool_is_busy_elsewhere() {
        // One of the pool's two threads is held by another task until the sweep has ended:
        // the sweep's second participant never starts, and the first takes its chunks.
        let colours = colours(&[1000, 1000, 1000]);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let (release, wait) = mpsc::channel::<()>();
        let (started, is_started) = mpsc::channel::<()>();
        pool.spawn(move || {
            started.send(()).unwrap();
            wait.recv().unwrap();
        });
        is_started.recv().unwrap();
        let (_, first) = record(&pool, &colours);
        assert_eq!(first.len(), 3);
        release.send(()).unwrap();
    }
}
