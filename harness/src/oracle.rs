//! The brute-force oracle: every feature point of a wide block, ranked.
//!
//! It shares only the definition ([`Pattern::for_each_point`]) and the
//! metric's rank with the evaluators. There is no pruning and no insertion
//! list: it gathers every point of the block of Chebyshev radius R (starting
//! at R = 2, a 5^d block), takes the n first by rank and then by ID (the
//! crate's order for ties), and accepts the n-th only if it is strictly
//! closer than the outside of that block, so no point outside can tie it;
//! otherwise it starts again with R + 1.

use worley::config::Metric;
use worley::definition::{Pattern, FRACTION_ULP};
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
        // The n nearest in the order rank, then ID: the n-th is put in its
        // place with every point before it no later, then those are sorted.
        let by_rank_then_id = |a: &Candidate<D>, b: &Candidate<D>| a.0.total_cmp(&b.0).then(a.2.cmp(&b.2));
        scratch.select_nth_unstable_by(order - 1, by_rank_then_id);
        scratch[..order].sort_by(by_rank_then_id);
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

/// The periodic point set written out for brute force over its images:
/// every feature point of the cells of one period (`period` cells per
/// axis), repeated at shifts of −2..=2 periods per axis, as (position in
/// cells, ID). Enough for periods of 3 cells or more and searches within
/// 2 cells of the sample.
pub fn periodic_images<const D: usize>(pattern: &Pattern<D>, period: [u32; D]) -> Vec<([f64; D], u32)> {
    let mut images = Vec::new();
    let cells: usize = period.iter().map(|&p| p as usize).product();
    for index in 0..cells {
        let mut rest = index;
        let cell: [i64; D] = std::array::from_fn(|a| {
            let c = rest % period[a] as usize;
            rest /= period[a] as usize;
            c as i64
        });
        for point in pattern.points(cell) {
            for shift in 0..5usize.pow(D as u32) {
                let mut rest = shift;
                let at: [f64; D] = std::array::from_fn(|a| {
                    let k = (rest % 5) as f64 - 2.0;
                    rest /= 5;
                    cell[a] as f64 + k * f64::from(period[a]) + f64::from(point.fraction[a]) * FRACTION_ULP
                });
                images.push((at, point.id));
            }
        }
    }
    images
}
