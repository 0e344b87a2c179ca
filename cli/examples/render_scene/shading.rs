//! Shading a frame: rays through the pixels, hits shaded in packets of
//! eight on all cores, tone mapping and writing the picture.

use crate::materials::{Shading, Textures};
use crate::scene::{Camera, Footprint, Width, World};
use glam::Vec3;
use rayon::prelude::*;
use worley_cli::picture::{to_byte, write_output, Rgb};

/// Renders linear colours: `spp` samples per pixel on a stratified jittered
/// grid (a square number), or the pixel centre for one.
pub(crate) fn render(textures: &Textures, world: &World, camera: &Camera, shading: Shading, spp: usize) -> Vec<Vec3> {
    let side = (spp as f64).sqrt().round() as usize;
    let mut image = vec![Vec3::ZERO; camera.width * camera.height];
    image.par_chunks_mut(camera.width).enumerate().for_each(|(y, row)| {
        // The row's samples, pixel after pixel.
        let samples: Vec<(usize, f32, f32)> = (0..camera.width)
            .flat_map(|x| {
                (0..side * side).map(move |k| {
                    if side == 1 {
                        return (x, x as f32 + 0.5, y as f32 + 0.5);
                    }
                    let counter = (((y * camera.width + x) * side * side + k) * 2) as u64;
                    let jx = worley::math::uniform(17, counter) as f32;
                    let jy = worley::math::uniform(17, counter + 1) as f32;
                    let (sx, sy) = ((k % side) as f32, (k / side) as f32);
                    (x, x as f32 + (sx + jx) / side as f32, y as f32 + (sy + jy) / side as f32)
                })
            })
            .collect();
        for packet in samples.chunks(8) {
            let rays: [Vec3; 8] = std::array::from_fn(|i| {
                let (_, sx, sy) = packet[i.min(packet.len() - 1)];
                camera.ray(sx, sy)
            });
            let dirs = rays.map(Vec3::normalize);
            let hits = dirs.map(|d| world.trace(camera.eye, d));
            let width = match shading {
                Shading::Filtered { width, .. } => width,
                Shading::Point => Width::Area,
            };
            let footprints: [Footprint; 8] = std::array::from_fn(|i| camera.footprint(rays[i], &hits[i], width));
            let mut colour = textures.shade8(world, &hits, &dirs, &footprints, shading);
            if let Shading::Filtered { split: true, .. } = shading {
                textures.split_floor(world, &hits, &dirs, &footprints, shading, &mut colour);
            }
            for (&(x, _, _), c) in packet.iter().zip(colour) {
                row[x] += c / (side * side) as f32;
            }
        }
    });
    image
}

/// A simple tone curve and gamma 2.2, in [0, 1].
pub(crate) fn tone(c: Vec3) -> [f32; 3] {
    let c = c / (c + Vec3::ONE) * 1.5;
    c.to_array().map(|v| v.clamp(0.0, 1.0).powf(1.0 / 2.2))
}

pub(crate) fn to_rgb(camera: &Camera, image: &[Vec3]) -> Rgb {
    Rgb { width: camera.width, height: camera.height, pixels: image.iter().map(|&c| tone(c).map(to_byte)).collect() }
}

pub(crate) fn write(path: &std::path::Path, bytes: &[u8]) -> Result<(), String> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    write_output(path, bytes)
}
