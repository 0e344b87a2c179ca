//! How best to estimate a texture's average over a footprint, per unit of
//! time: one point sample, the blend of `worley::filter` (one sample), or
//! the mean of k × k samples at the centres of the footprint's cells (with
//! or without each standing for its own smaller footprint).
//!
//! ```sh
//! cargo run --release -p worley-cli --example footprint_estimators
//! ```
//!
//! 2D textures, 4000 random points in [−1000, 1000]², footprints that are
//! axis-aligned squares of side w (user units: the mean F1 is 1, a cell is
//! about 2 units across) centred on the point; the truth is the mean of 24 × 24 point
//! samples over the square. Error: RMS of estimate − truth, divided by the
//! texture's standard deviation. Time: nanoseconds per estimate, eight
//! lanes per call, one thread, the median of seven round-robin runs.
//! Efficiency: error² × time (a Monte-Carlo estimator's variance times its
//! cost), lower is better.

use std::time::Instant;
use worley::math::uniform;
use worley::texture::{Combination, Fractal, Texture};
use worley::Config;

const POINTS: usize = 4000;
/// Truth: this many samples per side of the footprint.
const TRUTH: usize = 24;

/// The estimators compared.
const NAMES: [&str; 5] = ["point", "blend", "2x2 points", "2x2 blends", "3x3 points"];

/// One estimator's eight estimates: `kind` indexes [`NAMES`].
fn estimate<const N: usize>(t: &Texture<2, N>, x: &[[f64; 2]; 8], w: f64, kind: usize) -> [f32; 8] {
    let mean_of = |k: usize, blended: bool| {
        let mut sum = [0f32; 8];
        for j in 0..k {
            for i in 0..k {
                let o = [w * ((i as f64 + 0.5) / k as f64 - 0.5), w * ((j as f64 + 0.5) / k as f64 - 0.5)];
                let y = x.map(|p| [p[0] + o[0], p[1] + o[1]]);
                let v = if blended { t.filtered8(&y, [(w / k as f64) as f32; 8]) } else { t.value8(&y) };
                for (s, v) in sum.iter_mut().zip(v.to_array()) {
                    *s += v / (k * k) as f32;
                }
            }
        }
        sum
    };
    match kind {
        0 => t.value8(x).to_array(),
        1 => t.filtered8(x, [w as f32; 8]).to_array(),
        2 => mean_of(2, false),
        3 => mean_of(2, true),
        _ => mean_of(3, false),
    }
}

fn compare<const N: usize>(name: &str, t: &Texture<2, N>) {
    let mu = f64::from(t.blend_curve().mean());
    let xs: Vec<[f64; 2]> = (0..POINTS as u64)
        .map(|i| [2000.0 * uniform(5, 2 * i) - 1000.0, 2000.0 * uniform(5, 2 * i + 1) - 1000.0])
        .collect();
    let var = xs.iter().map(|x| (f64::from(t.value(*x)) - mu).powi(2)).sum::<f64>() / POINTS as f64;
    for w in [0.125, 0.25, 0.5, 1.0, 2.0, 8.0] {
        let truth: Vec<f64> = xs
            .iter()
            .map(|x| {
                let side = |i: usize| w * ((i as f64 + 0.5) / TRUTH as f64 - 0.5);
                let sum: f64 = (0..TRUTH * TRUTH)
                    .map(|k| f64::from(t.value([x[0] + side(k % TRUTH), x[1] + side(k / TRUTH)])))
                    .sum();
                sum / (TRUTH * TRUTH) as f64
            })
            .collect();
        let run = |kind: usize, out: &mut Vec<f32>| {
            out.clear();
            for chunk in xs.chunks_exact(8) {
                out.extend_from_slice(&estimate(t, chunk.try_into().expect("eight points"), w, kind));
            }
        };
        let mut times = vec![Vec::new(); NAMES.len()];
        let mut out = Vec::new();
        for _ in 0..7 {
            for (kind, times) in times.iter_mut().enumerate() {
                let started = Instant::now();
                run(kind, &mut out);
                times.push(started.elapsed().as_secs_f64() * 1e9 / POINTS as f64);
            }
        }
        for (kind, times) in times.iter_mut().enumerate() {
            run(kind, &mut out);
            let error =
                (out.iter().zip(&truth).map(|(e, t)| (f64::from(*e) - t).powi(2)).sum::<f64>() / POINTS as f64 / var)
                    .sqrt();
            times.sort_by(f64::total_cmp);
            let ns = times[times.len() / 2];
            println!("| {name} | {w} | {} | {error:.3} | {ns:.0} | {:.2} |", NAMES[kind], error * error * ns);
        }
    }
}

fn main() {
    let config = Config::default();
    println!("| texture | w | estimator | RMS error / std | ns per estimate | error² × ns |");
    println!("|---|---|---|---|---|---|");
    let f1 = Texture::<2, 1>::new(config, Combination::f(1), Fractal::default(), None).expect("a valid texture");
    compare("F1", &f1);
    let crackle =
        Texture::<2, 2>::new(config, Combination::crackle(), Fractal::default(), None).expect("a valid texture");
    compare("F2 - F1", &crackle);
    let fractal = Texture::<2, 1>::new(config, Combination::f(1), Fractal::octaves(4), None).expect("a valid texture");
    compare("F1, 4 octaves", &fractal);
}
