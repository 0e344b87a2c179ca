//! A renderer's use of the crate, in one file: a pinhole camera looks at a
//! ground plane, every pixel's hit is shaded by eights with its footprint
//! (a five-octave F2 − F1 texture whose fine octaves fade where a pixel
//! cannot show them), and the image is written as a binary PPM.
//!
//! ```sh
//! cargo run --release --example plane            # writes out/plane.ppm
//! cargo run --release --example plane -- my.ppm  # or a path of your own
//! ```

use std::io::Write;
use worley::texture::{Combination, Fractal, Texture};
use worley::{by_eights, Config};

const WIDTH: usize = 480;
const HEIGHT: usize = 270;
/// Vertical field of view, radians.
const FOV: f64 = 1.0;
/// The camera's height above the plane and its pitch below the horizon.
const HEIGHT_ABOVE: f64 = 2.0;
const PITCH: f64 = 0.3;
/// Texture frequency: features per unit on the plane.
const FREQUENCY: f64 = 1.5;

/// A hit on the plane y = 0, in texture coordinates, and the side of the
/// square that stands for its pixel there (the texture's footprint).
#[derive(Clone, Copy)]
struct Hit {
    at: [f64; 2],
    width: f32,
}

/// The ray through the centre of pixel (px, py), and where it meets the
/// plane; `None` above the horizon.
fn trace(px: usize, py: usize) -> Option<Hit> {
    let pixel = (FOV * 0.5).tan() * 2.0 / HEIGHT as f64; // one pixel's angle, near the axis
    let sx = (px as f64 + 0.5 - WIDTH as f64 * 0.5) * pixel;
    let sy = (HEIGHT as f64 * 0.5 - py as f64 - 0.5) * pixel;
    // Camera frame pitched down by PITCH: forward (0, −sin, cos), up (0, cos, sin).
    let (s, c) = PITCH.sin_cos();
    let d = [sx, sy * c - s, sy * s + c];
    let length = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if d[1] >= -1e-9 {
        return None;
    }
    let t = HEIGHT_ABOVE / -d[1];
    // The pixel's preimage is about t·pixel·|d| across the ray and that over
    // cos θ along it (θ from the plane's normal): a square of their
    // geometric mean stands for it.
    let cos = -d[1] / length;
    let width = t * pixel * length / cos.sqrt();
    Some(Hit { at: [t * d[0] * FREQUENCY, t * d[2] * FREQUENCY], width: (width * FREQUENCY) as f32 })
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1).unwrap_or_else(|| "out/plane.ppm".into());
    // Built once: F1 and F2 in 2D (the type's 2 is the order), five octaves.
    let texture = Texture::<2, 2>::new(Config::default(), Combination::crackle(), Fractal::octaves(5), None)?;
    // A fractal sum has no fixed range: measure where its values fall.
    let range = texture.measure_range(100_000, 1);

    // The frame's hits in pixel order, as a renderer collects them.
    let mut hits = Vec::new();
    let mut pixels = Vec::new();
    for py in 0..HEIGHT {
        for px in 0..WIDTH {
            if let Some(hit) = trace(px, py) {
                hits.push(hit);
                pixels.push(py * WIDTH + px);
            }
        }
    }
    // Eight hits per call with their footprints; a short last block is padded.
    let points: Vec<[f64; 2]> = hits.iter().map(|h| h.at).collect();
    let mut values = vec![0f32; hits.len()];
    let mut next = 0;
    by_eights(&points, &mut values, |x| {
        let width: [f32; 8] = std::array::from_fn(|i| hits[(next + i).min(hits.len() - 1)].width);
        next += 8;
        texture.filtered8(x, width).to_array()
    })?;

    // Mortar dark, stones light, a grey sky; NaN (none here) would be red.
    let mut image = vec![[150u8, 170, 200]; WIDTH * HEIGHT];
    for (&pixel, &v) in pixels.iter().zip(&values) {
        image[pixel] = if v.is_nan() {
            [255, 0, 0]
        } else {
            let g = range.remap(v);
            [(40.0 + 200.0 * g) as u8, (35.0 + 180.0 * g) as u8, (30.0 + 150.0 * g) as u8]
        };
    }
    if let Some(dir) = std::path::Path::new(&path).parent() {
        std::fs::create_dir_all(dir)?;
    }
    let mut file = std::io::BufWriter::new(std::fs::File::create(&path)?);
    write!(file, "P6\n{WIDTH} {HEIGHT}\n255\n")?;
    file.write_all(&image.concat())?;
    println!("{} hits shaded, values in [{:.3}, {:.3}] remapped, written to {path}", hits.len(), range.lo, range.hi);
    Ok(())
}
