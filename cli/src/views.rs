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

/// A plane of pixels through space, or a stack of such planes (a volume).
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
    /// Planes along axis 2, one pixel's width apart from `slice[0]` on
    /// (1: one plane; more only in 3D and 4D).
    pub depth: usize,
}

impl View {
    /// The view as a grid of `D`-dimensional points (axis 0 fastest, so the
    /// grid's order is the image's row-major order, plane after plane).
    pub fn grid<const D: usize>(&self) -> Grid<D> {
        let step = self.extent / self.width.max(1) as f64;
        let depth = if D > 2 { self.depth } else { 1 };
        Grid {
            origin: std::array::from_fn(|a| if a < 2 { self.origin[a] + 0.5 * step } else { self.slice[a - 2] }),
            step: std::array::from_fn(|a| if a < 2 || (a == 2 && depth > 1) { step } else { 0.0 }),
            size: std::array::from_fn(|a| match a {
                0 => self.width,
                1 => self.height,
                2 => depth,
                _ => 1,
            }),
        }
    }

    /// Every pixel of the first plane.
    pub fn whole(&self) -> Window {
        Window { x: 0, y: 0, width: self.width, height: self.height, plane: 0 }
    }
}

/// A rectangle of a view's pixels: columns `x..x + width` and rows
/// `y..y + height` of plane `plane`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Window {
    /// First column.
    pub x: usize,
    /// First row, from the top.
    pub y: usize,
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// The plane along axis 2 (0 for a single image).
    pub plane: usize,
}

impl Window {
    /// Pixels in the window.
    pub fn len(&self) -> usize {
        self.width * self.height
    }

    /// Whether the window has no pixels.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The grid row (see [`Grid::rows`]) of the window's row `r`.
    pub fn grid_row(&self, view: &View, r: usize) -> usize {
        self.plane * view.height + self.y + r
    }
}

/// Fills `out` (the window's pixels, row-major) band by band of rows on all
/// cores: `fill(r, dst)` gets the band's first row within the window and
/// its pixels. Bands are 64 rows, as the library's parallel grids take
/// (each band generates its cells and their margin once), or fewer for a
/// short window, down to 8, so that every core has four bands.
pub fn fill_window<T: Send>(window: &Window, out: &mut [T], fill: impl Fn(usize, &mut [T]) + Sync) {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let band = window.height.div_ceil(4 * threads).clamp(8, 64);
    worley_harness::for_each_chunk(out, band * window.width.max(1), &|b, dst| fill(b * band, dst));
}

/// The window's pixels from whole grid rows: `rows(first, buffer)` fills
/// whole rows of the view's grid from grid row `first` (the bits its
/// whole-grid call gives them; the buffer starts as copies of `empty`), and
/// `pick` turns each pixel of the window's columns into an output.
pub fn from_rows<U: Copy + Sync, T: Send>(
    view: &View,
    window: &Window,
    out: &mut [T],
    empty: U,
    rows: impl Fn(usize, &mut [U]) + Sync,
    pick: impl Fn(&U) -> T + Sync,
) {
    fill_window(window, out, |r, dst| {
        let band = dst.len() / window.width.max(1);
        let mut buffer = vec![empty; band * view.width];
        rows(window.grid_row(view, r), &mut buffer);
        for (line, full) in dst.chunks_mut(window.width.max(1)).zip(buffer.chunks(view.width.max(1))) {
            for (o, v) in line.iter_mut().zip(&full[window.x..window.x + window.width]) {
                *o = pick(v);
            }
        }
    });
}

/// The window's pixels eight grid points at a time (the last block of a
/// band repeats its last point).
pub fn by_eights<const D: usize, T: Copy + Send>(
    view: &View,
    window: &Window,
    out: &mut [T],
    f: impl Fn(&[[f64; D]; 8]) -> [T; 8] + Sync,
) {
    let grid = view.grid::<D>();
    let row = window.width.max(1);
    let index = |p: usize| window.grid_row(view, p / row) * view.width + window.x + p % row;
    fill_window(window, out, |r, dst| {
        for (c, d8) in dst.chunks_mut(8).enumerate() {
            let start = r * row + c * 8;
            let block: [[f64; D]; 8] = std::array::from_fn(|i| grid.point(index(start + i.min(d8.len() - 1))));
            d8.copy_from_slice(&f(&block)[..d8.len()]);
        }
    });
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
    render_window(texture, view, &view.whole(), shading, range, filtered)
}

/// [`render`] for a window of the view: its pixels are the same bits as
/// those pixels of the whole view, so windows baked apart assemble into
/// the whole image.
///
/// # Errors
/// An image with no pixels, or one too large to address.
pub fn render_window<const D: usize, const N: usize>(
    texture: &Texture<D, N>,
    view: &View,
    window: &Window,
    shading: Shading,
    range: Range,
    filtered: bool,
) -> Result<(Vec<f32>, Rgb), String> {
    let values = texture_values(texture, view, window, filtered)?;
    let footprint = footprint(view, filtered);
    let mut pixels = vec![[0u8; 3]; window.len()];
    match shading {
        Shading::Colour(map) => {
            for (p, &v) in pixels.iter_mut().zip(&values) {
                *p = map.colour(range.remap(v));
            }
        }
        Shading::Bump { strength, map } => {
            let light = glam::Vec3::new(-0.5, -0.6, 0.9).normalize();
            by_eights(view, window, &mut pixels, |block| {
                normals(texture, block, footprint, strength)
                    .map(|normal| map.colour(0.15 + 0.85 * normal.dot(light).max(0.0)))
            })
        }
        Shading::Flagstones { mortar } => {
            let config = worley::Config { order: 2, ..*texture.kernel().config() };
            let cells = Simd::<D, 2>::new(config, Outputs::Ids).map_err(|e| e.to_string())?;
            let stain = worley::perlin::Perlin::new(config.seed);
            by_eights(view, window, &mut pixels, |block| {
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
    Ok((values, Rgb { width: window.width, height: window.height, pixels }))
}

/// The footprint of a pixel: its width in input units, or 0 (point samples).
pub fn footprint(view: &View, filtered: bool) -> f32 {
    if filtered {
        view.grid::<2>().step[0] as f32
    } else {
        0.0
    }
}

/// The texture's values at the window's pixels, through whole grid rows
/// ([`Texture::filtered_grid_rows`]): the bits of [`Texture::filtered_grid`]
/// over the whole view.
///
/// # Errors
/// A window with no pixels or beyond the view, or a view too large to address.
pub fn texture_values<const D: usize, const N: usize>(
    texture: &Texture<D, N>,
    view: &View,
    window: &Window,
    filtered: bool,
) -> Result<Vec<f32>, String> {
    check(view, window)?;
    let grid = view.grid::<D>();
    let footprint = footprint(view, filtered);
    let mut values = vec![0f32; window.len()];
    from_rows(
        view,
        window,
        &mut values,
        0f32,
        |first, rows: &mut [f32]| {
            texture.filtered_grid_rows(&grid, footprint, first, rows).expect("whole rows within the grid")
        },
        |&v| v,
    );
    Ok(values)
}

/// The normals of the texture as a height field over the image plane (the
/// plane's normal bent by `strength` times the gradient), eight points.
pub fn normals<const D: usize, const N: usize>(
    texture: &Texture<D, N>,
    block: &[[f64; D]; 8],
    footprint: f32,
    strength: f32,
) -> [glam::Vec3; 8] {
    let g = texture.filtered_gradient8(block, [footprint; 8]);
    let (gx, gy) = (g.gradient[0].to_array(), g.gradient[1].to_array());
    std::array::from_fn(|i| bump(glam::Vec3::Z, glam::Vec3::new(gx[i], gy[i], 0.0), strength))
}

/// Checks that the window has pixels and lies within the view.
///
/// # Errors
/// One line saying what is wrong.
pub fn check(view: &View, window: &Window) -> Result<(), String> {
    view.grid::<4>().len().filter(|&n| n > 0).ok_or("the image must have pixels, and few enough to address")?;
    if window.len() > 1 << 28 {
        return Err("a region of at most 2^28 pixels at a time".into());
    }
    let inside = window.x + window.width <= view.width
        && window.y + window.height <= view.height
        && window.plane < view.depth.max(1);
    if window.is_empty() || !inside {
        return Err(format!(
            "the region {}x{} at ({}, {}) of plane {} is empty or outside the {}x{} image of {} plane(s)",
            window.width, window.height, window.x, window.y, window.plane, view.width, view.height, view.depth
        ));
    }
    Ok(())
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

/// F1 beside compact smooth F1 at the smoothnesses `s` (user units), then
/// the n-sphere's dots, on the same points (2D, the lanes): the first
/// tiles as a colour map over [0, `range`] user units, the last with a dot
/// of F1's point's colour wherever F1 is below the n-sphere radius (circles
/// that fit their cells and never overlap). Returns the tiles in that order.
///
/// # Errors
/// A configuration the lanes refuse (another metric than the Euclidean),
/// or an image with no pixels.
pub fn smooth_and_dots(
    config: worley::Config,
    view: &View,
    range: f32,
    s: &[f32],
) -> Result<Vec<(Vec<f32>, Rgb)>, String> {
    let grid = view.grid::<2>();
    let n = grid.len().filter(|&n| n > 0 && n <= 1 << 28).ok_or("the image must have 1 to 2^28 pixels")?;
    let smooth = worley::SimdSmooth::<2>::new(config).map_err(|e| e.to_string())?;
    let spheres = worley::SimdNSphere::<2>::new(config).map_err(|e| e.to_string())?;
    let points: Vec<[f64; 2]> = (0..n).map(|i| grid.point(i)).collect();
    let smoothed = |s: f32| {
        let mut out = vec![worley::Smooth32::INVALID; n];
        smooth.smooth_slice(&points, s, &mut out).map_err(|e| e.to_string())?;
        Ok::<_, String>(out)
    };
    let image =
        |values: Vec<f32>, pixels: Vec<[u8; 3]>| (values, Rgb { width: view.width, height: view.height, pixels });
    let heat = |values: Vec<f32>| {
        let pixels = values.iter().map(|&v| ColourMap::Heat.colour((v / range).clamp(0.0, 1.0))).collect();
        image(values, pixels)
    };
    // s = 0 is F1 itself.
    let f1 = smoothed(0.0)?;
    let mut tiles = vec![heat(f1.iter().map(|v| v.value).collect())];
    for &s in s {
        tiles.push(heat(smoothed(s)?.iter().map(|v| v.value).collect()));
    }
    let mut radii = vec![worley::NSphere32::INVALID; n];
    spheres.n_sphere_slice(&points, &mut radii).map_err(|e| e.to_string())?;
    let ratio: Vec<f32> = f1.iter().zip(&radii).map(|(f, r)| f.value / r.radius).collect();
    let pixels = ratio
        .iter()
        .zip(&radii)
        .map(|(&q, r)| if q < 1.0 { id_colour(r.feature).map(crate::picture::to_byte) } else { [236, 230, 218] })
        .collect();
    tiles.push(image(ratio, pixels));
    Ok(tiles)
}
