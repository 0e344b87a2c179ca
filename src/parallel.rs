//! The one place the crate reaches rayon (feature `parallel`): a slice of
//! outputs cut into chunks and filled on all cores.
//!
//! Every parallel entry point goes through [`for_each_chunk`], whose work
//! arrives as a `dyn` closure: rayon's generic machinery (splitting,
//! joining, the job types) is then compiled once per output type, where a
//! closure of each entry point's own type compiled it again for every
//! kernel and call site. A chunk holds thousands of samples, so the
//! indirect call per chunk costs nothing measurable.

/// `f(i, chunk)` for every chunk `i` of `size` items of `out` (the last may
/// be shorter), the chunks spread over rayon's threads.
pub(crate) fn for_each_chunk<T: Send>(out: &mut [T], size: usize, f: &(dyn Fn(usize, &mut [T]) + Sync)) {
    use rayon::prelude::*;
    out.par_chunks_mut(size.max(1)).enumerate().for_each(|(i, chunk)| f(i, chunk));
}
