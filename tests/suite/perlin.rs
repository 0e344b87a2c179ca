//! Perlin noise: one lane and eight bit-identical, against a plain f64
//! transcription of its definition, zero on the lattice, bounded, Lipschitz,
//! and NaN for bad input.

use worley::perlin::Perlin;
use worley_harness::uniform;

/// The definition, written out in f64 with no lanes: the lattice hash of
/// `perlin.rs` (seed, three multiply/xor-shift rounds, a finaliser), the top
/// byte's low four bits picking one of the cube-edge gradients, the quintic
/// fade and trilinear interpolation.
fn plain(seed: u64, x: [f64; 3]) -> f64 {
    let seed = (seed ^ (seed >> 32)) as u32;
    let hash = |c: [i64; 3]| {
        let mut h = seed;
        for (v, m) in c.iter().zip([0x9E37_79B1u32, 0x85EB_CA77, 0xC2B2_AE3D]) {
            h = (h ^ *v as u32).wrapping_mul(m);
            h ^= h >> 16;
        }
        h = h.wrapping_mul(0x7FEB_352D);
        h ^= h >> 13;
        h = h.wrapping_mul(0x846C_A68B);
        h ^ (h >> 16)
    };
    let gradients: [[f64; 3]; 16] = [
        [1., 1., 0.],
        [-1., 1., 0.],
        [1., -1., 0.],
        [-1., -1., 0.],
        [1., 0., 1.],
        [-1., 0., 1.],
        [1., 0., -1.],
        [-1., 0., -1.],
        [0., 1., 1.],
        [0., -1., 1.],
        [0., 1., -1.],
        [0., -1., -1.],
        [1., 1., 0.],
        [0., -1., 1.],
        [-1., 1., 0.],
        [0., -1., -1.],
    ];
    let fade = |t: f64| t * t * t * (t * (6.0 * t - 15.0) + 10.0);
    let cell = x.map(|v| v.floor());
    let f: [f64; 3] = std::array::from_fn(|a| x[a] - cell[a]);
    let mut total = 0.0;
    for corner in 0..8 {
        let o: [f64; 3] = std::array::from_fn(|a| (corner >> a & 1) as f64);
        let g = gradients[(hash(std::array::from_fn(|a| cell[a] as i64 + o[a] as i64)) >> 24 & 15) as usize];
        let dot: f64 = (0..3).map(|a| g[a] * (f[a] - o[a])).sum();
        let weight: f64 = (0..3).map(|a| if o[a] == 1.0 { fade(f[a]) } else { 1.0 - fade(f[a]) }).product();
        total += weight * dot;
    }
    total
}

fn point(i: usize, range: f64) -> [f64; 3] {
    std::array::from_fn(|a| (uniform(17, (i * 3 + a) as u64) - 0.5) * 2.0 * range)
}

#[test]
fn noise_matches_its_plain_definition() {
    for seed in [0, 1, 0xDEAD_BEEF_0000_0001] {
        let noise = Perlin::new(seed);
        let mut worst = 0f64;
        for i in 0..100_000 {
            let x = point(i, 300.0);
            worst = worst.max((noise.noise(x) as f64 - plain(seed, x)).abs());
        }
        assert!(worst < 2e-6, "seed {seed}: {worst}");
    }
}

#[test]
fn eight_lanes_equal_one_lane_bit_for_bit() {
    let noise = Perlin::new(5);
    for batch in 0..5_000 {
        let xs: [[f64; 3]; 8] = std::array::from_fn(|i| point(batch * 8 + i, 1e4));
        let eight = noise.noise8(&xs).to_array();
        let turbulence = noise.turbulence8(&xs, 4).to_array();
        for i in 0..8 {
            assert_eq!(eight[i].to_bits(), noise.noise(xs[i]).to_bits());
            assert_eq!(turbulence[i].to_bits(), noise.turbulence(xs[i], 4).to_bits());
        }
    }
}

#[test]
fn noise_is_zero_on_the_lattice_bounded_and_lipschitz() {
    let noise = Perlin::new(2);
    for i in 0..1000 {
        let c = point(i, 1e6).map(f64::floor);
        assert_eq!(noise.noise(c), 0.0, "{c:?}");
    }
    let h = 1e-4;
    let mut largest = 0f32;
    for i in 0..200_000 {
        let x = point(i, 500.0);
        let n = noise.noise(x);
        largest = largest.max(n.abs());
        // |∇n| ≤ 3·(2 + 15/8)·√3 is a loose bound on the slope.
        let y = [x[0] + h, x[1] - h, x[2] + h];
        assert!(((noise.noise(y) - n) as f64).abs() <= 21.0 * h * 3f64.sqrt() + 1e-6);
    }
    assert!(largest <= 1.1 && largest > 0.7, "largest |noise| {largest}");
    let t = noise.turbulence([0.3, 0.2, 0.1], 6);
    assert!(t > 0.0 && t < 2.2);
}

#[test]
fn bad_input_gives_nan_in_its_own_lane_only() {
    let noise = Perlin::new(0);
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 3e9, -1e300] {
        assert!(noise.noise([0.5, bad, 0.5]).is_nan());
        let mut xs = [[0.25, 0.5, 0.75]; 8];
        xs[3][2] = bad;
        let lanes = noise.noise8(&xs).to_array();
        assert!(lanes[3].is_nan());
        assert!(lanes.iter().enumerate().all(|(i, v)| i == 3 || v.to_bits() == lanes[0].to_bits()));
    }
}
