//! The continuity detectors: pairs of points straddling cell faces, edges
//! and corners, for F_k ([`continuity()`]) and for values that stand for a
//! footprint ([`filtered_continuity`]), and the lattice coordinates they
//! straddle.

use super::*;

/// A user coordinate x with x·S exactly the integer `k`, if one exists near
/// k/S.
pub fn lattice_coordinate(k: i64, scale: f64) -> Option<f64> {
    let mut x = k as f64 / scale;
    for _ in 0..4 {
        let u = x * scale;
        if u == k as f64 {
            return Some(x);
        }
        x = if u < k as f64 { x.next_up() } else { x.next_down() };
    }
    None
}

/// The smallest user coordinate x whose cell is `k`, that is, with the
/// rounded product x·S at least k. It lies exactly on the face when some x
/// has x·S = k ([`lattice_coordinate`]) and is the first coordinate past it
/// otherwise; `first_in_cell(k, S).next_down()` is the last one before it.
/// `scale` is a pattern's scale S (positive and finite) and |k| at most
/// 2^53.
pub fn first_in_cell(k: i64, scale: f64) -> f64 {
    let k = k as f64;
    let mut x = k / scale;
    // Rounded multiplication by a positive constant is monotone in x, and
    // k / S is within an ulp or two of the answer.
    while x * scale >= k {
        x = x.next_down();
    }
    while x * scale < k {
        x = x.next_up();
    }
    x
}

/// Straddling pairs: faces, edges and corners (and, every fourth pair,
/// a point exactly on a lattice plane against its neighbour one ulp below).
pub fn continuity<const D: usize, K: Kernel<D>>(kernel: &K, campaign: &Campaign, report: &mut Report) {
    let config = *kernel.config();
    let order = config.order;
    let pattern = kernel.pattern();
    let scale = pattern.scale();
    let cells = (campaign.range * scale).floor().max(1.0);
    let seed = campaign.seed ^ 0xC0_17_1A_17;
    let parts = chunked(campaign.pairs, |range| {
        let mut part = (vec![OrderReport::default(); order], 0u64);
        for i in range {
            let rnd = |j: u64| uniform(seed, i as u64 * 64 + j);
            // Which axes sit on a lattice plane: 1 (face) ..= D (corner).
            let on_lattice = 1 + i % D;
            let mut axes: [usize; D] = std::array::from_fn(|a| a);
            for a in (1..D).rev() {
                axes.swap(a, (rnd(40 + a as u64) * (a + 1) as f64) as usize);
            }
            let (xa, xb) = if i % 4 == 3 {
                // Exactly on the plane of axis axes[0], and one ulp below.
                let mut xa: [f64; D] = std::array::from_fn(|a| (2.0 * rnd(a as u64) - 1.0) * campaign.range);
                let k = ((2.0 * rnd(20) - 1.0) * cells).floor() as i64;
                let Some(x) = lattice_coordinate(k, scale) else {
                    continue;
                };
                xa[axes[0]] = x;
                let mut xb = xa;
                xb[axes[0]] = x.next_down();
                (xa, xb)
            } else {
                let eps = 10f64.powf(-9.0 + 6.0 * rnd(30));
                let mut ua = [0.0; D];
                let mut ub = [0.0; D];
                for (rank, &a) in axes.iter().enumerate() {
                    let c = ((2.0 * rnd(a as u64) - 1.0) * cells).floor();
                    let (u, e) = if rank < on_lattice {
                        let sign = if rnd(10 + a as u64) < 0.5 { -1.0 } else { 1.0 };
                        (c, sign * (0.1 + 0.9 * rnd(20 + a as u64)))
                    } else {
                        (c + rnd(50 + a as u64), 2.0 * rnd(20 + a as u64) - 1.0)
                    };
                    ua[a] = (u - eps * e) / scale;
                    ub[a] = (u + eps * e) / scale;
                }
                (ua, ub)
            };
            let (Some((ca, _)), Some((cb, _))) = (pattern.locate(xa), pattern.locate(xb)) else {
                continue;
            };
            part.1 += (ca != cb) as u64;
            let fa = kernel.evaluate(xa);
            let fb = kernel.evaluate(xb);
            let diff: [f64; D] = std::array::from_fn(|a| xa[a] - xb[a]);
            let dist = config.metric.distance(&diff);
            let magnitude = xa.iter().chain(&xb).fold(0.0f64, |m, v| m.max(v.abs()));
            for k in 0..order {
                let bound = dist
                    + kernel.error_bound(magnitude, fa.distance[k])
                    + kernel.error_bound(magnitude, fb.distance[k]);
                let jump = (fa.distance[k] - fb.distance[k]).abs();
                let p = &mut part.0[k];
                if jump.is_nan() || jump > bound {
                    p.continuity_violations += 1;
                    p.max_excess = p.max_excess.max(if jump.is_finite() { jump - dist } else { f64::INFINITY });
                }
            }
        }
        part
    });
    report.pairs = campaign.pairs as u64;
    for (orders, straddled) in parts {
        report.straddled += straddled;
        for (total, p) in report.orders.iter_mut().zip(orders) {
            total.continuity_violations += p.continuity_violations;
            total.max_excess = total.max_excess.max(p.max_excess);
        }
    }
}

/// What [`filtered_continuity`] found.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FilteredContinuity {
    /// Pairs straddling a cell face, edge or corner, at a common footprint.
    pub position_pairs: u64,
    /// Of those, pairs whose values differ by more than the Lipschitz bound.
    pub position_violations: u64,
    /// Pairs of footprints a relative step 10^−6 apart (around zero, the
    /// blend curve's knots and beyond), at a common point.
    pub footprint_pairs: u64,
    /// Of those, pairs whose values differ by more than the step allows.
    pub footprint_violations: u64,
    /// The largest difference seen in a footprint pair.
    pub largest_footprint_jump: f64,
}

/// The discontinuity detector for values that stand for a footprint,
/// `value(x, width)` (user units, a pattern of scale `scale`):
/// - in position, at a common random width, pairs a step of 10^−9 to
///   10^−3 cells across a lattice face, edge or corner, whose values may
///   differ by at most `lipschitz` times their Euclidean distance plus
///   `rounding` (a value that is L-Lipschitz in position, as a fractal sum
///   of 1-Lipschitz F_n with weights at most 1 is);
/// - in the footprint, at a common random point, widths w and w·(1 + 10^−6)
///   for w at zero (against 10^−7), at the blend curve's knots 2^(−6 + j/4)
///   and scattered between 2^−8 and 2^8: a value continuous in the width
///   with a slope below |v|·10^3 per relative unit changes by less than
///   `rounding` + 10^−3·(|v| + 1) across such a step; a jump (an octave
///   dropped while its weight is not yet 0, a mean that differs from the
///   blend's limit) exceeds it.
pub fn filtered_continuity<const D: usize>(
    value: impl Fn([f64; D], f32) -> f32 + Sync,
    scale: f64,
    lipschitz: f64,
    rounding: f64,
    pairs: usize,
    seed: u64,
) -> FilteredContinuity {
    let parts = chunked(pairs, |range| {
        let mut r = FilteredContinuity::default();
        for i in range {
            let rnd = |j: u64| uniform(seed, i as u64 * 64 + j);
            // Position: a pair across lattice planes of 1..=D axes.
            let width = (16.0 * rnd(0) - 8.0).exp2() as f32 * (rnd(1) < 0.9) as u8 as f32;
            let eps = 10f64.powf(-9.0 + 6.0 * rnd(2));
            let (mut a, mut b) = ([0.0; D], [0.0; D]);
            for axis in 0..D {
                let cell = ((2.0 * rnd(10 + axis as u64) - 1.0) * 200.0).floor();
                let (u, e) = if axis <= i % D {
                    (cell, 0.1 + 0.9 * rnd(20 + axis as u64))
                } else {
                    (cell + rnd(30 + axis as u64), 2.0 * rnd(20 + axis as u64) - 1.0)
                };
                a[axis] = (u - eps * e) / scale;
                b[axis] = (u + eps * e) / scale;
            }
            let distance = a.iter().zip(&b).map(|(p, q)| (p - q) * (p - q)).sum::<f64>().sqrt();
            let jump = f64::from(value(a, width) - value(b, width)).abs();
            r.position_pairs += 1;
            r.position_violations += (jump.is_nan() || jump > lipschitz * distance + rounding) as u64;
            // Footprint: around zero, a knot, or anywhere.
            let x: [f64; D] = std::array::from_fn(|axis| (2.0 * rnd(40 + axis as u64) - 1.0) * 1000.0);
            let (w, w2) = match i % 3 {
                0 => (0.0f32, 1e-7f32),
                1 => {
                    let w = ((rnd(50) * 49.0).floor() / 4.0 - 6.0).exp2() as f32;
                    (w, w * (1.0 + 1e-6))
                }
                _ => {
                    let w = (16.0 * rnd(51) - 8.0).exp2() as f32;
                    (w, w * (1.0 + 1e-6))
                }
            };
            let (v, v2) = (value(x, w), value(x, w2));
            let jump = f64::from(v - v2).abs();
            r.footprint_pairs += 1;
            r.largest_footprint_jump = r.largest_footprint_jump.max(jump);
            let allowed = rounding + 1e-3 * (f64::from(v.abs()) + 1.0);
            r.footprint_violations += (jump.is_nan() || jump > allowed) as u64;
        }
        r
    });
    parts.into_iter().fold(FilteredContinuity::default(), |t, p| FilteredContinuity {
        position_pairs: t.position_pairs + p.position_pairs,
        position_violations: t.position_violations + p.position_violations,
        footprint_pairs: t.footprint_pairs + p.footprint_pairs,
        footprint_violations: t.footprint_violations + p.footprint_violations,
        largest_footprint_jump: t.largest_footprint_jump.max(p.largest_footprint_jump),
    })
}
