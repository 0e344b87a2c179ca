//! A small CPU ray tracer that embeds the 8-lane kernel: a flagstone floor,
//! a sphere of crumpled foil and a sphere of reptile hide, shaded in packets
//! of eight hits, on all cores.
//!
//! Each pixel's footprint on the surface it hits comes from ray
//! differentials, and the textures stand for that footprint
//! (`worley::filter`): fine octaves, stone colours, mortar lines and stains
//! fade towards their means where a pixel covers many cells, so the
//! horizon shows no moiré and costs less.
//!
//! ```sh
//! cargo run --release -p worley-cli --example render_scene -- [WIDTH HEIGHT] [PATH] [--point] [--spp N] [--cover] [--split]
//! cargo run --release -p worley-cli --example render_scene -- --campaign [WIDTH HEIGHT] [DIR]
//! ```
//!
//! `--point` point-samples the textures (one sample per pixel unless
//! `--spp` asks for more, on a stratified jittered grid); `--cover` gives
//! wide footprints the colours of the stones they cover, `--split` shades
//! the floor at four points of mid-sized footprints (both measured in the
//! campaign); `--campaign` renders the scene and a plane receding to the
//! horizon every way (point sampling, filtered with each option, 4, 16
//! and 64 samples per pixel) against a
//! 256-samples-per-pixel reference, prints the table of error against time
//! per frame, and writes the plot and the pictures into DIR (default
//! `out/footprint`).

use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;
use worley::filter::{cell_cover8, BlendCurve};
use worley::perlin::Perlin;
use worley::texture::{bump, Combination, Fractal, Texture};
use worley::{Config, Outputs, Simd, SimdBorder};
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
/// Floor texture units per metre.
const FLOOR_SCALE: f32 = 2.2;
/// Floor footprints from this width (texture units) ramp up to four
/// texture sub-samples with [`Shading::Filtered`]'s `split` (over one
/// octave of width) ...
const SPLIT_FROM: f32 = 0.0625;
/// ... and ramp back down to one over the octave below this width, where
/// the blend alone is close to the footprint's mean.
const SPLIT_TO: f32 = 32.0;
/// Mortar where the border distance is below this (texture units).
const MORTAR: f32 = 0.035;
/// Footprints wider than this see the colours of the neighbouring stones
/// ([`cell_cover8`]); narrower ones see them only under the mortar, which
/// is at least this wide.
const COVER_FROM: f32 = 2.0 * MORTAR;
/// The stone's edge is rounded over this distance from its border.
const BEVEL: f32 = 0.12;

/// What the rays can meet: the floor up to `far`, and the two spheres or
/// none.
#[derive(Clone, Copy)]
struct World {
    spheres: bool,
    far: f32,
}

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

impl World {
    fn trace(&self, origin: Vec3, dir: Vec3) -> Hit {
        let mut hit = Hit { material: Material::Sky, t: f32::INFINITY, point: Vec3::ZERO, normal: Vec3::Y };
        if dir.y < -1e-4 {
            let t = -origin.y / dir.y;
            if t > 1e-3 && t < self.far {
                hit = Hit { material: Material::Floor, t, point: origin + t * dir, normal: Vec3::Y };
            }
        }
        if self.spheres {
            for (shape, material) in [(FOIL, Material::Foil), (HIDE, Material::Hide)] {
                if let Some(t) = sphere(origin, dir, shape).filter(|&t| t < hit.t) {
                    let point = origin + t * dir;
                    hit = Hit { material, t, point, normal: (point - shape.0) / shape.1 };
                }
            }
        }
        hit
    }

    fn in_shadow(&self, point: Vec3) -> bool {
        let sun = SUN.normalize();
        self.spheres && (sphere(point, sun, FOIL).is_some() || sphere(point, sun, HIDE).is_some())
    }
}

fn sky(dir: Vec3) -> Vec3 {
    let t = dir.y.clamp(0.0, 1.0);
    Vec3::new(0.75, 0.82, 0.9).lerp(Vec3::new(0.3, 0.45, 0.75), t)
}

/// How a pixel's footprint becomes one width.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Width {
    /// The side of the square with the footprint's area.
    Area,
    /// The footprint's longer axis.
    Major,
}

/// A pixel's footprint on the surface its ray hits (world units): how the
/// hit moves for one pixel along x and along y, and one width for it.
#[derive(Clone, Copy, Default)]
struct Footprint {
    dx: Vec3,
    dy: Vec3,
    width: f32,
}

impl Footprint {
    /// The footprint's extent along a unit direction of the surface: a
    /// straight edge across that direction is covered over this distance.
    fn across(&self, direction: Vec3) -> f32 {
        self.dx.dot(direction).abs() + self.dy.dot(direction).abs()
    }
}

/// How the textures are sampled.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Shading {
    /// At the hit point.
    Point,
    /// Standing for the pixel's footprint; with `cover`, a wide footprint
    /// sees the colours of the stones it covers ([`cell_cover8`]), else
    /// only its own stone's, blended towards the mean stone; with `split`,
    /// the floor's texture is evaluated at four points of footprints from
    /// [`SPLIT_FROM`] to [`SPLIT_TO`], each standing for a quarter of it.
    Filtered { width: Width, cover: bool, split: bool },
}

/// The textures, built once and shared by every thread.
struct Textures {
    /// The flagstones: the distance to the border of the sample's cell
    /// (even mortar whatever the spacing of the points), its normal for the
    /// bevel, and the cell's ID for the stone's colour.
    stones: SimdBorder<3>,
    /// F1..F4 with IDs and deltas: which stones a wide footprint covers.
    neighbours: Simd<3, 4>,
    /// Fractal F1, five octaves: the foil's crumple.
    crumple: Texture<3, 1>,
    /// Fractal F1, three octaves: the hide's scales.
    scales: Texture<3, 1>,
    stain: Perlin,
    /// Blend curves of the floor's fields, in floor texture units: the
    /// stone's identity, the mortar (border distance below [`MORTAR`]) and
    /// the stains.
    identity: BlendCurve,
    mortar: BlendCurve,
    stains: BlendCurve,
    /// The bevel's height, 1 − min(border / [`BEVEL`], 1), whose curve
    /// fades the bevel's bump.
    bevel: BlendCurve,
    /// The mean stone colour (each cell's colour weighs by its area).
    stone_mean: Vec3,
}

impl Textures {
    fn new() -> Self {
        let config = Config::default();
        let stones = SimdBorder::new(config).expect("a valid configuration");
        let ids = Simd::<3, 1>::new(config, Outputs::Ids).expect("a valid configuration");
        let stain = Perlin::new(3);
        let identity = BlendCurve::measure_identity(|p: &[[f64; 3]; 8]| ids.evaluate8(p).id[0].to_array(), 1);
        let mortar = BlendCurve::measure(
            |p: &[[f64; 3]; 8]| stones.border8(p).distance.to_array().map(|b| f32::from(u8::from(b < MORTAR))),
            2,
        );
        let stains = BlendCurve::measure(|p: &[[f64; 3]; 8]| stain.turbulence8(&stain_at(p), 4).to_array(), 3);
        let bevel = BlendCurve::measure(
            |p: &[[f64; 3]; 8]| stones.border8(p).distance.to_array().map(|b| 1.0 - (b / BEVEL).min(1.0)),
            4,
        );
        let samples = 1 << 14;
        let mut stone_mean = Vec3::ZERO;
        for i in 0..samples / 8 {
            let p: [[f64; 3]; 8] = std::array::from_fn(|k| {
                std::array::from_fn(|a| 2000.0 * worley::math::uniform(4, ((i * 8 + k) * 3 + a) as u64) - 1000.0)
            });
            for id in ids.evaluate8(&p).id[0].to_array() {
                stone_mean += Vec3::from(id_colour(id));
            }
        }
        let crumple = Texture::new(config, Combination::f(1), Fractal::octaves(5), None).expect("valid");
        let scales = Texture::new(config, Combination::f(1), Fractal { octaves: 3, lacunarity: 2.0, gain: 0.35 }, None)
            .expect("valid");
        // Measured now rather than inside the first frame.
        let _ = (crumple.blend_curve(), scales.blend_curve());
        Textures {
            stones,
            neighbours: Simd::new(Config { order: 4, ..config }, Outputs::IdsAndDeltas).expect("a valid configuration"),
            crumple,
            scales,
            stain,
            identity,
            mortar,
            stains,
            bevel,
            stone_mean: stone_mean / samples as f32,
        }
    }

    /// Shades eight hits with their footprints (world units): each
    /// material's texture is evaluated once for all eight lanes (lanes of
    /// other materials are evaluated and ignored, which costs less than
    /// splitting the packet).
    fn shade8(
        &self,
        world: &World,
        hits: &[Hit; 8],
        dirs: &[Vec3; 8],
        footprints: &[Footprint; 8],
        shading: Shading,
    ) -> [Vec3; 8] {
        let filtered = shading != Shading::Point;
        let mut colour = [Vec3::ZERO; 8];
        let has = |m: Material| hits.iter().any(|h| h.material == m);
        let sun = SUN.normalize();
        let light = |p: Vec3, n: Vec3| {
            let direct = if world.in_shadow(p) { 0.0 } else { n.dot(sun).max(0.0) };
            0.22 + 0.85 * direct
        };
        // A texture's footprint: the world width times its scale, where
        // filtered; a point otherwise.
        let footprint = |scale: f32| footprints.map(|f| if filtered { f.width * scale } else { 0.0 });
        if has(Material::Floor) {
            let scale = f64::from(FLOOR_SCALE);
            let at: [[f64; 3]; 8] = hits.map(|h| [h.point.x as f64 * scale, h.point.z as f64 * scale, 0.5]);
            let w = footprint(FLOOR_SCALE);
            let floor = |i: usize| hits[i].material == Material::Floor;
            let (a_id, a_mortar) = (self.identity.weight8(w), self.mortar.weight8(w));
            let a_stain = self.stains.weight8(w.map(|v| v * 1.5));
            let a_bevel = self.bevel.weight8(w);
            // Where no floor lane resolves the stones, their mean stands
            // for them without evaluation.
            let border = (0..8)
                .any(|i| floor(i) && (a_id[i] > 0.0 || a_mortar[i] > 0.0 || a_bevel[i] > 0.0))
                .then(|| self.stones.border8(&at));
            // Footprints wide enough to show the neighbouring stones.
            let cover = matches!(shading, Shading::Filtered { cover: true, .. });
            let shares = (cover && (0..8).any(|i| floor(i) && a_id[i] > 0.0 && w[i] > COVER_FROM)).then(|| {
                let f = self.neighbours.evaluate8(&at);
                (cell_cover8(&f, w), f.id.map(|v| v.to_array()))
            });
            let stains = (0..8)
                .any(|i| floor(i) && a_stain[i] > 0.0)
                .then(|| self.stain.turbulence8(&stain_at(&at), 4).to_array());
            for i in (0..8).filter(|&i| floor(i)) {
                let (edge, id, normal) = match &border {
                    Some(b) => (
                        b.distance.to_array()[i],
                        b.feature.to_array()[i],
                        [b.normal[0].to_array()[i], b.normal[1].to_array()[i]],
                    ),
                    None => (f32::INFINITY, worley::INVALID_ID, [0.0; 2]),
                };
                // The footprint's extent across the border (texture units):
                // the mortar's edges and the bevel's ridge are straight lines
                // at the pixel's scale.
                let across = FLOOR_SCALE * footprints[i].across(Vec3::new(normal[0], 0.0, normal[1]));
                // The mortar's cover of the footprint: a straight edge under
                // a box filter (the border distance rises at one per unit),
                // exact while the footprint stays in the sample's cell and
                // its neighbour's, so it blends towards the mortar's share of
                // the floor as the identity's weight falls.
                let mortar = if filtered {
                    let cover = if across > 0.0 {
                        ((MORTAR - edge) / across + 0.5).clamp(0.0, 1.0)
                    } else {
                        f32::from(u8::from(edge < MORTAR))
                    };
                    blend(cover, a_id[i], self.mortar.mean())
                } else {
                    f32::from(u8::from(edge < MORTAR))
                };
                // The stones the footprint covers, each by its share (from
                // COVER_FROM on, reached over one more COVER_FROM so the
                // colour is continuous in the footprint), blended towards the
                // mean stone as the identity's weight falls.
                let stone = if filtered && a_id[i] < 1.0 {
                    let own = if a_id[i] > 0.0 { Vec3::from(id_colour(id)) } else { Vec3::ZERO };
                    let seen = match &shares {
                        Some((share, ids)) if w[i] > COVER_FROM => {
                            let covered: Vec3 = (0..4).map(|k| Vec3::from(id_colour(ids[k][i])) * share[k][i]).sum();
                            let t = ((w[i] - COVER_FROM) / COVER_FROM).min(1.0);
                            own * (1.0 - t) + covered * t
                        }
                        _ => own,
                    };
                    seen * a_id[i] + self.stone_mean * (1.0 - a_id[i])
                } else {
                    Vec3::from(id_colour(id))
                };
                let stain = match stains {
                    Some(s) if filtered => blend(s[i], a_stain[i], self.stains.mean()),
                    Some(s) => s[i],
                    None => self.stains.mean(),
                };
                // The stone's edge is rounded down into the mortar: the
                // border distance rises at one per unit along its normal
                // (times FLOOR_SCALE); the bevel fades with
                // its own weight.
                let rim = (edge / BEVEL).min(1.0);
                let fade = if filtered { a_bevel[i] } else { 1.0 };
                let g = Vec3::new(normal[0], 0.0, normal[1]) * (1.0 - rim) * 2.0 * FLOOR_SCALE * fade;
                let base = Vec3::splat(0.28) * mortar + stone * 0.8 * (1.0 - 0.5 * stain.min(1.0)) * (1.0 - mortar);
                // The slope flips across the border's ridge: a footprint
                // straddling it sees this side's flank over its share and the
                // neighbour's, mirrored, over the rest.
                let own = if filtered && across > 0.0 { (edge / across + 0.5).min(1.0) } else { 1.0 };
                let lit = light(hits[i].point, bump(Vec3::Y, g, 0.35));
                let lit = if own < 1.0 {
                    own * lit + (1.0 - own) * light(hits[i].point, bump(Vec3::Y, -g, 0.35))
                } else {
                    lit
                };
                colour[i] = base * lit;
            }
        }
        if has(Material::Foil) {
            let at: [[f64; 3]; 8] = hits.map(|h| (h.point * 3.0).to_array().map(f64::from));
            let g = self.crumple.filtered_gradient8(&at, footprint(3.0));
            let grad: [[f32; 8]; 3] = g.gradient.map(|v| v.to_array());
            for i in (0..8).filter(|&i| hits[i].material == Material::Foil) {
                let n = bump(hits[i].normal, Vec3::new(grad[0][i], grad[1][i], grad[2][i]), 0.12);
                let reflected = dirs[i] - 2.0 * dirs[i].dot(n) * n;
                let seen = world.trace(hits[i].point + 1e-3 * n, reflected);
                let env = match seen.material {
                    Material::Sky => sky(reflected),
                    Material::Floor => Vec3::new(0.35, 0.33, 0.3),
                    _ => Vec3::new(0.45, 0.4, 0.3),
                };
                let half = (sun - dirs[i]).normalize();
                let spec = if world.in_shadow(hits[i].point) { 0.0 } else { n.dot(half).max(0.0).powf(60.0) };
                colour[i] = Vec3::new(0.85, 0.87, 0.9) * env + Vec3::splat(spec);
            }
        }
        if has(Material::Hide) {
            let at: [[f64; 3]; 8] = hits.map(|h| (h.point * 6.0).to_array().map(f64::from));
            let g = self.scales.filtered_gradient8(&at, footprint(6.0));
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

    /// The floor's lanes whose footprint is between [`SPLIT_FROM`] and
    /// [`SPLIT_TO`] (texture units) take, for a share that ramps from 0 to
    /// 1 over an octave of width at either end, the mean of four shadings
    /// at the centres of the footprint's quarters, each standing for its
    /// quarter: the footprint's average estimated from four samples rather
    /// than blended from one.
    fn split_floor(
        &self,
        world: &World,
        hits: &[Hit; 8],
        dirs: &[Vec3; 8],
        footprints: &[Footprint; 8],
        shading: Shading,
        colour: &mut [Vec3; 8],
    ) {
        let share: [f32; 8] = std::array::from_fn(|i| {
            if hits[i].material != Material::Floor {
                return 0.0;
            }
            let w = footprints[i].width * FLOOR_SCALE;
            let up = (w / SPLIT_FROM).log2().clamp(0.0, 1.0);
            let down = (SPLIT_TO / w).log2().clamp(0.0, 1.0);
            if up.is_nan() || down.is_nan() {
                0.0
            } else {
                up.min(down)
            }
        });
        if share.iter().all(|&s| s == 0.0) {
            return;
        }
        let quarter = footprints.map(|f| Footprint { dx: f.dx * 0.5, dy: f.dy * 0.5, width: f.width * 0.5 });
        let mut mean = [Vec3::ZERO; 8];
        for (a, b) in [(-0.25, -0.25), (0.25, -0.25), (-0.25, 0.25), (0.25, 0.25)] {
            let moved: [Hit; 8] = std::array::from_fn(|i| {
                let mut h = hits[i];
                if share[i] > 0.0 {
                    h.point += footprints[i].dx * a + footprints[i].dy * b;
                }
                h
            });
            let c = self.shade8(world, &moved, dirs, &quarter, shading);
            for (m, c) in mean.iter_mut().zip(c) {
                *m += c * 0.25;
            }
        }
        for ((c, m), s) in colour.iter_mut().zip(mean).zip(share) {
            if s > 0.0 {
                *c = *c * (1.0 - s) + m * s;
            }
        }
    }
}

/// The stains' coordinates from the floor's.
fn stain_at(p: &[[f64; 3]; 8]) -> [[f64; 3]; 8] {
    p.map(|q| [q[0] * 1.5, q[1] * 1.5, 0.3])
}

/// a·v + (1 − a)·mean, and v itself at a = 1.
fn blend(v: f32, a: f32, mean: f32) -> f32 {
    if a == 1.0 {
        v
    } else if a == 0.0 {
        mean
    } else {
        a * v + (1.0 - a) * mean
    }
}

/// A pinhole camera.
#[derive(Clone, Copy)]
struct Camera {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    /// Half the vertical field of view's tangent.
    fov: f32,
    width: usize,
    height: usize,
}

impl Camera {
    fn looking(eye: Vec3, at: Vec3, width: usize, height: usize) -> Self {
        let forward = (at - eye).normalize();
        let right = forward.cross(Vec3::Y).normalize() * -1.0;
        let up = right.cross(forward) * -1.0;
        Camera { eye, forward, right, up, fov: 0.75, width, height }
    }

    /// The unnormalised ray direction through image position (x, y) in
    /// pixels: forward + u·right + v·up.
    fn ray(&self, x: f32, y: f32) -> Vec3 {
        let (w, h) = (self.width as f32, self.height as f32);
        let u = (2.0 * x / w - 1.0) * self.fov * w / h;
        let v = (1.0 - 2.0 * y / h) * self.fov;
        self.forward + u * self.right + v * self.up
    }

    /// The footprint's width on the surface a ray hits (ray differentials:
    /// how the hit moves on the surface's tangent plane for one pixel along
    /// x and along y).
    fn footprint(&self, ray: Vec3, hit: &Hit, width: Width) -> Footprint {
        if hit.material == Material::Sky {
            return Footprint::default();
        }
        // P = eye + s·D on the plane through the hit with the hit's normal;
        // ∂P/∂u = s·(R − (R·n)/(D·n)·D), and one pixel is du = 2·fov/height.
        let s = hit.t / ray.length();
        let n = hit.normal;
        let dn = ray.dot(n);
        let pixel = 2.0 * self.fov / self.height as f32;
        let along = |r: Vec3| s * (r - r.dot(n) / dn * ray) * pixel;
        let (dx, dy) = (along(self.right), along(self.up));
        let w = match width {
            Width::Area => dx.cross(dy).length().sqrt(),
            Width::Major => dx.length().max(dy.length()),
        };
        if w.is_finite() {
            Footprint { dx, dy, width: w }
        } else {
            Footprint::default()
        }
    }
}

/// Renders linear colours: `spp` samples per pixel on a stratified jittered
/// grid (a square number), or the pixel centre for one.
fn render(textures: &Textures, world: &World, camera: &Camera, shading: Shading, spp: usize) -> Vec<Vec3> {
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
fn tone(c: Vec3) -> [f32; 3] {
    let c = c / (c + Vec3::ONE) * 1.5;
    c.to_array().map(|v| v.clamp(0.0, 1.0).powf(1.0 / 2.2))
}

fn to_rgb(camera: &Camera, image: &[Vec3]) -> Rgb {
    Rgb { width: camera.width, height: camera.height, pixels: image.iter().map(|&c| tone(c).map(to_byte)).collect() }
}

fn write(path: &std::path::Path, bytes: &[u8]) -> Result<(), String> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    write_output(path, bytes)
}

/// The scene's camera, and the plane's: low over the floor, the horizon
/// across the middle of the frame.
fn views(width: usize, height: usize) -> [(&'static str, World, Camera); 2] {
    [
        (
            "scene",
            World { spheres: true, far: 60.0 },
            Camera::looking(Vec3::new(0.0, 1.45, -1.4), Vec3::new(0.0, 0.8, 2.8), width, height),
        ),
        (
            "plane",
            World { spheres: false, far: 400.0 },
            Camera::looking(Vec3::new(0.0, 0.9, 0.0), Vec3::new(0.0, 0.35, 6.0), width, height),
        ),
    ]
}

fn main() -> Result<(), String> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut flag = |name: &str| args.iter().position(|a| a == name).map(|i| args.remove(i)).is_some();
    let point = flag("--point");
    let (cover, split) = (flag("--cover"), flag("--split"));
    let campaign = flag("--campaign");
    let spp = match args.iter().position(|a| a == "--spp") {
        Some(i) => {
            let n = args.get(i + 1).and_then(|s| s.parse::<usize>().ok()).filter(|&n| {
                let side = (n as f64).sqrt().round() as usize;
                (1..=1024).contains(&n) && side * side == n
            });
            args.drain(i..(i + 2).min(args.len()));
            n.ok_or("--spp takes a square number of samples per pixel from 1 to 1024")?
        }
        None => 1,
    };
    let number = |i: usize, default: usize| -> Result<usize, String> {
        args.get(i)
            .map_or(Ok(default), |s| s.parse().map_err(|_| format!("{s:?} is not a size: use WIDTH HEIGHT [PATH]")))
    };
    let (default_w, default_h) = if campaign { (640, 360) } else { (1280, 720) };
    let (width, height) = (number(0, default_w)?, number(1, default_h)?);
    if width == 0 || height == 0 || width > 16384 || height > 16384 {
        return Err("use a size from 1x1 to 16384x16384".into());
    }
    if campaign {
        let dir = args.get(2).cloned().unwrap_or_else(|| "out/footprint".into());
        return run_campaign(width, height, std::path::Path::new(&dir));
    }
    let path = args.get(2).cloned().unwrap_or_else(|| "out/scene.png".into());
    let started = Instant::now();
    let textures = Textures::new();
    let built = started.elapsed().as_secs_f64();
    let [(_, world, camera), _] = views(width, height);
    let shading =
        if point || spp > 1 { Shading::Point } else { Shading::Filtered { width: Width::Area, cover, split } };
    let image = render(&textures, &world, &camera, shading, spp);
    let elapsed = started.elapsed().as_secs_f64();
    write(std::path::Path::new(&path), &to_rgb(&camera, &image).to_png()?)?;
    println!(
        "rendered {width}x{height} ({}, {spp} sample(s) per pixel) in {elapsed:.2} s (textures built in {built:.2} s) \
         on {} threads ({:.2} M pixels/s); wrote {path}",
        if shading == Shading::Point { "point-sampled textures" } else { "filtered textures" },
        rayon::current_num_threads(),
        (width * height) as f64 / (elapsed - built) / 1e6
    );
    Ok(())
}

/// One way of rendering in the campaign.
struct Method {
    name: &'static str,
    /// The plot's label, and where it sits from the point (pixels), so the
    /// labels of nearby points do not overlap.
    label: (&'static str, i32, i32),
    shading: Shading,
    spp: usize,
}

/// A point of the plot: the view, the method's label, milliseconds per
/// frame and RMS error.
type Plotted = (&'static str, (&'static str, i32, i32), f64, f64);

/// What a method's frame measured.
struct Measured {
    seconds: f64,
    rms: f64,
    floor_rms: f64,
    high: f64,
}

/// Error of a frame against the reference, in tone-mapped [0, 1] values:
/// RMS over every pixel and channel, over the pixels whose every reference
/// sample met the floor (texture alone, no edges of geometry), and the
/// RMS of the error's high frequencies (the error minus its 5 × 5 box
/// average: moiré and salt-and-pepper noise, not a smooth bias).
fn errors(image: &[Vec3], reference: &[Vec3], floor_only: &[bool], width: usize, height: usize) -> (f64, f64, f64) {
    let diff: Vec<[f64; 3]> = image
        .iter()
        .zip(reference)
        .map(|(a, b)| {
            let (a, b) = (tone(*a), tone(*b));
            std::array::from_fn(|c| f64::from(a[c] - b[c]))
        })
        .collect();
    let sq = |d: &[f64; 3]| d.iter().map(|v| v * v).sum::<f64>() / 3.0;
    let rms = (diff.iter().map(sq).sum::<f64>() / diff.len() as f64).sqrt();
    let (mut fs, mut fc) = (0.0, 0usize);
    for (d, &f) in diff.iter().zip(floor_only) {
        if f {
            fs += sq(d);
            fc += 1;
        }
    }
    let mut high = 0.0;
    for y in 0..height {
        for x in 0..width {
            let mut mean = [0.0; 3];
            let mut count = 0.0;
            for yy in y.saturating_sub(2)..(y + 3).min(height) {
                for xx in x.saturating_sub(2)..(x + 3).min(width) {
                    for c in 0..3 {
                        mean[c] += diff[yy * width + xx][c];
                    }
                    count += 1.0;
                }
            }
            let d = diff[y * width + x];
            high += (0..3).map(|c| (d[c] - mean[c] / count).powi(2)).sum::<f64>() / 3.0;
        }
    }
    (rms, (fs / fc.max(1) as f64).sqrt(), (high / (width * height) as f64).sqrt())
}

fn run_campaign(width: usize, height: usize, dir: &std::path::Path) -> Result<(), String> {
    let started = Instant::now();
    let textures = Textures::new();
    println!(
        "textures and blend curves built in {:.2} s; {width}x{height}, {} threads",
        started.elapsed().as_secs_f64(),
        rayon::current_num_threads()
    );
    // The weights the floor's fields and F1 (the crumple's first octave) get
    // at a sixteenth of a unit and at one unit, and where they reach 0.
    for (name, curve) in [
        ("stone identity", &textures.identity),
        ("mortar", &textures.mortar),
        ("bevel", &textures.bevel),
        ("stains", &textures.stains),
        ("F1", textures.crumple.blend_curve()),
    ] {
        println!(
            "blend curve {name}: weight {:.3} at 1/16, {:.3} at 1, 0 from {:.3} (texture units)",
            curve.weight(0.0625),
            curve.weight(1.0),
            curve.cutoff()
        );
    }
    let methods = [
        Method { name: "(a) point sampling, 1 spp", label: ("a", 8, -5), shading: Shading::Point, spp: 1 },
        Method {
            name: "(b) filtered, 1 spp (area width)",
            label: ("b", -16, -5),
            shading: Shading::Filtered { width: Width::Area, cover: false, split: false },
            spp: 1,
        },
        Method {
            name: "(b) filtered, 1 spp (area width and cell cover)",
            label: ("b, cover", 8, 2),
            shading: Shading::Filtered { width: Width::Area, cover: true, split: false },
            spp: 1,
        },
        Method {
            name: "(b) filtered, 1 spp (area width and 4 floor sub-samples)",
            label: ("b, 4 floor sub-samples", 8, -5),
            shading: Shading::Filtered { width: Width::Area, cover: false, split: true },
            spp: 1,
        },
        Method {
            name: "(b') filtered, 1 spp (major-axis width)",
            label: ("b'", -4, -18),
            shading: Shading::Filtered { width: Width::Major, cover: false, split: false },
            spp: 1,
        },
        Method { name: "(c) point sampling, 4 spp", label: ("4 spp", 8, -5), shading: Shading::Point, spp: 4 },
        Method { name: "(c) point sampling, 16 spp", label: ("16 spp", 8, -5), shading: Shading::Point, spp: 16 },
        Method { name: "(c) point sampling, 64 spp", label: ("64 spp", 8, -5), shading: Shading::Point, spp: 64 },
    ];
    let mut table = String::from(
        "| view | method | ms per frame | RMS error | RMS error, floor pixels | high-frequency RMS error |\n|---|---|---|---|---|---|\n",
    );
    let mut plotted: Vec<Plotted> = Vec::new();
    for (view, world, camera) in views(width, height) {
        let t = Instant::now();
        let reference = render(&textures, &world, &camera, Shading::Point, 256);
        let reference_ms = t.elapsed().as_secs_f64() * 1e3;
        // Pixels whose reference samples all met the floor: the reference at
        // 256 samples, with the floor's colour replaced by a flag.
        let floor_only: Vec<bool> = floor_pixels(&world, &camera);
        write(&dir.join(format!("{view}_reference.png")), &to_rgb(&camera, &reference).to_png()?)?;
        // Every method renders once; then the cheap ones (up to 4 spp) four
        // more times, round-robin, so a slow spell of the machine falls on
        // all of them alike. A frame's time is the median of its runs.
        let mut images: Vec<Vec<Vec3>> = Vec::new();
        let mut times: Vec<Vec<f64>> = vec![Vec::new(); methods.len()];
        for round in 0..5 {
            for (i, m) in methods.iter().enumerate() {
                if round > 0 && m.spp > 4 {
                    continue;
                }
                let t = Instant::now();
                let image = render(&textures, &world, &camera, m.shading, m.spp);
                times[i].push(t.elapsed().as_secs_f64());
                if round == 0 {
                    images.push(image);
                }
            }
        }
        for ((m, image), times) in methods.iter().zip(&images).zip(&mut times) {
            times.sort_by(f64::total_cmp);
            let seconds = times[times.len() / 2];
            let (rms, floor_rms, high) = errors(image, &reference, &floor_only, width, height);
            let r = Measured { seconds, rms, floor_rms, high };
            table += &format!(
                "| {view} | {} | {:.1} | {:.4} | {:.4} | {:.4} |\n",
                m.name,
                r.seconds * 1e3,
                r.rms,
                r.floor_rms,
                r.high
            );
            plotted.push((view, m.label, r.seconds * 1e3, r.rms));
            if m.spp == 1 {
                let tag = match m.shading {
                    Shading::Point => "point",
                    Shading::Filtered { width: Width::Major, .. } => "filtered_major",
                    Shading::Filtered { cover: true, .. } => "filtered_cover",
                    Shading::Filtered { split: true, .. } => "filtered_split",
                    Shading::Filtered { .. } => "filtered",
                };
                write(&dir.join(format!("{view}_{tag}.png")), &to_rgb(&camera, image).to_png()?)?;
                // The error, eight times brighter.
                let error = Rgb {
                    width,
                    height,
                    pixels: image
                        .iter()
                        .zip(&reference)
                        .map(|(a, b)| {
                            let (a, b) = (tone(*a), tone(*b));
                            std::array::from_fn(|c| to_byte(8.0 * (a[c] - b[c]).abs()))
                        })
                        .collect(),
                };
                write(&dir.join(format!("{view}_{tag}_error.png")), &error.to_png()?)?;
            }
        }
        table += &format!("| {view} | reference, point sampling, 256 spp | {reference_ms:.1} | 0 | 0 | 0 |\n");
    }
    println!("{table}");
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    write(&dir.join("table.md"), table.as_bytes())?;
    write(&dir.join("error_against_time.svg"), plot(&plotted)?.as_bytes())?;
    println!("wrote the pictures, table.md and error_against_time.svg into {}", dir.display());
    Ok(())
}

/// Per pixel, whether all 256 reference samples meet the floor.
fn floor_pixels(world: &World, camera: &Camera) -> Vec<bool> {
    let side = 16;
    (0..camera.width * camera.height)
        .into_par_iter()
        .map(|p| {
            let (x, y) = (p % camera.width, p / camera.width);
            (0..side * side).all(|k| {
                let (sx, sy) = ((k % side) as f32 + 0.5, (k / side) as f32 + 0.5);
                let d = camera.ray(x as f32 + sx / side as f32, y as f32 + sy / side as f32).normalize();
                world.trace(camera.eye, d).material == Material::Floor
            })
        })
        .collect()
}

/// RMS error against milliseconds per frame, log-log, one series per view.
fn plot(points: &[Plotted]) -> Result<String, String> {
    use plotters::prelude::*;
    let fail = |e: &dyn std::fmt::Display| format!("cannot draw the plot: {e}");
    let (x_lo, x_hi) = points.iter().fold((f64::MAX, 0f64), |(l, h), p| (l.min(p.2), h.max(p.2)));
    let (y_lo, y_hi) = points.iter().fold((f64::MAX, 0f64), |(l, h), p| (l.min(p.3), h.max(p.3)));
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (820, 520)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| fail(&e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption("Error against the 256-spp reference, by time per frame", ("sans-serif", 16))
            .margin(14)
            .x_label_area_size(44)
            .y_label_area_size(60)
            .build_cartesian_2d((x_lo / 1.5..x_hi * 1.5).log_scale(), (y_lo / 1.5..y_hi * 1.5).log_scale())
            .map_err(|e| fail(&e))?;
        chart
            .configure_mesh()
            .y_label_formatter(&|v| format!("{v:.3}"))
            .x_label_formatter(&|v| format!("{v:.0}"))
            .x_desc("milliseconds per frame")
            .y_desc("RMS error (tone-mapped, 0..1)")
            .draw()
            .map_err(|e| fail(&e))?;
        for (view, colour) in [("scene", RGBColor(36, 113, 163)), ("plane", RGBColor(192, 57, 43))] {
            let series: Vec<_> = points.iter().filter(|p| p.0 == view).collect();
            chart
                .draw_series(series.iter().map(|p| Circle::new((p.2, p.3), 5, colour.filled())))
                .map_err(|e| fail(&e))?
                .label(view)
                .legend(move |(x, y)| Circle::new((x + 8, y), 5, colour.filled()));
            chart
                .draw_series(series.iter().map(|p| {
                    let (label, dx, dy) = p.1;
                    EmptyElement::at((p.2, p.3))
                        + Text::new(label.to_string(), (dx, dy), ("sans-serif", 11).into_font())
                }))
                .map_err(|e| fail(&e))?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE)
            .border_style(BLACK)
            .draw()
            .map_err(|e| fail(&e))?;
        root.present().map_err(|e| fail(&e))?;
    }
    Ok(svg)
}
