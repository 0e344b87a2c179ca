//! The checks behind the fuzz targets in `fuzz/`, kept in the library so
//! that the inputs the fuzzers found interesting replay as ordinary tests on
//! stable (`tests/suite/fuzz_regressions.rs`). Each check decodes arbitrary bytes
//! into an input and panics, with a message saying what broke, if the kernels
//! break a documented promise. Short inputs are padded with zeros, so every
//! byte string is a valid input.
//!
//! The six entry points are `#[inline]`: the crate that calls one (a fuzz
//! target, the regression test) compiles it and the kernels it instantiates,
//! so that building the harness alone, as every test build of the kernel
//! crate does, does not compile a dozen kernels that nothing there calls.

mod border;
mod filtered;

pub use border::border;
pub use filtered::filtered;

use worley::config::{Config, Metric, Mode, MAX_ORDER};
use worley::definition::{INVALID_ID, MAX_CELL_COORD};
use worley::reference::{Features, Reference};
use worley::simd::{lane, Features32, Grid, Outputs, Simd};

/// Reads bytes as little-endian words, zero past the end.
struct Bytes<'a> {
    data: &'a [u8],
    at: usize,
}

impl Bytes<'_> {
    fn byte(&mut self) -> u8 {
        let b = self.data.get(self.at).copied().unwrap_or(0);
        self.at += 1;
        b
    }
    fn u64(&mut self) -> u64 {
        u64::from_le_bytes(std::array::from_fn(|_| self.byte()))
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(std::array::from_fn(|_| self.byte()))
    }
    /// A coordinate that is usually ordinary: an i32 scaled by 2^−k, with
    /// k from the next byte (so values from 2^−31 to 2^31 and exact lattice
    /// values come up often).
    fn coordinate(&mut self) -> f64 {
        let v = self.u32() as i32;
        let k = self.byte() % 40;
        f64::from(v) * (-f64::from(k)).exp2()
    }
    fn metric(&mut self) -> Metric {
        match self.byte() % 4 {
            0 => Metric::Euclidean,
            1 => Metric::Manhattan,
            2 => Metric::Chebyshev,
            // Exponents from 1 to 4.94 in steps of 1/16, or powers of two
            // up to 2^20, where |d|^p overflows or flushes to zero in f32
            // and f64 alike.
            _ => {
                let e = self.byte();
                if e & 0x80 == 0 {
                    Metric::Minkowski(1.0 + f64::from(e % 64) / 16.0)
                } else {
                    Metric::Minkowski(f64::from(e % 21).exp2())
                }
            }
        }
    }
}

/// The SIMD kernel's stated error bound against the f64 reference.
fn bound(f: f64, scale: f64) -> f64 {
    4.0 * f32::EPSILON as f64 * (f + 1.0 / scale)
}

fn is_invalid32<const D: usize, const N: usize>(r: &Features32<D, N>) -> bool {
    r.distance.iter().all(|d| d.is_nan()) && r.id.iter().all(|&i| i == INVALID_ID)
}

fn same_bits<const D: usize, const N: usize>(a: &Features32<D, N>, b: &Features32<D, N>) -> bool {
    a.distance.map(f32::to_bits) == b.distance.map(f32::to_bits)
        && a.id == b.id
        && a.delta.map(|d| d.map(f32::to_bits)) == b.delta.map(|d| d.map(f32::to_bits))
}

/// Differential: eight decoded points in 2D, 3D or 4D, with an arbitrary
/// seed, metric, order (1 to 4) and mode. The 8-lane call and the
/// single-point call must be bit-identical; both must agree with the f64
/// reference within the stated bound, with the same IDs except at ties
/// within that bound, and be invalid exactly where the reference is.
#[inline]
pub fn differential(data: &[u8]) {
    let mut b = Bytes { data, at: 0 };
    let dim = 2 + b.byte() % 3;
    let order = 1 + usize::from(b.byte() % 4);
    let config = Config {
        seed: b.u64(),
        order,
        metric: b.metric(),
        mode: if b.byte() & 1 == 0 { Mode::Exact } else { Mode::Window },
        ..Config::default()
    };
    match dim {
        2 => differential_in::<2>(config, &mut b),
        3 => differential_in::<3>(config, &mut b),
        _ => differential_in::<4>(config, &mut b),
    }
}

fn differential_in<const D: usize>(config: Config, b: &mut Bytes) {
    match config.order {
        1 => differential_n::<D, 1>(config, b),
        2 => differential_n::<D, 2>(config, b),
        3 => differential_n::<D, 3>(config, b),
        _ => differential_n::<D, 4>(config, b),
    }
}

fn differential_n<const D: usize, const N: usize>(config: Config, b: &mut Bytes) {
    let simd = Simd::<D, N>::new(config, Outputs::IdsAndDeltas).expect("valid configuration");
    // One order more, to recognise a tie between F_n and F_{n+1}.
    let reference = Reference::<D>::new(Config { order: N + 1, ..config }).expect("valid configuration");
    let points: [[f64; D]; 8] = std::array::from_fn(|_| std::array::from_fn(|_| b.coordinate()));
    let eight = simd.evaluate8(&points);
    let scale = simd.pattern().scale();
    for (i, x) in points.iter().enumerate() {
        let got = lane(&eight, i);
        let single = simd.evaluate(*x);
        assert!(same_bits(&got, &single), "lane {i} of 8 differs from the single-point call at {x:?}");
        let want = reference.evaluate(*x);
        compare(&got, &want, scale, &format!("{config:?} at {x:?}"));
    }
}

/// Distances within the bound, IDs equal except at ties, invalid alike.
fn compare<const D: usize, const N: usize>(got: &Features32<D, N>, want: &Features<D>, scale: f64, what: &str) {
    if want.distance[0].is_nan() {
        assert!(is_invalid32(got), "{what}: the reference says invalid, the kernel gave {got:?}");
        return;
    }
    for k in 0..N {
        let (g, w) = (f64::from(got.distance[k]), want.distance[k]);
        if w.is_infinite() {
            assert!(g.is_infinite(), "{what}: F{} is {g}, the reference found no point", k + 1);
            continue;
        }
        let tol = bound(w, scale);
        assert!((g - w).abs() <= tol, "{what}: F{} = {g}, reference {w}, bound {tol}", k + 1);
        let tied = (k > 0 && w - want.distance[k - 1] <= 2.0 * tol) || want.distance[k + 1] - w <= 2.0 * tol;
        assert!(tied || got.id[k] == want.id[k], "{what}: F{} ID {} vs reference {}", k + 1, got.id[k], want.id[k]);
    }
}

/// Continuity: a sample near a lattice plane, edge or corner and a second
/// one a small step across it. In exact mode every F_k is 1-Lipschitz in its
/// metric, so |F_k(a) − F_k(b)| may not exceed the metric distance from a to
/// b, plus the rounding bounds, in the reference and in the SIMD kernel.
#[inline]
pub fn continuity(data: &[u8]) {
    let mut b = Bytes { data, at: 0 };
    let config = Config { seed: b.u64(), order: 4, metric: b.metric(), ..Config::default() };
    let simd = Simd::<3, 4>::new(config, Outputs::Distances).expect("valid configuration");
    let reference = Reference::<3>::new(config).expect("valid configuration");
    let scale = simd.pattern().scale();
    // A lattice point (cell coordinates up to ±2^31), then per axis either
    // an offset within 2^−k cells of it or an arbitrary fraction.
    let mut a = [0f64; 3];
    let mut c = [0f64; 3];
    for axis in 0..3 {
        let cell = f64::from(b.u32() as i32 >> (b.byte() % 32));
        let near = !b.byte().is_multiple_of(3);
        let eps = f64::from(b.u32() as i32) * (-f64::from(20 + b.byte() % 30)).exp2();
        let step = f64::from(b.u32() as i32) * (-f64::from(20 + b.byte() % 30)).exp2();
        let frac = if near { eps } else { f64::from(b.u32()) / 4_294_967_296.0 };
        a[axis] = (cell + frac) / scale;
        c[axis] = (cell + frac + if near { step } else { 0.0 }) / scale;
    }
    let between: [f64; 3] = std::array::from_fn(|i| a[i] - c[i]);
    let gap = config.metric.distance(&between);
    let (ra, rc) = (reference.evaluate(a), reference.evaluate(c));
    let (sa, sc) = (simd.evaluate(a), simd.evaluate(c));
    let magnitude = a.iter().chain(&c).fold(0.0f64, |m, v| m.max(v.abs()));
    for k in 0..4 {
        let slack = 16.0 * f64::EPSILON * (ra.distance[k] + 2.0 * magnitude + 1.0);
        let d = (ra.distance[k] - rc.distance[k]).abs();
        assert!(d <= gap + slack, "reference F{} jumps by {d} over {gap} between {a:?} and {c:?}", k + 1);
        let tol = bound(ra.distance[k], scale) + bound(rc.distance[k], scale);
        let d = f64::from(sa.distance[k] - sc.distance[k]).abs();
        assert!(d <= gap + tol + slack, "SIMD F{} jumps by {d} over {gap} between {a:?} and {c:?}", k + 1);
    }
}

/// Bad input: arbitrary bit patterns (NaN payloads, ±inf, subnormals, ±0,
/// huge values) through every public entry point. No panic; a sample the
/// reference cannot locate gives the documented invalid result everywhere;
/// any other gives sorted distances, finite in exact mode.
#[inline]
pub fn bad_input(data: &[u8]) {
    let mut b = Bytes { data, at: 0 };
    let config = Config { seed: b.u64(), order: 2, metric: b.metric(), ..Config::default() };
    let simd = Simd::<3, 2>::new(config, Outputs::IdsAndDeltas).expect("valid configuration");
    let reference = Reference::<3>::new(config).expect("valid configuration");
    let x: [f64; 3] = std::array::from_fn(|_| f64::from_bits(b.u64()));
    let y: [f32; 3] = std::array::from_fn(|_| f32::from_bits(b.u32()));
    let cell: [i64; 3] = std::array::from_fn(|_| b.u64() as i64);
    let located = simd.pattern().locate(x).is_some();
    let check = |r: &Features32<3, 2>, valid: bool, what: &str| {
        if valid {
            assert!(r.distance[0] <= r.distance[1], "{what}: unsorted or NaN {r:?}");
            assert!(r.distance.iter().all(|d| d.is_finite()), "{what}: not finite {r:?}");
        } else {
            assert!(is_invalid32(r), "{what}: expected the invalid result, got {r:?}");
        }
    };
    let r = reference.evaluate(x);
    assert_eq!(r.distance[0].is_nan(), !located, "reference at {x:?}");
    check(&simd.evaluate(x), located, &format!("evaluate {x:?}"));
    let y_located = simd.pattern().locate(y.map(f64::from)).is_some();
    check(&simd.evaluate_f32(y), y_located, &format!("evaluate_f32 {y:?}"));
    let eight = simd.evaluate8(&[x, [0.5; 3], x, x, [1.0; 3], x, x, x]);
    check(&lane(&eight, 0), located, "evaluate8 lane 0");
    check(&lane(&eight, 1), true, "evaluate8 lane 1 beside a bad lane");
    let lanes = simd.evaluate_lanes(std::array::from_fn(|a| wide::f32x8::splat(y[a])));
    check(&lane(&lanes, 7), y_located, "evaluate_lanes");
    let fraction = y;
    let cell_ok = fraction.iter().all(|f| (0.0..=1.0).contains(f))
        && cell.iter().all(|c| c.unsigned_abs() <= MAX_CELL_COORD as u64);
    check(&simd.evaluate_in_cell(cell, fraction), cell_ok, &format!("evaluate_in_cell {cell:?} {fraction:?}"));
    let in_ref = reference.evaluate_in_cell(cell, fraction.map(f64::from));
    assert_eq!(in_ref.distance[0].is_nan(), !cell_ok, "reference evaluate_in_cell {cell:?} {fraction:?}");
    let mut out = [Features32::<3, 2> { distance: [0.0; 2], delta: [[0.0; 3]; 2], id: [0; 2] }; 9];
    simd.evaluate_slice(&[x; 9], &mut out).expect("buffer fits");
    check(&out[8], located, "evaluate_slice tail");
    let grid = Grid { origin: x, step: [f64::from_bits(b.u64()), 1.0, 1.0], size: [3, 3, 1] };
    if simd.evaluate_grid(&grid, &mut out).is_ok() {
        for (i, o) in out.iter().enumerate() {
            let p = grid.point(i);
            check(o, simd.pattern().locate(p).is_some(), &format!("grid point {p:?}"));
        }
    }
}

/// Configurations: arbitrary field values, and metric names as typed on the
/// command line. Building either gives an evaluator for a configuration
/// `validate` accepts, or the error it reports; never a panic.
#[inline]
pub fn config(data: &[u8]) {
    let mut b = Bytes { data, at: 0 };
    let config = Config {
        seed: b.u64(),
        order: usize::from(b.byte() % 24),
        metric: match b.byte() % 5 {
            0 => Metric::Euclidean,
            1 => Metric::Manhattan,
            2 => Metric::Chebyshev,
            _ => Metric::Minkowski(f64::from_bits(b.u64())),
        },
        mode: if b.byte() & 1 == 0 { Mode::Exact } else { Mode::Window },
        density: f64::from_bits(b.u64()),
        bump: f64::from_bits(b.u64()),
    };
    let valid = config.validate().is_ok();
    assert_eq!(Reference::<2>::new(config).is_ok(), valid, "{config:?}");
    // The typed evaluator takes its order from its type, whatever
    // `config.order` holds.
    let simd = Simd::<2, 3>::new(config, Outputs::Distances);
    assert_eq!(simd.is_ok(), Config { order: 3, ..config }.validate().is_ok(), "{config:?}");
    if let Ok(simd) = simd {
        assert_eq!(simd.config().order, 3, "{config:?}");
    }
    if valid {
        assert!((1..=MAX_ORDER).contains(&config.order));
    }
    let text = String::from_utf8_lossy(&data[data.len().min(b.at)..]);
    if let Ok(metric) = text.parse::<Metric>() {
        assert!(metric.validate().is_ok(), "'{text}' parsed to an invalid {metric:?}");
    }
}
