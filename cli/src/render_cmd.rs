//! `worley render`: one image, or a window of it, as PNG, PFM and EXR.

use std::path::{Path, PathBuf};

use crate::bake::{self, Channel};
use crate::picture::{self, ColourMap, Rgb};
use crate::views::{self as render, Shading, View, Window};
use clap::ValueEnum;
use worley::config::DEFAULT_DENSITY;
use worley::texture::{Combination, Fractal, Range, Texture};
use worley::{Config, Metric, Period};
use worley_harness::uniform;

/// How values become colours (command-line form of [`Shading`]).
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum, Debug)]
pub enum ShadeArg {
    /// The value through the colour map.
    Colour,
    /// The value as a lit height field.
    Bump,
    /// Cells coloured by ID with mortar along F2 − F1.
    Flagstones,
}

/// Options of `worley render`.
#[derive(clap::Args, Debug, Clone)]
pub struct RenderArgs {
    /// Output PNG.
    #[arg(long, default_value = "out/render.png")]
    pub png: PathBuf,
    /// Also write the raw values as a greyscale PFM (32-bit floats).
    #[arg(long)]
    pub pfm: Option<PathBuf>,
    /// Also write an OpenEXR file (`-`: standard output) with the channels of
    /// --channels, compressed, the configuration in its header.
    #[arg(long)]
    pub exr: Option<PathBuf>,
    /// The EXR's channels, comma-separated: value (the texture, as the PFM),
    /// F1, F2, F2-F1, id (F1's feature ID, 32-bit unsigned), delta (to F1's
    /// point, one channel per axis), border, normal (the bump normal); or
    /// all. Default: value, F1, F2, F2-F1, id, delta, and border or normal
    /// where the combination or shading uses it.
    #[arg(long, value_parser = crate::bake::parse_channels, requires = "exr")]
    pub channels: Option<crate::bake::Channels>,
    /// Bake only the pixels X..X+W, Y..Y+H of the image, as X,Y,W,H (every
    /// output; the EXR places them in the whole image, see `worley stitch`).
    #[arg(long, value_parser = parse_region, conflicts_with = "tile")]
    pub region: Option<[usize; 4]>,
    /// Bake only band I of N (0 <= I < N) of the image's rows, as I/N: a job
    /// array's task I writes its band, `worley stitch` assembles them.
    #[arg(long, value_parser = parse_tile)]
    pub tile: Option<(usize, usize)>,
    /// Planes along axis 2 (3D and 4D), one pixel apart from the slice's
    /// Z on: the EXR holds one layer per plane (z0000, z0001, ...); the PNG
    /// and PFM show the first plane.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub depth: u32,
    /// Dimension: 2, or a plane through 3D or 4D.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u8).range(2..=4))]
    pub dim: u8,
    /// The combination: F1, F2-F1, 0.5F1+2F3, F1*F2, F3^2-F2^2 (F1..F4), border (the distance
    /// to the cell's border: even lines), smooth:S (compact smooth F1 with smoothness S in
    /// user units: rounded cells), or n-sphere (half the distance from F1's point to its
    /// nearest: one value per cell); the last three Euclidean only.
    #[arg(long, default_value = "F1", value_parser = parse_combination)]
    pub combo: Combination,
    /// Metric: euclidean, manhattan, chebyshev, or minkowski:P with P >= 1.
    #[arg(long, default_value = "euclidean", value_parser = crate::commands::parse_metric)]
    pub metric: Metric,
    /// Image size in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "512x512", value_parser = parse_size)]
    pub size: (usize, usize),
    /// Input units across the image's width (user units; cells when periodic).
    #[arg(long, default_value_t = 12.0)]
    pub extent: f64,
    /// The image's corner on axes 0 and 1, X,Y.
    #[arg(long, default_value = "0,0", value_parser = parse_pair)]
    pub origin: (f64, f64),
    /// Coordinates on axes 2 and 3 for a plane through 3D or 4D, given as Z or Z,W.
    #[arg(long, default_value = "0.5,0.5", value_parser = parse_pair)]
    pub slice: (f64, f64),
    /// Pattern seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Mean density λ of the population table.
    #[arg(long, default_value_t = DEFAULT_DENSITY)]
    pub density: f64,
    /// Colour map: gray, heat, ice, earth.
    #[arg(long, default_value = "heat", value_parser = parse_colour_map)]
    pub colour: ColourMap,
    /// Shading.
    #[arg(long, value_enum, default_value_t = ShadeArg::Colour)]
    pub shade: ShadeArg,
    /// Bump height per unit of value (input units), for --shade bump.
    #[arg(long, default_value_t = 0.6)]
    pub strength: f32,
    /// Let each pixel's value (and bump) stand for the pixel's footprint, a
    /// square of one pixel's width in input units, instead of its centre:
    /// no aliasing where a pixel covers many cells, and octaves finer than
    /// a pixel are not evaluated (see `worley::filter`).
    #[arg(long)]
    pub filtered: bool,
    /// Fractal octaves (1: the plain combination).
    #[arg(long, default_value_t = 1)]
    pub octaves: u32,
    /// Frequency factor between octaves.
    #[arg(long, default_value_t = 2.0)]
    pub lacunarity: f32,
    /// Amplitude factor between octaves.
    #[arg(long, default_value_t = 0.5)]
    pub gain: f32,
    /// Make the texture tile: whole cells per axis, P0,P1 (then P2 and P3 in 3D and 4D); the view
    /// is then in cells (a tile is --extent P0).
    #[arg(long, value_parser = parse_period)]
    pub period: Option<Cells>,
    /// Value range mapped to the colour map's ends, LO,HI (default: the
    /// 0.1 % and 99.9 % quantiles over 100 000 random samples).
    #[arg(long, value_parser = parse_pair)]
    pub range: Option<(f64, f64)>,
    /// Draw K random combinations C1F1+C2F2+C3F3+C4F4 (Figure 4.3 of the
    /// chapter) into a sheet of tiles of --size each, and print them.
    #[arg(long)]
    pub random_combos: Option<usize>,
    /// Seed of the random combinations.
    #[arg(long, default_value_t = 1)]
    pub combo_seed: u64,
}

fn parse_combination(s: &str) -> Result<Combination, String> {
    let c: Combination = s.parse()?;
    if c.order() > 4 {
        return Err(format!("{s:?} needs F{}: the command line renders F1..F4", c.order()));
    }
    Ok(c)
}

fn parse_size(s: &str) -> Result<(usize, usize), String> {
    let usage = "use WIDTHxHEIGHT with each from 1 to 16384, e.g. 512x512";
    let (w, h) = s.split_once('x').ok_or_else(|| format!("size {s:?}: {usage}"))?;
    let parse = |v: &str| v.parse::<usize>().ok().filter(|n| (1..=16384).contains(n));
    match (parse(w), parse(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(format!("size {s:?}: {usage}")),
    }
}

fn parse_region(s: &str) -> Result<[usize; 4], String> {
    let v: Vec<usize> = s.split(',').map(|v| v.trim().parse().ok()).collect::<Option<_>>().unwrap_or_default();
    match v[..] {
        [x, y, w, h] if w > 0 && h > 0 => Ok([x, y, w, h]),
        _ => Err(format!("region {s:?}: use X,Y,W,H, whole pixels with W and H above 0")),
    }
}

fn parse_tile(s: &str) -> Result<(usize, usize), String> {
    let usage = || format!("tile {s:?}: use I/N with 0 <= I < N, e.g. 0/4");
    let (i, n) = s.split_once('/').ok_or_else(usage)?;
    match (i.trim().parse::<usize>(), n.trim().parse::<usize>()) {
        (Ok(i), Ok(n)) if i < n => Ok((i, n)),
        _ => Err(usage()),
    }
}

fn parse_pair(s: &str) -> Result<(f64, f64), String> {
    let v: Vec<f64> = crate::commands::parse_list(s, "coordinate")?;
    let ok = v.iter().all(|x| x.is_finite());
    match v[..] {
        [a] if ok => Ok((a, a)),
        [a, b] if ok => Ok((a, b)),
        _ => Err(format!("{s:?}: use one or two finite numbers, A[,B]")),
    }
}

fn parse_colour_map(s: &str) -> Result<ColourMap, String> {
    s.parse()
}

/// Whole cells per axis (the last one repeats for the remaining axes).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Cells(pub Vec<u32>);

fn parse_period(s: &str) -> Result<Cells, String> {
    let usage = format!("period {s:?}: use 1 to 4 whole numbers of cells from 1 to {}", worley::simd::MAX_PERIOD);
    let v: Vec<u32> = crate::commands::parse_list(s, "period").map_err(|_| usage.clone())?;
    if v.is_empty() || v.len() > 4 || v.iter().any(|&p| p == 0 || p > worley::simd::MAX_PERIOD) {
        return Err(usage);
    }
    Ok(Cells(v))
}

impl RenderArgs {
    fn config(&self) -> Config {
        Config { seed: self.seed, metric: self.metric, density: self.density, ..Config::default() }
    }

    pub(crate) fn view(&self) -> View {
        View {
            width: self.size.0,
            height: self.size.1,
            origin: [self.origin.0, self.origin.1],
            extent: self.extent,
            slice: [self.slice.0, self.slice.1],
            depth: self.depth as usize,
        }
    }

    /// The pixels of each plane that this run bakes.
    fn window(&self) -> Result<Window, String> {
        let view = self.view();
        let window = match (self.region, self.tile) {
            (Some([x, y, width, height]), _) => Window { x, y, width, height, plane: 0 },
            (None, Some((i, n))) => crate::bake::band(&view, i, n)?,
            (None, None) => view.whole(),
        };
        render::check(&view, &window)?;
        Ok(window)
    }

    fn shading(&self) -> Shading {
        match self.shade {
            ShadeArg::Colour => Shading::Colour(self.colour),
            ShadeArg::Bump => Shading::Bump { strength: self.strength, map: self.colour },
            ShadeArg::Flagstones => Shading::Flagstones { mortar: 0.06 },
        }
    }

    fn fractal(&self) -> Fractal {
        Fractal { octaves: self.octaves, lacunarity: self.lacunarity, gain: self.gain }
    }
}

/// Renders `combo` as the arguments say: raw values and the image (of the
/// window of `--region` or `--tile` in the first plane).
pub fn render_combo(args: &RenderArgs, combo: &Combination) -> Result<(Vec<f32>, Rgb, Range), String> {
    with_texture(args, combo, &|bake| bake.render(&args.window()?))
}

/// What a texture of any dimension and order can do for the command.
trait Baker {
    /// The values and the image of a window, and the colour range.
    fn render(&self, window: &Window) -> Result<(Vec<f32>, Rgb, Range), String>;
    /// The EXR planes of the window in every plane of the view.
    fn planes(&self, window: &Window, channels: &[Channel]) -> Result<Vec<bake::Plane>, String>;
}

struct Textured<'a, const D: usize, const N: usize> {
    args: &'a RenderArgs,
    texture: Texture<D, N>,
    range: Range,
}

impl<const D: usize, const N: usize> Baker for Textured<'_, D, N> {
    fn render(&self, window: &Window) -> Result<(Vec<f32>, Rgb, Range), String> {
        let a = self.args;
        let (values, image) =
            render::render_window(&self.texture, &a.view(), window, a.shading(), self.range, a.filtered)?;
        Ok((values, image, self.range))
    }

    fn planes(&self, window: &Window, channels: &[Channel]) -> Result<Vec<bake::Plane>, String> {
        let (a, view) = (self.args, self.args.view());
        let source = bake::Source { texture: &self.texture, view: &view, filtered: a.filtered, strength: a.strength };
        let bar = if view.depth > 1 {
            crate::commands::progress(view.depth as u64, "planes")
        } else {
            indicatif::ProgressBar::hidden()
        };
        let mut planes = Vec::new();
        for plane in 0..view.depth {
            let window = Window { plane, ..*window };
            let value = if channels.contains(&Channel::Value) {
                render::texture_values(&self.texture, &view, &window, a.filtered)?
            } else {
                Vec::new()
            };
            let name = (view.depth > 1).then(|| format!("z{plane:04}"));
            let z = (D > 2).then(|| view.grid::<3>().point(plane * view.width * view.height)[2]);
            let channels = bake::channels(&source, &window, value, channels)?;
            planes.push(bake::Plane { name, z, channels, window });
            bar.inc(1);
        }
        bar.finish_and_clear();
        Ok(planes)
    }
}

/// Calls `f` with the texture the arguments describe.
fn with_texture<R>(
    args: &RenderArgs,
    combo: &Combination,
    f: &dyn Fn(&dyn Baker) -> Result<R, String>,
) -> Result<R, String> {
    fn go<const D: usize, const N: usize, R>(
        args: &RenderArgs,
        combo: &Combination,
        f: &dyn Fn(&dyn Baker) -> Result<R, String>,
    ) -> Result<R, String> {
        if args.depth > 1 && D < 3 {
            return Err(format!("--depth {}: planes along axis 2 need --dim 3 or 4", args.depth));
        }
        let period = match &args.period {
            None => None,
            Some(Cells(p)) => {
                let cells: [u32; D] = std::array::from_fn(|a| p.get(a).or(p.last()).copied().unwrap_or(1));
                Some(Period::new(cells).map_err(|e| e.to_string())?)
            }
        };
        let texture =
            Texture::<D, N>::new(args.config(), combo.clone(), args.fractal(), period).map_err(|e| e.to_string())?;
        let range = match args.range {
            Some((lo, hi)) => Range { lo: lo as f32, hi: hi as f32 },
            None => texture.measure_range(100_000, 1),
        };
        f(&Textured { args, texture, range })
    }
    let order = combo.order().max(if args.shade == ShadeArg::Flagstones { 2 } else { 1 });
    // Orders 1, 2 and 4, the kernels `check` and `tune` build too: a
    // combination of F3 takes F1..F4, whose first three are F1..F3 bit for
    // bit (each kernel instantiation is a sizeable part of the build).
    match (args.dim, order) {
        (2, 1) => go::<2, 1, R>(args, combo, f),
        (2, 2) => go::<2, 2, R>(args, combo, f),
        (2, _) => go::<2, 4, R>(args, combo, f),
        (3, 1) => go::<3, 1, R>(args, combo, f),
        (3, 2) => go::<3, 2, R>(args, combo, f),
        (3, _) => go::<3, 4, R>(args, combo, f),
        (_, 1) => go::<4, 1, R>(args, combo, f),
        (_, 2) => go::<4, 2, R>(args, combo, f),
        _ => go::<4, 4, R>(args, combo, f),
    }
}

/// The settings a bake's header records: the configuration and the view.
fn settings(args: &RenderArgs) -> Vec<(&'static str, String)> {
    let fractal = args.fractal();
    let mut list = vec![
        ("version", env!("CARGO_PKG_VERSION").to_string()),
        ("combination", args.combo.name()),
        ("order", args.combo.order().to_string()),
        ("dimension", args.dim.to_string()),
        ("seed", args.seed.to_string()),
        ("metric", format!("{:?}", args.metric)),
        ("density", args.density.to_string()),
        ("octaves", fractal.octaves.to_string()),
        ("lacunarity", fractal.lacunarity.to_string()),
        ("gain", fractal.gain.to_string()),
        // The first octave's, in the command's input units.
        ("frequency", "1".to_string()),
        ("filtered", args.filtered.to_string()),
        ("origin", format!("{},{}", args.origin.0, args.origin.1)),
        ("extent", args.extent.to_string()),
        ("pixel_step", (args.extent / args.size.0 as f64).to_string()),
        ("slice", format!("{},{}", args.slice.0, args.slice.1)),
    ];
    if let Some(Cells(p)) = &args.period {
        list.push(("period", p.iter().map(u32::to_string).collect::<Vec<_>>().join(",")));
    }
    list
}

/// The EXR of `args`: every plane's window with the asked channels.
fn write_exr(args: &RenderArgs, path: &Path) -> Result<(), String> {
    let window = args.window()?;
    let channels = match &args.channels {
        Some(list) => list.0.clone(),
        None => Channel::defaults(&args.combo, args.shade == ShadeArg::Bump),
    };
    if channels.contains(&Channel::Border) && args.metric != Metric::Euclidean {
        return Err("the border channel needs the Euclidean metric".into());
    }
    let planes = with_texture(args, &args.combo, &|bake| bake.planes(&window, &channels))?;
    let bytes = bake::encode(args.size.0, args.size.1, planes, &settings(args))?;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    picture::write_output(path, &bytes)
}

/// K random combinations C1F1+…+C4F4, coefficients uniform in [−1, 1]
/// rounded to 0.05, never all zero.
pub fn random_combinations(k: usize, seed: u64) -> Vec<Combination> {
    (0..k)
        .map(|i| {
            let mut c: Vec<f32> = (0..4)
                .map(|j| ((uniform(seed, (i * 4 + j) as u64) * 2.0 - 1.0) * 20.0).round() as f32 / 20.0 + 0.0)
                .collect();
            if c.iter().all(|&v| v == 0.0) {
                c[0] = 1.0;
            }
            Combination::Linear(c)
        })
        .collect()
}

fn write_outputs(png: &Path, pfm: Option<&Path>, values: &[f32], image: &Rgb) -> Result<(), String> {
    for p in std::iter::once(png).chain(pfm) {
        if let Some(dir) = p.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
        }
    }
    picture::write_output(png, &image.to_png()?)?;
    if let Some(pfm) = pfm {
        picture::write_output(pfm, &picture::to_pfm(image.width, image.height, values))?;
    }
    Ok(())
}

/// `worley render`.
pub fn render_command(args: &RenderArgs) -> Result<(), String> {
    let started = std::time::Instant::now();
    // When an image goes to standard output, the messages go to standard
    // error so that the image stays whole.
    let outputs = [Some(args.png.as_path()), args.pfm.as_deref(), args.exr.as_deref()];
    let piped = outputs.iter().flatten().filter(|p| p.as_os_str() == "-").count();
    if piped > 1 {
        return Err("only one of --png, --pfm and --exr can go to standard output (-)".into());
    }
    let piped = piped == 1;
    if args.random_combos.is_some()
        && (args.exr.is_some() || args.region.is_some() || args.tile.is_some() || args.depth > 1)
    {
        return Err("--random-combos draws a sheet: it takes no --exr, --region, --tile or --depth".into());
    }
    let say = |line: String| {
        if piped {
            eprintln!("{line}");
        } else {
            println!("{line}");
        }
    };
    let (values, image) = match args.random_combos {
        None => {
            let spinner = indicatif::ProgressBar::new_spinner().with_message("rendering");
            spinner.enable_steady_tick(std::time::Duration::from_millis(200));
            let (values, image, range) = render_combo(args, &args.combo)?;
            spinner.finish_and_clear();
            say(format!("{}: range [{:.4}, {:.4}] mapped to the colour map", args.combo.name(), range.lo, range.hi));
            (values, image)
        }
        Some(k) if (1..=64).contains(&k) => {
            let combos = random_combinations(k, args.combo_seed);
            let bar = crate::commands::progress(k as u64, "combinations");
            let mut tiles = Vec::new();
            for (i, c) in combos.iter().enumerate() {
                let (v, img, _) = render_combo(args, c)?;
                let Combination::Linear(cs) = c else { unreachable!("random combinations are linear") };
                bar.suspend(|| {
                    say(format!(
                        "{:>3}: C = [{:+.2}, {:+.2}, {:+.2}, {:+.2}]  {}",
                        i + 1,
                        cs[0],
                        cs[1],
                        cs[2],
                        cs[3],
                        c.name()
                    ))
                });
                tiles.push((v, img));
                bar.inc(1);
            }
            bar.finish_and_clear();
            crate::picture::sheet(&tiles, (k as f64).sqrt().ceil() as usize, 2)
        }
        Some(k) => return Err(format!("--random-combos {k}: use 1 to 64")),
    };
    write_outputs(&args.png, args.pfm.as_deref(), &values, &image)?;
    if let Some(exr) = &args.exr {
        let spinner = indicatif::ProgressBar::new_spinner().with_message("baking the EXR channels");
        spinner.enable_steady_tick(std::time::Duration::from_millis(200));
        write_exr(args, exr)?;
        spinner.finish_and_clear();
    }
    say(format!(
        "wrote {} ({}x{}){}{} in {:.2} s",
        args.png.display(),
        image.width,
        image.height,
        args.pfm.as_ref().map(|p| format!(", {}", p.display())).unwrap_or_default(),
        args.exr.as_ref().map(|p| format!(", {}", p.display())).unwrap_or_default(),
        started.elapsed().as_secs_f64()
    ));
    Ok(())
}
