//! The coherent grid path: the per-sample kernel's bits at every sample of
//! every grid, whatever the configuration, and ties ordered by ID on both
//! paths; a texture's grid values, whose octaves take the same path, the
//! bits of its value at each point.

use worley::{Config, Features32, Grid, Metric, Mode, Outputs, Simd};
use worley_harness::grids::{grid_identity, same_bits, texture_identity};
use worley_harness::Tier;

fn identical<const D: usize, const N: usize>(config: Config, grids: usize, range: f64) {
    // A texture's octaves on the same grids, through values_grid.
    let (samples, differing) = texture_identity::<D, N>(Config { order: N, ..config }, 5, grids, range);
    assert_eq!(differing, 0, "texture {D}D F{N} {config:?}: {differing} of {samples}");
    assert!(samples > grids * 20, "{samples}");
    for outputs in [Outputs::Distances, Outputs::Ids, Outputs::IdsAndDeltas] {
        let simd = Simd::<D, N>::new(Config { order: N, ..config }, outputs).unwrap();
        let found = grid_identity(&simd, 5, grids, range);
        assert_eq!(found.differing, 0, "{D}D F{N} {config:?} {outputs:?}: {found:?}");

        // Every grid of the campaign suits the coherent path in exact mode.
        let expected = if config.mode == Mode::Exact { grids } else { 0 };
        assert_eq!(found.coherent, expected, "{D}D F{N} {config:?} {outputs:?}: {found:?}");
        assert!(found.samples > grids * 20, "{found:?}");
    }
}

fn every_dimension_and_order(tier: Tier) {
    let c = Config::default();
    identical::<2, 1>(c, tier.of(300), 100.0);
    identical::<2, 3>(c, tier.of(200), 100.0);
    identical::<3, 1>(c, tier.of(300), 100.0);
    identical::<3, 2>(c, tier.of(200), 100.0);
    identical::<3, 4>(c, tier.of(100), 100.0);
    identical::<4, 1>(c, tier.of(100), 100.0);
    identical::<4, 2>(c, tier.of(60), 100.0);
    identical::<2, 16>(Config { density: 0.5, ..c }, tier.of(40), 100.0);
}

worley_harness::tiered!(
    grids_give_the_per_sample_bits_in_every_dimension_and_order,
    campaign_grids_give_the_per_sample_bits_in_every_dimension_and_order,
    every_dimension_and_order
);

worley_harness::tiered!(
    grids_give_the_per_sample_bits_for_every_metric_table_and_mode,
    campaign_grids_give_the_per_sample_bits_for_every_metric_table_and_mode,
    every_metric_table_and_mode
);

fn every_metric_table_and_mode(tier: Tier) {
    let c = Config::default();
    for metric in [Metric::Manhattan, Metric::Chebyshev, Metric::Minkowski(3.0), Metric::Minkowski(1.5)] {
        identical::<3, 2>(Config { metric, seed: 9, ..c }, tier.of(60), 100.0);
        identical::<2, 2>(Config { metric, seed: 9, ..c }, tier.of(60), 100.0);
    }
    identical::<3, 2>(Config { bump: 0.5, ..c }, tier.of(100), 100.0);
    identical::<3, 2>(Config { density: 1.0, ..c }, tier.of(100), 100.0);
    identical::<3, 1>(Config { density: 20.0, seed: 3, ..c }, tier.of(100), 100.0);
    identical::<3, 2>(Config { mode: Mode::Window, ..c }, tier.of(40), 100.0);
}

#[test]
fn grids_far_from_the_origin_give_the_per_sample_bits() {
    // Cells beyond the i32 range (the lane-wise locate of the per-sample
    // kernel) and near 2^40.
    identical::<3, 2>(Config::default(), 60, 3.0e10);
    identical::<2, 1>(Config::default(), 60, 1.0e12);
}

#[test]
fn the_parallel_grid_is_the_serial_grid() {
    let simd = Simd::<3, 2>::new(Config { order: 2, ..Config::default() }, Outputs::IdsAndDeltas).unwrap();
    let grid = Grid { origin: [-7.3, 2.2, 0.4], step: [0.05, 0.07, 0.3], size: [203, 97, 3] };
    assert!(simd.coherent_grid(&grid));
    let empty = Features32 { distance: [0.0; 2], delta: [[0.0; 3]; 2], id: [0; 2] };
    let n = grid.len().unwrap();
    let (mut serial, mut parallel) = (vec![empty; n], vec![empty; n]);
    simd.evaluate_grid(&grid, &mut serial).unwrap();
    simd.evaluate_grid_parallel(&grid, &mut parallel).unwrap();
    assert!(serial.iter().zip(&parallel).all(|(a, b)| same_bits(a, b)));
    for i in (0..n).step_by(97) {
        assert!(same_bits(&serial[i], &simd.evaluate(grid.point(i))), "sample {i}");
    }
}

#[test]
fn bands_of_rows_assemble_into_the_whole_grid() {
    let simd = Simd::<3, 2>::new(Config { order: 2, ..Config::default() }, Outputs::IdsAndDeltas).unwrap();
    let empty = Features32 { distance: [0.0; 2], delta: [[0.0; 3]; 2], id: [0; 2] };
    let grids = [
        // Coherent, rows across three slabs, more rows than a serial band.
        Grid { origin: [-7.3, 2.2, 0.4], step: [0.05, 0.07, 0.3], size: [61, 97, 3] },
        // Samples a cell apart: the per-sample path.
        Grid { origin: [3.1, -1.0, 0.2], step: [2.5, 1.5, 1.0], size: [13, 40, 2] },
        // A bad row: NaN where the kernel gives it.
        Grid { origin: [0.0, 1.0e300, 0.0], step: [0.01, -2.0e299, 0.0], size: [9, 12, 1] },
    ];
    for grid in &grids {
        let n = grid.len().unwrap();
        let mut whole = vec![empty; n];
        simd.evaluate_grid(grid, &mut whole).unwrap();
        let (row, rows) = (grid.size[0], grid.rows().unwrap());
        for (i, o) in whole.iter().enumerate().step_by(31) {
            assert!(same_bits(o, &simd.evaluate(grid.point(i))), "sample {i}");
        }
        let mut first = 0;
        for band in [1, 130, 3, 17, 60].into_iter().cycle() {
            let band = band.min(rows - first);
            let mut out = vec![empty; band * row];
            simd.evaluate_grid_rows(grid, first, &mut out).unwrap();
            let want = &whole[first * row..(first + band) * row];
            assert!(out.iter().zip(want).all(|(a, b)| same_bits(a, b)), "{grid:?} rows {first}..+{band}");
            first += band;
            if first == rows {
                break;
            }
        }
        // Not whole rows, or past the last row: an error, nothing written.
        let mut odd = vec![empty; row + 1];
        let err = simd.evaluate_grid_rows(grid, 0, &mut odd).unwrap_err();
        assert_eq!((err.needed, err.given), (row, row + 1));
        let mut two = vec![empty; 2 * row];
        let err = simd.evaluate_grid_rows(grid, rows - 1, &mut two).unwrap_err();
        assert_eq!(err.needed, row);
        assert!(two.iter().all(|o| o.distance == [0.0; 2]));
    }
}

#[test]
fn grids_with_bad_coordinates_take_the_per_sample_path() {
    let simd = Simd::<2, 1>::new(Config::default(), Outputs::Ids).unwrap();
    let empty = Features32 { distance: [0.0; 1], delta: [[0.0; 2]; 1], id: [0; 1] };
    for origin in [[f64::NAN, 0.0], [0.0, f64::INFINITY], [1.0e300, 0.0]] {
        let grid = Grid { origin, step: [0.01, 0.01], size: [9, 5] };
        assert!(!simd.coherent_grid(&grid));
        let mut out = vec![empty; 45];
        simd.evaluate_grid(&grid, &mut out).unwrap();
        for (i, o) in out.iter().enumerate() {
            assert!(same_bits(o, &simd.evaluate(grid.point(i))));
            assert!(o.distance[0].is_nan() && o.id[0] == worley::INVALID_ID);
        }
    }
}

/// A user coordinate x with x·S exactly `u`, if one is near u/S.
fn exact_coordinate(u: f64, scale: f64) -> Option<f64> {
    let mut x = u / scale;
    for _ in 0..6 {
        if x * scale == u {
            return Some(x);
        }
        x = if x * scale < u { x.next_up() } else { x.next_down() };
    }
    None
}

#[test]
fn ties_are_ordered_by_id_on_both_paths() {
    // The midpoint of two feature points of neighbouring cells is equally
    // far from both. Where every step of the kernel's delta is exact in f32
    // the two ranks are the same bits, and the point with the smaller ID
    // must come first, through the per-sample kernel and through a grid
    // whose tiles meet the points in another order.
    let config = Config { order: 4, seed: 11, ..Config::default() };
    let simd = Simd::<2, 4>::new(config, Outputs::IdsAndDeltas).unwrap();
    let pattern = simd.pattern().clone();
    let scale = pattern.scale();
    let unit = (1u64 << 24) as f64;
    let mut ties = 0;
    for i in 0..4000i64 {
        let (ca, cb) = ([i, 3 * i], [i + 1, 3 * i + (i % 2)]);
        let (pa, pb) = (pattern.points(ca), pattern.points(cb));
        let (Some(p), Some(q)) = (pa.first(), pb.first()) else { continue };
        let at = |c: [i64; 2], f: [u32; 2]| -> [f64; 2] { std::array::from_fn(|a| c[a] as f64 * unit + f[a] as f64) };
        let (xp, xq) = (at(ca, p.fraction), at(cb, q.fraction));
        // The midpoint in lane units (2^-24 cells), its cell and fraction.
        let m: [f64; 2] = std::array::from_fn(|a| (xp[a] + xq[a]) / 2.0);
        let cell: [i64; 2] = std::array::from_fn(|a| (m[a] / unit).floor() as i64);
        let f: [f64; 2] = std::array::from_fn(|a| m[a] - cell[a] as f64 * unit);
        // Every f32 step of both deltas exact: f, f − offset·2^24, and the
        // difference with the point's integer coordinate.
        let exact = |v: f64| (v as f32) as f64 == v;
        let steps_exact = [(ca, p), (cb, q)].iter().all(|(c, pt)| {
            (0..2).all(|a| {
                let shifted = f[a] - (c[a] - cell[a]) as f64 * unit;
                exact(f[a]) && exact(shifted) && exact(shifted - pt.fraction[a] as f64)
            })
        });
        if !steps_exact {
            continue;
        }
        let u: [f64; 2] = std::array::from_fn(|a| cell[a] as f64 + f[a] / unit);
        let Some(x) = exact_coordinate(u[0], scale) else { continue };
        let Some(y) = exact_coordinate(u[1], scale) else { continue };
        let one = simd.evaluate([x, y]);
        let Some(k) = (0..3).find(|&k| one.id[k] == p.id || one.id[k] == q.id) else { continue };
        assert_eq!(one.distance[k].to_bits(), one.distance[k + 1].to_bits(), "cells {ca:?} {cb:?}: not a tie");
        assert_eq!([one.id[k], one.id[k + 1]], [p.id.min(q.id), p.id.max(q.id)], "cells {ca:?} {cb:?}: order");
        // The tie as the last sample of a tile that starts a little lower.
        let step = [0.01 / scale, 0.013 / scale];
        let grid = Grid { origin: [x - 7.0 * step[0], y - 3.0 * step[1]], step, size: [8, 4] };
        let mut out = vec![one; 32];
        simd.evaluate_grid(&grid, &mut out).unwrap();
        assert!(simd.coherent_grid(&grid));
        let sample = 3 * 8 + 7;
        if grid.point(sample) == [x, y] {
            assert!(same_bits(&out[sample], &one), "cells {ca:?} {cb:?}: the grid differs at the tie");
            ties += 1;
        }
    }
    assert!(ties >= 20, "only {ties} ties exercised");
}
