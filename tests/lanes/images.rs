//! Brute force over the periodic images
//! ([`periodic_images`](worley_harness::oracle::periodic_images)): the
//! nearest image and squared distances.

/// Squared Euclidean distance.
pub fn d2<const D: usize>(p: &[f64; D], q: &[f64; D]) -> f64 {
    (0..D).map(|a| (p[a] - q[a]).powi(2)).sum()
}

/// The image nearest to `x` (in cells), the smallest ID among equals, as
/// its index; `skip` leaves one image out.
pub fn nearest<const D: usize>(images: &[([f64; D], u32)], x: &[f64; D], skip: Option<usize>) -> usize {
    let key = |j: usize| (d2(&images[j].0, x), images[j].1);
    (0..images.len()).filter(|&j| Some(j) != skip).min_by(|&a, &b| key(a).partial_cmp(&key(b)).unwrap()).unwrap()
}
