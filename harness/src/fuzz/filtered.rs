//! Filtered textures under fuzzing: [`Texture::filtered`] and its batch
//! calls at decoded positions, footprints and configurations.

use std::collections::HashMap;
use std::sync::{LazyLock, Mutex};

use worley::config::{Config, Metric};
use worley::texture::{Combination, Fractal, Texture};

use super::Bytes;

/// Filtered: a texture in 2D or 3D (F1, F2 − F1 or the border; Euclidean,
/// or Manhattan for F_n; one to six octaves of lacunarity 1.5 to 4 and gain
/// 0.25 to 0.95; one of four seeds), a pair of points a step of 10^−9 to
/// 10^−3 cells apart across a lattice face, edge or corner, and a width
/// (zero, or 2^−8 to 2^8 cells). Both values must be numbers, differ by at
/// most the texture's Lipschitz bound times the pair's distance plus
/// rounding, and change by no more than rounding + 10^−3·(|v| + 1) when the
/// width grows by a relative 10^−6 (the two tests of the harness's
/// discontinuity detector, `filtered_continuity`, written out here for one
/// decoded pair). Eight lanes must give the
/// one-point calls' bits, a zero width the point sample's, an infinite one
/// a number, and a NaN or negative width or a NaN coordinate NaN in its own
/// lane only; the slice call the 8-lane bits.
#[inline]
pub fn filtered(data: &[u8]) {
    let mut b = Bytes { data, at: 0 };
    let dim = 2 + b.byte() % 2;
    let kind = b.byte() % 3;
    let manhattan = kind < 2 && b.byte() & 1 == 1;
    let fractal = Fractal {
        octaves: 1 + u32::from(b.byte() % 6),
        lacunarity: 1.5 + f32::from(b.byte() % 6) * 0.5,
        gain: 0.25 + f32::from(b.byte() % 8) * 0.1,
    };
    let key = Key { kind, manhattan, seed: b.byte() % 4 };
    // Σ|c_k| of the combination: each F_k and the border are 1-Lipschitz in
    // their metric, and a Manhattan distance is at most √d Euclidean ones.
    let c = if kind == 1 { 2.0 } else { 1.0 } * if manhattan { f64::from(dim).sqrt() } else { 1.0 };
    // A texture measures its blend curve on its first filtered call (some
    // 10^5 evaluations): one texture per basis is kept with its curve, for
    // the whole process (the test threads that replay inputs share them),
    // and the decoded fractal sum is built from it (`Texture::with_fractal`).
    macro_rules! run {
        ($cache:ident, $d:literal, $n:literal) => {{
            static $cache: LazyLock<Mutex<HashMap<Key, Texture<$d, $n>>>> =
                LazyLock::new(|| Mutex::new(HashMap::new()));
            // A check that panicked while holding the lock left the map
            // whole: take it back.
            let mut map = $cache.lock().unwrap_or_else(|e| e.into_inner());
            let base = map.entry(key).or_insert_with(|| key.texture()).clone();
            drop(map);
            let t = base.with_fractal(fractal).expect("a valid fractal sum");
            filtered_in::<$d, $n>(&t, c, &mut b)
        }};
    }
    match (dim, kind) {
        (2, 1) => run!(CRACKLE2, 2, 2),
        (2, _) => run!(ONE2, 2, 1),
        (_, 1) => run!(CRACKLE3, 3, 2),
        _ => run!(ONE3, 3, 1),
    }
}

/// The basis and combination of a decoded texture.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
struct Key {
    kind: u8,
    manhattan: bool,
    seed: u8,
}

impl Key {
    /// The texture of one octave, its blend curve measured.
    fn texture<const D: usize, const N: usize>(&self) -> Texture<D, N> {
        let metric = if self.manhattan { Metric::Manhattan } else { Metric::Euclidean };
        let config = Config { seed: u64::from(self.seed), metric, ..Config::default() };
        let combination =
            [Combination::f(1), Combination::crackle(), Combination::Border][usize::from(self.kind)].clone();
        let t = Texture::new(config, combination, Fractal::default(), None).expect("a valid texture");
        t.blend_curve();
        t
    }
}

fn filtered_in<const D: usize, const N: usize>(t: &Texture<D, N>, c: f64, b: &mut Bytes) {
    let fractal = t.fractal();
    let lipschitz: f64 = (0..fractal.octaves)
        .map(|i| f64::from(fractal.gain).powi(i as i32) * f64::from(fractal.lacunarity).powi(i as i32))
        .sum::<f64>()
        * c;
    let scale = t.kernel().pattern().scale();
    let unit = |b: &mut Bytes| f64::from(b.byte()) / 255.0;
    let straddling = 1 + usize::from(b.byte()) % D;
    let eps = 10f64.powf(-9.0 + 6.0 * unit(b));
    let (mut x, mut y) = ([0.0; D], [0.0; D]);
    for a in 0..D {
        let cell = f64::from(b.u32() as i32 % 1000);
        let (u, e) =
            if a < straddling { (cell, 0.1 + 0.9 * unit(b)) } else { (cell + unit(b) * 0.999, 2.0 * unit(b) - 1.0) };
        x[a] = (u - eps * e) / scale;
        y[a] = (u + eps * e) / scale;
    }
    let width = if b.byte().is_multiple_of(4) { 0.0 } else { (16.0 * unit(b) - 8.0).exp2() as f32 / scale as f32 };
    let what =
        format!("{:?}, {:?}, {:?} at {x:?} and {y:?}, width {width}", t.kernel().config(), t.combination(), fractal);
    let (vx, vy) = (t.filtered(x, width), t.filtered(y, width));
    assert!(vx.is_finite() && vy.is_finite(), "{what}: {vx} and {vy}");
    let rounding = 1e-5 * (1.0 + f64::from(vx.abs()) + f64::from(vy.abs()));
    let distance = x.iter().zip(&y).map(|(p, q)| (p - q) * (p - q)).sum::<f64>().sqrt();
    let jump = f64::from(vx - vy).abs();
    assert!(jump <= lipschitz * distance + rounding, "{what}: {vx} and {vy}, {distance:e} apart (L = {lipschitz})");
    let wider = if width == 0.0 { 1e-7 } else { width * (1.0 + 1e-6) };
    let v2 = t.filtered(x, wider);
    let allowed = 1e-5 + 1e-3 * (f64::from(vx.abs()) + 1.0);
    assert!(f64::from(vx - v2).abs() <= allowed, "{what}: {vx} at width {width}, {v2} at {wider}");
    // Every entry point, good and bad lanes side by side.
    let mut nan = x;
    nan[D - 1] = f64::NAN;
    let xs = [x, y, x, x, x, x, nan, x];
    let widths = [width, width, 0.0, f32::INFINITY, f32::NAN, -1.0, width, wider];
    let lanes = t.filtered8(&xs, widths).to_array();
    let bits = |v: f32| v.to_bits();
    assert_eq!(bits(lanes[0]), bits(vx), "{what}: lane 0 against the one-point call");
    assert_eq!(bits(lanes[1]), bits(vy), "{what}: lane 1 against the one-point call");
    assert_eq!(bits(lanes[2]), bits(t.value(x)), "{what}: a zero width against the point sample");
    assert!(lanes[3].is_finite(), "{what}: an infinite width gave {}", lanes[3]);
    assert!(lanes[4].is_nan() && lanes[5].is_nan(), "{what}: NaN and negative widths gave {lanes:?}");
    assert!(lanes[6].is_nan(), "{what}: a NaN coordinate gave {}", lanes[6]);
    assert_eq!(bits(lanes[7]), bits(v2), "{what}: lane 7 against the one-point call");
    let mut slice = [0.0f32; 8];
    t.filtered_values(&xs, Some(&widths), &mut slice).expect("room for eight");
    assert_eq!(slice.map(bits), lanes.map(bits), "{what}: the slice call against eight lanes");
}
