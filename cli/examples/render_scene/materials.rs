//! The materials: flagstones with mortar and stains, crumpled foil and
//! reptile hide, each textured for a pixel's footprint or point-sampled.

use crate::scene::{sky, Footprint, Hit, Material, Width, World, SUN};
use glam::Vec3;
use worley::filter::{cell_cover8, BlendCurve};
use worley::perlin::Perlin;
use worley::texture::{bump, Combination, Fractal, Texture};
use worley::{Config, Outputs, Simd, SimdBorder};
use worley_cli::picture::id_colour;

/// Floor texture units per metre.
pub(crate) const FLOOR_SCALE: f32 = 2.2;
/// Floor footprints from this width (texture units) ramp up to four
/// texture sub-samples with [`Shading::Filtered`]'s `split` (over one
/// octave of width) ...
pub(crate) const SPLIT_FROM: f32 = 0.0625;
/// ... and ramp back down to one over the octave below this width, where
/// the blend alone is close to the footprint's mean.
pub(crate) const SPLIT_TO: f32 = 32.0;
/// Mortar where the border distance is below this (texture units).
pub(crate) const MORTAR: f32 = 0.035;
/// Footprints wider than this see the colours of the neighbouring stones
/// ([`cell_cover8`]); narrower ones see them only under the mortar, which
/// is at least this wide.
pub(crate) const COVER_FROM: f32 = 2.0 * MORTAR;
/// The stone's edge is rounded over this distance from its border.
pub(crate) const BEVEL: f32 = 0.12;

/// How the textures are sampled.
#[derive(Clone, Copy, PartialEq, Debug)]
pub(crate) enum Shading {
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
pub(crate) struct Textures {
    /// The flagstones: the distance to the border of the sample's cell
    /// (even mortar whatever the spacing of the points), its normal for the
    /// bevel, and the cell's ID for the stone's colour.
    pub(crate) stones: SimdBorder<3>,
    /// F1..F4 with IDs and deltas: which stones a wide footprint covers.
    pub(crate) neighbours: Simd<3, 4>,
    /// Fractal F1, five octaves: the foil's crumple.
    pub(crate) crumple: Texture<3, 1>,
    /// Fractal compact smooth F1, three octaves: the hide's scales, their
    /// creases rounded.
    pub(crate) scales: Texture<3, 1>,
    pub(crate) stain: Perlin,
    /// Blend curves of the floor's fields, in floor texture units: the
    /// stone's identity, the mortar (border distance below [`MORTAR`]) and
    /// the stains.
    pub(crate) identity: BlendCurve,
    pub(crate) mortar: BlendCurve,
    pub(crate) stains: BlendCurve,
    /// The bevel's height, 1 − min(border / [`BEVEL`], 1), whose curve
    /// fades the bevel's bump.
    pub(crate) bevel: BlendCurve,
    /// The mean stone colour (each cell's colour weighs by its area).
    pub(crate) stone_mean: Vec3,
}

impl Textures {
    pub(crate) fn new() -> Self {
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
        let scales_fractal = Fractal { octaves: 3, lacunarity: 2.0, gain: 0.35 };
        let scales = Texture::new(config, Combination::Smooth(0.15), scales_fractal, None).expect("valid");
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
    pub(crate) fn shade8(
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
                // Smooth F1 lies about s below F1 away from the points.
                let t = ((value[i] - 0.38) / 0.8).clamp(0.0, 1.0);
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
    pub(crate) fn split_floor(
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
pub(crate) fn stain_at(p: &[[f64; 3]; 8]) -> [[f64; 3]; 8] {
    p.map(|q| [q[0] * 1.5, q[1] * 1.5, 0.3])
}

/// a·v + (1 − a)·mean, and v itself at a = 1.
pub(crate) fn blend(v: f32, a: f32, mean: f32) -> f32 {
    if a == 1.0 {
        v
    } else if a == 0.0 {
        mean
    } else {
        a * v + (1.0 - a) * mean
    }
}
