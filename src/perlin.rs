//! Perlin's gradient noise (the "improved" form: quintic fade and the
//! twelve cube-edge gradients) and turbulence, for one point or eight.
//!
//! Written once over [`Lanes`] like the cellular kernel, so a point through
//! [`Perlin::noise`] and the same point in any lane of [`Perlin::noise8`]
//! are bit-identical. The lattice hash is an integer mix in u32 lanes (no
//! permutation table, so there is no gather), seeded per pattern.
//!
//! Noise is 0 at every lattice point and lies in about [−1, 1]. Coordinates
//! must be finite and below 2^31 in magnitude (the lattice wraps there);
//! anything else gives NaN.

use wide::f32x8;

use crate::simd::lanes::{Eight, Lanes, One};

/// Perlin noise with a seed.
#[derive(Clone, Copy, Debug)]
pub struct Perlin {
    seed: u32,
}

/// Largest coordinate magnitude accepted.
pub const MAX_COORD: f64 = 2_147_483_647.0;

impl Perlin {
    /// Noise of the given seed (only the low 32 bits are used).
    pub fn new(seed: u64) -> Self {
        Perlin { seed: (seed ^ (seed >> 32)) as u32 }
    }

    /// Noise at one point.
    ///
    /// ```
    /// let perlin = worley::perlin::Perlin::new(7);
    /// assert_eq!(perlin.noise([1.0, 2.0, 3.0]), 0.0); // zero on the lattice
    /// assert!(perlin.noise([1.5, 2.25, 3.125]).abs() <= 1.0);
    /// ```
    pub fn noise(&self, x: [f64; 3]) -> f32 {
        let mut out = [0f32; 1];
        One::f_store(self.lanes::<One>(&[x]), &mut out);
        out[0]
    }

    /// Noise at eight points, one per lane.
    ///
    /// ```
    /// let perlin = worley::perlin::Perlin::new(7);
    /// let points: [[f64; 3]; 8] = std::array::from_fn(|i| [i as f64 * 0.37, 0.5, 0.25]);
    /// assert_eq!(perlin.noise8(&points).to_array()[6], perlin.noise(points[6]));
    /// ```
    pub fn noise8(&self, x: &[[f64; 3]; 8]) -> f32x8 {
        self.lanes::<Eight>(x)
    }

    /// Turbulence Σ_{i < octaves} |noise(2^i x)| / 2^i at one point.
    pub fn turbulence(&self, x: [f64; 3], octaves: u32) -> f32 {
        let mut sum = 0f32;
        let mut scale = 1.0;
        for _ in 0..octaves {
            sum += self.noise(x.map(|v| v * scale)).abs() / scale as f32;
            scale *= 2.0;
        }
        sum
    }

    /// Turbulence at eight points; lane `i` equals [`Perlin::turbulence`].
    pub fn turbulence8(&self, x: &[[f64; 3]; 8], octaves: u32) -> f32x8 {
        let mut sum = f32x8::splat(0.0);
        let mut scale = 1.0;
        for _ in 0..octaves {
            let p = x.map(|q| q.map(|v| v * scale));
            sum += self.noise8(&p).abs() / f32x8::splat(scale as f32);
            scale *= 2.0;
        }
        sum
    }

    #[inline(always)]
    fn lanes<L: Lanes>(&self, xs: &[[f64; 3]]) -> L::F {
        let mut cell = [[0u32; 8]; 3];
        let mut frac = [[0f32; 8]; 3];
        let mut bad = [0f32; 8];
        for (i, x) in xs.iter().enumerate().take(L::N) {
            for a in 0..3 {
                let v = x[a];
                if v.is_nan() || v.abs() > MAX_COORD {
                    bad[i] = 1.0;
                    continue;
                }
                let floor = v.floor();
                cell[a][i] = floor as i64 as u32;
                frac[a][i] = (v - floor) as f32;
            }
        }
        let c: [L::U; 3] = std::array::from_fn(|a| L::u_load(&cell[a][..L::N]));
        let f: [L::F; 3] = std::array::from_fn(|a| L::f_load(&frac[a][..L::N]));
        let one = L::f(1.0);
        let g: [L::F; 3] = std::array::from_fn(|a| L::sub(f[a], one));
        let w: [L::F; 3] = std::array::from_fn(|a| fade::<L>(f[a]));
        // The eight corners: bit a of `corner` is the offset along axis a.
        let mut dots = [L::f(0.0); 8];
        for (corner, dot) in dots.iter_mut().enumerate() {
            let at = |a: usize| corner >> a & 1 == 1;
            let h = self.hash::<L>(std::array::from_fn(|a| if at(a) { L::u_add(c[a], L::u(1)) } else { c[a] }));
            let d: [L::F; 3] = std::array::from_fn(|a| if at(a) { g[a] } else { f[a] });
            *dot = gradient::<L>(h, d);
        }
        let lerp = |t: L::F, a: L::F, b: L::F| L::add(a, L::mul(t, L::sub(b, a)));
        let x0 = [lerp(w[0], dots[0], dots[1]), lerp(w[0], dots[2], dots[3])];
        let x1 = [lerp(w[0], dots[4], dots[5]), lerp(w[0], dots[6], dots[7])];
        let y0 = lerp(w[1], x0[0], x0[1]);
        let y1 = lerp(w[1], x1[0], x1[1]);
        let n = lerp(w[2], y0, y1);
        if bad[..L::N].iter().any(|&b| b != 0.0) {
            L::select(L::lt(L::f(0.5), L::f_load(&bad[..L::N])), L::f(f32::NAN), n)
        } else {
            n
        }
    }

    /// An integer mix of the lattice point and the seed (multiply and
    /// xor-shift rounds; the top byte picks the gradient).
    #[inline(always)]
    fn hash<L: Lanes>(&self, c: [L::U; 3]) -> L::U {
        let mut h = L::u(self.seed);
        for (v, m) in c.into_iter().zip([0x9E37_79B1u32, 0x85EB_CA77, 0xC2B2_AE3D]) {
            h = L::u_mul(L::u_xor(h, v), L::u(m));
            h = L::u_xor(h, L::u_shr16(h));
        }
        h = L::u_mul(h, L::u(0x7FEB_352D));
        h = L::u_xor(h, L::u_shr13(h));
        h = L::u_mul(h, L::u(0x846C_A68B));
        L::u_xor(h, L::u_shr16(h))
    }
}

/// 6t^5 − 15t^4 + 10t^3: zero first and second derivatives at 0 and 1.
#[inline(always)]
fn fade<L: Lanes>(t: L::F) -> L::F {
    let inner = L::add(L::mul(t, L::sub(L::mul(t, L::f(6.0)), L::f(15.0))), L::f(10.0));
    L::mul(L::mul(L::mul(t, t), t), inner)
}

/// The dot product of the corner's gradient with `d`: the gradient is one of
/// the twelve edge midpoints of the cube (±1, ±1, 0) and permutations, picked
/// by four bits of the hash, with four of them repeated to make sixteen.
#[inline(always)]
fn gradient<L: Lanes>(h: L::U, d: [L::F; 3]) -> L::F {
    let top = L::u_shr24(h);
    let pick = L::u24_to_f(L::u_and(top, L::u(15)));
    let first_is_x = L::lt(pick, L::f(7.5));
    let u = L::select(first_is_x, d[0], d[1]);
    // v: y for picks 0–3; x for 12 and 14; z otherwise.
    let twelve_or_fourteen = L::u24_to_f(L::u_and(top, L::u(13)));
    let is_x = L::and(L::lt(L::f(11.5), twelve_or_fourteen), L::lt(twelve_or_fourteen, L::f(12.5)));
    let v = L::select(L::lt(pick, L::f(3.5)), d[1], L::select(is_x, d[0], d[2]));
    let neg = |bit: u32, x: L::F| {
        let set = L::lt(L::f(0.5), L::u24_to_f(L::u_and(top, L::u(bit))));
        L::select(set, L::sub(L::f(0.0), x), x)
    };
    L::add(neg(1, u), neg(2, v))
}
