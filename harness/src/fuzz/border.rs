//! The border distance under fuzzing: [`SimdBorder`] through every entry
//! point against the f64 [`Reference::border`]; on the same points, compact
//! smooth F1 ([`SimdSmooth`]) against [`Reference::smooth_f1_compact`].

use worley::config::{Config, Mode};
use worley::definition::{Pattern, INVALID_ID};
use worley::reference::Reference;
use worley::simd::{Border32, SimdBorder, SimdSmooth, Smooth32};

use super::Bytes;

/// The border's stated bound (user units): b comes from deltas of length up
/// to F1 + 2b, each within a few f32 roundings, and from u = p_j − p₁
/// rounded once (`tests/lanes/border.rs` holds it on random points).
fn bound(f1: f64, b: f64, inv_scale: f64) -> f64 {
    4.0 * f64::from(f32::EPSILON) * (2.0 * f1 + 2.0 * b + inv_scale)
}

fn same_bits<const D: usize>(a: &Border32<D>, b: &Border32<D>) -> bool {
    a.distance.to_bits() == b.distance.to_bits()
        && a.normal.map(f32::to_bits) == b.normal.map(f32::to_bits)
        && a.feature == b.feature
        && a.neighbour == b.neighbour
}

/// Border: eight decoded points in 2D, 3D or 4D, an arbitrary seed, a
/// density from 0.5 to 10 points per cell and either mode; now and then one
/// lane is bad (NaN, ±∞ or beyond the kernel's range). The one-point,
/// 8-lane and slice calls must give the same bits; against the reference,
/// invalid exactly where it is, +∞ where it is, F1's point the same unless
/// F1 and F2 tie within the kernel's bound, the distance within the
/// border's stated bound, and the neighbour the same unless its bisector
/// plane ties with the reference's within that bound (measured here in
/// f64 from the two points' cells). Then compact smooth F1 at a decoded
/// smoothness (0 to 1.5 user units) on the same points: the same bits
/// through every entry point, invalid exactly where the reference is, +∞
/// where it is, the value within 4ε(R + 1/S) + ε|S| (R the reach) and
/// F1's point the same unless F1 and F2 tie.
#[inline]
pub fn border(data: &[u8]) {
    let mut b = Bytes { data, at: 0 };
    let dim = 2 + b.byte() % 3;
    let density = [0.5, 1.0, 2.0, 5.0, 10.0][usize::from(b.byte() % 5)];
    let config = Config {
        seed: b.u64(),
        density,
        mode: if b.byte() & 1 == 0 { Mode::Exact } else { Mode::Window },
        ..Config::default()
    };
    match dim {
        2 => border_in::<2>(config, &mut b),
        3 => border_in::<3>(config, &mut b),
        _ => border_in::<4>(config, &mut b),
    }
}

fn border_in<const D: usize>(config: Config, b: &mut Bytes) {
    let simd = SimdBorder::<D>::new(config).expect("a valid Euclidean configuration");
    let reference = Reference::<D>::new(config).expect("a valid configuration");
    let two = Reference::<D>::new(Config { order: 2, ..config }).expect("a valid configuration");
    let mut points: [[f64; D]; 8] = std::array::from_fn(|_| std::array::from_fn(|_| b.coordinate()));
    let bad = b.byte();
    if bad & 3 == 0 {
        points[usize::from(bad >> 2) % 8][0] =
            [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e300][usize::from(bad >> 5) % 4];
    }
    let s = [0.0, 0.05, 0.1, 0.3, 1.0, 1.5][usize::from(b.byte() % 6)];
    smooth_in::<D>(config, &points, s);
    let eight = simd.border8(&points);
    let mut slice = [Border32::<D>::default(); 8];
    simd.border_slice(&points, &mut slice).expect("room for eight");
    let scale = reference.pattern().scale();
    for (i, x) in points.iter().enumerate() {
        let got = eight.lane(i);
        let what = format!("{config:?} at {x:?}");
        assert!(same_bits(&got, &simd.border(*x)), "{what}: lane {i} of 8 differs from the one-point call");
        assert!(same_bits(&got, &slice[i]), "{what}: lane {i} of 8 differs from the slice call");
        let want = reference.border(*x).expect("a Euclidean configuration");
        if want.distance.is_nan() {
            let invalid = got.distance.is_nan() && got.feature == INVALID_ID && got.neighbour == INVALID_ID;
            assert!(invalid, "{what}: the reference says invalid, the kernel gave {got:?}");
            continue;
        }
        let f = two.evaluate(*x);
        let (f1, f2) = (f.distance[0], f.distance[1]);
        let f1_tie = f2 - f1 <= 2.0 * super::bound(f2, scale);
        assert!(f1_tie || got.feature == want.feature, "{what}: F1's point {got:?} against {want:?}");
        if want.distance.is_infinite() {
            assert_eq!(f64::from(got.distance), want.distance, "{what}: {got:?} against {want:?}");
            continue;
        }
        let allowed = bound(f1, want.distance, 1.0 / scale);
        let error = (f64::from(got.distance) - want.distance).abs();
        assert!(error <= allowed, "{what}: border {} against {} (bound {allowed:e})", got.distance, want.distance);
        if f1_tie || got.neighbour == want.neighbour {
            continue;
        }
        let radius = i64::from(want.shells.max(2)) + 1;
        let other = plane_distance(reference.pattern(), *x, got.feature, got.neighbour, radius);
        let other = other.unwrap_or_else(|| panic!("{what}: no point {} within {radius} cells", got.neighbour));
        assert!(
            (other - want.distance).abs() <= 2.0 * allowed,
            "{what}: neighbour {} at {other} against the reference's {} at {} (bound {allowed:e})",
            got.neighbour,
            want.neighbour,
            want.distance
        );
    }
}

/// The f64 distance (user units) from `x` to the bisector plane of the
/// points with IDs `feature` and `neighbour`, each the one nearest `x` of
/// that ID within `radius` cells of its cell.
fn plane_distance<const D: usize>(
    pattern: &Pattern<D>,
    x: [f64; D],
    feature: u32,
    neighbour: u32,
    radius: i64,
) -> Option<f64> {
    let (cell, f) = pattern.locate(x)?;
    let squared = |p: &[f64; D]| -> f64 { (0..D).map(|a| (f[a] - p[a]) * (f[a] - p[a])).sum() };
    let side = 2 * radius + 1;
    let (mut p1, mut pj): (Option<[f64; D]>, Option<[f64; D]>) = (None, None);
    for index in 0..side.pow(D as u32) {
        let mut rest = index;
        let offset: [i64; D] = std::array::from_fn(|_| {
            let o = rest % side - radius;
            rest /= side;
            o
        });
        let c: [i64; D] = std::array::from_fn(|a| cell[a] + offset[a]);
        for p in pattern.points(c) {
            let q = p.offset();
            let at: [f64; D] = std::array::from_fn(|a| offset[a] as f64 + q[a]);
            for (id, slot) in [(feature, &mut p1), (neighbour, &mut pj)] {
                if p.id == id && slot.is_none_or(|s| squared(&at) < squared(&s)) {
                    *slot = Some(at);
                }
            }
        }
    }
    let (p1, pj) = (p1?, pj?);
    let apart = (0..D).map(|a| (pj[a] - p1[a]) * (pj[a] - p1[a])).sum::<f64>().sqrt();
    Some((squared(&pj) - squared(&p1)) / (2.0 * apart) / pattern.scale())
}

fn smooth_in<const D: usize>(config: Config, points: &[[f64; D]; 8], s: f32) {
    let simd = SimdSmooth::<D>::new(config).expect("a valid Euclidean configuration");
    let reference = Reference::<D>::new(config).expect("a valid configuration");
    let two = Reference::<D>::new(Config { order: 2, ..config }).expect("a valid configuration");
    let eight = simd.smooth8(points, s);
    let mut slice = [Smooth32::<D>::INVALID; 8];
    simd.smooth_slice(points, s, &mut slice).expect("room for eight");
    let bits = |v: &Smooth32<D>| (v.value.to_bits(), v.gradient.map(f32::to_bits), v.feature);
    let scale = reference.pattern().scale();
    let sd = f64::from(s);
    for (i, x) in points.iter().enumerate() {
        let got = eight.lane(i);
        let what = format!("{config:?} s {s} at {x:?}");
        assert_eq!(bits(&got), bits(&simd.smooth(*x, s)), "{what}: lane {i} of 8 differs from the one-point call");
        assert_eq!(bits(&got), bits(&slice[i]), "{what}: lane {i} of 8 differs from the slice call");
        let want = reference.smooth_f1_compact(*x, sd);
        if want.value.is_nan() {
            assert!(got.value.is_nan() && got.feature == INVALID_ID, "{what}: invalid in the reference, {got:?}");
            continue;
        }
        if want.value.is_infinite() {
            assert_eq!(f64::from(got.value), want.value, "{what}: {got:?} against {want:?}");
            continue;
        }
        let f = two.evaluate(*x);
        let (f1, f2) = (f.distance[0], f.distance[1]);
        let f1_tie = f2 - f1 <= 2.0 * super::bound(f2, scale);
        assert!(f1_tie || got.feature == want.feature, "{what}: F1's point {got:?} against {want:?}");
        let h1 = (f1 * f1 + sd * sd).sqrt() - sd;
        let reach = ((h1 + 2.0 * sd).powi(2) - sd * sd).sqrt();
        let allowed = super::bound(reach, scale) + f64::from(f32::EPSILON) * want.value.abs();
        let error = (f64::from(got.value) - want.value).abs();
        assert!(error <= allowed, "{what}: {} against {} (bound {allowed:e})", got.value, want.value);
    }
}
