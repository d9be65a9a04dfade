//! How finely the CPU twins split their loops over rayon's pool.
//!
//! Every task that another thread takes costs a few microseconds however little it computes:
//! the steal, the cache lines it pulls over, and waking the thread if it had gone to sleep.
//! Implicit Euler's solve runs thousands of loops a frame, many of them over a few hundred
//! elements (a colour, a coarse level) or at a few nanoseconds an element (the conjugate-gradient
//! vector updates); split as finely as rayon splits by default (a few tasks per thread), such
//! loops cost more on many threads than on one. So each parallel loop asks for tasks of at
//! least `TASK_NANOS` of work (`with_min_len` of the grain of its kind of element), and a loop
//! shorter than two grains runs as one task on the calling thread: a plain loop, no other thread
//! involved. A Gauss–Seidel sweep's colours are the exception: they split across every thread
//! of the pool down to `COLOUR_ROWS`, inside one parallel region per sweep (`colour_run`).
//!
//! The grains divide `TASK_NANOS` by an element's cost, measured on one core of a 2-core AMD
//! EPYC with the solve's per-operation timings (the cotton T-shirt and the 128² benchmark
//! cloth). Splitting never changes a result: every loop writes each element from reads of
//! arrays that the loop does not write.

/// The least work a task is given, in ns: several times what handing it to another thread
/// costs, and small enough that a colour of the 128² benchmark cloth (about 2,000 vertices,
/// 0.5 ms) still splits into a task for each of 16 threads.
const TASK_NANOS: usize = 20_000;

/// Element-wise vector updates (a few flops on 16-byte values; about 3 ns).
pub const ARRAY: usize = TASK_NANOS / 3;

/// Rows of a block-sparse product or smoothing sweep, and coarse blocks of a Galerkin product
/// (a 3×3 block per neighbour; about 40 ns).
pub const ROW: usize = TASK_NANOS / 40;

/// The fewest rows a thread's share of a sweep's colour gets (a smoothing row is about 40 ns,
/// a vertex step about 400: 2.5 to 25 µs of work). The threads of a sweep are awake from the
/// colour before, so a share costs far less to hand over than `TASK_NANOS`.
pub const COLOUR_ROWS: usize = 64;

/// Vertices that gather their elements: forces, Hessians, energies, contacts (250 to 1,000 ns).
pub const VERTEX: usize = TASK_NANOS / 250;

/// A grain counted in blocks of `WORKGROUP_SIZE` elements, for loops over the kernels'
/// workgroup partials: at least one block.
pub const fn blocks(grain: usize) -> usize {
    let size = crate::model::layout::WORKGROUP_SIZE as usize;
    if grain > size {
        grain / size
    } else {
        1
    }
}

/// Whether a loop of `len` elements splits into tasks at `grain` (`with_min_len` halves a
/// range only while both halves keep a grain); a loop that does not runs on the calling thread
/// and may then update in place.
pub const fn splits(len: usize, grain: usize) -> bool {
    len >= 2 * grain
}
