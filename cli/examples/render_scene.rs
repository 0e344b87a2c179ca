//! A small CPU ray tracer that embeds the 8-lane kernel: a flagstone floor,
//! a sphere of crumpled foil and a sphere of reptile hide, shaded in packets
//! of eight hits, on all cores.
//!
//! ```sh
//! cargo run --release -p worley-cli --example render_scene -- [WIDTH HEIGHT] [out/scene.png]
//! ```

use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;
use worley::perlin::Perlin;
use worley::texture::{bump, Combination, Fractal, Texture};
use worley::{Config, SimdBorder};
use worley_cli::picture::{id_colour, to_byte, write_output, Rgb};

/// What a ray hit.
#[derive(Clone, Copy, PartialEq)]
enum Material {
    Sky,
    Floor,
    Foil,
    Hide,
}

#[derive(Clone, Copy)]
struct Hit {
    material: Material,
    t: f32,
    point: Vec3,
    normal: Vec3,
}

const FOIL: (Vec3, f32) = (Vec3::new(-1.15, 1.0, 3.0), 1.0);
const HIDE: (Vec3, f32) = (Vec3::new(1.2, 1.0, 2.6), 1.0);
const SUN: Vec3 = Vec3::new(-0.45, 0.8, -0.4);

fn sphere(origin: Vec3, dir: Vec3, (centre, radius): (Vec3, f32)) -> Option<f32> {
    let oc = origin - centre;
    let b = oc.dot(dir);
    let c = oc.length_squared() - radius * radius;
    let disc = b * b - c;
    if disc < 0.0 {
        return None;
    }
    let t = -b - disc.sqrt();
    (t > 1e-3).then_some(t)
}

fn trace(origin: Vec3, dir: Vec3) -> Hit {
    let mut hit = Hit { material: Material::Sky, t: f32::INFINITY, point: Vec3::ZERO, normal: Vec3::Y };
    if dir.y < -1e-4 {
        let t = -origin.y / dir.y;
        if t > 1e-3 && t < 60.0 {
            hit = Hit { material: Material::Floor, t, point: origin + t * dir, normal: Vec3::Y };
        }
    }
    for (shape, material) in [(FOIL, Material::Foil), (HIDE, Material::Hide)] {
        if let Some(t) = sphere(origin, dir, shape).filter(|&t| t < hit.t) {
            let point = origin + t * dir;
            hit = Hit { material, t, point, normal: (point - shape.0) / shape.1 };
        }
    }
    hit
}

fn in_shadow(point: Vec3) -> bool {
    let sun = SUN.normalize();
    sphere(point, sun, FOIL).is_some() || sphere(point, sun, HIDE).is_some()
}

fn sky(dir: Vec3) -> Vec3 {
    let t = dir.y.clamp(0.0, 1.0);
    Vec3::new(0.75, 0.82, 0.9).lerp(Vec3::new(0.3, 0.45, 0.75), t)
}

/// The textures, built once and shared by every thread.
struct Textures {
    /// The flagstones: the distance to the border of the sample's cell
    /// (even mortar whatever the spacing of the points, where F2 − F1
    /// widens into wedges between close pairs), its normal for the bevel,
    /// and the cell's ID for the stone's colour.
    stones: SimdBorder<3>,
    /// Fractal F1, five octaves: the foil's crumple.
    crumple: Texture<3, 1>,
    /// Fractal F1, three octaves: the hide's scales.
    scales: Texture<3, 1>,
    stain: Perlin,
}

impl Textures {
    fn new() -> Self {
        let config = Config::default();
        Textures {
            stones: SimdBorder::new(config).expect("a valid configuration"),
            crumple: Texture::new(config, Combination::f(1), Fractal::octaves(5), None).expect("valid"),
            scales: Texture::new(config, Combination::f(1), Fractal { octaves: 3, lacunarity: 2.0, gain: 0.35 }, None)
                .expect("valid"),
            stain: Perlin::new(3),
        }
    }

    /// Shades eight hits: each material's texture is evaluated once for all
    /// eight lanes (lanes of other materials are evaluated and ignored, which
    /// costs less than splitting the packet).
    fn shade8(&self, hits: &[Hit; 8], dirs: &[Vec3; 8]) -> [Vec3; 8] {
        let mut colour = [Vec3::ZERO; 8];
        let has = |m: Material| hits.iter().any(|h| h.material == m);
        let sun = SUN.normalize();
        let light = |p: Vec3, n: Vec3| {
            let direct = if in_shadow(p) { 0.0 } else { n.dot(sun).max(0.0) };
            0.22 + 0.85 * direct
        };
        if has(Material::Floor) {
            // Floor texture coordinates: 2.2 user units per metre.
            let at: [[f64; 3]; 8] = hits.map(|h| [h.point.x as f64 * 2.2, h.point.z as f64 * 2.2, 0.5]);
            let border = self.stones.border8(&at);
            let stains = self.stain.turbulence8(&at.map(|p| [p[0] * 1.5, p[1] * 1.5, 0.3]), 4).to_array();
            let (edge, id) = (border.distance.to_array(), border.feature.to_array());
            let (gx, gy) = (border.normal[0].to_array(), border.normal[1].to_array());
            for i in (0..8).filter(|&i| hits[i].material == Material::Floor) {
                let rim = (edge[i] / 0.12).min(1.0);
                // The stone's edge is rounded down into the mortar: the
                // border distance rises at one per unit along its normal
                // (times 2.2 texture units per metre).
                let g = Vec3::new(gx[i], 0.0, gy[i]) * (1.0 - rim) * 2.0 * 2.2;
                let n = bump(Vec3::Y, g, 0.35);
                let base = if edge[i] < 0.035 {
                    Vec3::splat(0.28)
                } else {
                    Vec3::from(id_colour(id[i])) * 0.8 * (1.0 - 0.5 * stains[i].min(1.0))
                };
                colour[i] = base * light(hits[i].point, n);
            }
        }
        if has(Material::Foil) {
            let at: [[f64; 3]; 8] = hits.map(|h| (h.point * 3.0).to_array().map(f64::from));
            let g = self.crumple.gradient8(&at);
            let grad: [[f32; 8]; 3] = g.gradient.map(|v| v.to_array());
            for i in (0..8).filter(|&i| hits[i].material == Material::Foil) {
                let n = bump(hits[i].normal, Vec3::new(grad[0][i], grad[1][i], grad[2][i]), 0.12);
                let reflected = dirs[i] - 2.0 * dirs[i].dot(n) * n;
                let seen = trace(hits[i].point + 1e-3 * n, reflected);
                let env = match seen.material {
                    Material::Sky => sky(reflected),
                    Material::Floor => Vec3::new(0.35, 0.33, 0.3),
                    _ => Vec3::new(0.45, 0.4, 0.3),
                };
                let half = (sun - dirs[i]).normalize();
                let spec = if in_shadow(hits[i].point) { 0.0 } else { n.dot(half).max(0.0).powf(60.0) };
                colour[i] = Vec3::new(0.85, 0.87, 0.9) * env + Vec3::splat(spec);
            }
        }
        if has(Material::Hide) {
            let at: [[f64; 3]; 8] = hits.map(|h| (h.point * 6.0).to_array().map(f64::from));
            let g = self.scales.gradient8(&at);
            let (value, grad) = (g.value.to_array(), g.gradient.map(|v| v.to_array()));
            for i in (0..8).filter(|&i| hits[i].material == Material::Hide) {
                let n = bump(hits[i].normal, Vec3::new(grad[0][i], grad[1][i], grad[2][i]), 0.05);
                let t = ((value[i] - 0.5) / 0.8).clamp(0.0, 1.0);
                let spot = Vec3::new(0.8, 0.7, 0.3).lerp(Vec3::new(0.08, 0.16, 0.05), t.sqrt());
                colour[i] = spot * light(hits[i].point, n);
            }
        }
        for i in (0..8).filter(|&i| hits[i].material == Material::Sky) {
            colour[i] = sky(dirs[i]);
        }
        colour
    }
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let number = |i: usize, default: usize| -> Result<usize, String> {
        args.get(i)
            .map_or(Ok(default), |s| s.parse().map_err(|_| format!("{s:?} is not a size: use WIDTH HEIGHT [PATH]")))
    };
    let (width, height) = (number(0, 1280)?, number(1, 720)?);
    let path = args.get(2).cloned().unwrap_or_else(|| "out/scene.png".into());
    if width == 0 || height == 0 || width > 16384 || height > 16384 {
        return Err("use a size from 1x1 to 16384x16384".into());
    }
    let started = Instant::now();
    let textures = Textures::new();
    let eye = Vec3::new(0.0, 1.45, -1.4);
    let forward = (Vec3::new(0.0, 0.8, 2.8) - eye).normalize();
    let right = forward.cross(Vec3::Y).normalize() * -1.0;
    let up = right.cross(forward) * -1.0;
    let fov = 0.75f32;
    let mut pixels = vec![[0u8; 3]; width * height];
    pixels.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        for (x0, packet) in row.chunks_mut(8).enumerate().map(|(c, p)| (c * 8, p)) {
            let dirs: [Vec3; 8] = std::array::from_fn(|i| {
                let x = (x0 + i.min(packet.len() - 1)) as f32;
                let u = (2.0 * (x + 0.5) / width as f32 - 1.0) * fov * width as f32 / height as f32;
                let v = (1.0 - 2.0 * (y as f32 + 0.5) / height as f32) * fov;
                (forward + u * right + v * up).normalize()
            });
            let hits = dirs.map(|d| trace(eye, d));
            let colour = textures.shade8(&hits, &dirs);
            for (p, c) in packet.iter_mut().zip(colour) {
                // A simple tone curve and gamma 2.2.
                let c = c / (c + Vec3::ONE) * 1.5;
                *p = c.to_array().map(|v| to_byte(v.max(0.0).powf(1.0 / 2.2)));
            }
        }
    });
    let elapsed = started.elapsed().as_secs_f64();
    let image = Rgb { width, height, pixels };
    if let Some(dir) = std::path::Path::new(&path).parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    write_output(std::path::Path::new(&path), &image.to_png()?)?;
    println!(
        "rendered {width}x{height} in {elapsed:.2} s on {} threads ({:.2} M pixels/s); wrote {path}",
        rayon::current_num_threads(),
        (width * height) as f64 / elapsed / 1e6
    );
    Ok(())
}
