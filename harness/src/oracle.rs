//! The brute-force oracle: every feature point of a wide block, sorted.
//!
//! It shares only the definition ([`Pattern::for_each_point`]) and the
//! metric's rank with the evaluators. There is no pruning and no insertion
//! list: it gathers every point of the block of Chebyshev radius R (starting
//! at R = 2, a 5^d block), sorts them all by rank and then by ID (the
//! crate's order for ties), and accepts the n-th only if it is strictly
//! closer than the outside of that block, so no point outside can tie it;
//! otherwise it starts again with R + 1.

use worley::config::Metric;
use worley::definition::Pattern;
use worley::reference::{Features, MAX_SHELLS};

/// One candidate: rank, delta in cell units, ID.
pub type Candidate<const D: usize> = (f64, [f64; D], u32);

/// The exact F1..Fn at `x` by exhaustive search. `scratch` is reused between
/// calls to avoid an allocation per sample.
pub fn brute_force<const D: usize>(
    pattern: &Pattern<D>,
    metric: Metric,
    order: usize,
    x: [f64; D],
    scratch: &mut Vec<Candidate<D>>,
) -> Features<D> {
    match pattern.locate(x) {
        Some((cell, f)) => brute_force_in_cell(pattern, metric, order, cell, f, scratch),
        None => Features::invalid(order),
    }
}

/// The exact F1..Fn at `cell + f` (cell units, f ∈ [0, 1]^d).
pub fn brute_force_in_cell<const D: usize>(
    pattern: &Pattern<D>,
    metric: Metric,
    order: usize,
    cell: [i64; D],
    f: [f64; D],
    scratch: &mut Vec<Candidate<D>>,
) -> Features<D> {
    for r in 2..=MAX_SHELLS as i64 {
        scratch.clear();
        let side = 2 * r + 1;
        for index in 0..side.pow(D as u32) {
            let mut rest = index;
            let mut offset = [0i64; D];
            for o in offset.iter_mut() {
                *o = rest % side - r;
                rest /= side;
            }
            let neighbour: [i64; D] = std::array::from_fn(|a| cell[a] + offset[a]);
            pattern.for_each_point(neighbour, |p| {
                let o = p.offset();
                let delta: [f64; D] = std::array::from_fn(|a| f[a] - (offset[a] as f64 + o[a]));
                scratch.push((metric.rank(&delta), delta, p.id));
            });
        }
        if scratch.len() < order {
            continue;
        }
        scratch.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.2.cmp(&b.2)));
        // Distance from the sample to the outside of the block.
        let mut edge = f64::INFINITY;
        for &fa in &f {
            edge = edge.min(fa + r as f64).min((r + 1) as f64 - fa);
        }
        if scratch[order - 1].0 < metric.rank_of_distance(edge) {
            let inv = 1.0 / pattern.scale();
            let mut out = Features::empty(order);
            out.shells = r as u32;
            for (k, (rank, delta, id)) in scratch.iter().take(order).enumerate() {
                out.distance[k] = metric.distance_of_rank(*rank) * inv;
                out.delta[k] = delta.map(|v| v * inv);
                out.id[k] = *id;
            }
            return out;
        }
    }
    Features::invalid(order)
}
