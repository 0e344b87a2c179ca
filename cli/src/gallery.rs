//! The gallery of the main job and `worley gallery`: the chapter's figures
//! and the textures, as sheets of tiles.

use std::path::{Path, PathBuf};

use crate::bake;
use crate::picture::{self, sheet, ColourMap, Rgb};
use crate::render_cmd::{random_combinations, render_combo, Cells, RenderArgs, ShadeArg};
use crate::views::{self as render, Window};
use worley::config::DEFAULT_DENSITY;
use worley::texture::Combination;
use worley::{Config, Metric};

/// The gallery: the chapter's figures and textures, into `dir`, each also
/// as an EXR of its raw values (one `value` channel, NaN in the gaps between
/// tiles) with `exr`. Returns the files written.
pub fn gallery(dir: &Path, tile: usize, show_progress: bool, exr: bool) -> Result<Vec<PathBuf>, String> {
    let base = RenderArgs {
        png: PathBuf::new(),
        pfm: None,
        exr: None,
        channels: None,
        region: None,
        tile: None,
        depth: 1,
        dim: 3,
        combo: Combination::f(1),
        metric: Metric::Euclidean,
        size: (tile, tile),
        extent: 8.0,
        origin: (0.0, 0.0),
        slice: (0.5, 0.5),
        seed: 0,
        density: DEFAULT_DENSITY,
        colour: ColourMap::Heat,
        shade: ShadeArg::Colour,
        strength: 0.6,
        octaves: 1,
        lacunarity: 2.0,
        gain: 0.5,
        period: None,
        range: None,
        random_combos: None,
        combo_seed: 1,
        filtered: false,
    };
    let with = |f: &dyn Fn(&mut RenderArgs)| {
        let mut a = base.clone();
        f(&mut a);
        a
    };
    let one = |a: &RenderArgs| render_combo(a, &a.combo).map(|(v, i, _)| (v, i));
    type Figure<'a> = (&'a str, Box<dyn Fn() -> Result<(Vec<f32>, Rgb), String> + 'a>);
    let figures: Vec<Figure> = vec![
        (
            "fig4_2_f1_f2_f3_crackle.png",
            Box::new(|| {
                let tiles: Result<Vec<_>, String> = ["F1", "F2", "F3", "F2-F1"]
                    .iter()
                    .map(|c| one(&with(&|a| a.combo = c.parse().expect("a valid combination"))))
                    .collect();
                Ok(sheet(&tiles?, 2, 2))
            }),
        ),
        (
            "fig4_3_random_combinations.png",
            Box::new(|| {
                let a = with(&|a| a.size = (tile / 2, tile / 2));
                let tiles: Result<Vec<_>, String> =
                    random_combinations(16, 1).iter().map(|c| render_combo(&a, c).map(|(v, i, _)| (v, i))).collect();
                Ok(sheet(&tiles?, 4, 2))
            }),
        ),
        (
            "fig4_10_manhattan_chebyshev.png",
            Box::new(|| {
                let tiles: Result<Vec<_>, String> = [Metric::Manhattan, Metric::Chebyshev]
                    .iter()
                    .map(|m| {
                        one(&with(&|a| {
                            a.metric = *m;
                            a.colour = ColourMap::Ice;
                        }))
                    })
                    .collect();
                Ok(sheet(&tiles?, 2, 2))
            }),
        ),
        (
            "crumple.png",
            Box::new(|| {
                one(&with(&|a| {
                    a.octaves = 5;
                    a.shade = ShadeArg::Bump;
                    a.strength = 0.1;
                    a.colour = ColourMap::Ice;
                }))
            }),
        ),
        ("flagstones.png", Box::new(|| one(&with(&|a| a.shade = ShadeArg::Flagstones)))),
        (
            "border_vs_crackle.png",
            Box::new(|| {
                let config = Config { seed: base.seed, density: base.density, ..Config::default() };
                let tiles = render::border_and_crackle(config, &base.view(), 0.8, 0.12)?;
                Ok(sheet(&tiles, 2, 2))
            }),
        ),
        (
            "smooth_f1_and_n_sphere.png",
            Box::new(|| {
                let config = Config { seed: base.seed, density: base.density, ..Config::default() };
                let tiles = render::smooth_and_dots(config, &base.view(), 1.6, &[0.15, 0.4])?;
                Ok(sheet(&tiles, 2, 2))
            }),
        ),
        (
            "tileable_2x2.png",
            Box::new(|| {
                let a = with(&|a| {
                    a.combo = Combination::crackle();
                    a.size = (tile / 2, tile / 2);
                    a.period = Some(Cells(vec![6]));
                    a.extent = 6.0;
                    a.octaves = 3;
                    a.colour = ColourMap::Earth;
                });
                let t = one(&a)?;
                Ok(sheet(&[t.clone(), t.clone(), t.clone(), t], 2, 0))
            }),
        ),
    ];
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let bar = if show_progress {
        crate::commands::progress(figures.len() as u64, "gallery")
    } else {
        indicatif::ProgressBar::hidden()
    };
    let mut written = Vec::new();
    for (name, make) in &figures {
        let (values, image) = make()?;
        let path = dir.join(name);
        picture::write_output(&path, &image.to_png()?)?;
        written.push(path.clone());
        if exr {
            let path = path.with_extension("exr");
            let window = Window { x: 0, y: 0, width: image.width, height: image.height, plane: 0 };
            let plane = bake::Plane {
                name: None,
                z: None,
                window,
                channels: vec![("value".into(), bake::Samples::F32(values))],
            };
            let settings = [("version", env!("CARGO_PKG_VERSION").to_string()), ("figure", name.to_string())];
            picture::write_output(&path, &bake::encode(image.width, image.height, vec![plane], &settings)?)?;
            written.push(path);
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(written)
}
