//! Grids through the coherent path against the per-sample kernel.
//!
//! [`Simd::evaluate_grid`] takes the coherent path (points generated once
//! per band of rows, tiles of samples against shared candidates) when
//! [`Simd::coherent_grid`] says so. Its results must be the per-sample
//! kernel's bits: [`Simd::evaluate`] at every [`Grid::point`], which the
//! oracle campaign proves exact on its own. This campaign draws grids that
//! stress the tiling: odd sizes, origins anywhere (on lattice planes too),
//! steps from a hundredth of a cell to an eighth along axis 0, negative
//! steps, rows a cell or more apart, and single rows. The same grids go
//! through a texture's [`Texture::values_grid`], whose octaves take the
//! coherent path as grids of their own, against [`Texture::value`] at every
//! point, which runs the per-sample kernel octave by octave.

use worley::simd::{Features32, Grid, Simd};
use worley::texture::{Combination, Fractal, Texture};
use worley::Config;

use crate::{first_in_cell, uniform};

/// What one campaign of grids found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct GridIdentity {
    /// Grids evaluated.
    pub grids: usize,
    /// Of which the coherent path took.
    pub coherent: usize,
    /// Samples compared.
    pub samples: usize,
    /// Samples whose distances, IDs or deltas from [`Simd::evaluate_grid`],
    /// or whose distances from [`Simd::evaluate_grid_distances`], differ in
    /// any bit from the per-sample kernel's.
    pub differing: usize,
    /// Samples of the same grids through [`Texture::values_grid`] of a
    /// three-octave sum of F_n on the same configuration
    /// ([`texture_identity`]).
    pub texture_samples: usize,
    /// Of which differ in any bit from [`Texture::value`] at the point.
    pub texture_differing: usize,
}

/// Grid `g` of a seeded campaign in a world of half-width `range` (user
/// units), with about `cells` cells per axis of the pattern of scale `scale`.
pub fn campaign_grid<const D: usize>(seed: u64, g: usize, range: f64, scale: f64) -> Grid<D> {
    let u = |k: u64| uniform(seed ^ 0x6A09_E667_F3BC_C908, (g as u64) * 64 + k);
    let cell = 1.0 / scale;
    let origin: [f64; D] = std::array::from_fn(|a| {
        let x = (2.0 * u(a as u64) - 1.0) * range;
        // One grid in four starts on a lattice plane of axis 0.
        if a == 0 && g % 4 == 1 {
            first_in_cell((x * scale).round() as i64, scale)
        } else {
            x
        }
    });
    let step: [f64; D] = std::array::from_fn(|a| {
        let sign = if u(8 + a as u64) < 0.2 { -1.0 } else { 1.0 };
        let size = if a == 0 {
            // From a hundredth to an eighth of a cell.
            cell * (0.01 + 0.115 * u(16 + a as u64))
        } else {
            match g % 5 {
                0 => 0.0,
                1 => cell * (0.8 + u(16 + a as u64)),
                _ => cell * 0.3 * u(16 + a as u64),
            }
        };
        sign * size
    });
    let size: [usize; D] = std::array::from_fn(|a| {
        let most = [70.0, 19.0, 4.0, 3.0][a];
        1 + (most * u(32 + a as u64)) as usize
    });
    Grid { origin, step, size }
}

/// Evaluates `grids` grids of the campaign with `simd.evaluate_grid` and
/// `simd.evaluate_grid_distances`, and compares every sample with
/// `simd.evaluate` at the same point, bit for bit. The texture fields are
/// left at zero: [`texture_identity`] fills them.
pub fn grid_identity<const D: usize, const N: usize>(
    simd: &Simd<D, N>,
    seed: u64,
    grids: usize,
    range: f64,
) -> GridIdentity {
    let scale = simd.pattern().scale();
    let empty = Features32::<D, N> { distance: [0.0; N], delta: [[0.0; D]; N], id: [0; N] };
    let mut found = GridIdentity::default();
    let mut out = Vec::new();
    let mut distances = Vec::new();
    for g in 0..grids {
        let grid = campaign_grid::<D>(seed, g, range, scale);
        let n = grid.len().expect("small grids");
        out.clear();
        out.resize(n, empty);
        simd.evaluate_grid(&grid, &mut out).expect("the buffer fits the grid");
        distances.clear();
        distances.resize(n, [0.0; N]);
        simd.evaluate_grid_distances(&grid, &mut distances).expect("the buffer fits the grid");
        found.grids += 1;
        found.coherent += usize::from(simd.coherent_grid(&grid));
        for (i, (got, d)) in out.iter().zip(&distances).enumerate() {
            let want = simd.evaluate(grid.point(i));
            found.samples += 1;
            let same_distances = d.map(f32::to_bits) == want.distance.map(f32::to_bits);
            found.differing += usize::from(!same_bits(got, &want) || !same_distances);
        }
    }
    found
}

/// The same grids through a texture of three octaves of F_n on `config`:
/// its [`Texture::values_grid`] against its [`Texture::value`] at every
/// point, bit for bit. Returns the samples compared and how many differ.
pub fn texture_identity<const D: usize, const N: usize>(
    config: Config,
    seed: u64,
    grids: usize,
    range: f64,
) -> (usize, usize) {
    let texture = Texture::<D, N>::new(config, Combination::f(N), Fractal::octaves(3), None).expect("F_n, 3 octaves");
    let scale = texture.kernel().pattern().scale();
    let (mut samples, mut differing) = (0, 0);
    let mut values = Vec::new();
    for g in 0..grids {
        let grid = campaign_grid::<D>(seed, g, range, scale);
        values.clear();
        values.resize(grid.len().expect("small grids"), 0.0);
        texture.values_grid(&grid, &mut values).expect("the buffer fits the grid");
        for (i, got) in values.iter().enumerate() {
            samples += 1;
            differing += usize::from(got.to_bits() != texture.value(grid.point(i)).to_bits());
        }
    }
    (samples, differing)
}

/// Whether two results are the same bits (NaN payloads included).
pub fn same_bits<const D: usize, const N: usize>(a: &Features32<D, N>, b: &Features32<D, N>) -> bool {
    a.distance.map(f32::to_bits) == b.distance.map(f32::to_bits)
        && a.id == b.id
        && a.delta.map(|d| d.map(f32::to_bits)) == b.delta.map(|d| d.map(f32::to_bits))
}
