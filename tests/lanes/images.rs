//! The periodic point set written out for brute force: every feature
//! point of one period, repeated at shifts of −2..=2 periods per axis
//! (enough for periods of 3 cells or more and searches within 2 cells).

use worley::definition::FRACTION_ULP;
use worley::{Config, Reference};

/// Every image as (position in cells, ID), for `config`'s pattern with
/// `period` cells per axis.
pub fn periodic_images<const D: usize>(config: Config, period: [u32; D]) -> Vec<([f64; D], u32)> {
    let pattern = Reference::<D>::new(config).unwrap().pattern().clone();
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

/// Squared Euclidean distance.
pub fn d2<const D: usize>(p: &[f64; D], q: &[f64; D]) -> f64 {
    (0..D).map(|a| (p[a] - q[a]).powi(2)).sum()
}

/// The image nearest to `x` (in cells, any real coordinates), the smallest
/// ID among equals, as its index.
pub fn nearest<const D: usize>(images: &[([f64; D], u32)], x: &[f64; D], skip: Option<usize>) -> usize {
    let key = |j: usize| (d2(&images[j].0, x), images[j].1);
    (0..images.len()).filter(|&j| Some(j) != skip).min_by(|&a, &b| key(a).partial_cmp(&key(b)).unwrap()).unwrap()
}
