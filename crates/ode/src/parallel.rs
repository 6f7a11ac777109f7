//! Data parallelism whose results do not depend on the thread count: the same bits on one core or on
//! every core, so that determinism stays a property of a run and not of the machine that ran it.
//!
//! Three patterns cover every loop of an implicit step, and each is written so that the arithmetic a
//! coordinate sees is the serial loop's, in the serial loop's order:
//!
//! - **Elementwise loops** ([`for_chunks`], [`for_chunks2`], [`for_chunks3`]): each coordinate is
//!   computed from its own inputs, so any split gives the same numbers.
//! - **Sums** ([`Sum`]): partial sums over fixed blocks of [`SUM_BLOCK`] terms, then the partials
//!   added in order. The blocks do not depend on the thread count, and a sum of at most `SUM_BLOCK`
//!   terms is the plain left-to-right sum.
//! - **Scatters** ([`Scatter`]): a loop over elements (springs, bending stencils) that adds each
//!   element's contribution to its vertices. The vertices are cut into contiguous parts, one a thread;
//!   each part walks, in the elements' order, every element that touches it and adds only to its own
//!   vertices. Every vertex then receives its contributions in the element order of the serial loop,
//!   so the result is the serial scatter's to the bit whatever the parts, and no two threads write the
//!   same memory. An element that spans two parts is computed by both (a few per part boundary on a
//!   mesh numbered with locality).
//!
//! The threads are rayon's: the global pool (every core by default, `RAYON_NUM_THREADS` to choose) or
//! the pool a caller runs the step in (`ThreadPool::install`); [`on_one_thread`] keeps everything on the
//! calling thread. Small problems stay on the calling thread, where starting threads would cost more
//! than it saves; that choice changes no result either.

use std::ops::Range;

use rayon::prelude::*;

/// Terms per partial sum of [`Sum`]: fixed, so that a sum's rounding is the same on any thread count.
pub const SUM_BLOCK: usize = 4096;

/// Below this many items a loop runs on the calling thread.
pub const PARALLEL_MIN: usize = 8192;

thread_local! {
    /// Set while [`on_one_thread`] runs: every loop here stays on the calling thread.
    static ONE_THREAD: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// The threads a parallel loop started here would use.
pub fn threads() -> usize {
    if ONE_THREAD.with(|o| o.get()) { 1 } else { rayon::current_num_threads() }
}

/// Whether the calling thread is inside [`on_one_thread`]: code with threads of its own (a sheet's
/// banded run in `anima-cloth`) asks, so that one switch keeps a whole run on one thread.
pub fn kept_on_one_thread() -> bool {
    ONE_THREAD.with(|o| o.get())
}

/// Runs `f` with every parallel loop of this module on the calling thread (what `anima run
/// --one-thread` asks for; the results are the same bits either way).
pub fn on_one_thread<T>(f: impl FnOnce() -> T) -> T {
    let before = ONE_THREAD.with(|o| o.replace(true));
    let out = f();
    ONE_THREAD.with(|o| o.set(before));
    out
}

/// Items per chunk of an elementwise loop over `n` items (a few chunks a thread, for balance).
fn chunk_len(n: usize) -> usize {
    n.div_ceil(4 * threads()).max(PARALLEL_MIN / 4)
}

fn serial(n: usize) -> bool {
    n < PARALLEL_MIN || threads() == 1
}

/// Calls `f(start, chunk)` over chunks of `a` that cover it, in parallel when `a` is large; `start` is
/// the index of the chunk's first item.
pub fn for_chunks<A: Send>(a: &mut [A], f: impl Fn(usize, &mut [A]) + Sync + Send) {
    if serial(a.len()) {
        return f(0, a);
    }
    let len = chunk_len(a.len());
    a.par_chunks_mut(len).enumerate().for_each(|(k, c)| f(k * len, c));
}

/// [`for_chunks`] for items that each cost much (a coarse aggregate's Galerkin block sums hundreds of
/// terms): chunks of at least `min_len` items, on every core once there are two such chunks.
pub fn for_chunks_min<A: Send>(a: &mut [A], min_len: usize, f: impl Fn(usize, &mut [A]) + Sync + Send) {
    let min_len = min_len.max(1);
    if a.len() < 2 * min_len || threads() == 1 {
        return f(0, a);
    }
    let len = a.len().div_ceil(4 * threads()).max(min_len);
    a.par_chunks_mut(len).enumerate().for_each(|(k, c)| f(k * len, c));
}

/// [`for_chunks`] over two slices of the same length, chunked alike.
pub fn for_chunks2<A: Send, B: Send>(
    a: &mut [A],
    b: &mut [B],
    f: impl Fn(usize, &mut [A], &mut [B]) + Sync + Send,
) {
    assert_eq!(a.len(), b.len(), "for_chunks2 needs slices of one length");
    if serial(a.len()) {
        return f(0, a, b);
    }
    let len = chunk_len(a.len());
    a.par_chunks_mut(len).zip(b.par_chunks_mut(len)).enumerate().for_each(|(k, (a, b))| f(k * len, a, b));
}

/// [`for_chunks`] over three slices of the same length, chunked alike.
pub fn for_chunks3<A: Send, B: Send, C: Send>(
    a: &mut [A],
    b: &mut [B],
    c: &mut [C],
    f: impl Fn(usize, &mut [A], &mut [B], &mut [C]) + Sync + Send,
) {
    assert!(a.len() == b.len() && a.len() == c.len(), "for_chunks3 needs slices of one length");
    if serial(a.len()) {
        return f(0, a, b, c);
    }
    let len = chunk_len(a.len());
    a.par_chunks_mut(len)
        .zip(b.par_chunks_mut(len))
        .zip(c.par_chunks_mut(len))
        .enumerate()
        .for_each(|(k, ((a, b), c))| f(k * len, a, b, c));
}

/// Sums over index ranges with a fixed blocking ([`SUM_BLOCK`]), keeping its partials between calls so
/// that a sum allocates nothing once it has seen its size.
#[derive(Debug, Clone, Default)]
pub struct Sum {
    partials: Vec<f64>,
}

impl Sum {
    pub fn new() -> Self {
        Self::default()
    }

    /// Σ over `0..n` of what `block` returns for each block of at most [`SUM_BLOCK`] indices, the block
    /// sums added in order. `block` must sum its range left to right for the result to be the serial
    /// sum when `n ≤ SUM_BLOCK`.
    pub fn run(&mut self, n: usize, block: impl Fn(Range<usize>) -> f64 + Sync + Send) -> f64 {
        let blocks = n.div_ceil(SUM_BLOCK);
        let range = |k: usize| k * SUM_BLOCK..((k + 1) * SUM_BLOCK).min(n);
        if blocks <= 1 {
            return block(0..n);
        }
        self.partials.resize(blocks, 0.0);
        if serial(n) {
            for (k, p) in self.partials.iter_mut().enumerate() {
                *p = block(range(k));
            }
        } else {
            self.partials.par_iter_mut().enumerate().for_each(|(k, p)| *p = block(range(k)));
        }
        self.partials.iter().sum()
    }

    /// Σ a_i · b_i over coordinates.
    pub fn dot<C: crate::Coord>(&mut self, a: &[C], b: &[C]) -> f64 {
        debug_assert_eq!(a.len(), b.len());
        self.run(a.len(), |r| a[r.clone()].iter().zip(&b[r]).map(|(x, y)| x.dot(*y)).sum::<f64>())
    }
}

/// The largest of `f(i)` over `0..n` (order does not matter for a maximum), in parallel when large.
pub fn max(n: usize, f: impl Fn(usize) -> f64 + Sync + Send) -> f64 {
    if serial(n) {
        return (0..n).map(f).fold(0.0, f64::max);
    }
    (0..n).into_par_iter().with_min_len(PARALLEL_MIN / 4).map(f).reduce(|| 0.0, f64::max)
}

/// Elements that add to vertices, split so that threads add to disjoint vertices in the serial order
/// (module docs). Built for one element list and one part count; [`Scatter::prepare`] rebuilds it when
/// either changes.
#[derive(Debug, Clone, Default)]
pub struct Scatter {
    /// Vertices, elements and parts the lists were built for, and a fingerprint of the elements.
    n: usize,
    n_elements: usize,
    fingerprint: u64,
    /// Vertices per part (the last part may have fewer).
    part_len: usize,
    /// Per part, the elements touching it, in increasing order.
    lists: Vec<Vec<u32>>,
}

/// Below this many elements a scatter runs as one part.
pub const SCATTER_MIN: usize = 4096;

impl Scatter {
    pub fn new() -> Self {
        Self::default()
    }

    /// Makes the lists for `n` vertices and the elements `vertices(e)` for `e < n_elements`, in as many
    /// parts as there are threads (one for small problems). Cheap when nothing changed: the element
    /// list is fingerprinted (one pass over it) and the lists are rebuilt only when the fingerprint,
    /// the counts or the threads differ.
    pub fn prepare<const K: usize>(
        &mut self,
        n: usize,
        n_elements: usize,
        vertices: impl Fn(usize) -> [u32; K],
    ) {
        let parts = if n_elements < SCATTER_MIN || n < 2 { 1 } else { threads().min(n) };
        let mut fingerprint = 0xcbf2_9ce4_8422_2325u64;
        for e in 0..n_elements {
            for v in vertices(e) {
                fingerprint = (fingerprint ^ v as u64).wrapping_mul(0x0100_0000_01b3);
            }
        }
        if self.n == n
            && self.n_elements == n_elements
            && self.fingerprint == fingerprint
            && self.lists.len() == parts
        {
            return;
        }
        self.n = n;
        self.n_elements = n_elements;
        self.fingerprint = fingerprint;
        self.part_len = n.div_ceil(parts).max(1);
        self.lists.resize_with(parts, Vec::new);
        for l in &mut self.lists {
            l.clear();
        }
        for e in 0..n_elements {
            let mut seen = [usize::MAX; K];
            for (k, v) in vertices(e).into_iter().enumerate() {
                let p = (v as usize / self.part_len).min(parts - 1);
                if !seen[..k].contains(&p) {
                    self.lists[p].push(e as u32);
                }
                seen[k] = p;
            }
        }
    }

    /// Whether the lists were made for `n` vertices and `n_elements` elements at the current thread
    /// count: a caller that knows when its elements change ([`Scatter::invalidate`]) can skip
    /// [`Scatter::prepare`]'s fingerprint pass when this holds.
    pub fn ready_for(&self, n: usize, n_elements: usize) -> bool {
        let parts = if n_elements < SCATTER_MIN || n < 2 { 1 } else { threads().min(n) };
        self.n == n && self.n_elements == n_elements && self.lists.len() == parts
    }

    /// Forgets the lists (the elements changed): the next [`Scatter::prepare`] rebuilds them.
    pub fn invalidate(&mut self) {
        self.lists.clear();
    }

    /// Parts (1 when the scatter runs on the calling thread).
    pub fn parts(&self) -> usize {
        self.lists.len()
    }

    /// Calls `f(vertices, elements, out)` for every part: `vertices` the part's range, `elements` the
    /// elements touching it in increasing order, `out` the part's slice of `out` (index i − start).
    pub fn run<T: Send>(&self, out: &mut [T], f: impl Fn(Range<usize>, &[u32], &mut [T]) + Sync + Send) {
        assert_eq!(out.len(), self.n, "Scatter::run after prepare for this many vertices");
        if self.lists.len() <= 1 {
            return f(0..self.n, self.lists.first().map_or(&[], |l| &l[..]), out);
        }
        let len = self.part_len;
        out.par_chunks_mut(len).zip(self.lists.par_iter()).enumerate().for_each(|(k, (o, l))| {
            f(k * len..k * len + o.len(), l, o);
        });
    }

    /// [`Scatter::run`] with two outputs split alike.
    pub fn run2<T: Send, U: Send>(
        &self,
        a: &mut [T],
        b: &mut [U],
        f: impl Fn(Range<usize>, &[u32], &mut [T], &mut [U]) + Sync + Send,
    ) {
        assert!(a.len() == self.n && b.len() == self.n, "Scatter::run2 after prepare for this many vertices");
        if self.lists.len() <= 1 {
            return f(0..self.n, self.lists.first().map_or(&[], |l| &l[..]), a, b);
        }
        let len = self.part_len;
        a.par_chunks_mut(len).zip(b.par_chunks_mut(len)).zip(self.lists.par_iter()).enumerate().for_each(
            |(k, ((a, b), l))| {
                f(k * len..k * len + a.len(), l, a, b);
            },
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pool(threads: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap()
    }

    #[test]
    fn sums_are_the_same_bits_on_any_thread_count_and_serial_when_short() {
        let values: Vec<f64> =
            (0..50_000).map(|k| ((k as f64) * 0.37).sin() * 1e3 / (1.0 + k as f64)).collect();
        let sum =
            |threads| pool(threads).install(|| Sum::new().run(values.len(), |r| values[r].iter().sum()));
        let one = sum(1);
        assert_eq!(one.to_bits(), sum(2).to_bits());
        assert_eq!(one.to_bits(), sum(4).to_bits());
        let short = &values[..SUM_BLOCK];
        let serial: f64 = short.iter().sum();
        assert_eq!(Sum::new().run(short.len(), |r| short[r].iter().sum()).to_bits(), serial.to_bits());
    }

    #[test]
    fn a_scatter_adds_in_the_serial_order_on_any_thread_count() {
        // A ring of pairs with long jumps, so that many elements span parts.
        let n = 20_000;
        let pairs: Vec<[u32; 2]> = (0..3 * n)
            .map(|e| [(e % n) as u32, ((e * 7919 + 13) % n) as u32])
            .filter(|[a, b]| a != b)
            .collect();
        let weight = |e: usize| ((e as f64) * 0.61).cos() * 1e-3 + 1.0 / (1.0 + e as f64);
        let mut serial = vec![0.0f64; n];
        for (e, [i, j]) in pairs.iter().enumerate() {
            serial[*i as usize] += weight(e);
            serial[*j as usize] -= weight(e);
        }
        for threads in [1, 2, 3, 4] {
            let out = pool(threads).install(|| {
                let mut s = Scatter::new();
                s.prepare(n, pairs.len(), |e| pairs[e]);
                assert_eq!(s.parts(), threads);
                let mut out = vec![0.0f64; n];
                s.run(&mut out, |range, elements, out| {
                    for &e in elements {
                        let [i, j] = pairs[e as usize].map(|v| v as usize);
                        if range.contains(&i) {
                            out[i - range.start] += weight(e as usize);
                        }
                        if range.contains(&j) {
                            out[j - range.start] -= weight(e as usize);
                        }
                    }
                });
                out
            });
            assert!(out.iter().zip(&serial).all(|(a, b)| a.to_bits() == b.to_bits()), "{threads} threads");
        }
    }
}
