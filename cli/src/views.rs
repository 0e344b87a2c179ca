//! Rendering a texture into an image: a view (a plane through 2D, 3D or 4D
//! space), a shading (colour map, shaded bump, flagstones), on all cores.
//!
//! Pixel (i, j), with i the column and j the row from the top, samples the
//! point whose first two coordinates are `origin + (i + ½, j + ½) · extent /
//! width` and whose remaining coordinates are `slice`. The raw values (the
//! PFM) are the texture's values at exactly those points.

use crate::picture::{id_colour, ColourMap, Rgb};
use worley::texture::{bump, Range, Texture};
use worley::{Grid, Outputs, Simd};

/// A plane of pixels through space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
    /// The image's corner on axes 0 and 1 (input units: user units, or cells
    /// for a periodic texture).
    pub origin: [f64; 2],
    /// Input units across the image's width.
    pub extent: f64,
    /// Coordinates on axes 2 and 3 (where the dimension has them).
    pub slice: [f64; 2],
}

impl View {
    /// The view as a grid of `D`-dimensional points (axis 0 fastest, so the
    /// grid's order is the image's row-major order).
    pub fn grid<const D: usize>(&self) -> Grid<D> {
        let step = self.extent / self.width.max(1) as f64;
        Grid {
            origin: std::array::from_fn(|a| if a < 2 { self.origin[a] + 0.5 * step } else { self.slice[a - 2] }),
            step: std::array::from_fn(|a| if a < 2 { step } else { 0.0 }),
            size: std::array::from_fn(|a| match a {
                0 => self.width,
                1 => self.height,
                _ => 1,
            }),
        }
    }
}

/// How values become colours.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shading {
    /// The value remapped by the range, through a colour map.
    Colour(ColourMap),
    /// The value as a height field lit from the upper left: the normal of the
    /// image plane perturbed by `strength` times the texture's gradient.
    Bump {
        /// Height per unit of texture value, in input units.
        strength: f32,
        /// Colour of the lit surface (by brightness).
        map: ColourMap,
    },
    /// Each cell a stone coloured by its F1 feature ID, mortar where
    /// F2 − F1 < `mortar` (user units), a rounded bevel from F2 − F1, and
    /// Perlin discolouration.
    Flagstones {
        /// Width of the mortar in F2 − F1.
        mortar: f32,
    },
}

/// The texture's raw values at the view's pixels (row-major, top row first)
/// and the shaded image. With `filtered`, each pixel's value and bump stand
/// for its footprint, a square of the grid's step
/// ([`Texture::filtered_grid`]); the flagstones stay point-sampled.
///
/// # Errors
/// An image with no pixels, or one too large to address.
pub fn render<const D: usize, const N: usize>(
    texture: &Texture<D, N>,
    view: &View,
    shading: Shading,
    range: Range,
    filtered: bool,
) -> Result<(Vec<f32>, Rgb), String> {
    let grid = view.grid::<D>();
    let n = grid.len().filter(|&n| n > 0 && n <= 1 << 28).ok_or("the image must have 1 to 2^28 pixels")?;
    let footprint = if filtered { grid.step[0] as f32 } else { 0.0 };
    let mut values = vec![0f32; n];
    texture.filtered_grid(&grid, footprint, &mut values).map_err(|e| e.to_string())?;
    let pixels = match shading {
        Shading::Colour(map) => values.iter().map(|&v| map.colour(range.remap(v))).collect(),
        Shading::Bump { strength, map } => {
            let light = glam::Vec3::new(-0.5, -0.6, 0.9).normalize();
            per_block(&grid, n, |block| {
                let g = texture.filtered_gradient8(block, [footprint; 8]);
                let (gx, gy) = (g.gradient[0].to_array(), g.gradient[1].to_array());
                std::array::from_fn(|i| {
                    let normal = bump(glam::Vec3::Z, glam::Vec3::new(gx[i], gy[i], 0.0), strength);
                    let lit = 0.15 + 0.85 * normal.dot(light).max(0.0);
                    map.colour(lit)
                })
            })
        }
        Shading::Flagstones { mortar } => {
            let config = worley::Config { order: 2, ..*texture.kernel().config() };
            let cells = Simd::<D, 2>::new(config, Outputs::Ids).map_err(|e| e.to_string())?;
            let stain = worley::perlin::Perlin::new(config.seed);
            per_block(&grid, n, |block| {
                // A periodic texture's flagstones tile with it.
                let f = match texture.period() {
                    Some(p) => cells.evaluate8_periodic(block, &p),
                    None => cells.evaluate8(block),
                };
                let (f1, f2, id) = (f.distance[0].to_array(), f.distance[1].to_array(), f.id[0].to_array());
                let spots = stain
                    .turbulence8(&block.map(|p| std::array::from_fn(|a| p.get(a).copied().unwrap_or(0.0) * 3.0)), 4)
                    .to_array();
                std::array::from_fn(|i| {
                    let edge = f2[i] - f1[i];
                    let stone = id_colour(id[i]);
                    let bevel = (edge / (3.0 * mortar)).clamp(0.0, 1.0).sqrt();
                    let shade = (0.55 + 0.45 * bevel) * (1.0 - 0.5 * spots[i].min(1.0));
                    let c = if edge < mortar {
                        [0.33, 0.31, 0.28].map(|m| m * (0.8 + 0.4 * bevel))
                    } else {
                        stone.map(|s| s * shade)
                    };
                    c.map(crate::picture::to_byte)
                })
            })
        }
    };
    Ok((values, Rgb { width: view.width, height: view.height, pixels }))
}

/// Runs `shade` over the grid's points eight at a time, on all cores.
fn per_block<const D: usize>(
    grid: &Grid<D>,
    n: usize,
    shade: impl Fn(&[[f64; D]; 8]) -> [[u8; 3]; 8] + Sync,
) -> Vec<[u8; 3]> {
    let mut pixels = vec![[0u8; 3]; n];
    grid.fill_by_eights(&mut pixels, shade).expect("the buffer holds one pixel per grid point");
    pixels
}

/// F2 − F1 beside twice the distance to the cell's border, on the same
/// points (2D, the f64 reference, which is exact for both; a plane through
/// 3D cells would cut bisector planes at a slant and widen their lines
/// there): the top row as a colour map over [0, `range`] user units, the
/// bottom row as mortar where each is below `mortar`. F2 − F1's lines widen
/// where two feature points lie close together; the border's are even.
/// Returns the four tiles in that order.
///
/// # Errors
/// An invalid configuration, or an image with no pixels.
pub fn border_and_crackle(
    config: worley::Config,
    view: &View,
    range: f32,
    mortar: f32,
) -> Result<Vec<(Vec<f32>, Rgb)>, String> {
    let basis = worley::Reference::<2>::new(worley::Config { order: 2, ..config }).map_err(|e| e.to_string())?;
    let grid = view.grid::<2>();
    let n = grid.len().filter(|&n| n > 0 && n <= 1 << 28).ok_or("the image must have 1 to 2^28 pixels")?;
    let parts = worley_harness::chunked(n, |pixels| {
        pixels
            .map(|i| {
                let x = grid.point(i);
                let f = basis.evaluate(x);
                let border = basis.border(x).map(|b| b.distance)?;
                Ok([(f.distance[1] - f.distance[0]) as f32, 2.0 * border as f32])
            })
            .collect::<Result<Vec<[f32; 2]>, worley::ConfigError>>()
    });
    let mut pairs = Vec::with_capacity(n);
    for part in parts {
        pairs.extend(part.map_err(|e| e.to_string())?);
    }
    let image = |values: Vec<f32>, colour: &dyn Fn(f32) -> [u8; 3]| {
        let pixels = values.iter().map(|&v| colour(v)).collect();
        (values, Rgb { width: view.width, height: view.height, pixels })
    };
    let heat = |v: f32| ColourMap::Heat.colour((v / range).clamp(0.0, 1.0));
    let lines = |v: f32| if v < mortar { [84, 79, 71] } else { [226, 220, 206] };
    let column = |k: usize| pairs.iter().map(|p| p[k]).collect::<Vec<f32>>();
    Ok(vec![image(column(0), &heat), image(column(1), &heat), image(column(0), &lines), image(column(1), &lines)])
}
